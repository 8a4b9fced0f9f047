// Spring rest lengths from water loss (Jeong Eq. 11-12, kernels/drying/shrink.h) on the Table 1 maple's 51102
// springs, at 1 and 2 threads, beside the formula as written with libm's pow, one spring at a
// time, on the same springs and masses. The masses are those of the maple after 400 frames of
// Algorithm 1 with maple-green (the collision benchmarks' dried state), so v_rel spans what a
// drying run meets; the parameters are maple-green's (sigma_vein 0.5, sigma_surf 1.5, alpha 1.3).
//
// Counter: springs/s. The kernel runs once per frame of a leaf, so its cost adds to every frame
// however few projection sweeps the frame needs.
//
// Measured (AVX2 machine, medians of 5): 575 us at 1 thread, 318 us at 2; libm 1246 us. Before the
// exponent stopped using an int64 -> double conversion, which AVX2 lacks and which had kept the
// whole loop scalar, a driver timing the kernel on the maple (best of 300 calls) saw 2034 / 1019
// us, against 356 / 233 us after.
#include "drying/layers.h"
#include "drying/shrink.h"
#include "fixture.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

namespace
{
sere_shrink_params maple_green()
{
	sere_shrink_params params{};
	params.sigma_vein = 0.5;
	params.sigma_surf = 1.5;
	params.alpha = 1.3;
	params.m_min = 0.1;
	params.min_length_ratio = 0.2;
	return params;
}

const sere_model& dried()
{
	return *sere_bench_dried_model( SERE_BENCH_MAPLE, 400 );
}

void BM_Shrink( benchmark::State& state )
{
	const int32_t threads = static_cast<int32_t>( state.range( 0 ) );
	const sere_model& m = dried();
	std::vector<float> rest( m.s.rest, m.s.rest + m.s.count );
	const sere_shrink_params params = maple_green();
	for ( auto _ : state )
	{
		sere_status status = sere_shrink( m.s.a, m.s.b, m.s.kind, m.s.rest0, rest.data(), 0, m.s.count, m.p.m, m.p.m0,
										  &params, threads );
		if ( status != SERE_OK )
		{
			state.SkipWithError( sere_status_text( status ) );
			break;
		}
		benchmark::DoNotOptimize( rest.data() );
	}
	state.counters["springs/s"] =
		benchmark::Counter( static_cast<double>( m.s.count ) * state.iterations(), benchmark::Counter::kIsRate );
}

// The kernel's floor: the same loads and stores per spring (both ends, the class byte, l0, the
// four masses m and m0 gathered, the rest length written) with one add per value in place of
// Eq. 11-12's arithmetic. Args: threads.
void BM_ShrinkFloor( benchmark::State& state )
{
	const int threads = static_cast<int>( state.range( 0 ) );
	const sere_model& m = dried();
	std::vector<float> rest( m.s.rest, m.s.rest + m.s.count );
	const int32_t* __restrict a = m.s.a, * __restrict b = m.s.b;
	const uint8_t* __restrict kind = m.s.kind;
	const float* __restrict rest0 = m.s.rest0;
	const double* __restrict mass = m.p.m, * __restrict mass0 = m.p.m0;
	float* __restrict out = rest.data();
	const int32_t count = m.s.count;
	for ( auto _ : state )
	{
#pragma omp parallel for simd num_threads( threads ) schedule( static )
		for ( int32_t s = 0; s < count; ++s )
		{
			double sum = ( mass[a[s]] + mass[b[s]] ) + ( mass0[a[s]] + mass0[b[s]] );
			out[s] = rest0[s] + static_cast<float>( sum + kind[s] );
		}
		benchmark::DoNotOptimize( out );
	}
	state.counters["springs/s"] =
		benchmark::Counter( static_cast<double>( count ) * state.iterations(), benchmark::Counter::kIsRate );
}

// Jeong Eq. 11-12 and the stop rules as shrink.h states them, with std::pow: the baseline the SIMD
// exp/log pair replaces.
void BM_ShrinkLibm( benchmark::State& state )
{
	const sere_model& m = dried();
	std::vector<float> rest( m.s.rest, m.s.rest + m.s.count );
	const sere_shrink_params params = maple_green();
	for ( auto _ : state )
	{
		for ( int32_t s = 0; s < m.s.count; ++s )
		{
			double ma = m.p.m[m.s.a[s]], mb = m.p.m[m.s.b[s]];
			double v_rel = ( ma + mb ) / ( m.p.m0[m.s.a[s]] + m.p.m0[m.s.b[s]] );
			double power = v_rel >= 0.0 && v_rel < 1.0 ? std::pow( 1.0 - v_rel, params.alpha ) : 0.0;
			double sigma = ( m.s.kind[s] & SERE_SPRING_VEIN ) ? params.sigma_vein : params.sigma_surf;
			double l0 = m.s.rest0[s];
			double length = l0 * ( 1.0 - sigma * power );
			if ( ma >= params.m_min && mb >= params.m_min && length >= params.min_length_ratio * l0 )
			{
				rest[s] = static_cast<float>( length );
			}
		}
		benchmark::DoNotOptimize( rest.data() );
	}
	state.counters["springs/s"] =
		benchmark::Counter( static_cast<double>( m.s.count ) * state.iterations(), benchmark::Counter::kIsRate );
}
} // namespace

BENCHMARK( BM_Shrink )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_ShrinkFloor )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_ShrinkLibm )->Unit( benchmark::kMicrosecond );
