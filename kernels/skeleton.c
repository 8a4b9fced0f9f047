#include "skeleton.h"

#include "triangulate.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* Dense evaluation of each spline span before arc-length resampling: 32 chords per span keep
 * the resampled points within 0.1% of a span's length of the true curve. */
#define SPLINE_SAMPLES 32

/* At most this many points on any sampled curve or in the blade: spacing too fine for the leaf
 * is an input error, not an allocation failure. */
#define MAX_CURVE_POINTS 1000000

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

static sere_status report( sere_skeleton_check* check, sere_skeleton_problem problem, int32_t vein, int32_t point )
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

/* ---------------------------------------------------------------------------------------------
 * Curves: centripetal Catmull–Rom through feature points, resampled by arc length (Sec. 4.1). */

static double dist2d( const double* a, const double* b )
{
	return hypot( a[0] - b[0], a[1] - b[1] );
}

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
		double t1 = t0 + sqrt( dist2d( p0, p1 ) );
		double t2 = t1 + sqrt( dist2d( p1, p2 ) );
		double t3 = t2 + sqrt( dist2d( p2, p3 ) );
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

static double polyline_length( const double* p, int32_t n )
{
	double length = 0.0;
	for ( int32_t i = 0; i + 1 < n; ++i )
	{
		length += dist2d( p + 2 * i, p + 2 * i + 2 );
	}
	return length;
}

