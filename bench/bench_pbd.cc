// One projection sweep over all 51,102 constraints of the Table 1 maple: the colored SIMD
// Gauss-Seidel, the Jacobi variant, the scalar AoS reference, and a gather/scatter loop with the
// same access pattern and no arithmetic (this machine's floor). Counter: constraints/s.
#include "fixture.h"
#include "pbd.h"
#include "ref/pbd_ref.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <vector>

namespace
{
struct scene
{
	const sere_model* model;
	std::vector<float> x, y, z, inv_m, rest;
	sere_pbd* pbd = nullptr;
};

// The maple with its Voronoi springs shortened by 10%, so every sweep has work to do.
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
	sere_pbd_create( m->s.a, m->s.b, m->s.count, m->p.count, &s.pbd );
	sere_pbd_set_rest( s.pbd, s.rest.data() );
	return s;
}

sere_pbd_params one_sweep()
{
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 1;
	params.tolerance = 1e-30f; // never converged: exactly one sweep per call
	return params;
}

void BM_PBDColored( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = one_sweep();
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	const sere_coloring* c = sere_pbd_coloring( s.pbd );
	state.counters["constraints/s"] =
		benchmark::Counter( static_cast<double>( s.model->s.count ) * state.iterations(), benchmark::Counter::kIsRate );
	state.counters["ns/constraint"] = benchmark::Counter( static_cast<double>( s.model->s.count ) * state.iterations(),
														  benchmark::Counter::kIsRate | benchmark::Counter::kInvert );
	state.counters["colors"] = c->color_count;
	state.counters["max_batch"] = c->max_batch;
	state.counters["min_batch"] = c->min_batch;
}

void BM_PBDJacobi( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = one_sweep();
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project_jacobi( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	state.counters["constraints/s"] =
		benchmark::Counter( static_cast<double>( s.model->s.count ) * state.iterations(), benchmark::Counter::kIsRate );
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
	state.counters["constraints/s"] =
		benchmark::Counter( static_cast<double>( m->s.count ) * state.iterations(), benchmark::Counter::kIsRate );
}

// The floor: the colored sweep's loads and stores (two particles per constraint, color by
// color, one barrier per color) with a trivial update instead of the projection.
void BM_GatherScatterFloor( benchmark::State& state )
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
	for ( auto _ : state )
	{
#pragma omp parallel
		for ( int32_t color = 0; color < colors; ++color )
		{
#pragma omp for simd schedule( static )
			for ( int32_t q = offsets[color]; q < offsets[color + 1]; ++q )
			{
				float dx = px[cb[q]] - px[ca[q]], dy = py[cb[q]] - py[ca[q]], dz = pz[cb[q]] - pz[ca[q]];
				px[ca[q]] += 1e-30f * dx, py[ca[q]] += 1e-30f * dy, pz[ca[q]] += 1e-30f * dz;
				px[cb[q]] -= 1e-30f * dx, py[cb[q]] -= 1e-30f * dy, pz[cb[q]] -= 1e-30f * dz;
			}
		}
		benchmark::ClobberMemory();
	}
	state.counters["constraints/s"] =
		benchmark::Counter( static_cast<double>( m->s.count ) * state.iterations(), benchmark::Counter::kIsRate );
}
} // namespace

BENCHMARK( BM_PBDColored )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDJacobi )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDReference )->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_GatherScatterFloor )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
