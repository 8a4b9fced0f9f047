/* Tests of the venation skeleton's motion (seed 003: Lu, Zhao, Guo 2009): forward kinematics
 * with its limits, skinning against the reference, piercing, the plant, determinism. */
#include "fixture.h"
#include "mesh/subdivide.h"
#include "ref/skeleton_ref.h"
#include "skeleton_leaf.h"
#include "wilt/skeleton.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define DEG ( 3.14159265358979323846 / 180.0 )

/* The generated skeleton (skeleton_generated) with its joint frames. */
static void skeleton_framed( sere_skeleton* s, const sere_venation_params* params, sere_joint_frames* f )
{
	skeleton_generated( s, params );
	cr_assert_eq( sere_joint_frames_create( f, s->joint_count ), SERE_OK );
}

/* skeleton_framed on the default venation with the midrib and the secondary veins bent by the
 * given total angles (degrees). */
static void skeleton_bent( sere_skeleton* s, sere_joint_frames* f, double mid_bend, double secondary_bend )
{
	sere_venation_params vp = sere_venation_params_default();
	vp.mid_bend = (float) ( mid_bend * DEG );
	vp.secondary_bend = (float) ( secondary_bend * DEG );
	skeleton_framed( s, &vp, f );
}

static void skeleton_free( sere_skeleton* s, sere_joint_frames* f )
{
	sere_joint_frames_destroy( f );
	sere_skeleton_destroy( s );
}

static sere_wilt_params no_limits( void )
{
	sere_wilt_params p = sere_wilt_params_default();
	p.droop_max = INFINITY;
	p.min_angle = 0.0f;
	return p;
}

/* Rest length of the segment parent → i and its posed length. */
static void segment_lengths( const sere_skeleton* s, const sere_joint_frames* f, int32_t i, double* rest,
							 double* posed )
{
	int32_t p = s->parent[i];
	*rest = sqrt( pow( (double) s->x[i] - s->x[p], 2 ) + pow( (double) s->y[i] - s->y[p], 2 ) +
				  pow( (double) s->z[i] - s->z[p], 2 ) );
	*posed = sqrt( pow( (double) f->x[i] - f->x[p], 2 ) + pow( (double) f->y[i] - f->y[p], 2 ) +
				   pow( (double) f->z[i] - f->z[p], 2 ) );
}

Test( skeleton, rotations_keep_segment_lengths_and_match_the_reference )
{
	sere_skeleton s;
	sere_joint_frames f;
	skeleton_bent( &s, &f, 150.0, 120.0 );
	double* rx = malloc( (size_t) s.joint_count * 3 * sizeof( double ) );
	double *ry = rx + s.joint_count, *rz = ry + s.joint_count;
	sere_wilt_params limited = sere_wilt_params_default();
	limited.droop_max = 2.0f;
	sere_wilt_params free_params = no_limits();
	const sere_wilt_params* modes[2] = { &free_params, &limited };
	float ts[5] = { 0.0f, 0.3f, 0.6f, 0.9f, 1.0f };
	for ( int mode = 0; mode < 2; ++mode )
	{
		for ( int k = 0; k < 5; ++k )
		{
			sere_pose_stats stats;
			cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, ts[k], modes[mode], &f, &stats ), SERE_OK );
			for ( int32_t i = 1; i < s.joint_count; ++i )
			{
				double rest, posed;
				segment_lengths( &s, &f, i, &rest, &posed );
				/* Positions are stored in float (about 6e-8 relative to a coordinate of 10);
				 * over a segment of 0.5 that is 1e-6 relative, so 1e-5. */
				cr_assert_float_eq( posed, rest, 1e-5 * rest, "mode %d t %g joint %d", mode, ts[k], i );
				/* R Rᵀ = I: each rotation is orthonormal up to float storage (1e-5). */
				for ( int a = 0; a < 3; ++a )
				{
					for ( int b = 0; b < 3; ++b )
					{
						double dot = 0.0;
						for ( int c = 0; c < 3; ++c )
						{
							dot += (double) f.m[3 * a + c][i] * f.m[3 * b + c][i];
						}
						cr_assert_float_eq( dot, a == b ? 1.0 : 0.0, 1e-5 );
					}
				}
			}
			if ( ts[k] == 0.0f )
			{
				cr_expect_eq( stats.turning, 0 );
				for ( int32_t i = 0; i < s.joint_count; ++i )
				{
					cr_assert_eq( f.x[i], s.x[i], "t = 0 is the rest pose" );
					cr_assert_eq( f.z[i], s.z[i] );
				}
			}
			if ( mode == 0 )
			{
				sere_skeleton_ref_pose( &s, ts[k], free_params.spread, rx, ry, rz );
				for ( int32_t i = 0; i < s.joint_count; ++i )
				{
					/* Two routes to the same rotations (accumulated frames vs. rotating every
					 * descendant in turn), both in double, the kernel's stored in float: 1e-5 of
					 * the leaf length 10. */
					cr_assert_float_eq( f.x[i], rx[i], 1e-4, "joint %d", i );
					cr_assert_float_eq( f.y[i], ry[i], 1e-4, "joint %d", i );
					cr_assert_float_eq( f.z[i], rz[i], 1e-4, "joint %d", i );
				}
			}
		}
	}
	free( rx );
	skeleton_free( &s, &f );
}

