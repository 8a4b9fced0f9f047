/* sere — private to the skeleton_*.c kernels (seed 003: Lu, Zhao, Guo 2009), not installed and
 * not part of the API: the sampled leaf skeleton, the curve and plane helpers and the posing
 * step that the blade, venation, wilting and plant files share. */
#pragma once

#include "wilt/skeleton.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846

/* At most this many points on any sampled curve or in the blade: spacing too fine for the leaf
 * is an input error, not an allocation failure. */
#define MAX_CURVE_POINTS 1000000

/* The sampled leaf: outline counter-clockwise from the base (index 0) through the tip, and the
 * midvein from base to tip sharing those two points exactly. */
typedef struct sere_skel_leaf_curves
{
	double* outline;
	int32_t outline_count;
	int32_t tip;
	double* mid;
	int32_t mid_count;
	double size;
} sere_skel_leaf_curves;

static inline sere_status sere_skel_report( sere_skeleton_check* check, sere_skeleton_problem problem, int32_t vein,
											int32_t point )
{
	if ( check != NULL )
	{
		check->problem = problem;
		check->vein = vein;
		check->point = point;
	}
	if ( problem == SERE_SKELETON_OK )
	{
		return SERE_OK;
	}
	return problem == SERE_SKELETON_NONFINITE ? SERE_ERR_NONFINITE : SERE_ERR_GEOMETRY;
}

static inline double sere_skel_dist2d( const double* a, const double* b )
{
	return hypot( a[0] - b[0], a[1] - b[1] );
}

static inline void sere_skel_mat_vec( const double m[9], const double v[3], double out[3] )
{
	for ( int r = 0; r < 3; ++r )
	{
		out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
	}
}

/* A float's and a double's bits, for the floors (sere_joint_grid_touch_band,
 * sere_skeleton_touch_pose): integer sums of what they read chain one cycle of latency an add,
 * where float sums would chain four and the floor would time its own sums. */
static inline uint32_t sere_skel_float_bits( float f )
{
	uint32_t u;
	memcpy( &u, &f, sizeof( u ) );
	return u;
}

static inline uint64_t sere_skel_double_bits( double d )
{
	uint64_t u;
	memcpy( &u, &d, sizeof( u ) );
	return u;
}

/* The spline through p resampled every `spacing` (at least min_pieces pieces); NULL on
 * allocation failure. */
double* sere_skel_curve_sample( const double* p, int32_t n, double spacing, int32_t min_pieces, int32_t* count );

/* Sum of the chord lengths of an open polyline of n points. */
double sere_skel_polyline_length( const double* p, int32_t n );

/* `pieces` equal arc-length pieces: writes pieces + 1 points, the ends exactly. */
void sere_skel_resample( const double* p, int32_t n, int32_t pieces, double* out );

/* Closed segments ab and cd share a point (touching counts). */
int sere_skel_segments_meet( const double* a, const double* b, const double* c, const double* d );

/* Distance from p to a polyline (closed: the last point joins the first). */
double sere_skel_polyline_distance( const double* p, const double* poly, int32_t n, int closed );

/* Few points, non-finite or repeated points in one curve of n points; *point names the first
 * offending point. */
sere_skeleton_problem sere_skel_check_curve( const double* p, int32_t n, int32_t* point );

/* Validates a leaf skeleton (Sec. 4.1) and samples its outline and midvein every `spacing`;
 * on success the caller frees c with sere_skel_leaf_curves_destroy. */
sere_status sere_skel_leaf_curves_build( const sere_leaf_skeleton* leaf, double spacing, sere_skel_leaf_curves* c,
										 sere_skeleton_check* check );

void sere_skel_leaf_curves_destroy( sere_skel_leaf_curves* c );

/* Arrays for joint_count joints (padded), zeroed struct on failure. */
sere_status sere_skel_create( sere_skeleton* s, int32_t joint_count );

/* SERE_ERR_ARGUMENT or SERE_ERR_NONFINITE for wilt parameters out of range. */
sere_status sere_skel_check_wilt_params( const sere_wilt_params* p );

/* Sec. 6, Lu Eq. 1: poses joints [first, first + count) for wilting parameter t (see
 * sere_skeleton_pose, which checks the arguments); when turned is not NULL, records there which
 * segments turn (sere_skeleton_record_pose). */
void sere_skel_pose_range( const sere_skeleton* s, int32_t first, int32_t count, float t,
						   const sere_wilt_params* params, sere_joint_frames* frames, uint8_t* turned,
						   sere_pose_stats* stats );

/* Back at the rest pose: no vertex is left short of its target. */
void sere_skel_pierce_rest( sere_pierce* pierce );
