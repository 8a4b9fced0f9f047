/* sere — Skeleton problems, and the curves and plane geometry the leaf skeleton is built from. Seed 003: Lu, Zhao, Guo
 * 2009. */
#include "core/geometry.h"
#include "wilt/internal/skeleton_shared.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

/* Dense evaluation of each spline span before arc-length resampling: 32 chords per span keep
 * the resampled points within 0.1% of a span's length of the true curve. */
#define SPLINE_SAMPLES 32

const char* sere_skeleton_problem_text( sere_skeleton_problem problem )
{
	switch ( problem )
	{
		case SERE_SKELETON_OK:
			return "ok";
		case SERE_SKELETON_FEW_POINTS:
			return "too few points (a curve or vein needs at least 2)";
		case SERE_SKELETON_NONFINITE:
			return "NaN or infinity in a coordinate or parameter";
		case SERE_SKELETON_REPEATED_POINT:
			return "two consecutive points coincide";
		case SERE_SKELETON_ENDS_APART:
			return "the boundary curves and the midvein do not meet at the base and the tip";
		case SERE_SKELETON_SELF_INTERSECTING:
			return "the outline crosses or touches itself";
		case SERE_SKELETON_MIDVEIN_OUTSIDE:
			return "the midvein leaves the outline";
		case SERE_SKELETON_NO_VEINS:
			return "no veins (a venation skeleton needs at least the midvein)";
		case SERE_SKELETON_BAD_PARENT:
			return "bad parent vein (vein 0 is the midvein with parent -1; others name an earlier vein)";
		case SERE_SKELETON_BAD_SEGMENTS:
			return "segment count out of range (1 to 4096 per vein)";
		case SERE_SKELETON_DETACHED:
			return "a vein starts farther from its parent vein than its own length";
		case SERE_SKELETON_BAD_BEND:
			return "bend angle outside [0, 180] degrees";
		case SERE_SKELETON_BAD_SPACING:
			return "sampling interval not positive or too fine for the leaf";
		case SERE_SKELETON_PROBLEM_COUNT:
			break;
	}
	return "unknown problem";
}

/* ---------------------------------------------------------------------------------------------
 * Curves: centripetal Catmull–Rom through feature points, resampled by arc length (Sec. 4.1). */

/* Writes (n − 1) * SPLINE_SAMPLES + 1 points. Centripetal knots (square root of chord length)
 * never overshoot into cusps or loops between close feature points, which keeps a leaf outline
 * simple where uniform Catmull–Rom would not. */
static void spline_dense( const double* p, int32_t n, double* out )
{
	int32_t w = 0;
	for ( int32_t i = 0; i + 1 < n; ++i )
	{
		double p0[2], p3[2];
		const double* p1 = p + 2 * i;
		const double* p2 = p + 2 * i + 2;
		for ( int a = 0; a < 2; ++a )
		{
			p0[a] = i > 0 ? p[2 * i - 2 + a] : 2.0 * p1[a] - p2[a];
			p3[a] = i + 2 < n ? p[2 * i + 4 + a] : 2.0 * p2[a] - p1[a];
		}
		double t0 = 0.0;
		double t1 = t0 + sqrt( sere_skel_dist2d( p0, p1 ) );
		double t2 = t1 + sqrt( sere_skel_dist2d( p1, p2 ) );
		double t3 = t2 + sqrt( sere_skel_dist2d( p2, p3 ) );
		for ( int32_t k = 0; k < SPLINE_SAMPLES; ++k )
		{
			double t = t1 + ( t2 - t1 ) * k / SPLINE_SAMPLES;
			for ( int a = 0; a < 2; ++a )
			{
				double a1 = ( ( t1 - t ) * p0[a] + ( t - t0 ) * p1[a] ) / ( t1 - t0 );
				double a2 = ( ( t2 - t ) * p1[a] + ( t - t1 ) * p2[a] ) / ( t2 - t1 );
				double a3 = ( ( t3 - t ) * p2[a] + ( t - t2 ) * p3[a] ) / ( t3 - t2 );
				double b1 = ( ( t2 - t ) * a1 + ( t - t0 ) * a2 ) / ( t2 - t0 );
				double b2 = ( ( t3 - t ) * a2 + ( t - t1 ) * a3 ) / ( t3 - t1 );
				out[2 * w + a] = ( ( t2 - t ) * b1 + ( t - t1 ) * b2 ) / ( t2 - t1 );
			}
			++w;
		}
	}
	out[2 * w] = p[2 * n - 2];
	out[2 * w + 1] = p[2 * n - 1];
}