Test( skeleton, wilting_turns_down_tips_first_and_not_past_straight_down )
{
	double mid[] = { 0, 0, 10, 0 };
	sere_vein_spec vein = { -1, 10, (float) ( 3.14159265358979323846 ), 2, mid };
	sere_skeleton s;
	cr_assert_eq( sere_skeleton_create( &vein, 1, &s, NULL ), SERE_OK );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = no_limits();
	p.spread = 0.5f;
	int32_t tip = s.joint_count - 1;
	float previous = 0.0f;
	for ( int k = 1; k <= 20; ++k )
	{
		sere_pose_stats stats;
		cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, k / 20.0f, &p, &f, &stats ), SERE_OK );
		/* The tip sinks monotonically; only gravity's plane is used (y stays 0). */
		cr_assert_leq( f.z[tip], previous + 1e-6f );
		previous = f.z[tip];
		for ( int32_t i = 0; i < s.joint_count; ++i )
		{
			cr_assert_float_eq( f.y[i], 0.0f, 1e-6f );
		}
		if ( k == 5 )
		{
			/* At t = 0.25 only joints with delay < 0.5 (the outer half) have started. */
			cr_expect_eq( f.z[4], 0.0f );
			cr_expect_lt( f.z[tip], f.z[7] );
		}
	}
	/* Total bend π over a horizontal vein: the segments reach straight down and stop there. */
	for ( int32_t i = 1; i < s.joint_count; ++i )
	{
		int32_t q = s.parent[i];
		double dz = (double) f.z[i] - f.z[q], dx = (double) f.x[i] - f.x[q];
		cr_assert_lt( atan2( -dz, dx ), 90.0 * DEG + 1e-5, "joint %d not past down", i );
	}
	double dz = (double) f.z[tip] - f.z[tip - 1], dx = (double) f.x[tip] - f.x[tip - 1];
	cr_expect_float_eq( atan2( -dz, dx ), 90.0 * DEG, 1e-5, "the tip segment hangs straight down" );
	skeleton_free( &s, &f );
}

/* The lowest a joint sinks below its rest height over the whole skeleton. */
static double deepest_droop( const sere_skeleton* s, const sere_joint_frames* f )
{
	double deepest = 0.0;
	for ( int32_t i = 0; i < s->joint_count; ++i )
	{
		deepest = fmax( deepest, (double) s->z[i] - f->z[i] );
	}
	return deepest;
}

/* The smallest included angle between adjacent segments of one vein. */
static double smallest_included_angle( const sere_skeleton* s, const sere_joint_frames* f )
{
	double smallest = 3.14159265358979323846;
	for ( int32_t i = 0; i < s->joint_count; ++i )
	{
		int32_t p = s->parent[i];
		if ( p < 0 || s->parent[p] < 0 || s->vein[p] != s->vein[i] )
		{
			continue;
		}
		int32_t g = s->parent[p];
		double a[3] = { (double) f->x[g] - f->x[p], (double) f->y[g] - f->y[p], (double) f->z[g] - f->z[p] };
		double b[3] = { (double) f->x[i] - f->x[p], (double) f->y[i] - f->y[p], (double) f->z[i] - f->z[p] };
		double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
		double la = sqrt( a[0] * a[0] + a[1] * a[1] + a[2] * a[2] ),
			   lb = sqrt( b[0] * b[0] + b[1] * b[1] + b[2] * b[2] );
		smallest = fmin( smallest, acos( fmax( -1.0, fmin( 1.0, dot / ( la * lb ) ) ) ) );
	}
	return smallest;
}

