// One step of the seed-002 mass-spring model (kernels/season/massspring.h) on the triangle layer of the
// Table 1 maple: its 4680 T particles and 8517 triangles give 13196 structural springs (the edges,
// 10 colors) and 12355 flexion springs (one per interior edge). The optimized kernel at 1 and 2
// threads beside the scalar reference twin (kernels/ref/massspring_ref.h) on the same mesh,
// springs and states, in one binary. Goal: a drying step costs a small multiple of one pass over
// the springs, and 2 threads beat 1.
//
// Scene, as harness/read/seasonleaf.c makes the season leaves: the maple scaled to length 1 (the units
// of massspring.h), a rest shape cupped by z = 0.25 r² about the centroid, masses in [0.1, 1] from
// Tang Eq. 3 on a gray pattern (veins white, the blade darkening with the distance from the base), the
// base particle and its ring of neighbours pinned, gravity −z, shrink 0.05 and curl 0.3 (the most
// withered level). From rest the blade curls and sags and the strain limit starts acting at step
// 8; a setup run of 400 steps keeps a snapshot every 20 steps.
//
// Each iteration steps the next snapshot in turn: its positions and velocities (6 x 4680 floats,
// 112 KB) are copied into the working state with the timer paused. So every iteration is a real
// step of a moving, limited blade, the mix of iterations is the mix of a drying run (the counters
// are averages over the timed steps: about 5 sweeps and 416 springs limited by the first sweep),
// and the optimized and reference rows time the same steps. Letting one state run on would drift
// towards rest, where the step needs a single sweep. The copy runs with the kernel's static
// schedule, so each thread finds its particles in its own cache.
//
// BM_MassSpringFloor is the step's floor (sere_massspring_touch): from each snapshot the same passes
// and barriers with the sweeps that snapshot's step took, sums for arithmetic. Measured: the step at
// 1.22-1.24x its floor at 1 thread, 1.24-1.26x at 2 (three runs, medians of 5).
//
// Counters: springs/s = (structural + flexion springs) x steps / wall time; sweeps, limited,
// hit_cap = the step's report averaged over the timed steps.
//
// Measured (2-core shared machine): with the band schedule (a sweep meets at 3 barriers: after
// the bands, the even cuts and the odd cuts) 1 thread 371-384 us and 2 threads 262-380 us,
// against 405-429 and 423-459 us with one barrier per color (10 per sweep), medians of 5 in
// five interleaved runs of both builds; the reference 532-547 us. 2-thread times depend on
// whether the second core is free: a thread that loses its core stalls every barrier. A 1-thread
// profile puts a third of the step in the limiter sweeps and a fifth in the per-particle gather
// of the spring forces.
#include "fixture.h"
#include "ref/massspring_ref.h"
#include "season/massspring.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace
{
constexpr float rest_cup = 0.25f;
// The drying run the snapshots are taken from: steps 1..run_steps from rest, a snapshot every
// snapshot_every steps (the limiter first acts at step 8).
constexpr int run_steps = 400;
constexpr int snapshot_every = 20;

struct state_t
{
	std::vector<float> x, y, z, vx, vy, vz;
};

struct scene
{
	int32_t n = 0;
	sere_massspring* ms = nullptr;
	sere_massspring_topology topology{};
	std::vector<float> inv_m;
	sere_massspring_params params{};
	std::vector<state_t> snapshots; // the states the iterations step from, in turn
	std::vector<int32_t> sweeps;	// the sweeps a step from each snapshot takes
	state_t work;
};

sere_massspring_particles particles( state_t& s, scene& sc )
{
	return sere_massspring_particles{ sc.n,		   s.x.data(),	s.y.data(),	 s.z.data(),
									  s.vx.data(), s.vy.data(), s.vz.data(), sc.inv_m.data() };
}

// The work state back to snapshot k, each thread copying the particles the kernel's static
// schedule gives it.
void restore( scene& sc, size_t k )
{
	const int32_t n = sc.n;
	const state_t& a = sc.snapshots[k];
	state_t& b = sc.work;
#pragma omp parallel for schedule( static )
	for ( int32_t i = 0; i < n; ++i )
	{
		b.x[i] = a.x[i], b.y[i] = a.y[i], b.z[i] = a.z[i];
		b.vx[i] = a.vx[i], b.vy[i] = a.vy[i], b.vz[i] = a.vz[i];
	}
}

scene& maple()
{
	static scene sc;
	if ( sc.ms != nullptr )
	{
		return sc;
	}
	const sere_model* m = sere_bench_model( SERE_BENCH_MAPLE );
	const int32_t n = m->triangle_particles;
	sc.n = n;
	float lo[2] = { m->p.x[0], m->p.y[0] }, hi[2] = { lo[0], lo[1] };
	double cx = 0.0, cy = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		lo[0] = std::min( lo[0], m->p.x[i] ), hi[0] = std::max( hi[0], m->p.x[i] );
		lo[1] = std::min( lo[1], m->p.y[i] ), hi[1] = std::max( hi[1], m->p.y[i] );
		cx += m->p.x[i], cy += m->p.y[i];
	}
	cx /= n, cy /= n;
	const double scale = 1.0 / std::max( hi[0] - lo[0], hi[1] - lo[1] );
	state_t& s = sc.work;
	for ( auto* v : { &s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz } )
	{
		v->assign( n, 0.0f );
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		double dx = ( m->p.x[i] - cx ) * scale, dy = ( m->p.y[i] - cy ) * scale;
		s.x[i] = static_cast<float>( dx );
		s.y[i] = static_cast<float>( dy );
		s.z[i] = rest_cup * static_cast<float>( dx * dx + dy * dy );
	}
	// Tang Eq. 3 masses: veins white (heaviest), the blade from light gray at the base to dark at the
	// far edge, so the tips deform most (Sec. 4.2).
	double dmax = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		dmax = std::max( dmax, m->d[i] );
	}
	std::vector<float> gray( n ), mass( n );
	for ( int32_t i = 0; i < n; ++i )
	{
		gray[i] = m->vein[i] ? 1.0f : static_cast<float>( 0.6 - 0.55 * m->d[i] / dmax );
	}
	sc.inv_m.resize( n );
	if ( sere_massspring_mass_from_gray( gray.data(), n, 0.1f, 1.0f, mass.data() ) != SERE_OK )
	{
		std::abort();
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		sc.inv_m[i] = 1.0f / mass[i];
	}
	// The base and its ring of neighbours hold the blade's attitude.
	const int32_t base = m->base;
	if ( base < 0 || base >= n )
	{
		std::abort();
	}
	sc.inv_m[base] = 0.0f;
	for ( int32_t t = 0; t < m->triangle_count; ++t )
	{
		const int32_t* q = m->tri + 3 * t;
		if ( q[0] == base || q[1] == base || q[2] == base )
		{
			sc.inv_m[q[0]] = sc.inv_m[q[1]] = sc.inv_m[q[2]] = 0.0f;
		}
	}
	if ( sere_massspring_create( s.x.data(), s.y.data(), s.z.data(), n, m->tri, m->triangle_count, &sc.ms ) != SERE_OK )
	{
		std::abort();
	}
	sc.topology = sere_massspring_get_topology( sc.ms );
	sc.params = sere_massspring_params_default();
	sc.params.shrink = 0.05f;
	sc.params.curl = 0.3f;
	sere_massspring_particles p = particles( s, sc );
	for ( int step = 1; step <= run_steps; ++step )
	{
		sere_status status = sere_massspring_step( sc.ms, &p, &sc.params, nullptr );
		if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
		{
			std::abort();
		}
		if ( step % snapshot_every == 0 )
		{
			sc.snapshots.push_back( s );
		}
	}
	for ( size_t k = 0; k < sc.snapshots.size(); ++k )
	{
		restore( sc, k );
		sere_massspring_report report{};
		sere_massspring_step( sc.ms, &p, &sc.params, &report );
		sc.sweeps.push_back( report.sweeps );
	}
	return sc;
}

