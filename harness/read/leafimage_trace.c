/* sere harness — Tracing: the silhouette's outline by marching squares. */
#include "read/leafimage_shared.h"

#include "core/array.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int in_region( const reader* r, int x, int y )
{
	return x >= 0 && y >= 0 && x < r->w && y < r->h && r->region[y * r->w + x];
}

static double coverage( const reader* r, int x, int y )
{
	if ( x < 0 || y < 0 || x >= r->w || y >= r->h )
	{
		return 0.0;
	}
	int32_t i = y * r->w + x;
	return r->ink_max[i] > 0 ? fmin( 1.0, (double) r->ink[i] / r->ink_max[i] ) : 0.0;
}

/* The inside and outside pixel of the crack leaving corner (cx, cy) in direction d (0 +x, 1 +y,
 * 2 -x, 3 -y; y down), with the inside on the walker's right as seen on screen. */
static void crack_pixels( int cx, int cy, int d, int* in, int* out )
{
	static const int table[4][4] = { { 0, 0, 0, -1 }, { -1, 0, 0, 0 }, { -1, -1, -1, 0 }, { 0, -1, -1, -1 } };
	in[0] = cx + table[d][0], in[1] = cy + table[d][1];
	out[0] = cx + table[d][2], out[1] = cy + table[d][3];
}

/* Marching squares along the region's boundary: follows the cracks between inside and outside
 * pixels (clockwise on screen) and puts one vertex on the segment joining the two pixel centres
 * of each crack, where the blade's coverage crosses 1/2. For an edge parallel to the crack,
 * inside coverage ci and outside co place it ci + co - 1/2 from the inside centre exactly. */
static sere_status trace_outline( reader* r, int32_t region_count, points* out )
{
	int32_t start = 0;
	while ( !r->region[start] )
	{
		start += 1;
	}
	const int sx = start % r->w, sy = start / r->w;
	static const int step[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
	int cx = sx, cy = sy, d = 0;
	const int64_t limit = 4 * (int64_t) region_count + 8;
	do
	{
		int in[2], outside[2];
		crack_pixels( cx, cy, d, in, outside );
		double ci = fmax( 0.5, coverage( r, in[0], in[1] ) ), co = fmin( 0.5, coverage( r, outside[0], outside[1] ) );
		double t = fmin( 0.98, fmax( 0.02, ci + co - 0.5 ) );
		const double point[2] = { in[0] + 0.5 + t * ( outside[0] - in[0] ), in[1] + 0.5 + t * ( outside[1] - in[1] ) };
		double* xy = sere_array_append( out->xy, &out->count, &out->capacity, 1024, point, sizeof( point ) );
		if ( xy == NULL )
		{
			return leafimage_fail( r, SERE_ERR_MEMORY, "out of memory tracing the outline" );
		}
		out->xy = xy;
		cx += step[d][0], cy += step[d][1];
		int turned = 0;
		for ( int k = 3; k <= 5 && !turned; ++k ) /* left, straight, right */
		{
			int next = ( d + k ) % 4;
			crack_pixels( cx, cy, next, in, outside );
			if ( in_region( r, in[0], in[1] ) && !in_region( r, outside[0], outside[1] ) )
			{
				d = next;
				turned = 1;
			}
		}
		if ( !turned || out->count > limit )
		{
			return leafimage_fail( r, SERE_ERR_GEOMETRY, "cannot trace the silhouette" );
		}
	} while ( cx != sx || cy != sy || d != 0 );
	return SERE_OK;
}

/* Taubin's lambda|mu smoothing: a shrinking Laplacian step then an inflating one, which removes
 * pixel-scale wiggles without shrinking the curve. Open polylines keep their end points. */
sere_status leafimage_trace_png( reader* r, points* traced, const char* no_leaf )
{
	sere_status status = leafimage_load_png( r );
	if ( status != SERE_OK )
	{
		return status;
	}
	r->kind = malloc( (size_t) r->n );
	r->ink = malloc( (size_t) r->n );
	r->ink_max = malloc( (size_t) r->n );
	r->region = malloc( (size_t) r->n );
	r->queue = malloc( sizeof( int32_t ) * (size_t) r->n );
	if ( r->kind == NULL || r->ink == NULL || r->ink_max == NULL || r->region == NULL || r->queue == NULL )
	{
		return leafimage_fail( r, SERE_ERR_MEMORY, "out of memory for a %d x %d image", r->w, r->h );
	}
	leafimage_classify( r );
	free( r->rgba );
	r->rgba = NULL;
	int32_t blade = leafimage_silhouette( r );
	if ( blade < MIN_BLADE_PIXELS )
	{
		return leafimage_fail( r, SERE_ERR_GEOMETRY, "no leaf: fewer than %d %s", MIN_BLADE_PIXELS, no_leaf );
	}
	return trace_outline( r, blade, traced );
}