Test( skeleton, droop_limit_holds )
{
	sere_skeleton s;
	sere_joint_frames f;
	skeleton_bent( &s, &f, 170.0, 150.0 );
	sere_wilt_params p = no_limits();
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 1.0f, &p, &f, NULL ), SERE_OK );
	double unlimited = deepest_droop( &s, &f );
	cr_assert_gt( unlimited, 3.0, "without the limit the tip sinks far" );
	float limits[3] = { 0.5f, 1.5f, 3.0f };
	for ( int k = 0; k < 3; ++k )
	{
		p.droop_max = limits[k];
		for ( int step = 1; step <= 10; ++step )
		{
			sere_pose_stats stats;
			cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, step / 10.0f, &p, &f, &stats ), SERE_OK );
			/* The limit is met exactly at the crossing in double; float storage of z (about
			 * 1e-6 here) is the tolerance. */
			cr_assert_leq( deepest_droop( &s, &f ), limits[k] + 1e-5, "limit %g t %g", limits[k], step / 10.0 );
			if ( step == 10 )
			{
				cr_expect_gt( stats.droop_limited, 0 );
				/* The limit is reached, not merely respected from afar. */
				cr_expect_gt( deepest_droop( &s, &f ), limits[k] - 1e-3 );
			}
		}
	}
	skeleton_free( &s, &f );
}

Test( skeleton, minimal_angle_limit_holds )
{
	/* Few joints and a strong bend: 4 segments turning 160° in all, 40° each. */
	double mid[] = { 0, 0, 10, 0 };
	double side[] = { 5, 0, 7, 4 };
	sere_vein_spec veins[2] = { { -1, 4, (float) ( 160.0 * DEG ), 2, mid },
								{ 0, 3, (float) ( 150.0 * DEG ), 2, side } };
	sere_skeleton s;
	cr_assert_eq( sere_skeleton_create( veins, 2, &s, NULL ), SERE_OK );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = no_limits();
	p.spread = 0.0f;
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 1.0f, &p, &f, NULL ), SERE_OK );
	cr_assert_lt( smallest_included_angle( &s, &f ), 145.0 * DEG, "without the limit the vein kinks" );
	p.min_angle = (float) ( 150.0 * DEG );
	for ( int step = 1; step <= 10; ++step )
	{
		sere_pose_stats stats;
		cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, step / 10.0f, &p, &f, &stats ), SERE_OK );
		/* Angles from float positions over segments of 2.5: about 1e-6 rad; 1e-4 is safe. */
		cr_assert_geq( smallest_included_angle( &s, &f ), 150.0 * DEG - 1e-4, "t %g", step / 10.0 );
		if ( step == 10 )
		{
			cr_expect_gt( stats.angle_limited, 0 );
		}
	}
	skeleton_free( &s, &f );
}

Test( skeleton, pose_rejects_bad_input )
{
	sere_skeleton s;
	sere_joint_frames f;
	skeleton_framed( &s, NULL, &f );
	/* each case from the default parameters; spread and droop_max replace theirs when nonzero */
	const struct
	{
		int32_t first;
		float water, spread, droop_max;
		sere_status status;
		const char* what;
	} cases[] = {
		{ 0, NAN, 0.0f, 0.0f, SERE_ERR_NONFINITE, "NaN water" },
		{ 1, 0.5f, 0.0f, 0.0f, SERE_ERR_ARGUMENT, "a range must be a whole tree" },
		{ 0, 0.5f, 1.0f, 0.0f, SERE_ERR_ARGUMENT, "spread 1" },
		{ 0, 0.5f, 0.0f, -1.0f, SERE_ERR_ARGUMENT, "a negative droop limit" },
		{ 0, 0.5f, 0.0f, NAN, SERE_ERR_NONFINITE, "a NaN droop limit" },
	};
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		sere_wilt_params p = sere_wilt_params_default();
		p.spread = cases[k].spread != 0.0f ? cases[k].spread : p.spread;
		p.droop_max = cases[k].droop_max != 0.0f ? cases[k].droop_max : p.droop_max;
		cr_expect_eq(
			sere_skeleton_pose( &s, cases[k].first, s.joint_count - cases[k].first, cases[k].water, &p, &f, NULL ),
			cases[k].status, "%s", cases[k].what );
	}
	skeleton_free( &s, &f );
}

/* The frames of n joints, work included, as bytes: posed, recorded and touched frames compare
 * with memcmp. */
static unsigned char* frames_copy( const sere_joint_frames* f, int32_t n )
{
	size_t floats = (size_t) n * sizeof( float ), doubles = 12 * (size_t) n * sizeof( double );
	unsigned char* copy = malloc( 12 * floats + doubles );
	const float* arrays[12] = { f->x, f->y, f->z };
	for ( int k = 0; k < 9; ++k )
	{
		arrays[3 + k] = f->m[k];
	}
	for ( int k = 0; k < 12; ++k )
	{
		memcpy( copy + k * floats, arrays[k], floats );
	}
	memcpy( copy + 12 * floats, f->work, doubles );
	return copy;
}

