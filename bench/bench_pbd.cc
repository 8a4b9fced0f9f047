// Projection sweeps over the 51,102 constraints of the Table 1 maple (13,197 particles): the
// colored SIMD Gauss-Seidel, the Jacobi variant, the scalar AoS reference, and two floors with
// a trivial operation in place of the projection: sere_pbd_touch (the colored solver's own
// schedule and memory traffic) and a plain SoA loop with AVX-512 gathers and scatters.
// Counter: constraints/s (and its inverse, ns per constraint projection).
//
// The Voronoi springs are shortened by 10% so every sweep has work to do. Each benchmark
// iteration continues from the state the previous one left: none of the solvers branches on the
// data (the reference only on degenerate springs), so the cost does not depend on the state,
// and the frustrated double layer stays bounded.
#include "fixture.h"
#include "pbd.h"
#include "ref/pbd_ref.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <vector>

namespace
{
struct scene
{
	const sere_model* model = nullptr;
	std::vector<float> x, y, z, inv_m, rest;
	sere_pbd* pbd = nullptr;
};

scene& maple()
{
	static scene s;
	if ( s.pbd != nullptr )
	{
		return s;
	}
	s.model = sere_bench_model( SERE_BENCH_MAPLE );
	const sere_model* m = s.model;
	s.x.assign( m->p.x, m->p.x + m->p.count );
	s.y.assign( m->p.y, m->p.y + m->p.count );
	s.z.assign( m->p.z, m->p.z + m->p.count );
	s.inv_m.assign( m->p.inv_m, m->p.inv_m + m->p.count );
	s.rest.assign( m->s.rest, m->s.rest + m->s.count );
	for ( int32_t k = 0; k < m->s.count; ++k )
	{
		s.rest[k] *= ( m->s.kind[k] & SERE_SPRING_LAYER_MASK ) == SERE_SPRING_V ? 0.9f : 1.0f;
	}
	if ( sere_pbd_create( m->s.a, m->s.b, m->s.count, m->p.count, &s.pbd ) != SERE_OK ||
		 sere_pbd_set_rest( s.pbd, s.rest.data() ) != SERE_OK )
	{
		std::abort();
	}
	return s;
}

sere_pbd_params sweeps( int32_t count )
{
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = count;
	params.tolerance = 1e-30f; // never converged: exactly `count` sweeps per call
	return params;
}

void rate( benchmark::State& state, double constraints_per_iteration )
{
	double total = constraints_per_iteration * static_cast<double>( state.iterations() );
	state.counters["constraints/s"] = benchmark::Counter( total, benchmark::Counter::kIsRate );
	state.counters["ns/constraint"] =
		benchmark::Counter( total, benchmark::Counter::kIsRate | benchmark::Counter::kInvert );
}

void schedule_counters( benchmark::State& state, const sere_pbd* pbd )
{
	sere_pbd_info info = sere_pbd_get_info( pbd );
	state.counters["colors"] = info.colors;
	state.counters["bands"] = info.bands;
	state.counters["min_batch"] = info.min_batch;
	state.counters["max_batch"] = info.max_batch;
}

// One sweep per call, including the copy of the positions into the solver's records and back.
void BM_PBDColored( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = sweeps( 1 );
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count );
	schedule_counters( state, s.pbd );
}

// 20 sweeps per call, as a frame runs them (the copies in and out amortized).
void BM_PBDColored20Sweeps( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = sweeps( 20 );
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	rate( state, 20.0 * s.model->s.count );
}

void BM_PBDJacobi( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = sweeps( 1 );
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project_jacobi( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count );
}

void BM_PBDReference( benchmark::State& state )
{
	scene& s = maple();
	const sere_model* m = s.model;
	std::vector<sere_ref_particle> particles( m->p.count );
	std::vector<sere_ref_spring> springs( m->s.count );
	for ( int32_t i = 0; i < m->p.count; ++i )
	{
		particles[i] = { s.x[i], s.y[i], s.z[i], s.inv_m[i] };
	}
	for ( int32_t k = 0; k < m->s.count; ++k )
	{
		springs[k] = { m->s.a[k], m->s.b[k], s.rest[k] };
	}
	float strain;
	for ( auto _ : state )
	{
		sere_pbd_ref_project( particles.data(), springs.data(), m->s.count, 1.0f, 1e-30f, 1, &strain );
		benchmark::ClobberMemory();
	}
	rate( state, m->s.count );
}

// The floor of the colored solver: one call of its schedule (copies in and out, bands, cuts,
// barriers, 128-bit loads and stores of both ends of every constraint) with a multiply by 1.
void BM_PBDFloor( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	for ( auto _ : state )
	{
		sere_pbd_touch( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data() );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count );
}

// The floor of the straightforward SoA layout: color after color, the loads and stores of both
// ends as AVX-512 gathers and scatters (what the compiler emits for the loop below), an OpenMP
// barrier per color. On this machine it costs about three times sere_pbd_touch, which is why
// the solver keeps (x, y, z, w) records and transposes them instead.
void BM_GatherScatterSoA( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	const sere_model* m = s.model;
	const sere_coloring* c = sere_pbd_coloring( s.pbd );
	std::vector<int32_t> a( m->s.count ), b( m->s.count );
	for ( int32_t k = 0; k < m->s.count; ++k )
	{
		a[k] = m->s.a[c->order[k]];
		b[k] = m->s.b[c->order[k]];
	}
	float* px = s.x.data();
	float* py = s.y.data();
	float* pz = s.z.data();
	const int32_t* ca = a.data();
	const int32_t* cb = b.data();
	const int32_t colors = c->color_count;
	const int32_t* offsets = c->offsets;
	// A multiply by a zero the compiler cannot see: no arithmetic it could drop, no subnormals.
	const float zero = static_cast<float>( state.range( 0 ) - state.range( 0 ) );
	for ( auto _ : state )
	{
#pragma omp parallel
		for ( int32_t color = 0; color < colors; ++color )
		{
#pragma omp for simd schedule( static )
			for ( int32_t q = offsets[color]; q < offsets[color + 1]; ++q )
			{
				float dx = px[cb[q]] - px[ca[q]], dy = py[cb[q]] - py[ca[q]], dz = pz[cb[q]] - pz[ca[q]];
				px[ca[q]] += zero * dx, py[ca[q]] += zero * dy, pz[ca[q]] += zero * dz;
				px[cb[q]] -= zero * dx, py[cb[q]] -= zero * dy, pz[cb[q]] -= zero * dz;
			}
		}
		benchmark::ClobberMemory();
	}
	rate( state, m->s.count );
}
} // namespace

BENCHMARK( BM_PBDColored )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDColored20Sweeps )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDJacobi )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDReference )->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDFloor )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_GatherScatterSoA )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