double sere_skel_polyline_length( const double* p, int32_t n )
{
	double length = 0.0;
	for ( int32_t i = 0; i + 1 < n; ++i )
	{
		length += sere_skel_dist2d( p + 2 * i, p + 2 * i + 2 );
	}
	return length;
}

/* `pieces` equal arc-length pieces: writes pieces + 1 points, the ends exactly. */
void sere_skel_resample( const double* p, int32_t n, int32_t pieces, double* out )
{
	double length = sere_skel_polyline_length( p, n );
	int32_t i = 0;
	double walked = 0.0; /* arc length at p[i] */
	out[0] = p[0];
	out[1] = p[1];
	for ( int32_t k = 1; k < pieces; ++k )
	{
		double target = length * k / pieces;
		while ( i + 2 < n && walked + sere_skel_dist2d( p + 2 * i, p + 2 * i + 2 ) < target )
		{
			walked += sere_skel_dist2d( p + 2 * i, p + 2 * i + 2 );
			++i;
		}
		double piece = sere_skel_dist2d( p + 2 * i, p + 2 * i + 2 );
		double f = piece > 0.0 ? ( target - walked ) / piece : 0.0;
		f = f < 0.0 ? 0.0 : ( f > 1.0 ? 1.0 : f );
		out[2 * k] = p[2 * i] + f * ( p[2 * i + 2] - p[2 * i] );
		out[2 * k + 1] = p[2 * i + 1] + f * ( p[2 * i + 3] - p[2 * i + 1] );
	}
	out[2 * pieces] = p[2 * n - 2];
	out[2 * pieces + 1] = p[2 * n - 1];
}

/* The spline through p resampled every `spacing` (at least min_pieces pieces); NULL on
 * allocation failure. */
double* sere_skel_curve_sample( const double* p, int32_t n, double spacing, int32_t min_pieces, int32_t* count )
{
	int32_t dense_count = ( n - 1 ) * SPLINE_SAMPLES + 1;
	double* dense = malloc( 2 * (size_t) dense_count * sizeof( double ) );
	if ( dense == NULL )
	{
		return NULL;
	}
	spline_dense( p, n, dense );
	double pieces = ceil( sere_skel_polyline_length( dense, dense_count ) / spacing - 1e-9 );
	int32_t m = pieces < min_pieces ? min_pieces : (int32_t) pieces;
	double* out = malloc( 2 * (size_t) ( m + 1 ) * sizeof( double ) );
	if ( out != NULL )
	{
		sere_skel_resample( dense, dense_count, m, out );
		*count = m + 1;
	}
	free( dense );
	return out;
}

/* ---------------------------------------------------------------------------------------------
 * Plane geometry. */

static double cross2( const double* o, const double* a, const double* b )
{
	return ( a[0] - o[0] ) * ( b[1] - o[1] ) - ( a[1] - o[1] ) * ( b[0] - o[0] );
}

/* Closed segments ab and cd share a point (touching counts). */
int sere_skel_segments_meet( const double* a, const double* b, const double* c, const double* d )
{
	double d1 = cross2( a, b, c ), d2 = cross2( a, b, d );
	double d3 = cross2( c, d, a ), d4 = cross2( c, d, b );
	if ( ( ( d1 > 0 && d2 < 0 ) || ( d1 < 0 && d2 > 0 ) ) && ( ( d3 > 0 && d4 < 0 ) || ( d3 < 0 && d4 > 0 ) ) )
	{
		return 1;
	}
	/* Collinear touching: a zero orientation with the point inside the other segment's box. */
	const double* s[4][3] = { { a, b, c }, { a, b, d }, { c, d, a }, { c, d, b } };
	double o[4] = { d1, d2, d3, d4 };
	for ( int k = 0; k < 4; ++k )
	{
		const double *p = s[k][0], *q = s[k][1], *r = s[k][2];
		if ( o[k] == 0.0 && r[0] >= fmin( p[0], q[0] ) && r[0] <= fmax( p[0], q[0] ) && r[1] >= fmin( p[1], q[1] ) &&
			 r[1] <= fmax( p[1], q[1] ) )
		{
			return 1;
		}
	}
	return 0;
}

/* Distance from p to a polyline (closed: the last point joins the first). */
double sere_skel_polyline_distance( const double* p, const double* poly, int32_t n, int closed )
{
	double best = INFINITY;
	int32_t segments = closed ? n : n - 1;
	for ( int32_t i = 0; i < segments; ++i )
	{
		double d = sere_point_segment_distance( p, poly + 2 * i, poly + 2 * ( ( i + 1 ) % n ) );
		best = d < best ? d : best;
	}
	return best;
}
