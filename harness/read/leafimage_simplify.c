/* sere harness — Smoothing and simplification of the traced outline, and the outline in leaf coordinates. */
#include "core/geometry.h"
#include "read/leafimage_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void leafimage_smooth( double* xy, int32_t n, int closed, double* scratch )
{
	static const double factor[2] = { 0.5, -0.53 };
	for ( int pass = 0; pass < SMOOTH_PASSES; ++pass )
	{
		for ( int f = 0; f < 2; ++f )
		{
			for ( int32_t i = 0; i < n; ++i )
			{
				int fixed = !closed && ( i == 0 || i == n - 1 );
				int32_t a = i > 0 ? i - 1 : n - 1, b = i + 1 < n ? i + 1 : 0;
				for ( int c = 0; c < 2; ++c )
				{
					double mean = 0.5 * ( xy[2 * a + c] + xy[2 * b + c] );
					scratch[2 * i + c] = fixed ? xy[2 * i + c] : xy[2 * i + c] + factor[f] * ( mean - xy[2 * i + c] );
				}
			}
			memcpy( xy, scratch, sizeof( double ) * 2 * (size_t) n );
		}
	}
}

/* Douglas-Peucker between vertices first and last (both kept), iteratively; stack holds
 * 2 (last - first + 1) ints. */
static void simplify( const double* xy, int32_t first, int32_t last, double tolerance, uint8_t* keep, int32_t* stack )
{
	int32_t top = 0;
	stack[top++] = first;
	stack[top++] = last;
	while ( top > 0 )
	{
		int32_t b = stack[--top], a = stack[--top];
		double worst = tolerance;
		int32_t at = -1;
		for ( int32_t i = a + 1; i < b; ++i )
		{
			double d = sere_point_segment_distance( xy + 2 * i, xy + 2 * a, xy + 2 * b );
			if ( d > worst )
			{
				worst = d, at = i;
			}
		}
		if ( at >= 0 )
		{
			keep[at] = 1;
			stack[top++] = a;
			stack[top++] = at;
			stack[top++] = at;
			stack[top++] = b;
		}
	}
}

/* Simplifies a polyline keeping every vertex already marked in keep. */
void leafimage_simplify_between_kept( const double* xy, int32_t n, double tolerance, uint8_t* keep, int32_t* stack )
{
	int32_t a = 0;
	for ( int32_t b = 1; b < n; ++b )
	{
		if ( keep[b] )
		{
			simplify( xy, a, b, tolerance, keep, stack );
			a = b;
		}
	}
}

double leafimage_outline_distance( const double* xy, int32_t n, const double* p )
{
	double d = INFINITY;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		d = fmin( d, sere_point_segment_distance( p, xy + 2 * j, xy + 2 * i ) );
	}
	return d;
}

/* Smooths and simplifies the traced loop (each optional), puts the base where the outline
 * passes nearest the dot, maps to leaf coordinates and orients counter-clockwise. Fails with
 * SERE_ERR_GEOMETRY if the result is not a simple polygon (a sub-pixel neck), so the caller can
 * retry with less processing. */
/* Simplifies the closed loop (n points, point n repeating point 0) keeping point 0 and the point
 * farthest from it, or keeps every point; writes the kept points to out and returns their number. */
static int32_t simplified_loop( const double* loop, int32_t n, int do_simplify, uint8_t* keep, int32_t* stack,
								double* out )
{
	if ( do_simplify )
	{
		int32_t far = 0;
		for ( int32_t i = 1; i < n; ++i )
		{
			if ( hypot( loop[2 * i] - loop[0], loop[2 * i + 1] - loop[1] ) >
				 hypot( loop[2 * far] - loop[0], loop[2 * far + 1] - loop[1] ) )
			{
				far = i;
			}
		}
		keep[0] = keep[far] = keep[n] = 1;
		leafimage_simplify_between_kept( loop, n + 1, OUTLINE_TOLERANCE, keep, stack );
	}
	else
	{
		memset( keep, 1, (size_t) n + 1 );
	}
	int32_t m = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( keep[i] )
		{
			out[2 * m] = loop[2 * i], out[2 * m + 1] = loop[2 * i + 1];
			m += 1;
		}
	}
	return m;
}

/* The base: the point of the loop (m points) nearest the dot's centre, which becomes a vertex.
 * Within a simplification tolerance of a vertex the base is that vertex, not a new one that
 * would leave a sliver of an edge. *first is the vertex the loop continues from after the base,
 * *inserted tells whether the base is a new vertex; returns the dot's distance to the loop. */