static bool frames_same( const sere_joint_frames* f, int32_t n, const unsigned char* copy )
{
	unsigned char* now = frames_copy( f, n );
	bool same = memcmp( now, copy, 12 * (size_t) n * ( sizeof( float ) + sizeof( double ) ) ) == 0;
	free( now );
	return same;
}

Test( skeleton, pose_floor_leaves_the_frames_as_they_were )
{
	sere_skeleton s;
	sere_joint_frames f;
	skeleton_bent( &s, &f, 150.0, 120.0 );
	const int32_t n = s.joint_count;
	uint8_t* turned = malloc( (size_t) n );
	sere_wilt_params limited = sere_wilt_params_default();
	limited.droop_max = 2.0f;
	sere_wilt_params free_params = no_limits();
	const sere_wilt_params* modes[2] = { &free_params, &limited };
	float ts[4] = { 0.0f, 0.3f, 0.7f, 1.0f };
	for ( int mode = 0; mode < 2; ++mode )
	{
		for ( int k = 0; k < 4; ++k )
		{
			sere_pose_stats posed, recorded;
			cr_assert_eq( sere_skeleton_pose( &s, 0, n, ts[k], modes[mode], &f, &posed ), SERE_OK );
			unsigned char* copy = frames_copy( &f, n );
			cr_assert_eq( sere_skeleton_pose( &s, 0, n, 0.5f * ts[k] + 0.1f, modes[mode], &f, NULL ), SERE_OK );
			memset( turned, 0xff, (size_t) n );
			cr_assert_eq( sere_skeleton_record_pose( &s, 0, n, ts[k], modes[mode], &f, turned, &recorded ), SERE_OK );
			cr_assert( frames_same( &f, n, copy ), "mode %d t %g: recording changed the pose", mode, ts[k] );
			cr_assert( memcmp( &posed, &recorded, sizeof( posed ) ) == 0 );
			int32_t turning = 0;
			for ( int32_t i = 0; i < n; ++i )
			{
				cr_assert( turned[i] <= 1, "joint %d not recorded", i );
				turning += turned[i];
			}
			cr_assert_eq( turned[0], 0, "the root has no segment" );
			cr_assert_eq( turning, recorded.turning, "mode %d t %g: %d turned, %d turning", mode, ts[k], turning,
						  recorded.turning );
			cr_assert( ts[k] == 0.0f ? turning == 0 : turning > n / 2, "mode %d t %g: %d of %d turned", mode, ts[k],
					   turning, n );
			cr_assert_eq( sere_skeleton_touch_pose( &s, 0, n, modes[mode], turned, &f ), SERE_OK );
			cr_assert( frames_same( &f, n, copy ), "mode %d t %g: the floor changed the frames", mode, ts[k] );
			free( copy );
		}
	}
	cr_expect_eq( sere_skeleton_record_pose( &s, 0, n, 0.5f, &limited, &f, NULL, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_skeleton_touch_pose( &s, 0, n, &limited, NULL, &f ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_skeleton_touch_pose( &s, 1, n - 1, &limited, turned, &f ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_skeleton_touch_pose( NULL, 0, n, &limited, turned, &f ), SERE_ERR_ARGUMENT );
	limited.droop_max = NAN;
	cr_expect_eq( sere_skeleton_touch_pose( &s, 0, n, &limited, turned, &f ), SERE_ERR_NONFINITE );
	free( turned );
	skeleton_free( &s, &f );
}

/* ------------------------------------------------------------------------------------------- */

Test( skeleton, skinning_equals_reference_bitwise )
{
	sere_skeleton s;
	sere_joint_frames f;
	skeleton_framed( &s, NULL, &f );
	sere_wilt_params p = sere_wilt_params_default();
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 0.8f, &p, &f, NULL ), SERE_OK );
	enum
	{
		N = 10007
	};
	static int32_t joint[N];
	static float ox[N], oy[N], oz[N], x[N], y[N], z[N], rx[N], ry[N], rz[N];
	uint64_t seed = 3;
	for ( int i = 0; i < N; ++i )
	{
		joint[i] = (int32_t) ( sere_test_unit( &seed ) * s.joint_count );
		ox[i] = (float) ( sere_test_unit( &seed ) - 0.5 );
		oy[i] = (float) ( sere_test_unit( &seed ) - 0.5 );
		oz[i] = (float) ( 0.1 * ( sere_test_unit( &seed ) - 0.5 ) );
	}
	/* Twice: joints at random (runs of about one vertex), then in runs as a plant binds them, of
	 * lengths about the kernel's chunk of 16 joint indices compared at once, and across its blocks
	 * of 2048 vertices; every run's joint differs from the run before. */
	for ( int order = 0; order < 2; ++order )
	{
		if ( order == 1 )
		{
			static const int lengths[] = { 1, 15, 16, 17, 31, 32, 33, 100, 2049, 5 };
			int run = 0, left = lengths[0];
			for ( int i = 0; i < N; ++i, --left )
			{
				if ( left == 0 )
				{
					run += 1;
					left = lengths[run % 10];
				}
				joint[i] = ( run * 7 ) % s.joint_count;
			}
			cr_assert_neq( 7 % s.joint_count, 0, "runs must change joint" );
		}
		sere_joint_frames_skin( &f, joint, ox, oy, oz, N, x, y, z, 0 );
		sere_skeleton_ref_skin( &f, joint, ox, oy, oz, N, rx, ry, rz );
		/* The same operations in the same order without contraction: identical bits. */
		cr_expect_eq( memcmp( x, rx, sizeof( x ) ), 0, "order %d", order );
		cr_expect_eq( memcmp( y, ry, sizeof( y ) ), 0, "order %d", order );
		cr_expect_eq( memcmp( z, rz, sizeof( z ) ), 0, "order %d", order );
	}
	skeleton_free( &s, &f );
}

/* ------------------------------------------------------------------------------------------- */

static int64_t count_intersections( const int32_t* tri, int32_t triangles, int32_t vertices, const float* x,
									const float* y, const float* z )
{
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, triangles, vertices, x, y, z, &bvh ), SERE_OK );
	int64_t count = sere_mesh_count_intersections( bvh, tri, triangles, x, y, z, 0 );
	sere_bvh_destroy( bvh );
	return count;
}