// Sums of the reports of all timed steps.
struct tally
{
	int64_t sweeps = 0, limited = 0, hit_cap = 0;
	void add( const sere_massspring_report& r )
	{
		sweeps += r.sweeps, limited += r.limited, hit_cap += r.hit_cap;
	}
};

void counters( benchmark::State& state, const scene& sc, const tally& t )
{
	const double steps = static_cast<double>( state.iterations() );
	const double springs = sc.topology.structural_count + sc.topology.flexion_count;
	state.counters["springs/s"] = benchmark::Counter( springs * steps, benchmark::Counter::kIsRate );
	state.counters["sweeps"] = static_cast<double>( t.sweeps ) / steps;
	state.counters["limited"] = static_cast<double>( t.limited ) / steps;
	state.counters["hit_cap"] = static_cast<double>( t.hit_cap ) / steps;
	state.counters["colors"] = sc.topology.color_count;
}

// Times step (a call returning the step's status and filling report) from each snapshot in turn,
// restored outside the timed region; a step that fails other than by not converging ends the
// benchmark with its error.
template <typename Step> void step_loop( benchmark::State& state, scene& sc, sere_massspring_report& report, Step step )
{
	tally t;
	size_t k = 0;
	for ( auto _ : state )
	{
		state.PauseTiming();
		restore( sc, k );
		k = ( k + 1 ) % sc.snapshots.size();
		state.ResumeTiming();
		sere_status status = step();
		benchmark::ClobberMemory();
		if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
		{
			state.SkipWithError( sere_status_text( status ) );
			break;
		}
		t.add( report );
	}
	counters( state, sc, t );
}