static double place_base( const double* loop, int32_t m, double dot_x, double dot_y, double base[2], int32_t* first,
						  int* inserted )
{
	const double dot[2] = { dot_x, dot_y };
	int32_t segment = 0;
	double best = INFINITY;
	for ( int32_t i = 0; i < m; ++i )
	{
		double d = sere_point_segment_distance( dot, loop + 2 * i, loop + 2 * ( ( i + 1 ) % m ) );
		if ( d < best )
		{
			best = d, segment = i;
		}
	}
	const double* a = loop + 2 * segment;
	const double* b = loop + 2 * ( ( segment + 1 ) % m );
	double ex = b[0] - a[0], ey = b[1] - a[1], length2 = ex * ex + ey * ey;
	double t =
		length2 > 0.0 ? fmin( 1.0, fmax( 0.0, ( ( dot_x - a[0] ) * ex + ( dot_y - a[1] ) * ey ) / length2 ) ) : 0.0;
	base[0] = a[0] + t * ex, base[1] = a[1] + t * ey;
	*first = segment;
	*inserted = 0;
	if ( hypot( base[0] - a[0], base[1] - a[1] ) <= OUTLINE_TOLERANCE )
	{
		base[0] = a[0], base[1] = a[1];
	}
	else if ( hypot( base[0] - b[0], base[1] - b[1] ) <= OUTLINE_TOLERANCE )
	{
		base[0] = b[0], base[1] = b[1];
		*first = ( segment + 1 ) % m;
	}
	else
	{
		*inserted = 1;
		*first = ( segment + 1 ) % m;
	}
	return best;
}

/* Reverses all but vertex 0 of a clockwise polygon of count points. */
static void make_counter_clockwise( double* xy, int32_t count )
{
	double twice_area = 0.0;
	for ( int32_t i = 0, j = count - 1; i < count; j = i++ )
	{
		twice_area += xy[2 * j] * xy[2 * i + 1] - xy[2 * i] * xy[2 * j + 1];
	}
	for ( int32_t i = 1, j = count - 1; twice_area < 0.0 && i < j; ++i, --j )
	{
		double x = xy[2 * i], y = xy[2 * i + 1];
		xy[2 * i] = xy[2 * j], xy[2 * i + 1] = xy[2 * j + 1];
		xy[2 * j] = x, xy[2 * j + 1] = y;
	}
}

sere_status leafimage_make_outline( const points* traced, int do_smooth, int do_simplify, double dot_x, double dot_y,
									outline* o )
{
	const int32_t n = traced->count;
	double* loop = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	double* scratch = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	uint8_t* keep = calloc( (size_t) n + 1, 1 );
	int32_t* stack = malloc( sizeof( int32_t ) * 2 * ( (size_t) n + 2 ) );
	o->xy = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	if ( loop == NULL || scratch == NULL || keep == NULL || stack == NULL || o->xy == NULL )
	{
		free( loop ), free( scratch ), free( keep ), free( stack ), free( o->xy );
		o->xy = NULL;
		return SERE_ERR_MEMORY;
	}
	memcpy( loop, traced->xy, sizeof( double ) * 2 * (size_t) n );
	if ( do_smooth )
	{
		leafimage_smooth( loop, n, 1, scratch );
	}
	loop[2 * n] = loop[0], loop[2 * n + 1] = loop[1];
	int32_t m = simplified_loop( loop, n, do_simplify, keep, stack, scratch );
	double base[2];
	int32_t first;
	int inserted;
	o->dot_distance = place_base( scratch, m, dot_x, dot_y, base, &first, &inserted );
	double scale = 0.0;
	for ( int32_t i = 0; i < m; ++i )
	{
		scale = fmax( scale, hypot( scratch[2 * i] - base[0], scratch[2 * i + 1] - base[1] ) );
	}
	/* y flips up (the clockwise-on-screen trace becomes counter-clockwise; checked below): vertex 0
	 * is the base, then the loop from `first` on, mapped by x = (px - bx) / s, y = (by - py) / s. */
	int32_t count = 0;
	o->xy[2 * count] = 0.0, o->xy[2 * count + 1] = 0.0;
	count += 1;
	for ( int32_t k = 0; k < m - ( inserted ? 0 : 1 ); ++k )
	{
		const double* p = scratch + 2 * ( ( first + k + ( inserted ? 0 : 1 ) ) % m );
		o->xy[2 * count] = ( p[0] - base[0] ) / scale;
		o->xy[2 * count + 1] = ( base[1] - p[1] ) / scale;
		count += 1;
	}
	free( loop ), free( scratch ), free( keep ), free( stack );
	make_counter_clockwise( o->xy, count );
	o->count = count;
	o->base_px = base[0], o->base_py = base[1], o->scale = scale;
	sere_leaf_shape shape = { 0.0, 0.0, count, o->xy, 0, NULL, 0, NULL };
	sere_shape_check check;
	if ( sere_shape_validate( &shape, &check ) != SERE_OK )
	{
		free( o->xy );
		o->xy = NULL;
		return SERE_ERR_GEOMETRY;
	}
	return SERE_OK;
}

/* Zhang-Suen thinning of the pixels listed in live (count of them; pixels outside the image
 * count as empty). Each sub-iteration marks pixels 2 and deletes them at its end, so every test
 * in it sees its starting image; the list shrinks with the strokes, so the cost follows the
 * vein pixels, not the image. */