Test( skeleton, intersection_count )
{
	/* Two triangles through each other, then apart, then sharing a corner and folded through. */
	float x[6] = { 0, 2, 0, 0.5f, 0.5f, 0.5f };
	float y[6] = { 0, 0, 2, 0.5f, 0.5f, -1 };
	float z[6] = { 0, 0, 0, -1, 1, 0 };
	int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	cr_expect_eq( count_intersections( tri, 2, 6, x, y, z ), 1 );
	z[3] = 0.5f;
	cr_expect_eq( count_intersections( tri, 2, 6, x, y, z ), 0 );
	/* Shared corner 0: the second triangle's far edge passes through the first. */
	int32_t shared[6] = { 0, 1, 2, 0, 3, 4 };
	x[3] = 1.0f, y[3] = 0.3f, z[3] = -1.0f;
	x[4] = 1.0f, y[4] = 0.3f, z[4] = 1.0f;
	cr_expect_eq( count_intersections( shared, 2, 6, x, y, z ), 1 );
	z[3] = 0.2f;
	cr_expect_eq( count_intersections( shared, 2, 6, x, y, z ), 0 );
	/* A planar mesh never counts, however many neighbours touch. */
	sere_tri_mesh m;
	skeleton_grid_leaf( &m, 10.0, 6.0, 0.3, 30, 20 );
	cr_expect_eq( count_intersections( m.tri, m.triangle_count, m.vertex_count, m.x, m.y, m.z ), 0 );
	sere_tri_mesh_destroy( &m );
}

