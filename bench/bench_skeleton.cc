// Venation skeleton wilting (seed 003): skinning, banding and forward kinematics at 1 and 2
// threads, their reference twins, Eigen (skinning) and Embree (nearest joint) as peers, and one
// frame of a plant of 100 leaves × about 5,000 vertices with and without the piercing check.
#include "mesh/subdivide.h"
#include "ref/skeleton_ref.h"
#include "wilt/skeleton.h"

#include <Eigen/Dense>
#include <benchmark/benchmark.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <embree3/rtcore.h>
#include <omp.h>
#include <vector>

namespace
{

constexpr int kLeaves = 100;
constexpr int kLeafVertices = 5000;
constexpr double kPi = 3.14159265358979323846;

void check( sere_status status, const char* what )
{
	if ( status != SERE_OK )
	{
		std::fprintf( stderr, "bench_skeleton: %s: %s\n", what, sere_status_text( status ) );
		std::abort();
	}
}

// The seed's parametric leaf (length 10, width 6, 9 feature points) meshed and subdivided once to
// about kLeafVertices vertices, with the default generated venation (a midvein in 20 and four
// secondary veins in 6: 45 joints); the plant puts kLeaves of them up a stem with a 137.5°
// phyllotaxis, onsets rising from the bottom leaf.
struct Plant
{
	sere_tri_mesh mesh{};
	sere_skeleton skeleton{};
	sere_plant* plant = nullptr;
	sere_wilt_params params{};

