// Descent sweeps (solve/vbd.h) over the springs of the Table 1 maple (13,197 particles, 51,102
// springs), beside their floor and the reference twin, with the XPBD step's energy of a drying
// frame (compliance 4e-6 at dt 0.002, kernels/drying/leaf.c). Compare with BM_XPBDColored in the
// same run: a descent sweep does more per spring (a 3 x 3 block and a Newton step per particle)
// but a frame needs fewer of them (docs/PERFORMANCE.md).
//
// Counters are per sweep: time/sweep, and spring ends/s (a sweep visits every spring from both
// ends). As in bench_pbd.cc, the Voronoi springs are shortened by 10% so every sweep has work.
//
// The threads:2 rows run as a caller's steps do: the step's tuner (core/internal/team.h) tries
// one thread for 4 calls after the first 8 and every 512, and keeps it where it is 1.2 times as
// fast (in the other guest's spells); SERE_ADAPTIVE_THREADS=0 times the team alone.
#include "fixture.h"
#include "ref/vbd_ref.h"
#include "solve/vbd.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <vector>

namespace
{
struct scene
{
	const sere_model* model = nullptr;
	std::vector<float> x, y, z, inv_m, rest;
	sere_vbd* vbd = nullptr;
};

scene& maple()
{
	static scene s;
	if ( s.vbd != nullptr )
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
	if ( sere_vbd_create( m->s.a, m->s.b, m->s.count, m->p.count, &s.vbd ) != SERE_OK ||
		 sere_vbd_set_rest( s.vbd, s.rest.data() ) != SERE_OK )
	{
		std::abort();
	}
	return s;
}

void rate( benchmark::State& state, double springs, int64_t sweeps )
{
	const double done = static_cast<double>( state.iterations() * sweeps );
	state.counters["spring ends/s"] = benchmark::Counter( 2.0 * springs * done, benchmark::Counter::kIsRate );
	state.counters["time/sweep"] =
		benchmark::Counter( done, benchmark::Counter::kIsRate | benchmark::Counter::kInvert );
}

// threads, sweeps a call. From the maple's own shape the sweeps reach the coordinates' rounding,
// where a step stops whatever its tolerance, after 43 sweeps, so a call runs 20 or 40 (the Table 1
// frames take about 23).
void per_call( benchmark::internal::Benchmark* b )
{
	b->ArgNames( { "threads", "sweeps" } )->ArgsProduct( { { 1, 2 }, { 20, 40 } } );
}

// One sere_vbd_step from the maple's own shape running exactly `sweeps` sweeps: packing, the
// colors' barriers, the exchange after every sweep and unpacking included.
void BM_VBDStep( benchmark::State& state )
{
	scene& s = maple();
	sere_vbd_set_threads( s.vbd, static_cast<int32_t>( state.range( 0 ) ) );
	sere_vbd_params params = sere_vbd_params_default();
	params.tolerance = 1e-30f;
	params.max_iterations = static_cast<int32_t>( state.range( 1 ) );
	sere_vbd_report report;
	const sere_model* m = s.model;
	for ( auto _ : state )
	{
		// every call from the model's own shape: a state the sweeps have converged from would stop
		// them early at the coordinates' rounding (the copy is 0.05% of a 200-sweep call)
		std::copy( m->p.x, m->p.x + m->p.count, s.x.begin() );
		std::copy( m->p.y, m->p.y + m->p.count, s.y.begin() );
		std::copy( m->p.z, m->p.z + m->p.count, s.z.begin() );
		if ( sere_vbd_step( s.vbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), &params, &report ) != SERE_OK ||
			 report.iterations != params.max_iterations )
		{
			state.SkipWithError( "sere_vbd_step failed or stopped early: such a call measures other sweeps" );
			break;
		}
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, state.range( 1 ) );
	const sere_vbd_info info = sere_vbd_get_info( s.vbd );
	state.counters["colors"] = info.colors;
	state.counters["padding"] = static_cast<double>( info.entries - info.springs ) / info.springs;
}

// The floor of BM_VBDStep at the same threads and sweeps (sere_vbd_touch_sweeps): the same call
// and schedule, every record, mass, prediction, neighbour record, stiffness and rest length
// loaded and the records stored, a sum in place of the Newton step.
void BM_VBDFloor( benchmark::State& state )
{
	scene& s = maple();
	sere_vbd_set_threads( s.vbd, static_cast<int32_t>( state.range( 0 ) ) );
	const int32_t sweeps = static_cast<int32_t>( state.range( 1 ) );
	for ( auto _ : state )
	{
		sere_vbd_touch_sweeps( s.vbd, s.x.data(), s.y.data(), s.z.data(), s.inv_m.data(), sweeps );
		benchmark::ClobberMemory();
	}
	rate( state, s.model->s.count, state.range( 1 ) );
}

// The twin (ref/vbd_ref.h), serial, in double, the particles in index order: a call capped at one
// sweep runs the stop check's gradient pass before and after it, so an iteration is one sweep
// and two gradient passes (each about half a sweep's work: no block, no solve).
void BM_VBDReference( benchmark::State& state )
{
	scene& s = maple();
	const sere_model* m = s.model;
	std::vector<double> stiffness( m->s.count, 0.002 * 0.002 / 4e-6 ), x( 3 * (size_t) m->p.count );
	for ( int32_t i = 0; i < m->p.count; ++i )
	{
		x[3 * i] = s.x[i], x[3 * i + 1] = s.y[i], x[3 * i + 2] = s.z[i];
	}
	const sere_vbd_ref_problem problem = { m->p.count,	   m->s.count, s.x.data(), s.y.data(),	  s.z.data(),
										   s.inv_m.data(), m->s.a,	   m->s.b,	   s.rest.data(), stiffness.data() };
	for ( auto _ : state )
	{
		benchmark::DoNotOptimize( sere_vbd_ref_descend( &problem, x.data(), 0.0, 1 ) );
		benchmark::ClobberMemory();
	}
	rate( state, m->s.count, 1 );
}
} // namespace

BENCHMARK( BM_VBDStep )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_VBDFloor )->Apply( per_call )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_VBDReference )->Unit( benchmark::kMicrosecond );