Test( skeleton, piercing_shortens_moves_through_the_mesh )
{
	/* A 10 × 10 sheet at z = 0 and a separate small flap above it, pushed partly through. */
	sere_tri_mesh sheet;
	skeleton_grid_leaf( &sheet, 4.0, 4.0, -1.0, 10, 10 );
	int32_t n = sheet.vertex_count + 3, f = sheet.triangle_count + 1;
	float *x = calloc( (size_t) n, sizeof( float ) ), *y = calloc( (size_t) n, sizeof( float ) );
	float *z = calloc( (size_t) n, sizeof( float ) ), *tx = calloc( (size_t) n, sizeof( float ) );
	float *ty = calloc( (size_t) n, sizeof( float ) ), *tz = calloc( (size_t) n, sizeof( float ) );
	int32_t* tri = malloc( 3 * (size_t) f * sizeof( int32_t ) );
	memcpy( x, sheet.x, (size_t) sheet.vertex_count * sizeof( float ) );
	memcpy( y, sheet.y, (size_t) sheet.vertex_count * sizeof( float ) );
	memcpy( tri, sheet.tri, 3 * (size_t) sheet.triangle_count * sizeof( int32_t ) );
	int32_t a = sheet.vertex_count;
	float flap[3][2] = { { 1.1f, 0.3f }, { 2.3f, 0.4f }, { 1.5f, -0.9f } };
	for ( int k = 0; k < 3; ++k )
	{
		x[a + k] = flap[k][0];
		y[a + k] = flap[k][1];
		z[a + k] = 0.5f;
		tri[3 * sheet.triangle_count + k] = a + k;
	}
	memcpy( tx, x, (size_t) n * sizeof( float ) );
	memcpy( ty, y, (size_t) n * sizeof( float ) );
	/* Two corners of the flap are pushed through the sheet, the third stays above. */
	memcpy( tz, z, (size_t) n * sizeof( float ) );
	tz[a] = tz[a + 1] = -0.5f;
	cr_assert_gt( count_intersections( tri, f, n, tx, ty, tz ), 0, "the unchecked move goes through" );
	sere_pierce* pierce;
	cr_assert_eq( sere_pierce_create( tri, f, n, x, y, z, NULL, &pierce ), SERE_OK );
	sere_pierce_stats stats;
	cr_assert_eq( sere_pierce_step( pierce, x, y, z, tx, ty, tz, 0.01f, &stats ), SERE_OK );
	cr_expect_eq( stats.shortened, 2 );
	cr_expect_eq( stats.reverted, 0 );
	cr_expect_eq( tz[a + 2], 0.5f );
	for ( int k = 0; k < 2; ++k )
	{
		/* Stopped `margin` above the sheet; float rounding of 0.5 − 0.49: 1e-6. */
		cr_expect_float_eq( tz[a + k], 0.01f, 1e-6f );
		cr_expect_eq( tx[a + k], x[a + k], "straight down: x unchanged" );
	}
	cr_expect_eq( count_intersections( tri, f, n, tx, ty, tz ), 0 );
	cr_expect_eq( sere_mesh_count_intersections( sere_pierce_bvh( pierce ), tri, f, tx, ty, tz, 0 ), 0,
				  "the workspace BVH is refit to the result" );

	/* An edge swept through a triangle while both its ends pass outside: no vertex pierces, the
	 * pull-back has to undo it. One big triangle at z = 0, one flap whose far corner drops
	 * outside it. */
	float bx[6] = { -1, 3, -1, -3, 5, -3 }, by[6] = { -1, -1, 3, 0.5f, 0.5f, 2 }, bz[6] = { 0, 0, 0, 1, 1, 1 };
	float cx[6], cy[6], cz[6];
	memcpy( cx, bx, sizeof( bx ) );
	memcpy( cy, by, sizeof( by ) );
	memcpy( cz, bz, sizeof( bz ) );
	cz[4] = -1.0f;
	int32_t two[6] = { 0, 1, 2, 3, 4, 5 };
	cr_assert_eq( count_intersections( two, 2, 6, cx, cy, cz ), 1 );
	sere_pierce* small;
	cr_assert_eq( sere_pierce_create( two, 2, 6, bx, by, bz, NULL, &small ), SERE_OK );
	cr_assert_eq( sere_pierce_step( small, bx, by, bz, cx, cy, cz, 0.01f, &stats ), SERE_OK );
	cr_expect_eq( stats.shortened, 0 );
	cr_expect_gt( stats.pulled_back, 0 );
	cr_expect_eq( count_intersections( two, 2, 6, cx, cy, cz ), 0 );
	cr_expect_lt( cz[4], 1.0f, "the corner still moved part of the way" );
	sere_pierce_destroy( small );
	sere_pierce_destroy( pierce );
	free( x );
	free( y );
	free( z );
	free( tx );
	free( ty );
	free( tz );
	free( tri );
	sere_tri_mesh_destroy( &sheet );
}

/* ------------------------------------------------------------------------------------------- */

/* A small plant: `leaves` grid leaves, alternately placed up a stem, onsets from the bottom. */
static sere_plant* small_plant( sere_tri_mesh* mesh, sere_skeleton* s, int32_t leaves, double lobes )
{
	skeleton_grid_leaf( mesh, 10.0, 6.0, lobes, 40, 24 );
	/* Four secondary veins that turn steeply: where the regions of two of them meet, rigid
	 * banding folds the blade, which gives the piercing check work to do. */
	sere_venation_params vp = sere_venation_params_default();
	vp.secondary_count = 4;
	vp.secondary_segments = 6;
	vp.angle = (float) ( 50.0 * DEG );
	vp.secondary_bend = (float) ( 60.0 * DEG );
	skeleton_generated( s, &vp );
	sere_leaf_template t = { mesh, s };
	sere_leaf_placement* l = calloc( (size_t) leaves, sizeof( sere_leaf_placement ) );
	for ( int32_t k = 0; k < leaves; ++k )
	{
		l[k].template_index = 0;
		l[k].base[2] = 4.0f * (float) k;
		l[k].azimuth = (float) ( k * 137.5 * DEG );
		l[k].elevation = (float) ( 35.0 * DEG );
		l[k].scale = 1.0f - 0.05f * (float) k;
		l[k].onset = 0.25f * (float) k;
	}
	sere_plant* plant;
	cr_assert_eq( sere_plant_create( &t, 1, l, leaves, &plant ), SERE_OK );
	free( l );
	return plant;
}