	Plant()
	{
		double l[18], r[18], m[18];
		check( sere_leaf_skeleton_generate( 10.0, 6.0, 9, l, r, m ), "leaf skeleton" );
		sere_leaf_skeleton leaf = { 9, 9, 9, l, r, m };
		// The lattice spacing that gives about kLeafVertices after one 1→4 pass (which
		// roughly quadruples the count), refined once from a first guess.
		double spacing = 0.2;
		for ( int pass = 0; pass < 2; ++pass )
		{
			sere_tri_mesh blade;
			check( sere_leaf_skeleton_mesh( &leaf, spacing, &blade, nullptr ), "blade" );
			sere_tri_mesh_destroy( &mesh );
			check( sere_subdivide( &blade, 1, 0.0f, &mesh ), "subdivide" );
			sere_tri_mesh_destroy( &blade );
			spacing *= std::sqrt( (double) mesh.vertex_count / kLeafVertices );
		}
		sere_venation_params vp = sere_venation_params_default();
		check( sere_skeleton_generate( &leaf, &vp, &skeleton, nullptr ), "venation" );
		sere_leaf_template t = { &mesh, &skeleton };
		std::vector<sere_leaf_placement> leaves( kLeaves );
		for ( int k = 0; k < kLeaves; ++k )
		{
			sere_leaf_placement& p = leaves[(size_t) k];
			p.template_index = 0;
			p.base[0] = p.base[1] = 0.0f;
			p.base[2] = 3.0f * (float) k;
			p.azimuth = (float) ( k * 137.5 * kPi / 180.0 );
			p.elevation = (float) ( 35.0 * kPi / 180.0 );
			p.scale = 1.0f;
			p.onset = 0.005f * (float) k;
		}
		check( sere_plant_create( &t, 1, leaves.data(), kLeaves, &plant ), "plant" );
		params = sere_wilt_params_default();
	}
	~Plant()
	{
		sere_plant_destroy( plant );
		sere_skeleton_destroy( &skeleton );
		sere_tri_mesh_destroy( &mesh );
	}
};

Plant& plant()
{
	static Plant p;
	return p;
}

void rate( benchmark::State& state, const char* name, double per_iteration )
{
	state.counters[name] =
		benchmark::Counter( per_iteration * (double) state.iterations(), benchmark::Counter::kIsRate );
}

// Joint frames posed at mid-wilt: the skinning input.
sere_joint_frames& posed()
{
	static sere_joint_frames frames = [] {
		Plant& p = plant();
		sere_joint_frames f;
		check( sere_joint_frames_create( &f, p.plant->joints.joint_count ), "frames" );
		for ( int32_t k = 0; k < p.plant->leaf_count; ++k )
		{
			int32_t first = p.plant->joint_first[k];
			check( sere_skeleton_pose( &p.plant->joints, first, p.plant->joint_first[k + 1] - first, 0.6f, &p.params,
									   &f, nullptr ),
				   "pose" );
		}
		return f;
	}();
	return frames;
}

// Times skin (the kernel or its scalar twin) over the posed plant's vertices; the vertex count.
template <typename Skin> int32_t skin_loop( benchmark::State& state, Skin skin )
{
	Plant& p = plant();
	sere_joint_frames& f = posed();
	sere_plant* s = p.plant;
	for ( auto _ : state )
	{
		skin( &f, s->joint, s->ox, s->oy, s->oz, s->vertex_count, s->tx, s->ty, s->tz );
		benchmark::ClobberMemory();
	}
	rate( state, "vertices/s", s->vertex_count );
	return s->vertex_count;
}

void BM_skeleton_skin( benchmark::State& state )
{
	const int32_t threads = (int32_t) state.range( 0 );
	int32_t vertices =
		skin_loop( state, [threads]( const sere_joint_frames* f, const int32_t* joint, const float* ox, const float* oy,
									 const float* oz, int32_t n, float* x, float* y, float* z ) {
			sere_joint_frames_skin( f, joint, ox, oy, oz, n, x, y, z, threads );
		} );
	// joint index + offset in, position out: 28 bytes per vertex
	rate( state, "bytes/s", 28.0 * vertices );
}

// The floor of BM_skeleton_skin: the same 28 bytes a vertex (its joint index and offset in, its
// position out) on the same threads, with adds for the transform: x = o + p_0, the joint indices
// summed. The frames (45 joints a leaf) stay in cache and the kernel loads each once per run of
// vertices sharing a joint, so their loads are left out (gathered per vertex they made this
// "floor" 1.6x slower than the kernel). The loop is declared SIMD as the kernel's runs are: without
// it the compiler cannot rule out that x, y, z alias the offsets, kept it scalar, and the "floor"
// ran 1.3x slower than the kernel.
void BM_skeleton_skin_floor( benchmark::State& state )
{
	const int threads = (int) state.range( 0 );
	int64_t indices = 0;
	int32_t vertices = skin_loop( state, [threads, &indices]( const sere_joint_frames* f, const int32_t* joint,
															  const float* ox, const float* oy, const float* oz,
															  int32_t n, float* x, float* y, float* z ) {
		const float px = f->x[0], py = f->y[0], pz = f->z[0];
		int64_t sum = 0;
#pragma omp parallel for simd schedule( static ) num_threads( threads ) reduction( + : sum )
		for ( int32_t i = 0; i < n; ++i )
		{
			sum += joint[i];
			x[i] = ox[i] + px;
			y[i] = oy[i] + py;
			z[i] = oz[i] + pz;
		}
		indices += sum;
	} );
	benchmark::DoNotOptimize( indices );
	rate( state, "bytes/s", 28.0 * vertices );
}

void BM_skeleton_skin_ref( benchmark::State& state )
{
	skin_loop( state, sere_skeleton_ref_skin );
}

// The textbook C++ route: a joint as an Eigen affine transform, vertices as Vector3f (AoS).
void BM_skeleton_skin_eigen( benchmark::State& state )
{
	omp_set_num_threads( (int) state.range( 0 ) );
	Plant& p = plant();
	sere_joint_frames& f = posed();
	sere_plant* s = p.plant;
	int32_t joints = s->joints.joint_count;
	std::vector<Eigen::Matrix3f> rotation( (size_t) joints );
	std::vector<Eigen::Vector3f> origin( (size_t) joints );
	for ( int32_t j = 0; j < joints; ++j )
	{
		for ( int k = 0; k < 9; ++k )
		{
			rotation[(size_t) j]( k / 3, k % 3 ) = f.m[k][j];
		}
		origin[(size_t) j] = Eigen::Vector3f( f.x[j], f.y[j], f.z[j] );
	}
	std::vector<Eigen::Vector3f> offset( (size_t) s->vertex_count ), out( (size_t) s->vertex_count );
	for ( int32_t i = 0; i < s->vertex_count; ++i )
	{
		offset[(size_t) i] = Eigen::Vector3f( s->ox[i], s->oy[i], s->oz[i] );
	}
	for ( auto _ : state )
	{
#pragma omp parallel for schedule( static )
		for ( int32_t i = 0; i < s->vertex_count; ++i )
		{
			size_t j = (size_t) s->joint[i];
			out[(size_t) i] = origin[j] + rotation[j] * offset[(size_t) i];
		}
		benchmark::ClobberMemory();
	}
	rate( state, "vertices/s", s->vertex_count );
}

// Times the banding of n queries against a grid over the joints on state.range( 0 ) threads, or
// with floor its memory floor: sere_joint_grid_touch_band after an untimed
// sere_joint_grid_record_band, the same cells and joint records read in the same order with sums
// for the distances. Both report the recorded traffic a query: the cells the ring searches opened,
// the joint records read and the share of queries their cell's candidate list answered.
void band_loop( benchmark::State& state, const float* jx, const float* jy, const float* jz, int32_t joints,
				const float* x, const float* y, const float* z, int32_t n, bool floor )
{
	omp_set_num_threads( (int) state.range( 0 ) );
	sere_joint_grid* grid;
	check( sere_joint_grid_create( jx, jy, jz, joints, &grid ), "grid" );
	std::vector<int32_t> joint( (size_t) n );
	sere_joint_grid_traffic traffic;
	check( sere_joint_grid_record_band( grid, x, y, z, n, joint.data(), &traffic ), "record" );
	for ( auto _ : state )
	{
		check( floor ? sere_joint_grid_touch_band( grid, x, y, z, n, joint.data(), nullptr )
					 : sere_joint_grid_band( grid, nullptr, nullptr, nullptr, x, y, z, n, joint.data(), nullptr,
											 nullptr, nullptr ),
			   floor ? "touch" : "band" );
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", n );
	state.counters["cells/query"] = (double) traffic.cells / n;
	state.counters["joints/query"] = (double) traffic.joints / n;
	state.counters["listed"] = (double) traffic.listed / n;
	sere_joint_grid_destroy( grid );
}

// Banding one leaf (Sec. 5.2): its ~5,000 vertices against its 45 joints.
void BM_skeleton_band_leaf( benchmark::State& state )
{
	Plant& p = plant();
	band_loop( state, p.skeleton.x, p.skeleton.y, p.skeleton.z, p.skeleton.joint_count, p.mesh.x, p.mesh.y, p.mesh.z,
			   p.mesh.vertex_count, false );
}

void BM_skeleton_band_leaf_floor( benchmark::State& state )
{
	Plant& p = plant();
	band_loop( state, p.skeleton.x, p.skeleton.y, p.skeleton.z, p.skeleton.joint_count, p.mesh.x, p.mesh.y, p.mesh.z,
			   p.mesh.vertex_count, true );
}

void BM_skeleton_band_leaf_ref( benchmark::State& state )
{
	Plant& p = plant();
	std::vector<int32_t> joint( (size_t) p.mesh.vertex_count );
	for ( auto _ : state )
	{
		sere_skeleton_ref_band( p.skeleton.x, p.skeleton.y, p.skeleton.z, p.skeleton.joint_count, p.mesh.x, p.mesh.y,
								p.mesh.z, p.mesh.vertex_count, joint.data() );
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", p.mesh.vertex_count );
}

// Banding at plant scale, where the index matters: every plant vertex against all 4,500 joints.
void BM_skeleton_band_plant( benchmark::State& state )
{
	sere_plant* s = plant().plant;
	band_loop( state, s->joints.x, s->joints.y, s->joints.z, s->joints.joint_count, s->rx, s->ry, s->rz,
			   s->vertex_count, false );
}

void BM_skeleton_band_plant_floor( benchmark::State& state )
{
	sere_plant* s = plant().plant;
	band_loop( state, s->joints.x, s->joints.y, s->joints.z, s->joints.joint_count, s->rx, s->ry, s->rz,
			   s->vertex_count, true );
}

// The brute-force twin scans a 1-in-25 sample of the queries (its rate is per query).
void BM_skeleton_band_plant_ref( benchmark::State& state )
{
	sere_plant* s = plant().plant;
	int32_t n = s->vertex_count / 25;
	std::vector<float> x( (size_t) n ), y( (size_t) n ), z( (size_t) n );
	for ( int32_t i = 0; i < n; ++i )
	{
		x[(size_t) i] = s->rx[25 * i];
		y[(size_t) i] = s->ry[25 * i];
		z[(size_t) i] = s->rz[25 * i];
	}
	std::vector<int32_t> joint( (size_t) n );
	for ( auto _ : state )
	{
		sere_skeleton_ref_band( s->joints.x, s->joints.y, s->joints.z, s->joints.joint_count, x.data(), y.data(),
								z.data(), n, joint.data() );
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", n );
}

// Embree 3: joints as a user geometry of point boxes; rtcPointQuery shrinks its radius to the
// best distance so far, the callback keeping the lower index on ties.
struct NearestQuery
{
	const sere_plant* plant;
	float p[3];
	float best_d2;
	int32_t best;
};

void joint_bounds( const RTCBoundsFunctionArguments* args )
{
	const auto* s = static_cast<const sere_plant*>( args->geometryUserPtr );
	unsigned j = args->primID;
	args->bounds_o->lower_x = args->bounds_o->upper_x = s->joints.x[j];
	args->bounds_o->lower_y = args->bounds_o->upper_y = s->joints.y[j];
	args->bounds_o->lower_z = args->bounds_o->upper_z = s->joints.z[j];
}

bool joint_visit( RTCPointQueryFunctionArguments* args )
{
	auto* q = static_cast<NearestQuery*>( args->userPtr );
	int32_t j = (int32_t) args->primID;
	const sere_skeleton& k = q->plant->joints;
	float dx = q->p[0] - k.x[j], dy = q->p[1] - k.y[j], dz = q->p[2] - k.z[j];
	float d2 = dx * dx + dy * dy + dz * dz;
	if ( d2 < q->best_d2 || ( d2 == q->best_d2 && j < q->best ) )
	{
		q->best_d2 = d2;
		q->best = j;
		args->query->radius = std::sqrt( d2 );
		return true;
	}
	return false;
}

void BM_skeleton_band_plant_embree( benchmark::State& state )
{
	int threads = (int) state.range( 0 );
	omp_set_num_threads( threads );
	sere_plant* s = plant().plant;
	std::string config = "threads=" + std::to_string( threads );
	RTCDevice device = rtcNewDevice( config.c_str() );
	RTCScene scene = rtcNewScene( device );
	RTCGeometry geometry = rtcNewGeometry( device, RTC_GEOMETRY_TYPE_USER );
	rtcSetGeometryUserPrimitiveCount( geometry, (unsigned) s->joints.joint_count );
	rtcSetGeometryUserData( geometry, s );
	rtcSetGeometryBoundsFunction( geometry, joint_bounds, nullptr );
	rtcCommitGeometry( geometry );
	rtcAttachGeometry( scene, geometry );
	rtcCommitScene( scene );
	std::vector<int32_t> joint( (size_t) s->vertex_count );
	for ( auto _ : state )
	{
#pragma omp parallel
		{
			RTCPointQueryContext context;
			rtcInitPointQueryContext( &context );
#pragma omp for schedule( static )
			for ( int32_t i = 0; i < s->vertex_count; ++i )
			{
				NearestQuery q = { s, { s->rx[i], s->ry[i], s->rz[i] }, INFINITY, -1 };
				RTCPointQuery query = { q.p[0], q.p[1], q.p[2], 0.0f, INFINITY };
				rtcPointQuery( scene, &query, &context, joint_visit, &q );
				joint[(size_t) i] = q.best;
			}
		}
		benchmark::ClobberMemory();
	}
	rate( state, "queries/s", s->vertex_count );
	rtcReleaseGeometry( geometry );
	rtcReleaseScene( scene );
	rtcReleaseDevice( device );
}

// Forward kinematics of every leaf (Sec. 6, Lu Eq. 1 with the droop and angle limits): sequential
// per leaf, leaves in parallel; or with floor its memory floor, sere_skeleton_touch_pose after an
// untimed sere_skeleton_record_pose of each leaf: the same reads and writes of the skeleton, the
// work and the frames in the same order, with sums for the rotations and the limits. Both report
// the share of joints whose segment turns and the rest positions the droop limit reads a joint (the
// turning joint's subtree).
void pose_loop( benchmark::State& state, bool floor )
{
	omp_set_num_threads( (int) state.range( 0 ) );
	Plant& p = plant();
	sere_plant* s = p.plant;
	sere_wilt_params params = p.params;
	params.droop_max = 3.0f;
	sere_joint_frames f;
	const int32_t joints = s->joints.joint_count;
	check( sere_joint_frames_create( &f, joints ), "frames" );
	std::vector<uint8_t> turned( (size_t) joints );
	for ( int32_t k = 0; k < s->leaf_count; ++k )
	{
		int32_t first = s->joint_first[k];
		check( sere_skeleton_record_pose( &s->joints, first, s->joint_first[k + 1] - first, 0.6f, &params, &f,
										  turned.data(), nullptr ),
			   "record" );
	}
	int64_t turning = 0, subtree = 0;
	for ( int32_t i = 0; i < joints; ++i )
	{
		turning += turned[(size_t) i];
		subtree += turned[(size_t) i] ? s->joints.end[i] - i : 0;
	}
	for ( auto _ : state )
	{
#pragma omp parallel for schedule( dynamic, 1 )
		for ( int32_t k = 0; k < s->leaf_count; ++k )
		{
			int32_t first = s->joint_first[k], count = s->joint_first[k + 1] - first;
			if ( floor )
			{
				sere_skeleton_touch_pose( &s->joints, first, count, &params, turned.data(), &f );
			}
			else
			{
				sere_skeleton_pose( &s->joints, first, count, 0.6f, &params, &f, nullptr );
			}
		}
		benchmark::ClobberMemory();
	}
	rate( state, "joints/s", joints );
	state.counters["turning"] = (double) turning / joints;
	state.counters["droop_reads/joint"] = (double) subtree / joints;
	sere_joint_frames_destroy( &f );
}

void BM_skeleton_pose( benchmark::State& state )
{
	pose_loop( state, false );
}

void BM_skeleton_pose_floor( benchmark::State& state )
{
	pose_loop( state, true );
}

// One frame of the plant at plant time 0.6, most leaves mid-wilt. With the piercing check a
// frame depends on the one before, so each iteration first rebuilds the state after the frame at
// 0.58 (untimed); that frame is run twice so the BVH is refit to it, as in a run of small steps,
// instead of being rebuilt inside the timed frame after the jump from rest.
void BM_plant_frame( benchmark::State& state )
{
	omp_set_num_threads( (int) state.range( 0 ) );
	Plant& p = plant();
	sere_wilt_params params = p.params;
	params.pierce = (int32_t) state.range( 1 );
	sere_wilt_stats stats{};
	for ( auto _ : state )
	{
		state.PauseTiming();
		sere_plant_reset( p.plant );
		check( sere_plant_frame( p.plant, 0.58f, &params, nullptr ), "frame" );
		check( sere_plant_frame( p.plant, 0.58f, &params, nullptr ), "frame" );
		state.ResumeTiming();
		check( sere_plant_frame( p.plant, 0.6f, &params, &stats ), "frame" );
	}
	rate( state, "vertices/s", p.plant->vertex_count );
	state.counters["vertices"] = p.plant->vertex_count;
	state.counters["triangles"] = p.plant->triangle_count;
	state.counters["shortened"] = stats.pierce.shortened;
	state.counters["pulled_back"] = stats.pierce.pulled_back;
	state.counters["bvh_rebuilt"] = stats.pierce.rebuilt;
}

} // namespace

BENCHMARK( BM_skeleton_skin )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_skin_floor )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_skin_ref )->UseRealTime();
BENCHMARK( BM_skeleton_skin_eigen )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_band_leaf )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_band_leaf_floor )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_band_leaf_ref )->UseRealTime();
BENCHMARK( BM_skeleton_band_plant )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_band_plant_floor )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_band_plant_ref )->UseRealTime();
BENCHMARK( BM_skeleton_band_plant_embree )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_pose )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_skeleton_pose_floor )->Arg( 1 )->Arg( 2 )->UseRealTime();
BENCHMARK( BM_plant_frame )
	->ArgsProduct( { { 1, 2 }, { 0, 1 } } )
	->ArgNames( { "threads", "pierce" } )
	->UseRealTime()
	->Unit( benchmark::kMillisecond );
