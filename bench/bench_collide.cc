// Self-collision (Sec. 5.3, Jeong Eq. 14): BVH refit and build, the proximity queries (vertex–triangle
// per vertex, edge–edge per vertex's edges), the push-out response and the Voronoi restore, on the
// Table 1 maple (bench/fixture.h: 4680 triangle-layer vertices, 8517 triangles, the leaf about 1
// across) flat; dried (the maple after
// 400 frames of Algorithm 1 with the maple-green preset: shrunk, curled and crumpled as the
// simulation leaves it); waved by a smooth random displacement field that also compresses it
// in-plane (a stress case: many contacts no normal push can resolve); and U-folded onto itself;
// beside the brute-force twins (both kinds) and Embree 3 doing the same vertex–triangle proximity
// search with rtcPointQuery. Every scene uses the thickness `sere run` uses on it: the harness default
// (sere_sim_params_default; the maple-green preset keeps it) times the triangle layer's
// shrinkage (sere_leaf_thickness_scale, 1 but for the dried leaf).

#include "common/params.h"
#include "drying/leaf.h"
#include "fixture.h"
#include "mesh/measure.h"
#include "read/build.h"
#include "ref/collide_ref.h"
#include "ref/measure_ref.h"
#include "solve/bvh.h"
#include "solve/collide.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace
{

constexpr double kPi = 3.14159265358979323846;

enum Shape
{
	kFlat,
	kDried,
	kWaved,
	kFolded,
	kDense,
};

template <typename T> struct Aligned
{
	T* data = nullptr;
	explicit Aligned( size_t n ) : data( static_cast<T*>( sere_alloc( sizeof( T ) * ( n > 0 ? n : 1 ) ) ) )
	{
	}
	~Aligned()
	{
		sere_free( data );
	}
	Aligned( const Aligned& ) = delete;
	Aligned& operator=( const Aligned& ) = delete;
};

// The Table 1 maple's triangle layer (4680 vertices, 8517 triangles, Morton-ordered by
// sere_model) with one Voronoi particle per triangle after it, as sere_model lays them out, plus
// the BVH and collision workspace made once.
constexpr int kDriedFrames = 400;

// The dense scene: the Table 1 maple dried to the end with the maple-green preset (Algorithm 1
// until a layer runs dry, as `sere run --until-dry` stops: 1081 frames), creased and rolled as the
// simulation leaves it, then one frame more without the collision pass, so the scene holds what
// the pass of a last frame meets. Made once per process by running the kernels.
constexpr int kDryFrameCap = 20000;

const sere_model* dense_model()
{
	static sere_model model;
	static bool made = false;
	if ( made )
	{
		return &model;
	}
	char err[1024], name[128];
	sere_sim_params params = sere_sim_params_default();
	sere_build_report report;
	if ( sere_params_load_preset( &params, "maple-green", err, sizeof( err ) ) != 0 ||
		 sere_harness_build( "data/leaves/maple.leaf", 13197, 51102, 0, &params, &model, &report, name, sizeof( name ),
							 err, sizeof( err ) ) != 0 )
	{
		std::fprintf( stderr, "sere-bench: %s (run from the repository root)\n", err );
		std::exit( 1 );
	}
	sere_leaf_sim* sim = nullptr;
	sere_status status = sere_leaf_create( &model, &sim );
	sere_leaf_params& leaf = params.leaf;
	sere_leaf_stats stats = {};
	int frames = 0;
	while ( status == SERE_OK && !stats.desiccated && frames < kDryFrameCap )
	{
		status = sere_leaf_step( sim, &leaf, &stats );
		frames += 1;
	}
	/* one more frame without the collision pass: the positions that pass meets, with the contacts
	 * the frame's dynamics made, not the ones it leaves after pushing them apart */
	leaf.collisions = false;
	if ( status == SERE_OK )
	{
		status = sere_leaf_step( sim, &leaf, &stats );
	}
	sere_leaf_destroy( sim );
	if ( status != SERE_OK || !stats.desiccated )
	{
		std::fprintf( stderr, "sere-bench: drying the maple to the end: %s after %d frames\n",
					  sere_status_text( status ), frames );
		std::exit( 1 );
	}
	std::fprintf( stderr, "sere-bench: the maple (maple-green) ran dry after %d frames for the dense scene\n", frames );
	made = true;
	return &model;
}

struct Scene
{
	const sere_model* model;
	float thickness;
	int32_t n;
	int32_t f;
	std::vector<int32_t> tri;
	Aligned<float> x, y, z, vx, vy, vz, inv_m, h;
	std::vector<float> x0, y0, z0;
	std::vector<int32_t> ring_start, ring; // each vertex's mesh-edge neighbours (for Embree's filter)
	sere_bvh* bvh = nullptr;
	sere_collide* collide = nullptr;

	explicit Scene( Shape shape )
		: model( shape == kDried   ? sere_bench_dried_model( SERE_BENCH_MAPLE, kDriedFrames )
				 : shape == kDense ? dense_model()
								   : sere_bench_model( SERE_BENCH_MAPLE ) ),
		  thickness( sere_sim_params_default().leaf.collide.thickness * sere_leaf_thickness_scale( model ) ),
		  n( model->triangle_particles ), f( model->triangle_count ), tri( model->tri, model->tri + 3 * (size_t) f ),
		  x( n + f ), y( n + f ), z( n + f ), vx( n + f ), vy( n + f ), vz( n + f ), inv_m( n ), h( f )
	{
		uint64_t state = 17;
		// the leaf in its plane (sere_model's u, v: the shape before any initial shaping)
		std::vector<double> u( model->u, model->u + n ), v( model->v, model->v + n );
		for ( int32_t k = 0; k < n; ++k )
		{
			x.data[k] = (float) u[k];
			y.data[k] = (float) v[k];
			inv_m.data[k] = 1.0f;
		}
		if ( shape == kDried || shape == kDense )
		{
			for ( int32_t k = 0; k < n; ++k )
			{
				x.data[k] = model->p.x[k], y.data[k] = model->p.y[k], z.data[k] = model->p.z[k];
			}
		}
		else if ( shape == kWaved )
		{
			// a smooth random displacement field (eight plane waves of wavelength 0.2 to 0.5, in all
			// three axes) strong enough to fold the sheet onto itself here and there, plus noise
			double wave[8][6];
			for ( auto& w : wave )
			{
				double angle = 2.0 * kPi * sere_splitmix_unit( &state ),
					   k = 2.0 * kPi * ( 2.0 + 3.0 * sere_splitmix_unit( &state ) );
				w[0] = k * std::cos( angle ), w[1] = k * std::sin( angle ),
				w[2] = 2.0 * kPi * sere_splitmix_unit( &state );
				w[3] = 0.0125 * ( 2.0 * sere_splitmix_unit( &state ) - 1.0 );
				w[4] = 0.0125 * ( 2.0 * sere_splitmix_unit( &state ) - 1.0 );
				w[5] = 0.025 * ( 2.0 * sere_splitmix_unit( &state ) - 1.0 );
			}
			for ( int32_t k = 0; k < n; ++k )
			{
				double d[3] = { 0.0, 0.0, 0.0 };
				for ( auto& w : wave )
				{
					double s = std::sin( w[0] * u[k] + w[1] * v[k] + w[2] );
					d[0] += w[3] * s, d[1] += w[4] * s, d[2] += w[5] * s;
				}
				x.data[k] = (float) ( u[k] + d[0] );
				y.data[k] = (float) ( v[k] + d[1] );
				z.data[k] = (float) ( d[2] + 0.3 * thickness * ( sere_splitmix_unit( &state ) - 0.5 ) );
			}
		}
		else if ( shape == kFolded )
		{
			// U-fold: two halves facing each other at 0.8 × thickness, joined by a half circle
			double lo = *std::min_element( u.begin(), u.end() ), hi = *std::max_element( u.begin(), u.end() );
			double gap = 0.8 * thickness, r = 0.5 * gap, a = 0.5 * ( hi - lo - kPi * r );
			for ( int32_t k = 0; k < n; ++k )
			{
				double s = u[k] - lo;
				if ( s <= a )
				{
					x.data[k] = (float) ( lo + s ), z.data[k] = 0.0f;
				}
				else if ( s <= a + kPi * r )
				{
					x.data[k] = (float) ( lo + a + r * std::sin( ( s - a ) / r ) );
					z.data[k] = (float) ( r - r * std::cos( ( s - a ) / r ) );
				}
				else
				{
					x.data[k] = (float) ( lo + a - ( s - a - kPi * r ) ), z.data[k] = (float) gap;
				}
			}
		}
		for ( int32_t k = 0; k < f; ++k )
		{
			h.data[k] = model->h[k];
		}
		sere_collide_restore_voronoi( x.data, y.data, z.data, vx.data, vy.data, vz.data, tri.data(), f, n, h.data, 0 );
		x0.assign( x.data, x.data + n + f );
		y0.assign( y.data, y.data + n + f );
		z0.assign( z.data, z.data + n + f );
		std::vector<std::vector<int32_t>> neighbours( (size_t) n );
		for ( int32_t t = 0; t < f; ++t )
		{
			for ( int k = 0; k < 3; ++k )
			{
				neighbours[(size_t) tri[3 * t + k]].push_back( tri[3 * t + ( k + 1 ) % 3] );
				neighbours[(size_t) tri[3 * t + ( k + 1 ) % 3]].push_back( tri[3 * t + k] );
			}
		}
		ring_start.push_back( 0 );
		for ( auto& list : neighbours )
		{
			std::sort( list.begin(), list.end() );
			list.erase( std::unique( list.begin(), list.end() ), list.end() );
			ring.insert( ring.end(), list.begin(), list.end() );
			ring_start.push_back( (int32_t) ring.size() );
		}
		sere_bvh_create( tri.data(), f, n, x.data, y.data, z.data, &bvh );
		sere_collide_create( bvh, 0, &collide );
	}

	// a corner of the triangle, or joined to one by a mesh edge: sere_collide_detect skips it
	bool excluded( int32_t vertex, const int32_t* corners ) const
	{
		for ( int k = 0; k < 3; ++k )
		{
			if ( corners[k] == vertex ||
				 std::binary_search( ring.begin() + ring_start[(size_t) vertex],
									 ring.begin() + ring_start[(size_t) vertex + 1], corners[k] ) )
			{
				return true;
			}
		}
		return false;
	}

	~Scene()
	{
		sere_collide_destroy( collide );
		sere_bvh_destroy( bvh );
	}

	// A new collision workspace whose candidate list has settled on the scene as reset, for a pass
	// the list serves. The list's skin narrows after each list that served more than 16 detections,
	// from 0.25 thickness to its floor of 0.125 after four (collide_detect.c, SKIN): over the
	// calls and repetitions of a benchmark the list shrank, so a run timed lists of 1294, then 809,
	// then 775 pairs on the flat maple (2691 to 1632 on the dense one), and a list made after other
	// benchmarks depended on which ran. Five lists on new tree builds, each serving 17 passes, leave
	// the list at the floor, the one a still scene settles to, whatever ran before.
	void settle_list( const sere_collide_params& p )
	{
		sere_collide_destroy( collide );
		collide = nullptr;
		sere_collide_create( bvh, 0, &collide );
		sere_collide_state st = state();
		for ( int list = 0; list < 5; ++list )
		{
			sere_bvh_build( bvh, x.data, y.data, z.data );
			for ( int pass = 0; pass < 18; ++pass )
			{
				reset();
				sere_collide_resolve( collide, bvh, &st, &p, nullptr );
			}
		}
		reset();
	}

	void reset()
	{
		std::memcpy( x.data, x0.data(), sizeof( float ) * x0.size() );
		std::memcpy( y.data, y0.data(), sizeof( float ) * y0.size() );
		std::memcpy( z.data, z0.data(), sizeof( float ) * z0.size() );
		std::memset( vx.data, 0, sizeof( float ) * x0.size() );
		std::memset( vy.data, 0, sizeof( float ) * x0.size() );
		std::memset( vz.data, 0, sizeof( float ) * x0.size() );
	}

	// The scene as reset, then with moved every triangle-layer vertex displaced by a smooth field
	// of at most 0.1 thickness, what a Table 1 frame moves a vertex by: a detection a list made at
	// the reset positions serves a frame into the list's life (its skin is at least 0.125).
	void reset( bool moved )
	{
		reset();
		float a = moved ? 0.1f * thickness / std::sqrt( 3.0f ) : 0.0f;
		for ( int32_t k = 0; moved && k < n; ++k )
		{
			float u = x0[(size_t) k] / thickness, v = y0[(size_t) k] / thickness;
			x.data[k] += a * std::sin( 0.7f * u + 0.3f * v );
			y.data[k] += a * std::sin( 0.5f * v - 0.4f * u + 1.0f );
			z.data[k] += a * std::sin( 0.6f * ( u + v ) + 2.0f );
		}
	}

	sere_collide_state state()
	{
		// the scene as reset is the start of the step: the response measures sides there, as
		// sere_leaf_step has it do
		return sere_collide_state{ x.data,	y.data,		z.data,	   vx.data,	  vy.data,
								   vz.data, inv_m.data, x0.data(), y0.data(), z0.data() };
	}
};

Scene& scene( Shape shape )
{
	static std::map<Shape, std::unique_ptr<Scene>> scenes;
	auto& s = scenes[shape];
	if ( !s )
	{
		s = std::make_unique<Scene>( shape );
	}
	s->reset();
	sere_bvh_build( s->bvh, s->x.data, s->y.data, s->z.data );
	return *s;
}

// The scene on as many threads as the benchmark's first argument.
Scene& threaded_scene( benchmark::State& state, Shape shape )
{
	Scene& s = scene( shape );
	omp_set_num_threads( (int) state.range( 0 ) );
	return s;
}

sere_collide_params params( const Scene& s )
{
	sere_collide_params p = sere_collide_params_default();
	p.thickness = s.thickness;
	return p;
}

void rate( benchmark::State& state, const char* name, double per_iteration )
{
	state.counters[name] =
		benchmark::Counter( per_iteration * (double) state.iterations(), benchmark::Counter::kIsRate );
}

// Times one pass over the tree (refit or build) on the scene's positions.
template <typename Pass> void tree_loop( benchmark::State& state, Shape shape, Pass pass )
{
	Scene& s = threaded_scene( state, shape );
	for ( auto _ : state )
	{
		pass( s.bvh, s.x.data, s.y.data, s.z.data );
		benchmark::ClobberMemory();
	}
	rate( state, "triangles/s", s.f );
}

void BM_bvh_refit( benchmark::State& state, Shape shape )
{
	tree_loop( state, shape, sere_bvh_refit );
}

void BM_bvh_build( benchmark::State& state, Shape shape )
{
	tree_loop( state, shape, sere_bvh_build );
}

// Detection with the candidate list dropped each iteration, so every one searches the tree; with
// refit, the tree is refit first, as a frame does.
void detect_loop( benchmark::State& state, Shape shape, bool refit )
{
	Scene& s = threaded_scene( state, shape );
	int32_t contacts = 0;
	for ( auto _ : state )
	{
		sere_collide_drop_list( s.collide );
		if ( refit )
		{
			sere_bvh_refit( s.bvh, s.x.data, s.y.data, s.z.data );
		}
		sere_collide_detect( s.collide, s.bvh, s.x.data, s.y.data, s.z.data, s.thickness, &contacts );
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", s.n );
	state.counters["contacts"] = contacts;
	int32_t edges = 0;
	sere_collide_edge_contacts( s.collide, &edges );
	state.counters["edge_contacts"] = edges;
}

void BM_collide_detect( benchmark::State& state, Shape shape )
{
	detect_loop( state, shape, false );
}

// Response alone on the contacts of one detection; the positions are reset between iterations
// outside the timed region.
void BM_collide_respond( benchmark::State& state, Shape shape )
{
	Scene& s = threaded_scene( state, shape );
	int32_t contacts = 0;
	sere_collide_detect( s.collide, s.bvh, s.x.data, s.y.data, s.z.data, s.thickness, &contacts );
	sere_collide_state st = s.state();
	sere_collide_params p = params( s );
	for ( auto _ : state )
	{
		state.PauseTiming();
		s.reset();
		state.ResumeTiming();
		sere_collide_respond( s.collide, s.bvh, &st, &p, nullptr );
		benchmark::ClobberMemory();
	}
	int32_t edges = 0;
	sere_collide_edge_contacts( s.collide, &edges );
	rate( state, "contacts/s", contacts + edges );
	state.counters["contacts"] = contacts;
	state.counters["edge_contacts"] = edges;
}

// rounds rounds of refit (rebuild when degraded), detect and respond (sere_collide_resolve),
// then, when restore is set, the Voronoi restore of Jeong Eq. 14; the scene is reset between
// iterations outside the timed region. Unless listed, the candidate list is dropped there too, so
// every detection searches the tree (a frame after the motion outgrew the list); listed settles the
// list first (Scene::settle_list, so every call times the same list) and keeps it, so every
// detection is served by it (a frame moving less than the list's skin).
void collide_loop( benchmark::State& state, Shape shape, int32_t rounds, bool restore, bool listed = false,
				   bool moved = false )
{
	Scene& s = threaded_scene( state, shape );
	sere_collide_state st = s.state();
	sere_collide_params p = params( s );
	p.rounds = rounds;
	if ( listed )
	{
		s.settle_list( p );
	}
	sere_collide_stats stats = {};
	for ( auto _ : state )
	{
		state.PauseTiming();
		s.reset( moved );
		if ( !listed )
		{
			sere_collide_drop_list( s.collide );
		}
		state.ResumeTiming();
		sere_collide_resolve( s.collide, s.bvh, &st, &p, &stats );
		if ( restore )
		{
			sere_collide_restore_voronoi( s.x.data, s.y.data, s.z.data, s.vx.data, s.vy.data, s.vz.data, s.tri.data(),
										  s.f, s.n, s.h.data, 0 );
		}
		benchmark::ClobberMemory();
	}
	rate( state, "vertices/s", s.n );
	state.counters["contacts"] = stats.contacts;
	state.counters["edge_contacts"] = stats.edge_contacts;
	state.counters["unresolved"] = stats.unresolved;
	state.counters["iterations"] = stats.iterations;
}

// One round without the Voronoi restore: the part of a frame the collision goal counts (at 2
// threads, within 1/20 of the paper's Collisions column for the maple, 24.28 ms).
void BM_collide_pass( benchmark::State& state, Shape shape )
{
	collide_loop( state, shape, 1, false );
}

// The pass with the candidate list serving each detection (collide_detect.c, SKIN): a frame whose motion
// stays within the list's skin, as most Table 1 frames do. range(1) = 1 moves the scene from where
// the list was made (Scene::reset), so the pass tests the listed pairs that motion can have
// brought within the thickness (list_reach2); at 0 it tests only those within it already.
void BM_collide_pass_listed( benchmark::State& state, Shape shape )
{
	collide_loop( state, shape, 1, false, true, state.range( 1 ) != 0 );
}

// The paper's Collisions column: the pass with range(1) rounds, then Jeong Eq. 14.
void BM_collide_frame( benchmark::State& state, Shape shape )
{
	collide_loop( state, shape, (int32_t) state.range( 1 ), true );
}

void BM_collide_restore_voronoi( benchmark::State& state )
{
	Scene& s = scene( kDried );
	for ( auto _ : state )
	{
		sere_collide_restore_voronoi( s.x.data, s.y.data, s.z.data, s.vx.data, s.vy.data, s.vz.data, s.tri.data(), s.f,
									  s.n, s.h.data, (int32_t) state.range( 0 ) );
		benchmark::ClobberMemory();
	}
	rate( state, "triangles/s", s.f );
}

// The search alone, for the comparison with Embree: refit + per-vertex query + exact test (and
// the edge–edge search, which Embree's does not do).
void BM_collide_search( benchmark::State& state, Shape shape )
{
	detect_loop( state, shape, true );
}

// The floor of BM_collide_detect's searching detection (sere_collide_touch_search): one search
// recorded before the timing, then replayed each iteration, moving the memory the search moves in
// its order with adds in place of its tests. Beside BM_collide_detect (the same search without the
// refit) it says how many times its memory traffic the search takes; the counters say how much
// that traffic is.
void BM_collide_search_floor( benchmark::State& state, Shape shape )
{
	Scene& s = threaded_scene( state, shape );
	sere_bvh_refit( s.bvh, s.x.data, s.y.data, s.z.data );
	sere_collide_traffic traffic = {};
	if ( sere_collide_record_search( s.collide, s.bvh, s.x.data, s.y.data, s.z.data, s.thickness, &traffic ) !=
		 SERE_OK )
	{
		state.SkipWithError( "the search could not be recorded" );
		return;
	}
	for ( auto _ : state )
	{
		sere_collide_touch_search( s.collide, s.bvh, s.x.data, s.y.data, s.z.data, &traffic );
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", s.n );
	state.counters["nodes"] = (double) traffic.nodes;
	state.counters["triangles"] = (double) traffic.leaves;
	state.counters["bound_pairs"] = (double) traffic.bound_pairs;
	state.counters["exact_pairs"] = (double) traffic.exact_pairs;
	state.counters["contacts"] = (double) traffic.contacts;
}

// The floor of BM_collide_pass_listed (sere_collide_touch_served): on the list settled as there, one
// served pass is recorded before the timing, then each iteration replays it, the scene reset between
// iterations outside the timed region as there: the list's check, the listed pairs' gathers, the
// contact and gather lists and the response's passes for the iterations it ran, with the tests'
// outcomes read from the record and adds in place of the arithmetic. Beside BM_collide_pass_listed
// it says how many times its memory traffic the served pass takes; the counters say how much that
// traffic is.
void BM_collide_pass_listed_floor( benchmark::State& state, Shape shape )
{
	Scene& s = threaded_scene( state, shape );
	sere_collide_state st = s.state();
	sere_collide_params p = params( s );
	s.settle_list( p );
	bool moved = state.range( 1 ) != 0;
	s.reset( moved );
	sere_collide_traffic traffic = {};
	if ( sere_collide_record_served( s.collide, s.bvh, &st, &p, &traffic ) != SERE_OK )
	{
		state.SkipWithError( "the served pass could not be recorded" );
		return;
	}
	for ( auto _ : state )
	{
		state.PauseTiming();
		s.reset( moved );
		state.ResumeTiming();
		sere_collide_touch_served( s.collide, s.bvh, &st, &traffic );
		benchmark::ClobberMemory();
	}
	rate( state, "vertices/s", s.n );
	state.counters["exact_pairs"] = (double) traffic.exact_pairs;
	state.counters["contacts"] = (double) traffic.contacts;
	state.counters["evaluated"] = (double) traffic.evaluated;
	state.counters["gathered"] = (double) traffic.gathered;
}

void BM_collide_ref_pairs( benchmark::State& state, Shape shape )
{
	Scene& s = scene( shape );
	std::vector<int32_t> a( 1 << 20 ), b( 1 << 20 );
	int64_t pairs = 0;
	for ( auto _ : state )
	{
		pairs = sere_collide_ref_pairs( s.x.data, s.y.data, s.z.data, s.n, s.tri.data(), s.f, s.thickness, a.data(),
										b.data(), (int64_t) a.size() );
		benchmark::DoNotOptimize( pairs );
	}
	rate( state, "pairs tested/s", (double) s.n * s.f );
	state.counters["contacts"] = (double) pairs;
}

// The edge–edge twin: all pairs of the maple's 13 thousand edges.
void BM_collide_ref_edge_pairs( benchmark::State& state, Shape shape )
{
	Scene& s = scene( shape );
	std::vector<int32_t> ends( 4 << 20 );
	int64_t pairs = 0;
	for ( auto _ : state )
	{
		pairs = sere_collide_ref_edge_pairs( s.x.data, s.y.data, s.z.data, nullptr, nullptr, nullptr, s.tri.data(), s.f,
											 s.thickness, ends.data(), nullptr, (int64_t) ends.size() / 4 );
		benchmark::DoNotOptimize( pairs );
	}
	state.counters["edge_contacts"] = (double) pairs;
}

// The crossing count a run makes every frame (edges through triangles they do not touch: what the
// collision pass must keep at zero), on the scene's positions; its twin below is the brute force.
void BM_crossings_count( benchmark::State& state, Shape shape )
{
	Scene& s = threaded_scene( state, shape );
	sere_crossings* c = nullptr;
	if ( sere_crossings_create( s.tri.data(), s.f, s.n, &c ) != SERE_OK ||
		 sere_crossings_set_threads( c, (int32_t) state.range( 0 ) ) != SERE_OK )
	{
		state.SkipWithError( "sere_crossings_create failed" );
		return;
	}
	int64_t count = 0;
	for ( auto _ : state )
	{
		if ( sere_crossings_count( c, s.x.data, s.y.data, s.z.data, &count ) != SERE_OK )
		{
			state.SkipWithError( "sere_crossings_count failed" );
			break;
		}
		benchmark::DoNotOptimize( count );
	}
	sere_crossings_destroy( c );
	rate( state, "triangles/s", s.f );
	state.counters["crossings"] = (double) count;
}

void BM_crossings_ref_count( benchmark::State& state, Shape shape )
{
	Scene& s = scene( shape );
	int64_t count = 0;
	for ( auto _ : state )
	{
		count = sere_crossings_ref_count( s.x.data, s.y.data, s.z.data, s.n, s.tri.data(), s.f );
		benchmark::DoNotOptimize( count );
	}
	rate( state, "triangles/s", s.f );
	state.counters["crossings"] = (double) count;
}

// Embree 3 doing the same search: a triangle geometry refit on commit, then rtcPointQuery per
// vertex with radius = thickness, whose callback skips the same triangles (a corner, or joined
// to one by a mesh edge) and applies the same exact test, so both report the same pairs.
struct EmbreeQuery
{
	const Scene* scene;
	int32_t vertex;
	float p[3];
	float h2;
	std::vector<int64_t>* found;
};

bool embree_visit( RTCPointQueryFunctionArguments* args )
{
	auto* q = static_cast<EmbreeQuery*>( args->userPtr );
	const int32_t* v = &q->scene->tri[3 * (size_t) args->primID];
	const Scene& s = *q->scene;
	if ( s.excluded( q->vertex, v ) )
	{
		return false;
	}
	float a[3] = { s.x.data[v[0]], s.y.data[v[0]], s.z.data[v[0]] };
	float b[3] = { s.x.data[v[1]], s.y.data[v[1]], s.z.data[v[1]] };
	float c[3] = { s.x.data[v[2]], s.y.data[v[2]], s.z.data[v[2]] };
	float w[3];
	if ( sere_closest_point_triangle( q->p, a, b, c, w ) < q->h2 )
	{
		q->found->push_back( (int64_t) q->vertex << 32 | args->primID );
	}
	return false;
}

void BM_embree_search( benchmark::State& state, Shape shape )
{
	Scene& s = scene( shape );
	int threads = (int) state.range( 0 );
	omp_set_num_threads( threads );
	std::string config = "threads=" + std::to_string( threads );
	RTCDevice device = rtcNewDevice( config.c_str() );
	RTCScene rtc = rtcNewScene( device );
	rtcSetSceneFlags( rtc, RTC_SCENE_FLAG_DYNAMIC );
	RTCGeometry geometry = rtcNewGeometry( device, RTC_GEOMETRY_TYPE_TRIANGLE );
	rtcSetGeometryBuildQuality( geometry, RTC_BUILD_QUALITY_REFIT );
	// stride 16 keeps every vertex load inside the buffer, as Embree requires
	auto* vertices = static_cast<float*>(
		rtcSetNewGeometryBuffer( geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 4 * sizeof( float ), s.n ) );
	auto* indices = static_cast<uint32_t*>(
		rtcSetNewGeometryBuffer( geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof( uint32_t ), s.f ) );
	for ( size_t k = 0; k < s.tri.size(); ++k )
	{
		indices[k] = (uint32_t) s.tri[k];
	}
	auto upload = [&]() {
#pragma omp parallel for schedule( static )
		for ( int32_t k = 0; k < s.n; ++k )
		{
			vertices[4 * k + 0] = s.x.data[k];
			vertices[4 * k + 1] = s.y.data[k];
			vertices[4 * k + 2] = s.z.data[k];
			vertices[4 * k + 3] = 0.0f;
		}
		rtcUpdateGeometryBuffer( geometry, RTC_BUFFER_TYPE_VERTEX, 0 );
		rtcCommitGeometry( geometry );
	};
	upload();
	rtcAttachGeometry( rtc, geometry );
	rtcCommitScene( rtc );
	std::vector<std::vector<int64_t>> found( (size_t) threads );
	size_t contacts = 0;
	for ( auto _ : state )
	{
		upload();
		rtcCommitScene( rtc );
#pragma omp parallel
		{
			std::vector<int64_t>& mine = found[(size_t) omp_get_thread_num()];
			mine.clear();
			RTCPointQueryContext context;
			rtcInitPointQueryContext( &context );
			EmbreeQuery q = { &s, 0, { 0, 0, 0 }, s.thickness * s.thickness, &mine };
#pragma omp for schedule( dynamic, 64 )
			for ( int32_t k = 0; k < s.n; ++k )
			{
				q.vertex = k;
				q.p[0] = s.x.data[k], q.p[1] = s.y.data[k], q.p[2] = s.z.data[k];
				RTCPointQuery query = { q.p[0], q.p[1], q.p[2], 0.0f, s.thickness };
				rtcPointQuery( rtc, &query, &context, embree_visit, &q );
			}
		}
		contacts = 0;
		for ( auto& f : found )
		{
			contacts += f.size();
		}
		benchmark::DoNotOptimize( contacts );
	}
	rate( state, "queries/s", s.n );
	state.counters["contacts"] = (double) contacts;
	rtcReleaseGeometry( geometry );
	rtcReleaseScene( rtc );
	rtcReleaseDevice( device );
}

} // namespace

namespace
{

// Which shapes each benchmark runs on, registered under the names BENCHMARK_CAPTURE gives
// (BM_collide_detect/dense/2/real_time): one row a benchmark in place of a line a pair.
enum Runs
{
	kThreads, // 1 and 2 threads, real time
	kFrames,  // (threads, collision rounds) = (1, 1), (2, 1), (2, 2), real time
	kOnce,	  // the brute-force references, in milliseconds
	kMoved,	  // (threads, moved) = (1, 0), (1, 1), (2, 0), (2, 1), real time
};

struct Registration
{
	const char* name;
	void ( *run )( benchmark::State&, Shape );
	Runs runs;
	std::vector<Shape> shapes;
};

const char* const kShapeNames[] = { "flat", "dried", "waved", "folded", "dense" };

const int kRegistered = [] {
	const Registration table[] = {
		{ "BM_bvh_refit", BM_bvh_refit, kThreads, { kFlat, kDried } },
		{ "BM_bvh_build", BM_bvh_build, kThreads, { kDried } },
		{ "BM_collide_detect", BM_collide_detect, kThreads, { kFlat, kDried, kWaved, kFolded, kDense } },
		{ "BM_collide_respond", BM_collide_respond, kThreads, { kDried, kWaved, kFolded } },
		{ "BM_collide_frame", BM_collide_frame, kFrames, { kFlat, kDried, kWaved, kFolded } },
		{ "BM_collide_pass", BM_collide_pass, kThreads, { kFlat, kDried, kDense } },
		{ "BM_collide_pass_listed", BM_collide_pass_listed, kMoved, { kFlat, kDense } },
		{ "BM_collide_pass_listed_floor", BM_collide_pass_listed_floor, kMoved, { kFlat, kDense } },
		{ "BM_collide_search", BM_collide_search, kThreads, { kFlat, kDried, kWaved, kDense } },
		{ "BM_collide_search_floor", BM_collide_search_floor, kThreads, { kFlat, kDried, kWaved, kDense } },
		{ "BM_embree_search", BM_embree_search, kThreads, { kFlat, kDried, kWaved, kDense } },
		{ "BM_collide_ref_pairs", BM_collide_ref_pairs, kOnce, { kDried, kDense } },
		{ "BM_collide_ref_edge_pairs", BM_collide_ref_edge_pairs, kOnce, { kDried, kDense } },
		{ "BM_crossings_count", BM_crossings_count, kThreads, { kFlat, kDried, kDense } },
		{ "BM_crossings_ref_count", BM_crossings_ref_count, kOnce, { kDried } },
	};
	for ( const Registration& row : table )
	{
		for ( Shape shape : row.shapes )
		{
			std::string name = std::string( row.name ) + "/" + kShapeNames[shape];
			benchmark::internal::Benchmark* b = benchmark::RegisterBenchmark( name.c_str(), row.run, shape );
			if ( row.runs == kThreads )
			{
				b->Arg( 1 )->Arg( 2 )->UseRealTime();
			}
			else if ( row.runs == kFrames )
			{
				b->Args( { 1, 1 } )->Args( { 2, 1 } )->Args( { 2, 2 } )->UseRealTime();
			}
			else if ( row.runs == kMoved )
			{
				b->Args( { 1, 0 } )->Args( { 1, 1 } )->Args( { 2, 0 } )->Args( { 2, 1 } )->UseRealTime();
			}
			else
			{
				b->Unit( benchmark::kMillisecond );
			}
		}
	}
	return 0;
}();

} // namespace

BENCHMARK( BM_collide_restore_voronoi )->Arg( 1 )->Arg( 2 )->UseRealTime();