Test( skeleton, wilting_never_self_intersects )
{
	/* A plain and a lobed (concave) blade on a plant of three leaves: with the piercing check
	 * no frame intersects itself or another leaf. */
	for ( int lobed = 0; lobed < 2; ++lobed )
	{
		sere_tri_mesh mesh;
		sere_skeleton s;
		sere_plant* plant = small_plant( &mesh, &s, 3, lobed ? 0.3 : 0.0 );
		sere_wilt_params p = sere_wilt_params_default();
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( plant->tri, plant->triangle_count, plant->vertex_count, plant->x, plant->y,
									   plant->z, &bvh ),
					  SERE_OK );
		if ( !lobed )
		{
			/* Rigid banding alone folds the blade where two secondary veins' regions meet
			 * (the check has something to do here). */
			p.pierce = 0;
			int64_t unchecked = 0;
			for ( int frame = 1; frame <= 30; ++frame )
			{
				cr_assert_eq( sere_plant_frame( plant, frame / 20.0f, &p, NULL ), SERE_OK );
				cr_assert_eq( sere_bvh_refit( bvh, plant->x, plant->y, plant->z ), SERE_OK );
				unchecked += sere_mesh_count_intersections( bvh, plant->tri, plant->triangle_count, plant->x, plant->y,
															plant->z, 0 );
			}
			cr_assert_gt( unchecked, 0 );
			p.pierce = 1;
			sere_plant_reset( plant );
		}
		for ( int frame = 1; frame <= 30; ++frame )
		{
			sere_wilt_stats stats;
			cr_assert_eq( sere_plant_frame( plant, frame / 20.0f, &p, &stats ), SERE_OK );
			cr_assert_eq( sere_bvh_refit( bvh, plant->x, plant->y, plant->z ), SERE_OK );
			cr_assert_eq( sere_mesh_count_intersections( bvh, plant->tri, plant->triangle_count, plant->x, plant->y,
														 plant->z, 0 ),
						  0, "lobed %d frame %d", lobed, frame );
			cr_assert_eq( stats.pierce.reverted, 0 );
		}
		/* The plant did wilt: every leaf is at t = 1 and its tip far below its rest height. */
		for ( int32_t k = 0; k < plant->leaf_count; ++k )
		{
			cr_expect_eq( plant->leaf_t[k], 1.0f );
			int32_t tip = plant->joint_first[k] + 20; /* the midvein tip: joint 20 in depth-first order */
			cr_expect_lt( plant->frames.z[tip], plant->joints.z[tip] - 2.0f );
		}
		sere_bvh_destroy( bvh );
		sere_plant_destroy( plant );
		sere_tri_mesh_destroy( &mesh );
		sere_skeleton_destroy( &s );
	}
}

Test( skeleton, plant_keeps_texture_coordinates_and_starts_from_the_bottom )
{
	sere_tri_mesh mesh;
	sere_skeleton s;
	sere_plant* plant = small_plant( &mesh, &s, 4, 0.0 );
	size_t bytes = (size_t) plant->vertex_count * sizeof( float );
	float* u = malloc( bytes );
	float* v = malloc( bytes );
	memcpy( u, plant->u, bytes );
	memcpy( v, plant->v, bytes );
	sere_wilt_params p = sere_wilt_params_default();
	/* At time 0.5 leaves 0 and 1 (onsets 0 and 0.25) wilt, leaves 2 and 3 have not started. */
	for ( int frame = 1; frame <= 5; ++frame )
	{
		cr_assert_eq( sere_plant_frame( plant, frame * 0.1f, &p, NULL ), SERE_OK );
	}
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double moved = 0.0;
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			moved = fmax( moved, fabs( (double) plant->z[i] - plant->rz[i] ) );
		}
		if ( k < 2 )
		{
			cr_expect_gt( moved, 0.1, "leaf %d wilts", k );
		}
		else
		{
			cr_expect_eq( moved, 0.0, "leaf %d waits", k );
		}
	}
	cr_expect_gt( plant->leaf_t[0], plant->leaf_t[1] );
	/* Sec. 6: texture coordinates are computed before the deformation and never remapped. */
	for ( int frame = 6; frame <= 25; ++frame )
	{
		cr_assert_eq( sere_plant_frame( plant, frame * 0.1f, &p, NULL ), SERE_OK );
	}
	cr_expect_eq( memcmp( u, plant->u, bytes ), 0 );
	cr_expect_eq( memcmp( v, plant->v, bytes ), 0 );
	/* Back to rest exactly. */
	sere_plant_reset( plant );
	cr_expect_eq( memcmp( plant->x, plant->rx, bytes ), 0 );
	free( u );
	free( v );
	sere_plant_destroy( plant );
	sere_tri_mesh_destroy( &mesh );
	sere_skeleton_destroy( &s );
}