void BM_MassSpringStep( benchmark::State& state )
{
	const int saved = omp_get_max_threads();
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& sc = maple();
	sere_massspring_particles p = particles( sc.work, sc );
	sere_massspring_report report{};
	step_loop( state, sc, report, [&] { return sere_massspring_step( sc.ms, &p, &sc.params, &report ); } );
	omp_set_num_threads( saved );
}

// The step's floor (sere_massspring_touch): from each snapshot in turn, the memory traffic of a step
// with the sweeps the step took from it, with sums for arithmetic; so it times the same mix of steps.
void BM_MassSpringFloor( benchmark::State& state )
{
	const int saved = omp_get_max_threads();
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	scene& sc = maple();
	sere_massspring_particles p = particles( sc.work, sc );
	sere_massspring_report report{};
	size_t next = 0;
	step_loop( state, sc, report, [&] {
		report.sweeps = sc.sweeps[next];
		next = ( next + 1 ) % sc.sweeps.size();
		return sere_massspring_touch( sc.ms, &p, report.sweeps );
	} );
	omp_set_num_threads( saved );
}

// The scalar twin on the same springs (the kernel's topology, structural springs in color order,
// so both sweep them in the same order) from the same state.
void BM_MassSpringReference( benchmark::State& state )
{
	scene& sc = maple();
	sere_massspring_particles p = particles( sc.work, sc );
	std::vector<float> fx( sc.n ), fy( sc.n ), fz( sc.n );
	sere_massspring_report report{};
	step_loop( state, sc, report, [&] {
		return sere_massspring_ref_step( &sc.topology, &p, &sc.params, fx.data(), fy.data(), fz.data(), &report );
	} );
}
} // namespace

BENCHMARK( BM_MassSpringStep )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_MassSpringFloor )
	->ArgName( "threads" )
	->Arg( 1 )
	->Arg( 2 )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_MassSpringReference )->Unit( benchmark::kMicrosecond );
