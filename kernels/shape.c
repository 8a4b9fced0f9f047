#include "shape.h"

#include <math.h>
#include <stdlib.h>

/* Distances below this fraction of the leaf's size count as "on" a curve (a branch point on
 * its parent, the base on the outline): generous enough for text files written with 6 digits. */
#define SHAPE_TOLERANCE 1e-4

const char* sere_shape_problem_text( sere_shape_problem problem )
{
	switch ( problem )
	{
		case SERE_SHAPE_OK:
			return "ok";
		case SERE_SHAPE_FEW_OUTLINE_POINTS:
			return "an outline needs at least 3 points";
		case SERE_SHAPE_NONFINITE:
			return "NaN or infinite coordinate";
		case SERE_SHAPE_SELF_INTERSECTING:
			return "the outline intersects itself (or is not counter-clockwise)";
		case SERE_SHAPE_VEIN_OUTSIDE:
			return "vein point outside the outline";
		case SERE_SHAPE_VEIN_DISCONNECTED:
			return "vein not connected to the base (its first point must be the base or lie on its parent)";
		case SERE_SHAPE_BAD_VEIN:
			return "vein with fewer than 2 points, a bad parent index or order";
		case SERE_SHAPE_BASE_OFF_OUTLINE:
			return "the base does not lie on the outline";
	}
	return "unknown problem";
}

double sere_shape_area( const sere_leaf_shape* shape )
{
	const double* p = shape->outline_xy;
	int32_t n = shape->outline_count;
	double twice = 0.0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		twice += p[2 * j] * p[2 * i + 1] - p[2 * i] * p[2 * j + 1];
	}
	return 0.5 * twice;
}

double sere_shape_perimeter( const sere_leaf_shape* shape )
{
	const double* p = shape->outline_xy;
	int32_t n = shape->outline_count;
	double length = 0.0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		length += hypot( p[2 * i] - p[2 * j], p[2 * i + 1] - p[2 * j + 1] );
	}
	return length;
}

static double orient( double ax, double ay, double bx, double by, double cx, double cy )
{
	return ( bx - ax ) * ( cy - ay ) - ( by - ay ) * ( cx - ax );
}

static int segments_cross( const double* a, const double* b, const double* c, const double* d )
{
	double o1 = orient( a[0], a[1], b[0], b[1], c[0], c[1] ), o2 = orient( a[0], a[1], b[0], b[1], d[0], d[1] );
	double o3 = orient( c[0], c[1], d[0], d[1], a[0], a[1] ), o4 = orient( c[0], c[1], d[0], d[1], b[0], b[1] );
	if ( ( ( o1 > 0 && o2 < 0 ) || ( o1 < 0 && o2 > 0 ) ) && ( ( o3 > 0 && o4 < 0 ) || ( o3 < 0 && o4 > 0 ) ) )
	{
		return 1;
	}
	/* Touching or overlapping collinear edges also make the outline non-simple. */
	double lo_x = fmin( a[0], b[0] ), hi_x = fmax( a[0], b[0] ), lo_y = fmin( a[1], b[1] ), hi_y = fmax( a[1], b[1] );
	if ( o1 == 0 && c[0] >= lo_x && c[0] <= hi_x && c[1] >= lo_y && c[1] <= hi_y )
	{
		return 1;
	}
	if ( o2 == 0 && d[0] >= lo_x && d[0] <= hi_x && d[1] >= lo_y && d[1] <= hi_y )
	{
		return 1;
	}
	return 0;
}

static double point_segment_distance( const double* p, const double* a, const double* b )
{
	double ex = b[0] - a[0], ey = b[1] - a[1];
	double length2 = ex * ex + ey * ey;
	double t = length2 > 0.0 ? ( ( p[0] - a[0] ) * ex + ( p[1] - a[1] ) * ey ) / length2 : 0.0;
	t = fmin( 1.0, fmax( 0.0, t ) );
	return hypot( a[0] + t * ex - p[0], a[1] + t * ey - p[1] );
}

static int inside( const double* xy, int32_t n, const double* p )
{
	int in = 0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		double xi = xy[2 * i], yi = xy[2 * i + 1], xj = xy[2 * j], yj = xy[2 * j + 1];
		if ( ( yi > p[1] ) != ( yj > p[1] ) && p[0] < xj + ( p[1] - yj ) * ( xi - xj ) / ( yi - yj ) )
		{
			in = !in;
		}
	}
	return in;
}

typedef struct span
{
	double lo;
	int32_t edge;
} span;

static int compare_span( const void* pa, const void* pb )
{
	const span* a = pa;
	const span* b = pb;
	if ( a->lo != b->lo )
	{
		return a->lo < b->lo ? -1 : 1;
	}
	return ( a->edge > b->edge ) - ( a->edge < b->edge );
}

static sere_status fail( sere_shape_check* check, sere_shape_problem problem, int32_t vein, int32_t point )
{
	check->problem = problem;
	check->vein = vein;
	check->point = point;
	return problem == SERE_SHAPE_NONFINITE ? SERE_ERR_NONFINITE : SERE_ERR_GEOMETRY;
}

