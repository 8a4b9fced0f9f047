// Projection sweeps over the 51,102 constraints of the Table 1 maple (13,197 particles): the
// colored SIMD Gauss-Seidel, the Jacobi variant, the scalar AoS reference, and two floors with
// a trivial operation in place of the projection: sere_pbd_touch_sweeps (the colored solver's
// own call, schedule and memory traffic) and a plain SoA loop with AVX-512 gathers and scatters.
//
// Every counter is per sweep, whatever the sweeps per call: ns/constraint is the wall time of a
// call over (sweeps x constraints), constraints/s its inverse, time/sweep the time of a call over
// its sweeps. A call costs its sweeps plus a fixed part (the entry check for NaN and negative
// masses, packing the caller's positions into records and back, the parallel region); the
// sweeps:1 rows carry all of that fixed part, the sweeps:200 rows almost none. The real
// workload (kernels/drying/leaf.c) asks for up to 200 sweeps per frame in one call (10 per call when
// the stall stop is on), so the sweeps:20 and sweeps:200 rows are the ones that matter; the
// colored solver and its floor run the same calls, so their ratio at equal threads and sweeps
// is the ratio of arithmetic plus memory to memory alone. On this 2-core shared machine the
// 2-thread rows of short calls swing by 2x with other processes' load: packing and unpacking
// move half the records between the cores' caches, and a thread that loses its core stalls the
// other at the next synchronization; compare rows of one run.
//
// The Voronoi springs are shortened by 10% so every sweep has work to do. Each benchmark
// iteration continues from the state the previous one left: none of the solvers branches on the
// data (the reference only on degenerate springs), so the cost does not depend on the state,
// and the frustrated double layer stays bounded.
#include "fixture.h"
#include "ref/pbd_ref.h"
#include "solve/pbd.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <cfloat>
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
	s.rest = sere_bench_frustrated_rest( m );
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

// Per-sweep rates of a benchmark whose every iteration runs `sweeps` sweeps.
void rate( benchmark::State& state, double constraints, int64_t sweeps )
{
	double done = static_cast<double>( state.iterations() * sweeps );
	state.counters["constraints/s"] = benchmark::Counter( constraints * done, benchmark::Counter::kIsRate );
	state.counters["ns/constraint"] =
		benchmark::Counter( constraints * done, benchmark::Counter::kIsRate | benchmark::Counter::kInvert );
	state.counters["time/sweep"] =
		benchmark::Counter( done, benchmark::Counter::kIsRate | benchmark::Counter::kInvert );
}

// threads, sweeps per call.
void per_call( benchmark::internal::Benchmark* b )
{
	b->ArgNames( { "threads", "sweeps" } )->ArgsProduct( { { 1, 2 }, { 1, 20, 200 } } );
}

// Times project (sere_pbd_project or its Jacobi twin) on the maple with the benchmark's threads
// and sweeps (its two arguments); the scene, for further counters.
template <typename Project> scene& project_loop( benchmark::State& state, Project project )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = sweeps( static_cast<int32_t>( state.range( 1 ) ) );
	sere_pbd_report report;
	for ( auto _ : state )
	{
		project( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, state.range( 1 ) );
	return s;
}

// One call of sere_pbd_project running exactly `sweeps` sweeps (never converged), copies of
// the positions into the solver's records and back included.
void BM_PBDColored( benchmark::State& state )
{
	scene& s = project_loop( state, sere_pbd_project );
	sere_pbd_info info = sere_pbd_get_info( s.pbd );
	state.counters["colors"] = info.colors;
	state.counters["bands"] = info.bands;
	state.counters["padding"] = static_cast<double>( info.lanes - s.model->s.count ) / s.model->s.count;
}

// The sweeps of a drying frame: XPBD (kernels/drying/leaf.c: compliance 4e-6 at dt 0.002, so
// alpha~ = 1), multipliers from zero at each call. Per constraint it also loads the compliance
// weight and the multiplier and stores the multiplier, and divides three times (strain, Δλ,
// factor) where PBD divides twice; its floor is BM_XPBDFloor (the records' traffic and those
// 12 bytes).
void BM_XPBDColored( benchmark::State& state )
{
	project_loop( state, []( sere_pbd* pbd, float* x, float* y, float* z, const float* inv_m,
							 const sere_pbd_params* params, sere_pbd_report* report ) {
		sere_pbd_params step = *params;
		step.compliance = 4e-6f;
		step.dt = 0.002f;
		return sere_pbd_project( pbd, x, y, z, inv_m, &step, report );
	} );
}

// The floor of BM_PBDColored at the same threads and sweeps: the same call (entry check,
// packing, parallel region, bands and cuts with their barriers, the exchange after every
// sweep, unpacking) with each constraint's two 128-bit record loads and stores but a multiply
// by 1 for the arithmetic.
void BM_PBDFloor( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	const int32_t count = static_cast<int32_t>( state.range( 1 ) );
	for ( auto _ : state )
	{
		sere_pbd_touch_sweeps( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), count );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, state.range( 1 ) );
}

// The floor of BM_XPBDColored: BM_PBDFloor's call plus each constraint's weight load and
// multiplier load and store (sere_pbd_touch_sweeps_xpbd), the multipliers zeroed at the start as
// an XPBD call zeroes them.
void BM_XPBDFloor( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	const int32_t count = static_cast<int32_t>( state.range( 1 ) );
	for ( auto _ : state )
	{
		sere_pbd_touch_sweeps_xpbd( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), count );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, state.range( 1 ) );
}

// A call that converges in its first sweep (λ_C = FLT_MAX): one sweep plus the read-only pass
// that confirms the returned positions; minus BM_PBDColored at sweeps:1 it is that pass's cost,
// paid once per converged call.
void BM_PBDColoredConverged( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& s = maple();
	sere_pbd_params params = sweeps( 1 );
	params.tolerance = FLT_MAX;
	sere_pbd_report report;
	for ( auto _ : state )
	{
		sere_pbd_project( s.pbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, 1 );
}

void BM_PBDJacobi( benchmark::State& state )
{
	project_loop( state, sere_pbd_project_jacobi );
}

// The serial baseline; it has no per-call part, so one sweep per iteration is its sweep cost.
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
	rate( state, m->s.count, 1 );
}

// The floor of the straightforward SoA layout: color after color, the loads and stores of both
// ends as AVX-512 gathers and scatters (what the compiler emits for the loop below), an OpenMP
// barrier per color. On this machine it costs 3 to 6 times a sweep of sere_pbd_touch_sweeps
// (a 1-sweep call to a sweep of a 200-sweep call), which is why the solver keeps (x, y, z, w)
// records and transposes them instead.
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
	rate( state, m->s.count, 1 );
}
} // namespace

BENCHMARK( BM_PBDColored )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_XPBDColored )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDFloor )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_XPBDFloor )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDColoredConverged )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDJacobi )
	->ArgNames( { "threads", "sweeps" } )
	->ArgsProduct( { { 1, 2 }, { 1, 20 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PBDReference )->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_GatherScatterSoA )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