/* `pieces` equal arc-length pieces: writes pieces + 1 points, the ends exactly. */
static void resample( const double* p, int32_t n, int32_t pieces, double* out )
{
	double length = polyline_length( p, n );
	int32_t i = 0;
	double walked = 0.0; /* arc length at p[i] */
	out[0] = p[0];
	out[1] = p[1];
	for ( int32_t k = 1; k < pieces; ++k )
	{
		double target = length * k / pieces;
		while ( i + 2 < n && walked + dist2d( p + 2 * i, p + 2 * i + 2 ) < target )
		{
			walked += dist2d( p + 2 * i, p + 2 * i + 2 );
			++i;
		}
		double piece = dist2d( p + 2 * i, p + 2 * i + 2 );
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
static double* curve_sample( const double* p, int32_t n, double spacing, int32_t min_pieces, int32_t* count )
{
	int32_t dense_count = ( n - 1 ) * SPLINE_SAMPLES + 1;
	double* dense = malloc( 2 * (size_t) dense_count * sizeof( double ) );
	if ( dense == NULL )
	{
		return NULL;
	}
	spline_dense( p, n, dense );
	double pieces = ceil( polyline_length( dense, dense_count ) / spacing - 1e-9 );
	int32_t m = pieces < min_pieces ? min_pieces : (int32_t) pieces;
	double* out = malloc( 2 * (size_t) ( m + 1 ) * sizeof( double ) );
	if ( out != NULL )
	{
		resample( dense, dense_count, m, out );
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
static int segments_meet( const double* a, const double* b, const double* c, const double* d )
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

static double point_segment_distance( const double* p, const double* a, const double* b )
{
	double ex = b[0] - a[0], ey = b[1] - a[1];
	double l2 = ex * ex + ey * ey;
	double f = l2 > 0.0 ? ( ( p[0] - a[0] ) * ex + ( p[1] - a[1] ) * ey ) / l2 : 0.0;
	f = f < 0.0 ? 0.0 : ( f > 1.0 ? 1.0 : f );
	return hypot( p[0] - a[0] - f * ex, p[1] - a[1] - f * ey );
}

/* Distance from p to a polyline (closed: the last point joins the first). */
static double polyline_distance( const double* p, const double* poly, int32_t n, int closed )
{
	double best = INFINITY;
	int32_t segments = closed ? n : n - 1;
	for ( int32_t i = 0; i < segments; ++i )
	{
		double d = point_segment_distance( p, poly + 2 * i, poly + 2 * ( ( i + 1 ) % n ) );
		best = d < best ? d : best;
	}
	return best;
}

/* Crossing number; points on the outline may go either way, callers keep away from it. */
static int inside_polygon( const double* p, const double* poly, int32_t n )
{
	int inside = 0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		const double* a = poly + 2 * i;
		const double* b = poly + 2 * j;
		if ( ( a[1] > p[1] ) != ( b[1] > p[1] ) && p[0] < ( b[0] - a[0] ) * ( p[1] - a[1] ) / ( b[1] - a[1] ) + a[0] )
		{
			inside = !inside;
		}
	}
	return inside;
}

static double polygon_area( const double* poly, int32_t n )
{
	double twice = 0.0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		twice += poly[2 * j] * poly[2 * i + 1] - poly[2 * i] * poly[2 * j + 1];
	}
	return 0.5 * twice;
}

/* ---------------------------------------------------------------------------------------------
 * Leaf skeleton (Sec. 4.1). */

sere_status sere_leaf_skeleton_parametric( double length, double width, int32_t feature_count, double* left_xy,
										   double* right_xy, double* mid_xy )
{
	if ( !isfinite( length ) || !isfinite( width ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( length <= 0.0 || width <= 0.0 || feature_count < 3 || feature_count > MAX_CURVE_POINTS || left_xy == NULL ||
		 right_xy == NULL || mid_xy == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* Half-width sqrt(ξ)(1 − ξ), scaled to 1 at its maximum ξ = 1/3: a vertical tangent at the
	 * base (rounded) and a straight approach to the tip (pointed), the ovate blade of Fig. 2. */
	double peak = sqrt( 1.0 / 3.0 ) * ( 2.0 / 3.0 );
	for ( int32_t i = 0; i < feature_count; ++i )
	{
		double xi = (double) i / ( feature_count - 1 );
		double half = 0.5 * width * sqrt( xi ) * ( 1.0 - xi ) / peak;
		mid_xy[2 * i] = left_xy[2 * i] = right_xy[2 * i] = length * xi;
		mid_xy[2 * i + 1] = 0.0;
		left_xy[2 * i + 1] = half;
		right_xy[2 * i + 1] = -half;
	}
	return SERE_OK;
}

/* The sampled leaf: outline counter-clockwise from the base (index 0) through the tip, and the
 * midvein from base to tip sharing those two points exactly. */
typedef struct leaf_curves
{
	double* outline;
	int32_t outline_count;
	int32_t tip;
	double* mid;
	int32_t mid_count;
	double size;
} leaf_curves;

static void leaf_curves_free( leaf_curves* c )
{
	free( c->outline );
	free( c->mid );
	memset( c, 0, sizeof( *c ) );
}

static sere_skeleton_problem check_curve( const double* p, int32_t n, int32_t* point )
{
	if ( p == NULL || n < 2 )
	{
		*point = -1;
		return SERE_SKELETON_FEW_POINTS;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		*point = i;
		if ( !isfinite( p[2 * i] ) || !isfinite( p[2 * i + 1] ) )
		{
			return SERE_SKELETON_NONFINITE;
		}
		if ( i > 0 && p[2 * i] == p[2 * i - 2] && p[2 * i + 1] == p[2 * i - 1] )
		{
			return SERE_SKELETON_REPEATED_POINT;
		}
	}
	*point = -1;
	return SERE_SKELETON_OK;
}

static sere_status leaf_curves_build( const sere_leaf_skeleton* leaf, double spacing, leaf_curves* c,
									  sere_skeleton_check* check )
{
	memset( c, 0, sizeof( *c ) );
	if ( leaf == NULL )
	{
		return report( check, SERE_SKELETON_FEW_POINTS, -1, -1 );
	}
	const double* curves[3] = { leaf->left_xy, leaf->right_xy, leaf->mid_xy };
	int32_t counts[3] = { leaf->left_count, leaf->right_count, leaf->mid_count };
	for ( int k = 0; k < 3; ++k )
	{
		int32_t point;
		sere_skeleton_problem problem = check_curve( curves[k], counts[k], &point );
		if ( problem == SERE_SKELETON_OK && counts[k] > MAX_CURVE_POINTS )
		{
			problem = SERE_SKELETON_FEW_POINTS;
		}
		if ( problem != SERE_SKELETON_OK )
		{
			return report( check, problem, k, point );
		}
	}
	if ( !isfinite( spacing ) )
	{
		return report( check, SERE_SKELETON_NONFINITE, -1, -1 );
	}
	double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
	for ( int k = 0; k < 3; ++k )
	{
		for ( int32_t i = 0; i < counts[k]; ++i )
		{
			for ( int a = 0; a < 2; ++a )
			{
				lo[a] = fmin( lo[a], curves[k][2 * i + a] );
				hi[a] = fmax( hi[a], curves[k][2 * i + a] );
			}
		}
	}
	c->size = hypot( hi[0] - lo[0], hi[1] - lo[1] );
	if ( !( spacing > 0.0 ) || c->size / spacing > 0.25 * MAX_CURVE_POINTS || c->size == 0.0 )
	{
		return report( check, SERE_SKELETON_BAD_SPACING, -1, -1 );
	}

	/* The three curves meet at the base and at the tip; small gaps (digitizing noise) are closed
	 * by moving the ends onto the left curve's. */
	const double* base = leaf->left_xy;
	const double* tip = leaf->left_xy + 2 * ( leaf->left_count - 1 );
	double tolerance = 0.01 * c->size;
	for ( int k = 1; k < 3; ++k )
	{
		if ( dist2d( curves[k], base ) > tolerance )
		{
			return report( check, SERE_SKELETON_ENDS_APART, k, 0 );
		}
		if ( dist2d( curves[k] + 2 * ( counts[k] - 1 ), tip ) > tolerance )
		{
			return report( check, SERE_SKELETON_ENDS_APART, k, counts[k] - 1 );
		}
	}
	if ( dist2d( base, tip ) <= tolerance )
	{
		return report( check, SERE_SKELETON_ENDS_APART, 0, counts[0] - 1 );
	}
	double* sampled[3] = { NULL, NULL, NULL };
	int32_t sampled_count[3] = { 0, 0, 0 };
	for ( int k = 0; k < 3; ++k )
	{
		double* copy = malloc( 2 * (size_t) counts[k] * sizeof( double ) );
		if ( copy == NULL )
		{
			free( sampled[0] );
			free( sampled[1] );
			return SERE_ERR_MEMORY;
		}
		memcpy( copy, curves[k], 2 * (size_t) counts[k] * sizeof( double ) );
		copy[0] = base[0];
		copy[1] = base[1];
		copy[2 * counts[k] - 2] = tip[0];
		copy[2 * counts[k] - 1] = tip[1];
		int32_t point;
		if ( check_curve( copy, counts[k], &point ) != SERE_SKELETON_OK )
		{
			free( copy );
			free( sampled[0] );
			free( sampled[1] );
			return report( check, SERE_SKELETON_REPEATED_POINT, k, point );
		}
		sampled[k] = curve_sample( copy, counts[k], spacing, 2, &sampled_count[k] );
		free( copy );
		if ( sampled[k] == NULL )
		{
			free( sampled[0] );
			free( sampled[1] );
			return SERE_ERR_MEMORY;
		}
	}

	/* Outline: one boundary base → tip, the other tip → base without repeating the ends. */
	int32_t nl = sampled_count[0], nr = sampled_count[1];
	int32_t n = nl + nr - 2;
	c->outline = malloc( 2 * (size_t) n * sizeof( double ) );
	c->mid = sampled[2];
	c->mid_count = sampled_count[2];
	if ( c->outline == NULL )
	{
		free( sampled[0] );
		free( sampled[1] );
		leaf_curves_free( c );
		return SERE_ERR_MEMORY;
	}
	memcpy( c->outline, sampled[1], 2 * (size_t) nr * sizeof( double ) );
	for ( int32_t i = nl - 2; i >= 1; --i )
	{
		c->outline[2 * ( nr + nl - 2 - i )] = sampled[0][2 * i];
		c->outline[2 * ( nr + nl - 2 - i ) + 1] = sampled[0][2 * i + 1];
	}
	c->outline_count = n;
	c->tip = nr - 1;
	free( sampled[0] );
	free( sampled[1] );
	if ( polygon_area( c->outline, n ) < 0.0 )
	{
		/* Clockwise: reverse all but the base so the base stays first. */
		for ( int32_t i = 1, j = n - 1; i < j; ++i, --j )
		{
			double tx = c->outline[2 * i], ty = c->outline[2 * i + 1];
			c->outline[2 * i] = c->outline[2 * j];
			c->outline[2 * i + 1] = c->outline[2 * j + 1];
			c->outline[2 * j] = tx;
			c->outline[2 * j + 1] = ty;
		}
		c->tip = n - c->tip;
	}

	/* Simple outline: no two non-adjacent edges meet, and it encloses an area. */
	if ( !( fabs( polygon_area( c->outline, n ) ) > 1e-12 * c->size * c->size ) )
	{
		leaf_curves_free( c );
		return report( check, SERE_SKELETON_SELF_INTERSECTING, -1, -1 );
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t j = i + 2; j < n; ++j )
		{
			if ( i == 0 && j == n - 1 )
			{
				continue;
			}
			if ( segments_meet( c->outline + 2 * i, c->outline + 2 * ( i + 1 ), c->outline + 2 * j,
								c->outline + 2 * ( ( j + 1 ) % n ) ) )
			{
				leaf_curves_free( c );
				return report( check, SERE_SKELETON_SELF_INTERSECTING, -1, -1 );
			}
		}
	}
	/* The midvein runs inside: its interior points are inside the outline and no midvein segment
	 * meets an outline edge away from the base and the tip. */
	for ( int32_t i = 1; i + 1 < c->mid_count; ++i )
	{
		const double* p = c->mid + 2 * i;
		if ( !inside_polygon( p, c->outline, n ) )
		{
			leaf_curves_free( c );
			return report( check, SERE_SKELETON_MIDVEIN_OUTSIDE, 2, -1 );
		}
	}
	for ( int32_t i = 0; i + 1 < c->mid_count; ++i )
	{
		for ( int32_t j = 0; j < n; ++j )
		{
			int32_t j1 = ( j + 1 ) % n;
			int touches_base = i == 0 && ( j == 0 || j1 == 0 );
			int touches_tip = i + 2 == c->mid_count && ( j == c->tip || j1 == c->tip );
			if ( touches_base || touches_tip )
			{
				continue;
			}
			if ( segments_meet( c->mid + 2 * i, c->mid + 2 * i + 2, c->outline + 2 * j, c->outline + 2 * j1 ) )
			{
				leaf_curves_free( c );
				return report( check, SERE_SKELETON_MIDVEIN_OUTSIDE, 2, -1 );
			}
		}
	}
	return report( check, SERE_SKELETON_OK, -1, -1 );
}

sere_status sere_leaf_skeleton_validate( const sere_leaf_skeleton* leaf, double spacing, sere_skeleton_check* check )
{
	leaf_curves c;
	sere_status status = leaf_curves_build( leaf, spacing, &c, check );
	if ( status == SERE_OK )
	{
		leaf_curves_free( &c );
	}
	return status;
}

sere_status sere_blade_create( const sere_leaf_skeleton* leaf, double spacing, sere_tri_mesh* mesh,
							   sere_skeleton_check* check )
{
	memset( mesh, 0, sizeof( *mesh ) );
	leaf_curves c;
	sere_status status = leaf_curves_build( leaf, spacing, &c, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t b = c.outline_count;
	int32_t inner_mid = c.mid_count - 2;
	double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
	for ( int32_t i = 0; i < b; ++i )
	{
		for ( int a = 0; a < 2; ++a )
		{
			lo[a] = fmin( lo[a], c.outline[2 * i + a] );
			hi[a] = fmax( hi[a], c.outline[2 * i + a] );
		}
	}
	/* Hexagonal lattice rows; the count bound below keeps the allocation honest. */
	double row = spacing * sqrt( 3.0 ) / 2.0;
	double columns = floor( ( hi[0] - lo[0] ) / spacing ) + 2.0;
	double rows = floor( ( hi[1] - lo[1] ) / row ) + 2.0;
	if ( columns * rows + b + c.mid_count > MAX_CURVE_POINTS )
	{
		leaf_curves_free( &c );
		return report( check, SERE_SKELETON_BAD_SPACING, -1, -1 );
	}
	int32_t capacity = (int32_t) ( columns * rows ) + b + c.mid_count;
	double* x = malloc( (size_t) capacity * sizeof( double ) );
	double* y = malloc( (size_t) capacity * sizeof( double ) );
	int32_t* segments = malloc( 2 * (size_t) c.mid_count * sizeof( int32_t ) );
	if ( x == NULL || y == NULL || segments == NULL )
	{
		free( x );
		free( y );
		free( segments );
		leaf_curves_free( &c );
		return SERE_ERR_MEMORY;
	}
	int32_t count = 0;
	for ( int32_t i = 0; i < b; ++i )
	{
		x[count] = c.outline[2 * i];
		y[count++] = c.outline[2 * i + 1];
	}
	for ( int32_t i = 1; i + 1 < c.mid_count; ++i )
	{
		x[count] = c.mid[2 * i];
		y[count++] = c.mid[2 * i + 1];
	}
	for ( int32_t j = 0; j < (int32_t) rows; ++j )
	{
		for ( int32_t i = 0; i < (int32_t) columns; ++i )
		{
			double p[2] = { lo[0] + ( i + ( ( j & 1 ) ? 0.5 : 0.0 ) ) * spacing, lo[1] + ( j + 0.5 ) * row };
			if ( inside_polygon( p, c.outline, b ) && polyline_distance( p, c.outline, b, 1 ) >= 0.5 * spacing &&
				 polyline_distance( p, c.mid, c.mid_count, 0 ) >= 0.5 * spacing )
			{
				x[count] = p[0];
				y[count++] = p[1];
			}
		}
	}
	/* The midvein is a chain of constrained edges from the base (point 0) to the tip. */
	int32_t segment_count = 0;
	int32_t previous = 0;
	for ( int32_t i = 0; i < inner_mid; ++i )
	{
		segments[2 * segment_count] = previous;
		segments[2 * segment_count++ + 1] = b + i;
		previous = b + i;
	}
	segments[2 * segment_count] = previous;
	segments[2 * segment_count++ + 1] = c.tip;

	sere_cdt_input input = { x, y, count, b, segments, segment_count };
	sere_triangulation triangulation = { 0 };
	status = sere_triangulate( &input, &triangulation );
	if ( status == SERE_OK && triangulation.merged_count != 0 )
	{
		status = SERE_ERR_GEOMETRY;
	}
	if ( status == SERE_OK )
	{
		status = sere_tri_mesh_alloc( mesh, count, triangulation.triangle_count );
	}
	if ( status == SERE_OK )
	{
		for ( int32_t i = 0; i < count; ++i )
		{
			mesh->x[i] = (float) x[i];
			mesh->y[i] = (float) y[i];
			mesh->u[i] = (float) ( ( x[i] - lo[0] ) / ( hi[0] - lo[0] ) );
			mesh->v[i] = (float) ( ( y[i] - lo[1] ) / ( hi[1] - lo[1] ) );
		}
		memcpy( mesh->tri, triangulation.tri, 3 * (size_t) triangulation.triangle_count * sizeof( int32_t ) );
	}
	sere_triangulation_destroy( &triangulation );
	free( x );
	free( y );
	free( segments );
	leaf_curves_free( &c );
	return status;
}

/* ---------------------------------------------------------------------------------------------
 * Venation skeleton (Sec. 4.2). */

void sere_skeleton_destroy( sere_skeleton* skeleton )
{
	sere_free( skeleton->x );
	sere_free( skeleton->y );
	sere_free( skeleton->z );
	sere_free( skeleton->parent );
	sere_free( skeleton->end );
	sere_free( skeleton->vein );
	sere_free( skeleton->bend );
	sere_free( skeleton->delay );
	memset( skeleton, 0, sizeof( *skeleton ) );
}

static sere_status skeleton_alloc( sere_skeleton* s, int32_t joint_count )
{
	memset( s, 0, sizeof( *s ) );
	size_t n = (size_t) sere_pad( joint_count > 0 ? joint_count : 1 );
	s->x = sere_alloc( n * sizeof( float ) );
	s->y = sere_alloc( n * sizeof( float ) );
	s->z = sere_alloc( n * sizeof( float ) );
	s->parent = sere_alloc( n * sizeof( int32_t ) );
	s->end = sere_alloc( n * sizeof( int32_t ) );
	s->vein = sere_alloc( n * sizeof( int32_t ) );
	s->bend = sere_alloc( n * sizeof( float ) );
	s->delay = sere_alloc( n * sizeof( float ) );
	if ( s->x == NULL || s->y == NULL || s->z == NULL || s->parent == NULL || s->end == NULL || s->vein == NULL ||
		 s->bend == NULL || s->delay == NULL )
	{
		sere_skeleton_destroy( s );
		return SERE_ERR_MEMORY;
	}
	s->joint_count = joint_count;
	return SERE_OK;
}

/* Joints as the veins list them, before the depth-first reordering. */
typedef struct raw_joints
{
	double* xy;
	int32_t* parent;
	int32_t* vein;
	float* bend;
} raw_joints;

static void raw_joints_free( raw_joints* r )
{
	free( r->xy );
	free( r->parent );
	free( r->vein );
	free( r->bend );
}

/* Depth-first preorder (children in their listed order) makes every subtree a contiguous range,
 * which the droop limit of sere_skeleton_pose walks. delay is 1 − (path length from the root) /
 * (longest such path): the seed rotates "from the boundary to root" (Sec. 7). */
static sere_status skeleton_order( const raw_joints* r, int32_t n, int32_t vein_count, sere_skeleton* out )
{
	int32_t* first_child = malloc( (size_t) ( n + 1 ) * sizeof( int32_t ) );
	int32_t* children = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* stack = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* new_index = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* old_index = malloc( (size_t) n * sizeof( int32_t ) );
	double* path = malloc( (size_t) n * sizeof( double ) );
	sere_status status = SERE_ERR_MEMORY;
	if ( first_child == NULL || children == NULL || stack == NULL || new_index == NULL || old_index == NULL ||
		 path == NULL )
	{
		goto done;
	}
	memset( first_child, 0, (size_t) ( n + 1 ) * sizeof( int32_t ) );
	for ( int32_t i = 1; i < n; ++i )
	{
		++first_child[r->parent[i] + 1];
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		first_child[i + 1] += first_child[i];
	}
	int32_t* fill = stack; /* reused as fill cursors before the traversal */
	memcpy( fill, first_child, (size_t) n * sizeof( int32_t ) );
	for ( int32_t i = 1; i < n; ++i )
	{
		children[fill[r->parent[i]]++] = i;
	}
	int32_t size = 0, next = 0;
	stack[size++] = 0;
	while ( size > 0 )
	{
		int32_t i = stack[--size];
		new_index[i] = next;
		old_index[next++] = i;
		for ( int32_t k = first_child[i + 1] - 1; k >= first_child[i]; --k )
		{
			stack[size++] = children[k];
		}
	}
	status = skeleton_alloc( out, n );
	if ( status != SERE_OK )
	{
		goto done;
	}
	out->vein_count = vein_count;
	double longest = 0.0;
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = old_index[k];
		out->x[k] = (float) r->xy[2 * i];
		out->y[k] = (float) r->xy[2 * i + 1];
		out->z[k] = 0.0f;
		out->parent[k] = i == 0 ? -1 : new_index[r->parent[i]];
		out->vein[k] = r->vein[i];
		out->bend[k] = r->bend[i];
		out->end[k] = k + 1;
		path[k] = i == 0 ? 0.0 : path[out->parent[k]] + dist2d( r->xy + 2 * i, r->xy + 2 * r->parent[i] );
		longest = path[k] > longest ? path[k] : longest;
	}
	for ( int32_t k = n - 1; k > 0; --k )
	{
		int32_t p = out->parent[k];
		out->end[p] = out->end[k] > out->end[p] ? out->end[k] : out->end[p];
	}
	for ( int32_t k = 0; k < n; ++k )
	{
		out->delay[k] = longest > 0.0 ? (float) ( 1.0 - path[k] / longest ) : 0.0f;
	}
done:
	free( first_child );
	free( children );
	free( stack );
	free( new_index );
	free( old_index );
	free( path );
	return status;
}

sere_status sere_skeleton_build( const sere_vein_spec* veins, int32_t vein_count, sere_skeleton* skeleton,
								 sere_skeleton_check* check )
{
	memset( skeleton, 0, sizeof( *skeleton ) );
	if ( veins == NULL || vein_count < 1 )
	{
		return report( check, SERE_SKELETON_NO_VEINS, -1, -1 );
	}
	int64_t joint_count = 1;
	int32_t longest_polyline = 0;
	for ( int32_t k = 0; k < vein_count; ++k )
	{
		const sere_vein_spec* v = veins + k;
		if ( k == 0 ? v->parent != -1 : ( v->parent < 0 || v->parent >= k ) )
		{
			return report( check, SERE_SKELETON_BAD_PARENT, k, -1 );
		}
		if ( v->segments < 1 || v->segments > SERE_MAX_SEGMENTS )
		{
			return report( check, SERE_SKELETON_BAD_SEGMENTS, k, -1 );
		}
		if ( !isfinite( v->bend ) )
		{
			return report( check, SERE_SKELETON_NONFINITE, k, -1 );
		}
		if ( v->bend < 0.0f || v->bend > (float) PI )
		{
			return report( check, SERE_SKELETON_BAD_BEND, k, -1 );
		}
		int32_t point;
		sere_skeleton_problem problem = check_curve( v->xy, v->point_count, &point );
		if ( problem == SERE_SKELETON_OK && v->point_count > MAX_CURVE_POINTS )
		{
			problem = SERE_SKELETON_FEW_POINTS;
		}
		if ( problem != SERE_SKELETON_OK )
		{
			return report( check, problem, k, point );
		}
		joint_count += v->segments;
		longest_polyline = v->point_count > longest_polyline ? v->point_count : longest_polyline;
	}
	if ( joint_count > ( 1 << 24 ) )
	{
		return report( check, SERE_SKELETON_BAD_SEGMENTS, -1, -1 );
	}
	int32_t n = (int32_t) joint_count;
	raw_joints r;
	r.xy = malloc( 2 * (size_t) n * sizeof( double ) );
	r.parent = malloc( (size_t) n * sizeof( int32_t ) );
	r.vein = malloc( (size_t) n * sizeof( int32_t ) );
	r.bend = malloc( (size_t) n * sizeof( float ) );
	int32_t* attach = malloc( (size_t) vein_count * sizeof( int32_t ) );
	int32_t* first = malloc( (size_t) vein_count * sizeof( int32_t ) );
	double* polyline = malloc( 2 * (size_t) longest_polyline * sizeof( double ) );
	double* cut = malloc( 2 * (size_t) ( SERE_MAX_SEGMENTS + 1 ) * sizeof( double ) );
	sere_status status = SERE_ERR_MEMORY;
	if ( r.xy == NULL || r.parent == NULL || r.vein == NULL || r.bend == NULL || attach == NULL || first == NULL ||
		 polyline == NULL || cut == NULL )
	{
		goto done;
	}
	r.xy[0] = veins[0].xy[0];
	r.xy[1] = veins[0].xy[1];
	r.parent[0] = -1;
	r.vein[0] = 0;
	r.bend[0] = 0.0f;
	int32_t count = 1;
	for ( int32_t k = 0; k < vein_count; ++k )
	{
		const sere_vein_spec* v = veins + k;
		/* The joint the vein hangs from: the root for the midvein, else the nearest joint of the
		 * parent vein (its own joints or the joint it hangs from), the lower index on ties. */
		int32_t a = 0;
		if ( k > 0 )
		{
			int32_t p = v->parent;
			a = attach[p];
			double best = dist2d( r.xy + 2 * a, v->xy );
			for ( int32_t j = first[p]; j < first[p] + veins[p].segments; ++j )
			{
				double d = dist2d( r.xy + 2 * j, v->xy );
				if ( d < best )
				{
					best = d;
					a = j;
				}
			}
			if ( best > polyline_length( v->xy, v->point_count ) )
			{
				status = report( check, SERE_SKELETON_DETACHED, k, 0 );
				goto done;
			}
		}
		attach[k] = a;
		first[k] = count;
		/* The start moves onto the attachment joint, so the vein leaves its parent there without
		 * doubling back to where the user clicked. */
		memcpy( polyline, v->xy, 2 * (size_t) v->point_count * sizeof( double ) );
		polyline[0] = r.xy[2 * a];
		polyline[1] = r.xy[2 * a + 1];
		if ( polyline_length( polyline, v->point_count ) == 0.0 )
		{
			status = report( check, SERE_SKELETON_REPEATED_POINT, k, 1 );
			goto done;
		}
		resample( polyline, v->point_count, v->segments, cut );
		for ( int32_t s = 1; s <= v->segments; ++s )
		{
			r.xy[2 * count] = cut[2 * s];
			r.xy[2 * count + 1] = cut[2 * s + 1];
			r.parent[count] = s == 1 ? a : count - 1;
			r.vein[count] = k;
			r.bend[count] = v->bend / (float) v->segments;
			++count;
		}
	}
	status = skeleton_order( &r, n, vein_count, skeleton );
	if ( status == SERE_OK )
	{
		report( check, SERE_SKELETON_OK, -1, -1 );
	}
done:
	raw_joints_free( &r );
	free( attach );
	free( first );
	free( polyline );
	free( cut );
	return status;
}

sere_venation_params sere_venation_params_default( void )
{
	sere_venation_params p;
	p.mid_segments = 20;
	p.secondary_count = 8;
	p.secondary_segments = 8;
	p.angle = (float) ( 45.0 * PI / 180.0 );
	p.mid_bend = (float) ( 80.0 * PI / 180.0 );
	p.secondary_bend = (float) ( 50.0 * PI / 180.0 );
	p.start = 0.1f;
	p.stop = 0.6f;
	return p;
}

/* First positive ray parameter at which o + λ d meets the closed polygon, or INFINITY. */
static double ray_polygon( const double* o, const double* d, const double* poly, int32_t n )
{
	double best = INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		const double* a = poly + 2 * i;
		const double* b = poly + 2 * ( ( i + 1 ) % n );
		double ex = b[0] - a[0], ey = b[1] - a[1];
		double den = d[0] * ey - d[1] * ex;
		if ( den == 0.0 )
		{
			continue;
		}
		double wx = a[0] - o[0], wy = a[1] - o[1];
		double lambda = ( wx * ey - wy * ex ) / den;
		double mu = ( wx * d[1] - wy * d[0] ) / den;
		if ( lambda > 0.0 && mu >= 0.0 && mu <= 1.0 && lambda < best )
		{
			best = lambda;
		}
	}
	return best;
}

sere_status sere_venation_generate( const sere_leaf_skeleton* leaf, const sere_venation_params* params,
									sere_skeleton* skeleton, sere_skeleton_check* check )
{
	memset( skeleton, 0, sizeof( *skeleton ) );
	if ( params == NULL || leaf == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !isfinite( params->angle ) || !isfinite( params->mid_bend ) || !isfinite( params->secondary_bend ) ||
		 !isfinite( params->start ) || !isfinite( params->stop ) )
	{
		return report( check, SERE_SKELETON_NONFINITE, -1, -1 );
	}
	if ( params->secondary_count < 0 || params->secondary_count > 1024 || !( params->angle > 0.0f ) ||
		 !( params->angle < (float) PI ) || params->start < 0.0f || params->stop > 1.0f ||
		 params->start > params->stop )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( leaf->mid_xy == NULL || leaf->mid_count < 2 || !isfinite( leaf->mid_xy[0] ) || !isfinite( leaf->mid_xy[1] ) ||
		 !isfinite( leaf->mid_xy[2 * leaf->mid_count - 2] ) || !isfinite( leaf->mid_xy[2 * leaf->mid_count - 1] ) )
	{
		return report( check,
					   leaf->mid_xy == NULL || leaf->mid_count < 2 ? SERE_SKELETON_FEW_POINTS : SERE_SKELETON_NONFINITE,
					   2, -1 );
	}
	/* Fine sampling (a 200th of the base–tip distance) so generated veins follow the curves. */
	double chord = dist2d( leaf->mid_xy, leaf->mid_xy + 2 * ( leaf->mid_count - 1 ) );
	leaf_curves c;
	sere_status status = leaf_curves_build( leaf, chord > 0.0 ? chord / 200.0 : 1.0, &c, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t count = 1 + params->secondary_count;
	sere_vein_spec* specs = calloc( (size_t) count, sizeof( sere_vein_spec ) );
	double* ends = malloc( 4 * (size_t) count * sizeof( double ) );
	if ( specs == NULL || ends == NULL )
	{
		free( specs );
		free( ends );
		leaf_curves_free( &c );
		return SERE_ERR_MEMORY;
	}
	specs[0] = ( sere_vein_spec ){ -1, params->mid_segments, params->mid_bend, c.mid_count, c.mid };
	double length = polyline_length( c.mid, c.mid_count );
	int32_t pairs = ( params->secondary_count + 1 ) / 2;
	for ( int32_t j = 0; j < params->secondary_count; ++j )
	{
		/* Right (−) then left (+), pair by pair from the base toward the tip. */
		double side = ( j % 2 == 0 ) ? -1.0 : 1.0;
		/* Each starts at a joint of the midvein (its segments are equal in arc length), so the
		 * vein leaves the midvein without a kink. */
		double f = params->start + ( params->stop - params->start ) * ( j / 2 + 0.5 ) / pairs;
		double joint = round( f * params->mid_segments );
		joint = joint < 1.0 ? 1.0 : ( joint > params->mid_segments - 1 ? params->mid_segments - 1 : joint );
		double target = params->mid_segments > 1 ? joint / params->mid_segments * length : f * length;
		double walked = 0.0;
		int32_t i = 0;
		while ( i + 2 < c.mid_count && walked + dist2d( c.mid + 2 * i, c.mid + 2 * i + 2 ) < target )
		{
			walked += dist2d( c.mid + 2 * i, c.mid + 2 * i + 2 );
			++i;
		}
		const double* a = c.mid + 2 * i;
		const double* b = a + 2;
		double piece = dist2d( a, b );
		double g = ( target - walked ) / piece;
		g = g < 0.0 ? 0.0 : ( g > 1.0 ? 1.0 : g );
		double* s = ends + 4 * j;
		s[0] = a[0] + g * ( b[0] - a[0] );
		s[1] = a[1] + g * ( b[1] - a[1] );
		double tx = ( b[0] - a[0] ) / piece, ty = ( b[1] - a[1] ) / piece;
		double ca = cos( params->angle ), sa = side * sin( params->angle );
		double d[2] = { ca * tx - sa * ty, sa * tx + ca * ty };
		double lambda = ray_polygon( s, d, c.outline, c.outline_count );
		if ( !isfinite( lambda ) )
		{
			free( specs );
			free( ends );
			leaf_curves_free( &c );
			return report( check, SERE_SKELETON_MIDVEIN_OUTSIDE, 2, -1 );
		}
		s[2] = s[0] + 0.9 * lambda * d[0];
		s[3] = s[1] + 0.9 * lambda * d[1];
		specs[1 + j] = ( sere_vein_spec ){ 0, params->secondary_segments, params->secondary_bend, 2, s };
	}
	status = sere_skeleton_build( specs, count, skeleton, check );
	free( specs );
	free( ends );
	leaf_curves_free( &c );
	return status;
}

/* ---------------------------------------------------------------------------------------------
 * Banding (Sec. 5.2): a uniform grid over the joints, searched ring by ring. */

struct sere_joint_grid
{
	int32_t count;
	int32_t dim[3];
	float lo[3];
	float inv_h;
	double h;
	double slack;	  /* rounding allowance of the cell bounds */
	int32_t* start;	  /* cell c holds items [start[c], start[c + 1]) */
	int32_t* items;	  /* joint indices, ascending within a cell */
	float *x, *y, *z; /* joint positions in item order, so a cell is read contiguously */
	/* Per cell, every joint that can be nearest to a point inside it (ascending, with its
	 * position); an empty list sends the query to the ring search. */
	int32_t* candidate_start;
	int32_t* candidate;
	float *cx, *cy, *cz;
};

/* A cell keeps a candidate list only up to this length; cells far from every joint (where the
 * list would be long) use the ring search instead. */
#define GRID_CANDIDATES 48

static int32_t cell_of( float p, float lo, float inv_h, int32_t dim )
{
	float f = ( p - lo ) * inv_h;
	if ( !( f >= 0.0f ) )
	{
		return 0;
	}
	if ( f >= (float) dim )
	{
		return dim - 1;
	}
	return (int32_t) f;
}

void sere_joint_grid_destroy( sere_joint_grid* grid )
{
	if ( grid == NULL )
	{
		return;
	}
	sere_free( grid->start );
	sere_free( grid->items );
	sere_free( grid->x );
	sere_free( grid->y );
	sere_free( grid->z );
	sere_free( grid->candidate_start );
	sere_free( grid->candidate );
	sere_free( grid->cx );
	sere_free( grid->cy );
	sere_free( grid->cz );
	free( grid );
}

/* Exact nearest joint by rings of cells around the query's (clamped) cell, stopping once the
 * nearest face of the visited block is farther than the best joint found. */
static int32_t ring_nearest( const sere_joint_grid* g, float x, float y, float z )
{
	float q[3] = { x, y, z };
	int32_t c[3];
	for ( int a = 0; a < 3; ++a )
	{
		c[a] = cell_of( q[a], g->lo[a], g->inv_h, g->dim[a] );
	}
	int32_t best = -1;
	float best_d2 = INFINITY;
	for ( int32_t r = 0;; ++r )
	{
		int32_t lo[3], hi[3];
		for ( int a = 0; a < 3; ++a )
		{
			lo[a] = c[a] - r > 0 ? c[a] - r : 0;
			hi[a] = c[a] + r < g->dim[a] - 1 ? c[a] + r : g->dim[a] - 1;
		}
		/* The shell of cells at Chebyshev distance exactly r from the query's cell. */
		for ( int32_t iz = lo[2]; iz <= hi[2]; ++iz )
		{
			for ( int32_t iy = lo[1]; iy <= hi[1]; ++iy )
			{
				int on_shell = abs( iz - c[2] ) == r || abs( iy - c[1] ) == r;
				int32_t step = on_shell || hi[0] - lo[0] < 1 ? 1 : hi[0] - lo[0];
				for ( int32_t ix = lo[0]; ix <= hi[0]; ix += step )
				{
					if ( !on_shell && abs( ix - c[0] ) != r )
					{
						continue;
					}
					int32_t cell = ( iz * g->dim[1] + iy ) * g->dim[0] + ix;
					for ( int32_t k = g->start[cell]; k < g->start[cell + 1]; ++k )
					{
						float dx = x - g->x[k], dy = y - g->y[k], dz = z - g->z[k];
						float d2 = dx * dx + dy * dy + dz * dz;
						int32_t j = g->items[k];
						if ( d2 < best_d2 || ( d2 == best_d2 && j < best ) )
						{
							best_d2 = d2;
							best = j;
						}
					}
				}
			}
		}
		/* Every unvisited cell lies beyond a face of the visited block that is not on the grid
		 * boundary; the nearest such face bounds the distance to any joint not yet seen. */
		double bound = INFINITY;
		for ( int a = 0; a < 3; ++a )
		{
			if ( lo[a] > 0 )
			{
				bound = fmin( bound, (double) q[a] - ( (double) g->lo[a] + lo[a] * g->h ) );
			}
			if ( hi[a] < g->dim[a] - 1 )
			{
				bound = fmin( bound, (double) g->lo[a] + ( hi[a] + 1 ) * g->h - (double) q[a] );
			}
		}
		if ( bound == INFINITY )
		{
			return best;
		}
		bound -= g->slack;
		if ( best >= 0 && bound > 0.0 && (double) best_d2 < bound * bound * ( 1.0 - 1e-6 ) )
		{
			return best;
		}
	}
}

/* Candidate lists are built from the cells within this Chebyshev radius of a cell; cells with no
 * joint that close, or whose list would reach farther, keep no list. */
#define GRID_REACH 4

/* The candidate list of one cell: with D the distance from the cell centre c to some joint and r
 * the half-diagonal, a point q of the cell has its nearest joint J within |q − c| + D ≤ r + D of
 * q, so |c − J| ≤ D + 2r. The radius is widened by 1e-5 relative and the rounding slack, so the
 * joint a float brute-force scan would pick is always in the list. */
static int32_t cell_candidates( const sere_joint_grid* g, int32_t ix, int32_t iy, int32_t iz, int32_t* out )
{
	double centre[3];
	int32_t at[3] = { ix, iy, iz }, lo[3], hi[3];
	for ( int a = 0; a < 3; ++a )
	{
		centre[a] = (double) g->lo[a] + ( at[a] + 0.5 ) * g->h;
		lo[a] = at[a] - GRID_REACH > 0 ? at[a] - GRID_REACH : 0;
		hi[a] = at[a] + GRID_REACH < g->dim[a] - 1 ? at[a] + GRID_REACH : g->dim[a] - 1;
	}
	double nearest = INFINITY;
	for ( int pass = 0; pass < 2; ++pass )
	{
		double radius = ( nearest + sqrt( 3.0 ) * g->h ) * ( 1.0 + 1e-5 ) + 4.0 * g->slack;
		if ( pass == 1 && !( radius <= ( GRID_REACH - 1 ) * g->h ) )
		{
			/* Too far from every joint for a short list: the ring search answers here. */
			return 0;
		}
		int32_t count = 0;
		for ( int32_t jz = lo[2]; jz <= hi[2]; ++jz )
		{
			for ( int32_t jy = lo[1]; jy <= hi[1]; ++jy )
			{
				for ( int32_t jx = lo[0]; jx <= hi[0]; ++jx )
				{
					int32_t cell = ( jz * g->dim[1] + jy ) * g->dim[0] + jx;
					for ( int32_t m = g->start[cell]; m < g->start[cell + 1]; ++m )
					{
						double e = sqrt( pow( g->x[m] - centre[0], 2 ) + pow( g->y[m] - centre[1], 2 ) +
										 pow( g->z[m] - centre[2], 2 ) );
						if ( pass == 0 )
						{
							nearest = e < nearest ? e : nearest;
						}
						else if ( e <= radius )
						{
							if ( count == GRID_CANDIDATES )
							{
								return 0;
							}
							out[count++] = g->items[m];
						}
					}
				}
			}
		}
		if ( pass == 1 )
		{
			/* Ascending joint order, so ties resolve as in a brute-force scan. */
			for ( int32_t a = 1; a < count; ++a )
			{
				int32_t v = out[a], b = a;
				while ( b > 0 && out[b - 1] > v )
				{
					out[b] = out[b - 1];
					--b;
				}
				out[b] = v;
			}
			return count;
		}
	}
	return 0;
}

sere_status sere_joint_grid_create( const float* x, const float* y, const float* z, int32_t joint_count,
									sere_joint_grid** grid )
{
	*grid = NULL;
	if ( x == NULL || y == NULL || z == NULL || joint_count < 1 || joint_count > ( 1 << 24 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	const float* p[3] = { x, y, z };
	for ( int32_t i = 0; i < joint_count; ++i )
	{
		for ( int a = 0; a < 3; ++a )
		{
			if ( !isfinite( p[a][i] ) )
			{
				return SERE_ERR_NONFINITE;
			}
			lo[a] = fminf( lo[a], p[a][i] );
			hi[a] = fmaxf( hi[a], p[a][i] );
		}
	}
	/* About one joint per cell over the axes the joints actually spread along (a leaf's joints
	 * are planar, a vein's nearly linear): h is the k-th root of the k-dimensional extent per
	 * joint, at least a 128th of the largest extent so the grid stays small. The box is padded
	 * by two cells along those axes (half a cell along the others) so the blade around the
	 * veins falls inside it and takes the candidate-list path. */
	double extent[3], largest = 0.0, product = 1.0;
	int active = 0;
	for ( int a = 0; a < 3; ++a )
	{
		extent[a] = (double) hi[a] - (double) lo[a];
		largest = extent[a] > largest ? extent[a] : largest;
	}
	for ( int a = 0; a < 3; ++a )
	{
		if ( extent[a] > 1e-6 * largest )
		{
			product *= extent[a];
			++active;
		}
	}
	double h = active > 0 ? pow( product / joint_count, 1.0 / active ) : 1.0;
	h = h > largest / 128.0 ? h : largest / 128.0;
	h = h > 0.0 ? h : 1.0;
	sere_joint_grid* g = calloc( 1, sizeof( sere_joint_grid ) );
	if ( g == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	g->count = joint_count;
	g->h = h;
	g->inv_h = (float) ( 1.0 / h );
	int64_t cells = 1;
	double magnitude = h;
	for ( int a = 0; a < 3; ++a )
	{
		double pad = ( extent[a] > 1e-6 * largest ? 2.0 : 0.5 ) * h;
		g->lo[a] = (float) ( lo[a] - pad );
		double d = ceil( ( extent[a] + 2.0 * pad ) / h );
		g->dim[a] = d < 1.0 ? 1 : ( d > 192.0 ? 192 : (int32_t) d );
		cells *= g->dim[a];
		magnitude = fmax( magnitude, fabs( (double) g->lo[a] ) + extent[a] + 2.0 * pad );
	}
	g->slack = 8.0 * FLT_EPSILON * magnitude;
	g->start = sere_alloc( (size_t) ( cells + 1 ) * sizeof( int32_t ) );
	g->items = sere_alloc( (size_t) joint_count * sizeof( int32_t ) );
	g->x = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->y = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->z = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->candidate_start = sere_alloc( (size_t) ( cells + 1 ) * sizeof( int32_t ) );
	int32_t* cell = malloc( (size_t) joint_count * sizeof( int32_t ) );
	int32_t* fill = malloc( (size_t) cells * sizeof( int32_t ) );
	int32_t* list = malloc( (size_t) cells * GRID_CANDIDATES * sizeof( int32_t ) );
	if ( g->start == NULL || g->items == NULL || g->x == NULL || g->y == NULL || g->z == NULL ||
		 g->candidate_start == NULL || cell == NULL || fill == NULL || list == NULL )
	{
		free( cell );
		free( fill );
		free( list );
		sere_joint_grid_destroy( g );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t i = 0; i < joint_count; ++i )
	{
		int32_t cx = cell_of( x[i], g->lo[0], g->inv_h, g->dim[0] );
		int32_t cy = cell_of( y[i], g->lo[1], g->inv_h, g->dim[1] );
		int32_t cz = cell_of( z[i], g->lo[2], g->inv_h, g->dim[2] );
		cell[i] = ( cz * g->dim[1] + cy ) * g->dim[0] + cx;
		++g->start[cell[i] + 1];
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		g->start[c + 1] += g->start[c];
	}
	/* Counting sort in joint order keeps each cell's joints ascending. */
	memcpy( fill, g->start, (size_t) cells * sizeof( int32_t ) );
	for ( int32_t i = 0; i < joint_count; ++i )
	{
		int32_t k = fill[cell[i]]++;
		g->items[k] = i;
		g->x[k] = x[i];
		g->y[k] = y[i];
		g->z[k] = z[i];
	}
	/* Candidate lists, cell by cell in parallel (each cell writes its own slot). */
#pragma omp parallel for schedule( dynamic, 16 )
	for ( int64_t c = 0; c < cells; ++c )
	{
		int32_t ix = (int32_t) ( c % g->dim[0] ), iy = (int32_t) ( ( c / g->dim[0] ) % g->dim[1] );
		int32_t iz = (int32_t) ( c / ( (int64_t) g->dim[0] * g->dim[1] ) );
		fill[c] = cell_candidates( g, ix, iy, iz, list + c * GRID_CANDIDATES );
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		g->candidate_start[c + 1] = g->candidate_start[c] + fill[c];
	}
	size_t total = (size_t) g->candidate_start[cells];
	g->candidate = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( int32_t ) );
	g->cx = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	g->cy = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	g->cz = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	if ( g->candidate == NULL || g->cx == NULL || g->cy == NULL || g->cz == NULL )
	{
		free( cell );
		free( fill );
		free( list );
		sere_joint_grid_destroy( g );
		return SERE_ERR_MEMORY;
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		for ( int32_t k = 0; k < fill[c]; ++k )
		{
			int32_t j = list[c * GRID_CANDIDATES + k];
			int32_t at = g->candidate_start[c] + k;
			g->candidate[at] = j;
			g->cx[at] = x[j];
			g->cy[at] = y[j];
			g->cz[at] = z[j];
		}
	}
	free( fill );
	free( list );
	free( cell );
	*grid = g;
	return SERE_OK;
}

int32_t sere_joint_grid_nearest( const sere_joint_grid* g, float x, float y, float z )
{
	float fx = ( x - g->lo[0] ) * g->inv_h, fy = ( y - g->lo[1] ) * g->inv_h, fz = ( z - g->lo[2] ) * g->inv_h;
	if ( fx >= 0.0f && fy >= 0.0f && fz >= 0.0f && fx < (float) g->dim[0] && fy < (float) g->dim[1] &&
		 fz < (float) g->dim[2] )
	{
		int32_t c = ( (int32_t) fz * g->dim[1] + (int32_t) fy ) * g->dim[0] + (int32_t) fx;
		int32_t begin = g->candidate_start[c], end = g->candidate_start[c + 1];
		if ( begin < end )
		{
			int32_t best = -1;
			float best_d2 = INFINITY;
			for ( int32_t k = begin; k < end; ++k )
			{
				float dx = x - g->cx[k], dy = y - g->cy[k], dz = z - g->cz[k];
				float d2 = dx * dx + dy * dy + dz * dz;
				/* ascending joints: the first of equal distances is the lower index */
				if ( d2 < best_d2 )
				{
					best_d2 = d2;
					best = g->candidate[k];
				}
			}
			return best;
		}
	}
	return ring_nearest( g, x, y, z );
}

sere_status sere_band( const sere_joint_grid* grid, const float* jx, const float* jy, const float* jz, const float* x,
					   const float* y, const float* z, int32_t vertex_count, int32_t* joint, float* ox, float* oy,
					   float* oz )
{
	if ( grid == NULL || x == NULL || y == NULL || z == NULL || joint == NULL || vertex_count < 0 ||
		 ( ox != NULL && ( oy == NULL || oz == NULL || jx == NULL || jy == NULL || jz == NULL ) ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
#pragma omp parallel for schedule( static ) reduction( | : bad )
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		bad |= !isfinite( x[i] ) || !isfinite( y[i] ) || !isfinite( z[i] );
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
#pragma omp parallel for schedule( static )
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		int32_t j = sere_joint_grid_nearest( grid, x[i], y[i], z[i] );
		joint[i] = j;
		if ( ox != NULL )
		{
			ox[i] = x[i] - jx[j];
			oy[i] = y[i] - jy[j];
			oz[i] = z[i] - jz[j];
		}
	}
	return SERE_OK;
}

/* ---------------------------------------------------------------------------------------------
 * Wilting (Sec. 6, Eq. 1). */

sere_wilt_params sere_wilt_params_default( void )
{
	sere_wilt_params p;
	p.droop_max = INFINITY;
	p.min_angle = (float) ( 120.0 * PI / 180.0 );
	p.spread = 0.5f;
	p.pierce_margin = 1e-3f;
	p.pierce = 1;
	return p;
}

void sere_joint_frames_destroy( sere_joint_frames* frames )
{
	sere_free( frames->x );
	sere_free( frames->y );
	sere_free( frames->z );
	for ( int k = 0; k < 9; ++k )
	{
		sere_free( frames->m[k] );
	}
	sere_free( frames->work );
	memset( frames, 0, sizeof( *frames ) );
}

sere_status sere_joint_frames_alloc( sere_joint_frames* frames, int32_t joint_count )
{
	memset( frames, 0, sizeof( *frames ) );
	if ( joint_count < 1 || joint_count > ( 1 << 24 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	size_t n = (size_t) sere_pad( joint_count );
	int failed = 0;
	frames->x = sere_alloc( n * sizeof( float ) );
	frames->y = sere_alloc( n * sizeof( float ) );
	frames->z = sere_alloc( n * sizeof( float ) );
	failed |= frames->x == NULL || frames->y == NULL || frames->z == NULL;
	for ( int k = 0; k < 9; ++k )
	{
		frames->m[k] = sere_alloc( n * sizeof( float ) );
		failed |= frames->m[k] == NULL;
	}
	frames->work = sere_alloc( 12 * n * sizeof( double ) );
	if ( failed || frames->work == NULL )
	{
		sere_joint_frames_destroy( frames );
		return SERE_ERR_MEMORY;
	}
	frames->capacity = (int32_t) n;
	return SERE_OK;
}

/* Rotation by `angle` about the unit axis n (Rodrigues), row-major. */
static void axis_rotation( const double n[3], double angle, double r[9] )
{
	double c = cos( angle ), s = sin( angle ), k = 1.0 - c;
	r[0] = c + k * n[0] * n[0];
	r[1] = k * n[0] * n[1] - s * n[2];
	r[2] = k * n[0] * n[2] + s * n[1];
	r[3] = k * n[1] * n[0] + s * n[2];
	r[4] = c + k * n[1] * n[1];
	r[5] = k * n[1] * n[2] - s * n[0];
	r[6] = k * n[2] * n[0] - s * n[1];
	r[7] = k * n[2] * n[1] + s * n[0];
	r[8] = c + k * n[2] * n[2];
}

static void mat_vec( const double m[9], const double v[3], double out[3] )
{
	for ( int r = 0; r < 3; ++r )
	{
		out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
	}
}

static void mat_mul( const double a[9], const double b[9], double out[9] )
{
	for ( int r = 0; r < 3; ++r )
	{
		for ( int c = 0; c < 3; ++c )
		{
			out[3 * r + c] = a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c];
		}
	}
}

/* The largest φ in [0, limit] such that f(ψ) = a cos ψ + b sin ψ stays ≥ h for ψ ∈ [0, φ].
 * With f = R cos(ψ − β), the feasible phases are |ψ − β| ≤ γ = acos(h / R); ψ leaves them at
 * β + γ. A start just outside (rounding at a limit reached by an earlier joint) that is
 * falling gives 0; one that is rising is let through. */
static double first_exit( double a, double b, double h, double limit )
{
	double r = hypot( a, b );
	if ( h <= -r )
	{
		return limit;
	}
	if ( h >= r )
	{
		return 0.0;
	}
	double delta = -atan2( b, a ); /* phase at ψ = 0 */
	double gamma = acos( h / r );
	if ( delta > gamma )
	{
		return 0.0;
	}
	double exit = gamma - delta;
	return exit < limit ? exit : limit;
}

enum
{
	LIMIT_NONE,
	LIMIT_DOWN,
	LIMIT_ANGLE,
	LIMIT_DROOP
};

static void pose_range( const sere_skeleton* s, int32_t first, int32_t count, float t, const sere_wilt_params* params,
						sere_joint_frames* frames, sere_pose_stats* stats )
{
	double* work = frames->work;
	double spread = params->spread;
	double progress_scale = 1.0 / ( 1.0 - spread );
	double cos_limit = -cos( (double) params->min_angle ); /* Sec. 6: included angle ≥ min_angle */
	int droop = isfinite( params->droop_max );
	sere_pose_stats st = { 0, 0, 0, 0 };
	for ( int32_t i = first; i < first + count; ++i )
	{
		double* pi = work + 12 * (size_t) i;
		double* qi = pi + 3;
		int32_t p = s->parent[i];
		if ( p < 0 )
		{
			pi[0] = s->x[i];
			pi[1] = s->y[i];
			pi[2] = s->z[i];
			memset( qi, 0, 9 * sizeof( double ) );
			qi[0] = qi[4] = qi[8] = 1.0;
			continue;
		}
		const double* pp = work + 12 * (size_t) p;
		const double* qp = pp + 3;
		/* The segment p → i as its ancestors' rotations left it. */
		double u0[3] = { (double) s->x[i] - s->x[p], (double) s->y[i] - s->y[p], (double) s->z[i] - s->z[p] };
		double u[3];
		mat_vec( qp, u0, u );
		double progress = ( t - spread * s->delay[i] ) * progress_scale;
		progress = progress < 0.0 ? 0.0 : ( progress > 1.0 ? 1.0 : progress );
		double phi = s->bend[i] * progress;
		double r[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
		double length = sqrt( u[0] * u[0] + u[1] * u[1] + u[2] * u[2] );
		double horizontal = hypot( u[0], u[1] );
		/* A vertical segment has no plane with d: pointing down it is done, pointing up it waits. */
		if ( phi > 0.0 && horizontal > 1e-12 * length )
		{
			++st.turning;
			int limit = LIMIT_NONE;
			/* n = u × d / |u × d| with d = (0, 0, −1): horizontal, so the segment swings in the
			 * vertical plane through it and d (Fig. 4a). */
			double n[3] = { -u[1] / horizontal, u[0] / horizontal, 0.0 };
			/* Eq. 1: P(φ) = P_p + |u| (cos φ û + sin φ ê) with ê = n × û, for φ up to the angle Ω
			 * between u and d, where the segment points straight down. */
			double omega = atan2( horizontal, -u[2] );
			if ( omega <= phi )
			{
				phi = omega;
				limit = LIMIT_DOWN;
			}
			int32_t g = s->parent[p];
			if ( params->min_angle > 0.0f && g >= 0 && s->vein[p] == s->vein[i] )
			{
				const double* pg = work + 12 * (size_t) g;
				double w[3] = { pp[0] - pg[0], pp[1] - pg[1], pp[2] - pg[2] };
				double wl = sqrt( w[0] * w[0] + w[1] * w[1] + w[2] * w[2] );
				double uh[3] = { u[0] / length, u[1] / length, u[2] / length };
				double e[3] = { n[1] * uh[2], -n[0] * uh[2], n[0] * uh[1] - n[1] * uh[0] };
				double a = ( w[0] * uh[0] + w[1] * uh[1] + w[2] * uh[2] ) / wl;
				double b = ( w[0] * e[0] + w[1] * e[1] + w[2] * e[2] ) / wl;
				double exit = first_exit( a, b, cos_limit, phi );
				if ( exit < phi )
				{
					phi = exit;
					limit = LIMIT_ANGLE;
				}
			}
			if ( droop )
			{
				/* Every joint k of the subtree turns rigidly about the horizontal axis through
				 * P_p: z_k(φ) = z_p + a cos φ + b sin φ must stay ≥ z_k^rest − droop_max. */
				for ( int32_t k = i; k < s->end[i]; ++k )
				{
					double v0[3] = { (double) s->x[k] - s->x[p], (double) s->y[k] - s->y[p],
									 (double) s->z[k] - s->z[p] };
					double v[3];
					mat_vec( qp, v0, v );
					double a = v[2];
					double b = n[0] * v[1] - n[1] * v[0];
					double h = (double) s->z[k] - params->droop_max - pp[2];
					if ( h < 0.0 && h * h >= a * a + b * b )
					{
						continue;
					}
					double exit = first_exit( a, b, h, phi );
					if ( exit < phi )
					{
						phi = exit;
						limit = LIMIT_DROOP;
					}
				}
			}
			st.down_limited += limit == LIMIT_DOWN;
			st.angle_limited += limit == LIMIT_ANGLE;
			st.droop_limited += limit == LIMIT_DROOP;
			axis_rotation( n, phi, r );
		}
		double v[3];
		mat_vec( r, u, v );
		pi[0] = pp[0] + v[0];
		pi[1] = pp[1] + v[1];
		pi[2] = pp[2] + v[2];
		mat_mul( r, qp, qi );
	}
	for ( int32_t i = first; i < first + count; ++i )
	{
		const double* pi = work + 12 * (size_t) i;
		frames->x[i] = (float) pi[0];
		frames->y[i] = (float) pi[1];
		frames->z[i] = (float) pi[2];
		for ( int k = 0; k < 9; ++k )
		{
			frames->m[k][i] = (float) pi[3 + k];
		}
	}
	if ( stats != NULL )
	{
		*stats = st;
	}
}

static sere_status check_wilt_params( const sere_wilt_params* p )
{
	if ( p == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( isnan( p->droop_max ) || !isfinite( p->min_angle ) || !isfinite( p->spread ) || !isfinite( p->pierce_margin ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( p->droop_max < 0.0f || p->min_angle < 0.0f || p->min_angle > (float) PI || p->spread < 0.0f ||
		 !( p->spread < 1.0f ) || p->pierce_margin < 0.0f )
	{
		return SERE_ERR_ARGUMENT;
	}
	return SERE_OK;
}

sere_status sere_skeleton_pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
								const sere_wilt_params* params, sere_joint_frames* frames, sere_pose_stats* stats )
{
	sere_status status = check_wilt_params( params );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( !isfinite( t ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( skeleton == NULL || frames == NULL || first < 0 || count < 1 || first > skeleton->joint_count - count ||
		 frames->capacity < first + count || skeleton->parent[first] != -1 || skeleton->end[first] != first + count )
	{
		return SERE_ERR_ARGUMENT;
	}
	t = t < 0.0f ? 0.0f : ( t > 1.0f ? 1.0f : t );
	pose_range( skeleton, first, count, t, params, frames, stats );
	return SERE_OK;
}

/* Vertices are skinned in blocks of this many; a block is the unit of parallel work. */
#define SKIN_BLOCK 2048

void sere_skin( const sere_joint_frames* frames, const int32_t* joint, const float* ox, const float* oy,
				const float* oz, int32_t vertex_count, float* x, float* y, float* z )
{
	const float *px = frames->x, *py = frames->y, *pz = frames->z;
	float* const* m = frames->m;
	int32_t blocks = ( vertex_count + SKIN_BLOCK - 1 ) / SKIN_BLOCK;
	/* Rigid binding (Sec. 6): x = p_j + R_j o. Vertices of one joint that sit together (a plant
	 * orders each leaf's vertices by joint) form a run: its transform is loaded once and
	 * broadcast, and the run streams through unit-stride SIMD with no gathers. Any order is
	 * correct; scattered joints just make runs of one. */
#pragma omp parallel for schedule( static )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t i = b * SKIN_BLOCK;
		int32_t end = i + SKIN_BLOCK < vertex_count ? i + SKIN_BLOCK : vertex_count;
		while ( i < end )
		{
			int32_t j = joint[i];
			int32_t e = i + 1;
			while ( e < end && joint[e] == j )
			{
				++e;
			}
			float tx = px[j], ty = py[j], tz = pz[j];
			float m0 = m[0][j], m1 = m[1][j], m2 = m[2][j];
			float m3 = m[3][j], m4 = m[4][j], m5 = m[5][j];
			float m6 = m[6][j], m7 = m[7][j], m8 = m[8][j];
#pragma omp simd
			for ( int32_t k = i; k < e; ++k )
			{
				float a = ox[k], c = oy[k], d = oz[k];
				x[k] = tx + ( ( m0 * a + m1 * c ) + m2 * d );
				y[k] = ty + ( ( m3 * a + m4 * c ) + m5 * d );
				z[k] = tz + ( ( m6 * a + m7 * c ) + m8 * d );
			}
			i = e;
		}
	}
}

/* ---------------------------------------------------------------------------------------------
 * Piercing (Sec. 6) and the self-intersection count. */

/* Where segment p0 → p1 crosses triangle abc: the fraction along the segment, or −1. The
 * segment must change sides of the triangle's plane and cross it inside the closed triangle.
 * Coplanar segments never count (a planar rest mesh is not self-intersecting). */
static double segment_triangle( const double p0[3], const double p1[3], const double a[3], const double b[3],
								const double c[3] )
{
	double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	double d0 = n[0] * ( p0[0] - a[0] ) + n[1] * ( p0[1] - a[1] ) + n[2] * ( p0[2] - a[2] );
	double d1 = n[0] * ( p1[0] - a[0] ) + n[1] * ( p1[1] - a[1] ) + n[2] * ( p1[2] - a[2] );
	if ( ( d0 >= 0.0 ) == ( d1 >= 0.0 ) || d0 == d1 )
	{
		return -1.0;
	}
	double s = d0 / ( d0 - d1 );
	double q[3] = { p0[0] + s * ( p1[0] - p0[0] ), p0[1] + s * ( p1[1] - p0[1] ), p0[2] + s * ( p1[2] - p0[2] ) };
	const double* corner[3] = { a, b, c };
	for ( int k = 0; k < 3; ++k )
	{
		const double* u = corner[k];
		const double* v = corner[( k + 1 ) % 3];
		double ex = v[0] - u[0], ey = v[1] - u[1], ez = v[2] - u[2];
		double wx = q[0] - u[0], wy = q[1] - u[1], wz = q[2] - u[2];
		double side = n[0] * ( ey * wz - ez * wy ) + n[1] * ( ez * wx - ex * wz ) + n[2] * ( ex * wy - ey * wx );
		if ( side < 0.0 )
		{
			return -1.0;
		}
	}
	return s;
}

static void corner( const float* x, const float* y, const float* z, int32_t i, double out[3] )
{
	out[0] = x[i];
	out[1] = y[i];
	out[2] = z[i];
}

/* Eight consecutive vertices share one walk down the tree (sere_bvh_query_group); vertices of a
 * plant are ordered by joint, so the eight boxes are close together. */
typedef struct pierce_group
{
	const int32_t* tri;
	const float *x, *y, *z; /* previous positions: the mesh a move must not pass through */
	int32_t first;			/* the vertex of lane 0 */
	double p0[SERE_BVH_WIDTH][3], p1[SERE_BVH_WIDTH][3];
	double hit[SERE_BVH_WIDTH]; /* smallest crossing fraction per lane */
} pierce_group;

static void pierce_visit( void* context, int32_t t, uint32_t lanes )
{
	pierce_group* g = context;
	const int32_t* c = g->tri + 3 * t;
	double a[3], b[3], d[3];
	corner( g->x, g->y, g->z, c[0], a );
	corner( g->x, g->y, g->z, c[1], b );
	corner( g->x, g->y, g->z, c[2], d );
	while ( lanes != 0 )
	{
		int k = __builtin_ctz( lanes );
		lanes &= lanes - 1;
		int32_t v = g->first + k;
		if ( c[0] == v || c[1] == v || c[2] == v )
		{
			continue;
		}
		double s = segment_triangle( g->p0[k], g->p1[k], a, b, d );
		if ( s >= 0.0 && s < g->hit[k] )
		{
			g->hit[k] = s;
		}
	}
}

static int32_t pierce_limit( const sere_bvh* bvh, const int32_t* tri, const float* px, const float* py, const float* pz,
							 float* x, float* y, float* z, int32_t vertex_count, float margin, uint8_t* modified )
{
	int32_t shortened = 0;
	int32_t groups = ( vertex_count + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for schedule( dynamic, 32 ) reduction( + : shortened )
	for ( int32_t b = 0; b < groups; ++b )
	{
		pierce_group g;
		sere_bvh_group boxes;
		g.tri = tri;
		g.x = px;
		g.y = py;
		g.z = pz;
		g.first = b * SERE_BVH_WIDTH;
		boxes.count = vertex_count - g.first < SERE_BVH_WIDTH ? vertex_count - g.first : SERE_BVH_WIDTH;
		int moving = 0;
		for ( int k = 0; k < boxes.count; ++k )
		{
			int32_t i = g.first + k;
			g.hit[k] = INFINITY;
			corner( px, py, pz, i, g.p0[k] );
			corner( x, y, z, i, g.p1[k] );
			int still = x[i] == px[i] && y[i] == py[i] && z[i] == pz[i];
			moving |= !still;
			/* A vertex that does not move cannot pierce anything: a NaN box leaves its lane out. */
			boxes.lo_x[k] = still ? NAN : fminf( px[i], x[i] );
			boxes.lo_y[k] = fminf( py[i], y[i] );
			boxes.lo_z[k] = fminf( pz[i], z[i] );
			boxes.hi_x[k] = fmaxf( px[i], x[i] );
			boxes.hi_y[k] = fmaxf( py[i], y[i] );
			boxes.hi_z[k] = fmaxf( pz[i], z[i] );
		}
		if ( !moving )
		{
			continue;
		}
		sere_bvh_query_group( bvh, &boxes, pierce_visit, &g );
		for ( int k = 0; k < boxes.count; ++k )
		{
			if ( g.hit[k] <= 1.0 )
			{
				int32_t i = g.first + k;
				double d[3] = { g.p1[k][0] - g.p0[k][0], g.p1[k][1] - g.p0[k][1], g.p1[k][2] - g.p0[k][2] };
				double length = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
				double s = g.hit[k] - margin / length;
				s = s > 0.0 ? s : 0.0;
				x[i] = (float) ( g.p0[k][0] + s * d[0] );
				y[i] = (float) ( g.p0[k][1] + s * d[1] );
				z[i] = (float) ( g.p0[k][2] + s * d[2] );
				modified[i] = 1;
				++shortened;
			}
		}
	}
	return shortened;
}

static int edge_hits( const float* x, const float* y, const float* z, const int32_t* from, int e0, int e1,
					  const int32_t* onto )
{
	double p0[3], p1[3], a[3], b[3], c[3];
	corner( x, y, z, from[e0], p0 );
	corner( x, y, z, from[e1], p1 );
	corner( x, y, z, onto[0], a );
	corner( x, y, z, onto[1], b );
	corner( x, y, z, onto[2], c );
	return segment_triangle( p0, p1, a, b, c ) >= 0.0;
}

/* The corners of `from` against the plane of `onto`, with exactly the arithmetic of
 * segment_triangle, so an edge whose ends do not change sides here fails its plane test there. */
static void plane_sides( const float* x, const float* y, const float* z, const int32_t* onto, const int32_t* from,
						 double d[3] )
{
	double a[3], b[3], c[3];
	corner( x, y, z, onto[0], a );
	corner( x, y, z, onto[1], b );
	corner( x, y, z, onto[2], c );
	double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	for ( int k = 0; k < 3; ++k )
	{
		double p[3];
		corner( x, y, z, from[k], p );
		d[k] = n[0] * ( p[0] - a[0] ) + n[1] * ( p[1] - a[1] ) + n[2] * ( p[2] - a[2] );
	}
}

static int may_cross( const double d[3], int i, int j )
{
	return ( d[i] >= 0.0 ) != ( d[j] >= 0.0 ) && d[i] != d[j];
}

/* Triangles s and o intersect: sharing an edge they never count (only a coplanar fold could
 * make them); sharing one corner, only the edges opposite it can cross the other triangle
 * anywhere but at that corner; otherwise any of the six edges. An edge is tested only when its
 * ends lie on both sides of the other triangle's plane, which rejects most pairs cheaply. */
static int triangles_intersect( const float* x, const float* y, const float* z, const int32_t* s, const int32_t* o )
{
	int shared = 0, s_at = -1, o_at = -1;
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = 0; j < 3; ++j )
		{
			if ( s[i] == o[j] )
			{
				++shared;
				s_at = i;
				o_at = j;
			}
		}
	}
	if ( shared > 1 )
	{
		return 0;
	}
	double ds[3], dn[3];
	plane_sides( x, y, z, o, s, ds );
	plane_sides( x, y, z, s, o, dn );
	if ( shared == 1 )
	{
		int s1 = ( s_at + 1 ) % 3, s2 = ( s_at + 2 ) % 3, o1 = ( o_at + 1 ) % 3, o2 = ( o_at + 2 ) % 3;
		return ( may_cross( ds, s1, s2 ) && edge_hits( x, y, z, s, s1, s2, o ) ) ||
			   ( may_cross( dn, o1, o2 ) && edge_hits( x, y, z, o, o1, o2, s ) );
	}
	for ( int k = 0; k < 3; ++k )
	{
		int l = ( k + 1 ) % 3;
		if ( ( may_cross( ds, k, l ) && edge_hits( x, y, z, s, k, l, o ) ) ||
			 ( may_cross( dn, k, l ) && edge_hits( x, y, z, o, k, l, s ) ) )
		{
			return 1;
		}
	}
	return 0;
}

static void triangle_box( const float* x, const float* y, const float* z, const int32_t* c, float lo[3], float hi[3] )
{
	const float* p[3] = { x, y, z };
	for ( int a = 0; a < 3; ++a )
	{
		lo[a] = fminf( fminf( p[a][c[0]], p[a][c[1]] ), p[a][c[2]] );
		hi[a] = fmaxf( fmaxf( p[a][c[0]], p[a][c[1]] ), p[a][c[2]] );
	}
}

struct sere_pierce
{
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t* tri;
	int32_t* group;		/* rigid group of each vertex, or NULL */
	uint8_t* off_pose;	/* vertex left short of its target by the previous step */
	uint8_t* modified;	/* vertex moved short of its target in this step */
	uint8_t* flag;		/* vertex is a corner of an intersecting pair this round */
	uint8_t* halvings;	/* how often a vertex has been pulled back this step */
	uint8_t* candidate; /* triangle to search this round */
	sere_bvh* bvh;
};

/* Eight consecutive triangles share one walk down the tree. */
typedef struct pair_group
{
	const int32_t* tri;
	const float *x, *y, *z;
	int32_t first; /* the triangle of lane 0 */
	/* Triangles that search (all when NULL); a pair of two searching triangles is taken from the
	 * lower one only, so every pair is tested once. */
	const uint8_t* candidate;
	uint8_t* flag; /* when not NULL, the corners of both triangles of every pair are flagged */
	/* When not NULL: pairs whose six corners share a group and all moved with it skip the test. */
	const int32_t* group;
	const uint8_t *off_pose, *modified;
	int64_t count;
} pair_group;

/* All six corners in one rigid group, each at the caller's target both before and after this
 * step: the pair moved as one rigid body, so it cannot have come to intersect. */
static int moved_rigidly( const pair_group* g, const int32_t* s, const int32_t* o )
{
	int32_t k = g->group[s[0]];
	for ( int c = 0; c < 3; ++c )
	{
		if ( g->group[s[c]] != k || g->group[o[c]] != k || g->off_pose[s[c]] | g->modified[s[c]] ||
			 g->off_pose[o[c]] | g->modified[o[c]] )
		{
			return 0;
		}
	}
	return 1;
}

static void pair_visit( void* context, int32_t other, uint32_t lanes )
{
	pair_group* g = context;
	const int32_t* o = g->tri + 3 * other;
	while ( lanes != 0 )
	{
		int k = __builtin_ctz( lanes );
		lanes &= lanes - 1;
		int32_t self = g->first + k;
		if ( other == self || ( other < self && ( g->candidate == NULL || g->candidate[other] ) ) )
		{
			continue;
		}
		const int32_t* s = g->tri + 3 * self;
		if ( ( g->group != NULL && moved_rigidly( g, s, o ) ) || !triangles_intersect( g->x, g->y, g->z, s, o ) )
		{
			continue;
		}
		++g->count;
		if ( g->flag != NULL )
		{
			for ( int c = 0; c < 3; ++c )
			{
				/* Every writer stores the same value, so the result does not depend on the order. */
#pragma omp atomic write
				g->flag[s[c]] = 1;
#pragma omp atomic write
				g->flag[o[c]] = 1;
			}
		}
	}
}

/* Intersecting pairs among the triangles [first, first + 8) whose `candidate` flag is set (all
 * when candidate is NULL). */
static int64_t pair_search( const sere_bvh* bvh, const int32_t* tri, int32_t triangle_count, const float* x,
							const float* y, const float* z, int32_t first, const uint8_t* candidate, uint8_t* flag,
							const struct sere_pierce* rigid )
{
	pair_group g = { tri, x, y, z, first, candidate, flag, NULL, NULL, NULL, 0 };
	if ( rigid != NULL )
	{
		g.group = rigid->group;
		g.off_pose = rigid->off_pose;
		g.modified = rigid->modified;
	}
	sere_bvh_group boxes;
	boxes.count = triangle_count - first < SERE_BVH_WIDTH ? triangle_count - first : SERE_BVH_WIDTH;
	int any = 0;
	for ( int k = 0; k < boxes.count; ++k )
	{
		float lo[3], hi[3];
		triangle_box( x, y, z, tri + 3 * ( first + k ), lo, hi );
		int use = candidate == NULL || candidate[first + k];
		any |= use;
		boxes.lo_x[k] = use ? lo[0] : NAN;
		boxes.lo_y[k] = lo[1];
		boxes.lo_z[k] = lo[2];
		boxes.hi_x[k] = hi[0];
		boxes.hi_y[k] = hi[1];
		boxes.hi_z[k] = hi[2];
	}
	if ( any )
	{
		sere_bvh_query_group( bvh, &boxes, pair_visit, &g );
	}
	return g.count;
}

int64_t sere_mesh_intersections( const sere_bvh* bvh, const int32_t* tri, int32_t triangle_count, const float* x,
								 const float* y, const float* z )
{
	int64_t total = 0;
	int32_t groups = ( triangle_count + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for schedule( dynamic, 32 ) reduction( + : total )
	for ( int32_t b = 0; b < groups; ++b )
	{
		total += pair_search( bvh, tri, triangle_count, x, y, z, b * SERE_BVH_WIDTH, NULL, NULL, NULL );
	}
	return total;
}

/* Pull-backs halve the remaining move this many times before undoing it. */
#define PIERCE_HALVINGS 4
#define PIERCE_ROUNDS	32

void sere_pierce_destroy( sere_pierce* pierce )
{
	if ( pierce == NULL )
	{
		return;
	}
	sere_free( pierce->tri );
	sere_free( pierce->group );
	sere_free( pierce->off_pose );
	sere_free( pierce->modified );
	sere_free( pierce->flag );
	sere_free( pierce->halvings );
	sere_free( pierce->candidate );
	sere_bvh_destroy( pierce->bvh );
	free( pierce );
}

sere_status sere_pierce_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count, const float* x,
								const float* y, const float* z, const int32_t* rigid_group, sere_pierce** out )
{
	*out = NULL;
	if ( tri == NULL || triangle_count < 1 || vertex_count < 3 || triangle_count > INT32_MAX / 3 - SERE_PAD )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_pierce* p = calloc( 1, sizeof( sere_pierce ) );
	if ( p == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	p->vertex_count = vertex_count;
	p->triangle_count = triangle_count;
	p->tri = sere_alloc( (size_t) sere_pad( 3 * triangle_count ) * sizeof( int32_t ) );
	p->flag = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->halvings = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->off_pose = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->modified = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->candidate = sere_alloc( (size_t) sere_pad( triangle_count ) );
	if ( rigid_group != NULL )
	{
		p->group = sere_alloc( (size_t) sere_pad( vertex_count ) * sizeof( int32_t ) );
	}
	if ( p->tri == NULL || p->flag == NULL || p->halvings == NULL || p->off_pose == NULL || p->modified == NULL ||
		 p->candidate == NULL || ( rigid_group != NULL && p->group == NULL ) )
	{
		sere_pierce_destroy( p );
		return SERE_ERR_MEMORY;
	}
	memcpy( p->tri, tri, 3 * (size_t) triangle_count * sizeof( int32_t ) );
	if ( rigid_group != NULL )
	{
		memcpy( p->group, rigid_group, (size_t) vertex_count * sizeof( int32_t ) );
	}
	sere_status status = sere_bvh_create( tri, triangle_count, vertex_count, x, y, z, &p->bvh );
	if ( status != SERE_OK )
	{
		sere_pierce_destroy( p );
		return status;
	}
	*out = p;
	return SERE_OK;
}

const sere_bvh* sere_pierce_bvh( const sere_pierce* pierce )
{
	return pierce->bvh;
}

static int moved( const float* px, const float* py, const float* pz, const float* x, const float* y, const float* z,
				  int32_t i )
{
	return x[i] != px[i] || y[i] != py[i] || z[i] != pz[i];
}

sere_status sere_pierce_step( sere_pierce* p, const float* px, const float* py, const float* pz, float* x, float* y,
							  float* z, float margin, sere_pierce_stats* stats )
{
	if ( p == NULL || px == NULL || py == NULL || pz == NULL || x == NULL || y == NULL || z == NULL ||
		 !( margin >= 0.0f ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_pierce_stats st = { 0, 0, 0, 0, 0 };
	bool rebuilt = false;
	sere_status status = sere_bvh_update( p->bvh, px, py, pz, SERE_BVH_REBUILD_RATIO, &rebuilt );
	if ( status != SERE_OK )
	{
		return status;
	}
	st.rebuilt = rebuilt;
	int32_t n = p->vertex_count, f = p->triangle_count;
	int bad = 0;
#pragma omp parallel for schedule( static ) reduction( | : bad )
	for ( int32_t i = 0; i < n; ++i )
	{
		bad |= !isfinite( x[i] ) || !isfinite( y[i] ) || !isfinite( z[i] );
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	/* The seed's check: no vertex passes through the mesh as it was. */
	memset( p->modified, 0, (size_t) n );
	st.shortened = pierce_limit( p->bvh, p->tri, px, py, pz, x, y, z, n, margin, p->modified );

	/* Then no triangle may end up through another. Only triangles with a moving corner can
	 * meet a new partner; later rounds search around the vertices just pulled back. */
	memset( p->halvings, 0, (size_t) n );
#pragma omp parallel for schedule( static )
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* c = p->tri + 3 * t;
		p->candidate[t] = (uint8_t) ( moved( px, py, pz, x, y, z, c[0] ) || moved( px, py, pz, x, y, z, c[1] ) ||
									  moved( px, py, pz, x, y, z, c[2] ) );
	}
	for ( ;; )
	{
		status = sere_bvh_refit( p->bvh, x, y, z );
		if ( status != SERE_OK )
		{
			return status;
		}
		if ( st.rounds == PIERCE_ROUNDS )
		{
			/* The previous state did not intersect; going back to it always succeeds. */
			memcpy( x, px, (size_t) n * sizeof( float ) );
			memcpy( y, py, (size_t) n * sizeof( float ) );
			memcpy( z, pz, (size_t) n * sizeof( float ) );
			memset( p->modified, 1, (size_t) n );
			st.reverted = 1;
			status = sere_bvh_refit( p->bvh, x, y, z );
			break;
		}
		memset( p->flag, 0, (size_t) n );
		int64_t found = 0;
		int32_t groups = ( f + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for schedule( dynamic, 32 ) reduction( + : found )
		for ( int32_t b = 0; b < groups; ++b )
		{
			found += pair_search( p->bvh, p->tri, f, x, y, z, b * SERE_BVH_WIDTH, p->candidate, p->flag,
								  p->group != NULL ? p : NULL );
		}
		if ( found == 0 )
		{
			break;
		}
		++st.rounds;
		int32_t pulled = 0;
#pragma omp parallel for schedule( static ) reduction( + : pulled )
		for ( int32_t i = 0; i < n; ++i )
		{
			if ( !p->flag[i] || !moved( px, py, pz, x, y, z, i ) )
			{
				continue;
			}
			if ( p->halvings[i] < PIERCE_HALVINGS )
			{
				x[i] = 0.5f * ( x[i] + px[i] );
				y[i] = 0.5f * ( y[i] + py[i] );
				z[i] = 0.5f * ( z[i] + pz[i] );
				++p->halvings[i];
			}
			else
			{
				x[i] = px[i];
				y[i] = py[i];
				z[i] = pz[i];
			}
			p->modified[i] = 1;
			++pulled;
		}
		st.pulled_back += pulled;
#pragma omp parallel for schedule( static )
		for ( int32_t t = 0; t < f; ++t )
		{
			const int32_t* c = p->tri + 3 * t;
			p->candidate[t] = p->flag[c[0]] | p->flag[c[1]] | p->flag[c[2]];
		}
	}
	memcpy( p->off_pose, p->modified, (size_t) n );
	if ( stats != NULL )
	{
		*stats = st;
	}
	return status;
}

/* ---------------------------------------------------------------------------------------------
 * Plant (Sec. 7). */

void sere_plant_destroy( sere_plant* plant )
{
	if ( plant == NULL )
	{
		return;
	}
	sere_free( plant->joint_first );
	sere_free( plant->vertex_first );
	sere_free( plant->triangle_first );
	sere_free( plant->onset );
	sere_free( plant->leaf_t );
	sere_skeleton_destroy( &plant->joints );
	sere_joint_frames_destroy( &plant->frames );
	sere_free( plant->joint );
	float* arrays[] = { plant->ox, plant->oy, plant->oz, plant->x, plant->y,  plant->z,	 plant->rx,
						plant->ry, plant->rz, plant->u,	 plant->v, plant->tx, plant->ty, plant->tz };
	for ( size_t k = 0; k < sizeof( arrays ) / sizeof( arrays[0] ); ++k )
	{
		sere_free( arrays[k] );
	}
	sere_free( plant->tri );
	sere_free( plant->leaf_stats );
	sere_pierce_destroy( plant->pierce );
	free( plant );
}

static sere_status check_template( const sere_leaf_template* t )
{
	if ( t->mesh == NULL || t->skeleton == NULL || t->mesh->vertex_count < 3 || t->mesh->triangle_count < 1 ||
		 t->skeleton->joint_count < 2 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < 3 * t->mesh->triangle_count; ++i )
	{
		if ( t->mesh->tri[i] < 0 || t->mesh->tri[i] >= t->mesh->vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return SERE_OK;
}

sere_status sere_plant_create( const sere_leaf_template* templates, int32_t template_count,
							   const sere_leaf_placement* leaves, int32_t leaf_count, sere_plant** out )
{
	*out = NULL;
	if ( templates == NULL || leaves == NULL || template_count < 1 || leaf_count < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t k = 0; k < template_count; ++k )
	{
		sere_status status = check_template( templates + k );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	int64_t joints = 0, vertices = 0, triangles = 0;
	for ( int32_t k = 0; k < leaf_count; ++k )
	{
		const sere_leaf_placement* l = leaves + k;
		if ( l->template_index < 0 || l->template_index >= template_count )
		{
			return SERE_ERR_ARGUMENT;
		}
		if ( !isfinite( l->base[0] ) || !isfinite( l->base[1] ) || !isfinite( l->base[2] ) || !isfinite( l->azimuth ) ||
			 !isfinite( l->elevation ) || !isfinite( l->scale ) || !isfinite( l->onset ) )
		{
			return SERE_ERR_NONFINITE;
		}
		if ( !( l->scale > 0.0f ) )
		{
			return SERE_ERR_ARGUMENT;
		}
		const sere_leaf_template* t = templates + l->template_index;
		joints += t->skeleton->joint_count;
		vertices += t->mesh->vertex_count;
		triangles += t->mesh->triangle_count;
	}
	if ( joints > ( 1 << 24 ) || vertices > INT32_MAX / 4 || triangles > INT32_MAX / 4 )
	{
		return SERE_ERR_CAPACITY;
	}
	sere_plant* p = calloc( 1, sizeof( sere_plant ) );
	if ( p == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	p->leaf_count = leaf_count;
	p->vertex_count = (int32_t) vertices;
	p->triangle_count = (int32_t) triangles;
	size_t nl = (size_t) sere_pad( leaf_count + 1 );
	size_t nv = (size_t) sere_pad( (int32_t) vertices );
	p->joint_first = sere_alloc( nl * sizeof( int32_t ) );
	p->vertex_first = sere_alloc( nl * sizeof( int32_t ) );
	p->triangle_first = sere_alloc( nl * sizeof( int32_t ) );
	p->onset = sere_alloc( nl * sizeof( float ) );
	p->leaf_t = sere_alloc( nl * sizeof( float ) );
	p->leaf_stats = sere_alloc( nl * sizeof( sere_pose_stats ) );
	p->joint = sere_alloc( nv * sizeof( int32_t ) );
	float** arrays[] = { &p->ox, &p->oy, &p->oz, &p->x, &p->y,	&p->z,	&p->rx,
						 &p->ry, &p->rz, &p->u,	 &p->v, &p->tx, &p->ty, &p->tz };
	int failed = 0;
	for ( size_t k = 0; k < sizeof( arrays ) / sizeof( arrays[0] ); ++k )
	{
		*arrays[k] = sere_alloc( nv * sizeof( float ) );
		failed |= *arrays[k] == NULL;
	}
	p->tri = sere_alloc( (size_t) sere_pad( 3 * (int32_t) triangles ) * sizeof( int32_t ) );
	sere_status status = SERE_ERR_MEMORY;
	if ( failed || p->joint_first == NULL || p->vertex_first == NULL || p->triangle_first == NULL || p->onset == NULL ||
		 p->leaf_t == NULL || p->leaf_stats == NULL || p->joint == NULL || p->tri == NULL )
	{
		goto fail;
	}
	status = skeleton_alloc( &p->joints, (int32_t) joints );
	if ( status == SERE_OK )
	{
		status = sere_joint_frames_alloc( &p->frames, (int32_t) joints );
	}
	if ( status != SERE_OK )
	{
		goto fail;
	}
	p->joints.vein_count = 0;

	/* Banding happens once per template in leaf coordinates; every leaf made from it reuses the
	 * joint of each vertex, so leaves never band to a neighbour's joints. */
	int32_t** banding = calloc( (size_t) template_count, sizeof( int32_t* ) );
	if ( banding == NULL )
	{
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	int32_t** rank = calloc( (size_t) template_count, sizeof( int32_t* ) );
	int32_t** order = calloc( (size_t) template_count, sizeof( int32_t* ) );
	if ( rank == NULL || order == NULL )
	{
		free( rank );
		free( order );
		free( banding );
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	for ( int32_t k = 0; k < template_count && status == SERE_OK; ++k )
	{
		const sere_tri_mesh* m = templates[k].mesh;
		const sere_skeleton* s = templates[k].skeleton;
		sere_joint_grid* grid = NULL;
		banding[k] = malloc( (size_t) m->vertex_count * sizeof( int32_t ) );
		rank[k] = malloc( (size_t) m->vertex_count * sizeof( int32_t ) );
		int32_t* first = calloc( (size_t) s->joint_count + 1, sizeof( int32_t ) );
		status = banding[k] == NULL || rank[k] == NULL || first == NULL
					 ? SERE_ERR_MEMORY
					 : sere_joint_grid_create( s->x, s->y, s->z, s->joint_count, &grid );
		if ( status == SERE_OK )
		{
			status =
				sere_band( grid, NULL, NULL, NULL, m->x, m->y, m->z, m->vertex_count, banding[k], NULL, NULL, NULL );
		}
		if ( status == SERE_OK )
		{
			/* Each leaf's vertices are ordered by joint (stable), so skinning streams runs of
			 * one joint and a joint's region is contiguous in memory. */
			for ( int32_t i = 0; i < m->vertex_count; ++i )
			{
				++first[banding[k][i] + 1];
			}
			for ( int32_t j = 0; j < s->joint_count; ++j )
			{
				first[j + 1] += first[j];
			}
			for ( int32_t i = 0; i < m->vertex_count; ++i )
			{
				rank[k][i] = first[banding[k][i]]++;
			}
			/* Triangles follow their lowest vertex (stably), so consecutive triangles are
			 * neighbours too and share BVH walks in the piercing check. */
			order[k] = malloc( (size_t) m->triangle_count * sizeof( int32_t ) );
			int32_t* count = calloc( (size_t) m->vertex_count + 1, sizeof( int32_t ) );
			if ( order[k] == NULL || count == NULL )
			{
				status = SERE_ERR_MEMORY;
			}
			else
			{
				for ( int32_t t = 0; t < m->triangle_count; ++t )
				{
					const int32_t* c = m->tri + 3 * t;
					int32_t low = rank[k][c[0]] < rank[k][c[1]] ? rank[k][c[0]] : rank[k][c[1]];
					low = rank[k][c[2]] < low ? rank[k][c[2]] : low;
					++count[low + 1];
				}
				for ( int32_t i = 0; i < m->vertex_count; ++i )
				{
					count[i + 1] += count[i];
				}
				for ( int32_t t = 0; t < m->triangle_count; ++t )
				{
					const int32_t* c = m->tri + 3 * t;
					int32_t low = rank[k][c[0]] < rank[k][c[1]] ? rank[k][c[0]] : rank[k][c[1]];
					low = rank[k][c[2]] < low ? rank[k][c[2]] : low;
					order[k][count[low]++] = t;
				}
			}
			free( count );
		}
		free( first );
		sere_joint_grid_destroy( grid );
	}
	int32_t jf = 0, vf = 0, tf = 0;
	for ( int32_t k = 0; k < leaf_count && status == SERE_OK; ++k )
	{
		const sere_leaf_placement* l = leaves + k;
		const sere_leaf_template* t = templates + l->template_index;
		const sere_skeleton* s = t->skeleton;
		const sere_tri_mesh* m = t->mesh;
		p->joint_first[k] = jf;
		p->vertex_first[k] = vf;
		p->triangle_first[k] = tf;
		p->onset[k] = l->onset;
		/* World = base + scale · Rz(azimuth) Ry(−elevation) · leaf: the midvein (+x) is lifted
		 * by the elevation, then turned to its azimuth. */
		double ce = cos( l->elevation ), se = sin( l->elevation );
		double ca = cos( l->azimuth ), sa = sin( l->azimuth );
		double sc = l->scale;
		double rot[9] = { ca * ce, -sa, -ca * se, sa * ce, ca, -sa * se, se, 0.0, ce };
		for ( int32_t i = 0; i < s->joint_count; ++i )
		{
			double local[3] = { s->x[i], s->y[i], s->z[i] };
			double w[3];
			mat_vec( rot, local, w );
			int32_t g = jf + i;
			p->joints.x[g] = (float) ( l->base[0] + sc * w[0] );
			p->joints.y[g] = (float) ( l->base[1] + sc * w[1] );
			p->joints.z[g] = (float) ( l->base[2] + sc * w[2] );
			p->joints.parent[g] = s->parent[i] < 0 ? -1 : jf + s->parent[i];
			p->joints.end[g] = jf + s->end[i];
			p->joints.vein[g] = p->joints.vein_count + s->vein[i];
			p->joints.bend[g] = s->bend[i];
			p->joints.delay[g] = s->delay[i];
		}
		for ( int32_t i = 0; i < m->vertex_count; ++i )
		{
			double local[3] = { m->x[i], m->y[i], m->z[i] };
			double w[3];
			mat_vec( rot, local, w );
			int32_t v = vf + rank[l->template_index][i];
			int32_t j = jf + banding[l->template_index][i];
			p->rx[v] = p->x[v] = (float) ( l->base[0] + sc * w[0] );
			p->ry[v] = p->y[v] = (float) ( l->base[1] + sc * w[1] );
			p->rz[v] = p->z[v] = (float) ( l->base[2] + sc * w[2] );
			p->joint[v] = j;
			p->ox[v] = p->rx[v] - p->joints.x[j];
			p->oy[v] = p->ry[v] - p->joints.y[j];
			p->oz[v] = p->rz[v] - p->joints.z[j];
			p->u[v] = m->u[i];
			p->v[v] = m->v[i];
		}
		for ( int32_t q = 0; q < m->triangle_count; ++q )
		{
			const int32_t* c = m->tri + 3 * order[l->template_index][q];
			for ( int a = 0; a < 3; ++a )
			{
				p->tri[3 * ( tf + q ) + a] = vf + rank[l->template_index][c[a]];
			}
		}
		p->joints.vein_count += s->vein_count;
		jf += s->joint_count;
		vf += m->vertex_count;
		tf += m->triangle_count;
	}
	p->joint_first[leaf_count] = jf;
	p->vertex_first[leaf_count] = vf;
	p->triangle_first[leaf_count] = tf;
	for ( int32_t k = 0; k < template_count; ++k )
	{
		free( banding[k] );
		free( rank[k] );
		free( order[k] );
	}
	free( banding );
	free( rank );
	free( order );
	if ( status == SERE_OK )
	{
		status =
			sere_pierce_create( p->tri, p->triangle_count, p->vertex_count, p->x, p->y, p->z, p->joint, &p->pierce );
	}
	if ( status != SERE_OK )
	{
		goto fail;
	}
	*out = p;
	return SERE_OK;
fail:
	sere_plant_destroy( p );
	return status;
}

void sere_plant_reset( sere_plant* plant )
{
	size_t bytes = (size_t) plant->vertex_count * sizeof( float );
	memcpy( plant->x, plant->rx, bytes );
	memcpy( plant->y, plant->ry, bytes );
	memcpy( plant->z, plant->rz, bytes );
	memset( plant->pierce->off_pose, 0, (size_t) plant->vertex_count );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		plant->leaf_t[k] = 0.0f;
	}
}

sere_status sere_plant_frame( sere_plant* plant, float time, const sere_wilt_params* params, sere_wilt_stats* stats )
{
	sere_status status = check_wilt_params( params );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( plant == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !isfinite( time ) )
	{
		return SERE_ERR_NONFINITE;
	}
	/* The forward kinematics of a leaf is sequential from its root; leaves are independent. */
#pragma omp parallel for schedule( dynamic, 1 )
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		float t = time - plant->onset[k];
		t = t < 0.0f ? 0.0f : ( t > 1.0f ? 1.0f : t );
		plant->leaf_t[k] = t;
		int32_t first = plant->joint_first[k];
		pose_range( &plant->joints, first, plant->joint_first[k + 1] - first, t, params, &plant->frames,
					plant->leaf_stats + k );
	}
	sere_wilt_stats st;
	memset( &st, 0, sizeof( st ) );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		st.pose.turning += plant->leaf_stats[k].turning;
		st.pose.droop_limited += plant->leaf_stats[k].droop_limited;
		st.pose.angle_limited += plant->leaf_stats[k].angle_limited;
		st.pose.down_limited += plant->leaf_stats[k].down_limited;
	}
	if ( params->pierce )
	{
		sere_skin( &plant->frames, plant->joint, plant->ox, plant->oy, plant->oz, plant->vertex_count, plant->tx,
				   plant->ty, plant->tz );
		status = sere_pierce_step( plant->pierce, plant->x, plant->y, plant->z, plant->tx, plant->ty, plant->tz,
								   params->pierce_margin, &st.pierce );
		if ( status != SERE_OK )
		{
			return status;
		}
		float* swap;
		swap = plant->x, plant->x = plant->tx, plant->tx = swap;
		swap = plant->y, plant->y = plant->ty, plant->ty = swap;
		swap = plant->z, plant->z = plant->tz, plant->tz = swap;
	}
	else
	{
		sere_skin( &plant->frames, plant->joint, plant->ox, plant->oy, plant->oz, plant->vertex_count, plant->x,
				   plant->y, plant->z );
	}
	if ( stats != NULL )
	{
		*stats = st;
	}
	return SERE_OK;
}