static sere_status set_plant_threads( void* plant, int32_t threads )
{
	return sere_plant_set_threads( (sere_plant*) plant, threads );
}

/* The plant's thread setter holds the one limit of every object (docs/DESIGN.md §4), and keeps
 * the count it took. */
Test( skeleton, plant_threads_take_zero_to_the_limit )
{
	sere_tri_mesh mesh;
	sere_skeleton s;
	sere_plant* plant = small_plant( &mesh, &s, 2, 0.0 );
	sere_test_expect_thread_range( "plant", plant, set_plant_threads );
	cr_expect_eq( plant->threads, 0 ); /* the range's last count */
	sere_plant_destroy( plant );
	sere_tri_mesh_destroy( &mesh );
	sere_skeleton_destroy( &s );
}

Test( skeleton, one_and_two_threads_identical )
{
	float* result[2][3];
	int32_t counts[2][2];
	for ( int run = 0; run < 2; ++run )
	{
		omp_set_num_threads( run + 1 );
		sere_tri_mesh mesh;
		sere_skeleton s;
		sere_plant* plant = small_plant( &mesh, &s, 5, 0.3 );
		sere_wilt_params p = sere_wilt_params_default();
		p.droop_max = 4.0f;
		sere_wilt_stats stats;
		counts[run][0] = counts[run][1] = 0;
		for ( int frame = 1; frame <= 30; ++frame )
		{
			cr_assert_eq( sere_plant_frame( plant, frame / 15.0f, &p, &stats ), SERE_OK );
			counts[run][0] += stats.pierce.shortened;
			counts[run][1] += stats.pierce.pulled_back;
		}
		size_t bytes = (size_t) plant->vertex_count * sizeof( float );
		float* xyz[3] = { plant->x, plant->y, plant->z };
		for ( int a = 0; a < 3; ++a )
		{
			result[run][a] = malloc( bytes );
			memcpy( result[run][a], xyz[a], bytes );
		}
		if ( run == 1 )
		{
			for ( int a = 0; a < 3; ++a )
			{
				cr_expect_eq( memcmp( result[0][a], result[1][a], bytes ), 0, "axis %d", a );
			}
		}
		sere_plant_destroy( plant );
		sere_tri_mesh_destroy( &mesh );
		sere_skeleton_destroy( &s );
	}
	cr_expect_eq( counts[0][0], counts[1][0] );
	cr_expect_eq( counts[0][1], counts[1][1] );
	for ( int run = 0; run < 2; ++run )
	{
		for ( int a = 0; a < 3; ++a )
		{
			free( result[run][a] );
		}
	}
	omp_set_num_threads( 2 );
}

Test( skeleton, plant_rejects_bad_input )
{
	sere_tri_mesh mesh;
	sere_skeleton s;
	skeleton_grid_leaf( &mesh, 10.0, 6.0, 0.0, 10, 6 );
	skeleton_generated( &s, NULL );
	sere_leaf_template t = { &mesh, &s };
	sere_leaf_placement l = { 0, { 0, 0, 0 }, 0.0f, 0.5f, 1.0f, 0.0f };
	sere_plant* plant;
	l.template_index = 1;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_ARGUMENT );
	l.template_index = 0;
	l.scale = 0.0f;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_ARGUMENT );
	l.scale = 1.0f;
	l.base[1] = NAN;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_NONFINITE );
	l.base[1] = 0.0f;
	cr_assert_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_OK );
	sere_wilt_params p = sere_wilt_params_default();
	cr_expect_eq( sere_plant_frame( plant, INFINITY, &p, NULL ), SERE_ERR_NONFINITE );
	p.min_angle = 4.0f;
	cr_expect_eq( sere_plant_frame( plant, 0.5f, &p, NULL ), SERE_ERR_ARGUMENT );
	sere_plant_destroy( plant );
	sere_tri_mesh_destroy( &mesh );
	sere_skeleton_destroy( &s );
}