sere_status sere_shape_validate( const sere_leaf_shape* shape, sere_shape_check* check )
{
	check->problem = SERE_SHAPE_OK;
	check->vein = -1;
	check->point = -1;
	if ( shape == NULL || ( shape->outline_count > 0 && shape->outline_xy == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = shape->outline_count;
	const double* xy = shape->outline_xy;
	if ( n < 3 )
	{
		return fail( check, SERE_SHAPE_FEW_OUTLINE_POINTS, -1, -1 );
	}
	double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( !isfinite( xy[2 * i] ) || !isfinite( xy[2 * i + 1] ) )
		{
			return fail( check, SERE_SHAPE_NONFINITE, -1, i );
		}
		x0 = fmin( x0, xy[2 * i] ), x1 = fmax( x1, xy[2 * i] );
		y0 = fmin( y0, xy[2 * i + 1] ), y1 = fmax( y1, xy[2 * i + 1] );
	}
	for ( int32_t i = 0; i < 2 * shape->vein_point_count; ++i )
	{
		if ( !isfinite( shape->vein_xy[i] ) )
		{
			return fail( check, SERE_SHAPE_NONFINITE, -1, i / 2 );
		}
	}
	if ( !isfinite( shape->base_x ) || !isfinite( shape->base_y ) )
	{
		return fail( check, SERE_SHAPE_NONFINITE, -1, -1 );
	}
	if ( !( sere_shape_area( shape ) > 0.0 ) )
	{
		return fail( check, SERE_SHAPE_SELF_INTERSECTING, -1, 0 );
	}
	const double tolerance = SHAPE_TOLERANCE * fmax( x1 - x0, y1 - y0 );

	/* Simple polygon: sweep edges by their lowest x and test each against the edges whose x
	 * ranges overlap (n log n for leaf outlines, whose edges are short). */
	span* spans = malloc( sizeof( span ) * (size_t) n );
	if ( spans == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t j = ( i + 1 ) % n;
		spans[i].lo = fmin( xy[2 * i], xy[2 * j] );
		spans[i].edge = i;
	}
	qsort( spans, (size_t) n, sizeof( span ), compare_span );
	for ( int32_t s = 0; s < n; ++s )
	{
		int32_t e = spans[s].edge, e1 = ( e + 1 ) % n;
		double hi = fmax( xy[2 * e], xy[2 * e1] );
		for ( int32_t r = s + 1; r < n && spans[r].lo <= hi; ++r )
		{
			int32_t f = spans[r].edge, f1 = ( f + 1 ) % n;
			if ( f == e1 || f1 == e )
			{
				/* Adjacent edges share one point; they overlap only when folding back. */
				int32_t shared = f == e1 ? e1 : e;
				int32_t a = f == e1 ? e : e1, b = f == e1 ? f1 : f;
				double o =
					orient( xy[2 * a], xy[2 * a + 1], xy[2 * shared], xy[2 * shared + 1], xy[2 * b], xy[2 * b + 1] );
				double dot = ( xy[2 * a] - xy[2 * shared] ) * ( xy[2 * b] - xy[2 * shared] ) +
							 ( xy[2 * a + 1] - xy[2 * shared + 1] ) * ( xy[2 * b + 1] - xy[2 * shared + 1] );
				if ( n > 3 && o == 0 && dot > 0 )
				{
					free( spans );
					return fail( check, SERE_SHAPE_SELF_INTERSECTING, -1, shared );
				}
				continue;
			}
			if ( segments_cross( xy + 2 * e, xy + 2 * e1, xy + 2 * f, xy + 2 * f1 ) ||
				 segments_cross( xy + 2 * f, xy + 2 * f1, xy + 2 * e, xy + 2 * e1 ) )
			{
				free( spans );
				return fail( check, SERE_SHAPE_SELF_INTERSECTING, -1, e1 );
			}
		}
	}
	free( spans );

	/* The base lies on the outline. */
	double base[2] = { shape->base_x, shape->base_y };
	double nearest = INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		nearest = fmin( nearest, point_segment_distance( base, xy + 2 * i, xy + 2 * ( ( i + 1 ) % n ) ) );
	}
	if ( nearest > tolerance )
	{
		return fail( check, SERE_SHAPE_BASE_OFF_OUTLINE, -1, -1 );
	}

	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		if ( vein->count < 2 || vein->first < 0 || vein->first + vein->count > shape->vein_point_count ||
			 vein->parent >= v || vein->parent < -1 || vein->order < 1 )
		{
			return fail( check, SERE_SHAPE_BAD_VEIN, v, vein->first );
		}
		const double* p = shape->vein_xy + 2 * vein->first;
		if ( vein->parent < 0 )
		{
			if ( hypot( p[0] - base[0], p[1] - base[1] ) > tolerance )
			{
				return fail( check, SERE_SHAPE_VEIN_DISCONNECTED, v, vein->first );
			}
		}
		else
		{
			const sere_vein* parent = shape->veins + vein->parent;
			const double* q = shape->vein_xy + 2 * parent->first;
			double d = INFINITY;
			for ( int32_t k = 0; k + 1 < parent->count; ++k )
			{
				d = fmin( d, point_segment_distance( p, q + 2 * k, q + 2 * k + 2 ) );
			}
			if ( d > tolerance )
			{
				return fail( check, SERE_SHAPE_VEIN_DISCONNECTED, v, vein->first );
			}
		}
		/* Every later point strictly inside (a vein starting at the base starts on the outline). */
		for ( int32_t k = 1; k < vein->count; ++k )
		{
			if ( !inside( xy, n, p + 2 * k ) )
			{
				return fail( check, SERE_SHAPE_VEIN_OUTSIDE, v, vein->first + k );
			}
		}
	}
	return SERE_OK;
}
