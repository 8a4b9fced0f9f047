#include "mesh/sample.h"
#include "mesh/triangulate.h"
#include "read/leafload.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Checks the CDT properties: counter-clockwise triangles, every constraint present as an edge
 * (split at points lying on it), Euler's formula for a disk, and the empty circumcircle of
 * every edge that is not constrained. */
static void check_cdt( const char* name, const sere_cdt_input* in, const sere_triangulation* t, int expect_all_used )
{
	int32_t n = in->point_count;
	const double* x = in->x;
	const double* y = in->y;
	/* edges as sorted (lo, hi) pairs with their triangles */
	int32_t edge_count = 3 * t->triangle_count;
	int64_t* keys = malloc( sizeof( int64_t ) * edge_count );
	uint8_t* used = calloc( n, 1 );
	for ( int32_t k = 0; k < t->triangle_count; ++k )
	{
		const int32_t* v = t->tri + 3 * k;
		double area = ( x[v[1]] - x[v[0]] ) * ( y[v[2]] - y[v[0]] ) - ( x[v[2]] - x[v[0]] ) * ( y[v[1]] - y[v[0]] );
		cr_assert_gt( area, 0.0, "%s: triangle %d not counter-clockwise", name, k );
		for ( int e = 0; e < 3; ++e )
		{
			int32_t a = v[e], b = v[( e + 1 ) % 3];
			used[a] = 1;
			keys[3 * k + e] = a < b ? (int64_t) a * n + b : (int64_t) b * n + a;
		}
	}
	/* Euler for a disk: V − E + F = 1. */
	int32_t vertices = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		vertices += used[i];
	}
	int64_t* sorted = malloc( sizeof( int64_t ) * edge_count );
	memcpy( sorted, keys, sizeof( int64_t ) * edge_count );
	for ( int32_t i = 1; i < edge_count; ++i ) /* insertion sort is fine for test sizes */
	{
		int64_t key = sorted[i];
		int32_t j = i - 1;
		while ( j >= 0 && sorted[j] > key )
		{
			sorted[j + 1] = sorted[j];
			--j;
		}
		sorted[j + 1] = key;
	}
	int32_t unique = 0;
	for ( int32_t i = 0; i < edge_count; ++i )
	{
		unique += i == 0 || sorted[i] != sorted[i - 1];
	}
	cr_expect_eq( vertices - unique + t->triangle_count, 1, "%s: Euler characteristic", name );
	if ( expect_all_used )
	{
		cr_expect_eq( vertices, n - t->merged_count, "%s: every point is a vertex", name );
	}
	/* Empty circumcircle: no vertex strictly inside any triangle's circumcircle, except behind
	 * a constraint. Checked on unconstrained interior edges: the opposite vertex of the
	 * neighbour must not be inside (long double; 1e-12 relative slack for the rounding of
	 * coordinates of size ~1). */
	for ( int32_t k = 0; k < t->triangle_count; ++k )
	{
		const int32_t* v = t->tri + 3 * k;
		for ( int32_t m = k + 1; m < t->triangle_count; ++m )
		{
			const int32_t* w = t->tri + 3 * m;
			int shared = 0, other = -1;
			for ( int q = 0; q < 3; ++q )
			{
				int hit = w[q] == v[0] || w[q] == v[1] || w[q] == v[2];
				shared += hit;
				other = hit ? other : w[q];
			}
			if ( shared != 2 )
			{
				continue;
			}
			/* the shared edge: is it constrained? */
			int a = -1, b = -1;
			for ( int q = 0; q < 3; ++q )
			{
				if ( v[q] == w[0] || v[q] == w[1] || v[q] == w[2] )
				{
					if ( a < 0 )
						a = v[q];
					else
						b = v[q];
				}
			}
			int constrained = 0;
			int32_t nb = in->boundary_count;
			for ( int32_t s = 0; s < nb && !constrained; ++s )
			{
				int32_t p = t->vertex_map[s], q = t->vertex_map[( s + 1 ) % nb];
				constrained = ( p == a && q == b ) || ( p == b && q == a );
			}
			for ( int32_t s = 0; s < in->segment_count && !constrained; ++s )
			{
				int32_t p = t->vertex_map[in->segments[2 * s]], q = t->vertex_map[in->segments[2 * s + 1]];
				constrained = ( p == a && q == b ) || ( p == b && q == a );
			}
			if ( constrained )
			{
				continue;
			}
			long double ax = x[v[0]] - x[other], ay = y[v[0]] - y[other];
			long double bx = x[v[1]] - x[other], by = y[v[1]] - y[other];
			long double cx = x[v[2]] - x[other], cy = y[v[2]] - y[other];
			long double det = ( ax * ax + ay * ay ) * ( bx * cy - cx * by ) +
							  ( bx * bx + by * by ) * ( cx * ay - ax * cy ) +
							  ( cx * cx + cy * cy ) * ( ax * by - bx * ay );
			cr_assert_leq( det, 1e-12L, "%s: point %d inside the circumcircle of triangle %d", name, other, k );
		}
	}
	free( keys ), free( sorted ), free( used );
}

Test( triangulate, adversarial_inputs )
{
	double x[200], y[200];
	int32_t n = 0, g = 8;
	/* a grid: every interior quad is cocircular; long collinear runs on the boundary */
	for ( int32_t i = 0; i < g; ++i )
		x[n] = i, y[n++] = 0;
	for ( int32_t j = 0; j < g; ++j )
		x[n] = g, y[n++] = j;
	for ( int32_t i = g; i > 0; --i )
		x[n] = i, y[n++] = g;
	for ( int32_t j = g; j > 0; --j )
		x[n] = 0, y[n++] = j;
	int32_t nb = n;
	for ( int32_t j = 1; j < g; ++j )
		for ( int32_t i = 1; i < g; ++i )
			x[n] = i, y[n++] = j;
	sere_cdt_input in = { x, y, n, nb, NULL, 0 };
	sere_triangulation t;
	cr_assert_eq( sere_triangulate( &in, &t ), SERE_OK );
	cr_expect_eq( t.triangle_count, 2 * n - nb - 2 );
	check_cdt( "grid", &in, &t, 1 );
	sere_triangulation_destroy( &t );

	/* a constraint through six collinear interior points: split at each */
	int32_t segment[2] = { nb + 0, nb + 6 };
	in.segments = segment;
	in.segment_count = 1;
	cr_assert_eq( sere_triangulate( &in, &t ), SERE_OK );
	check_cdt( "collinear constraint", &in, &t, 1 );
	sere_triangulation_destroy( &t );

	/* duplicates merge into the first copy */
	x[n] = 3, y[n++] = 3;
	x[n] = 3, y[n++] = 3;
	in.point_count = n;
	cr_assert_eq( sere_triangulate( &in, &t ), SERE_OK );
	cr_expect_eq( t.merged_count, 2 );
	cr_expect_eq( t.vertex_map[n - 1], nb + 2 * ( g - 1 ) + 2 );
	check_cdt( "duplicates", &in, &t, 1 );
	sere_triangulation_destroy( &t );
	in.point_count = n - 2;

	/* crossing constraints cannot be honoured without Steiner points */
	int32_t crossing[4] = { nb + 0, nb + 48, nb + 6, nb + 42 };
	in.segments = crossing;
	in.segment_count = 2;
	cr_expect_eq( sere_triangulate( &in, &t ), SERE_ERR_GEOMETRY );

	/* a thin spike and two lobes nearly touching (gap 1e-6 of the size) */
	double spx[7] = { 0, 1, 1, 0.5, 0.50001, 0.49999, 0 }, spy[7] = { 0, 0, 1, 1, 3, 3, 1 };
	sere_cdt_input spike = { spx, spy, 7, 7, NULL, 0 };
	cr_assert_eq( sere_triangulate( &spike, &t ), SERE_OK );
	check_cdt( "spike", &spike, &t, 1 );
	sere_triangulation_destroy( &t );
	double lx[8] = { 0, 1, 1, 0.5 + 1e-6, 0.5 + 1e-6, 0.5 - 1e-6, 0.5 - 1e-6, 0 };
	double ly[8] = { 0, 0, 1, 1, 0.2, 0.2, 1, 1 };
	sere_cdt_input lobes = { lx, ly, 8, 8, NULL, 0 };
	cr_assert_eq( sere_triangulate( &lobes, &t ), SERE_OK );
	check_cdt( "nearly touching lobes", &lobes, &t, 1 );
	sere_triangulation_destroy( &t );

	/* errors: clockwise, self-intersecting, NaN, too few points */
	double cwx[4] = { 0, 0, 1, 1 }, cwy[4] = { 0, 1, 1, 0 };
	sere_cdt_input cw = { cwx, cwy, 4, 4, NULL, 0 };
	cr_expect_eq( sere_triangulate( &cw, &t ), SERE_ERR_GEOMETRY );
	double bx[4] = { 0, 1, 1, 0 }, by[4] = { 0, 1, 0, 1 };
	sere_cdt_input bow = { bx, by, 4, 4, NULL, 0 };
	cr_expect_eq( sere_triangulate( &bow, &t ), SERE_ERR_GEOMETRY );
	double nx[3] = { 0, 1, NAN }, ny[3] = { 0, 0, 1 };
	sere_cdt_input bad = { nx, ny, 3, 3, NULL, 0 };
	cr_expect_eq( sere_triangulate( &bad, &t ), SERE_ERR_NONFINITE );
	bad.point_count = 2;
	cr_expect_eq( sere_triangulate( &bad, &t ), SERE_ERR_ARGUMENT );
}

Test( triangulate, shipped_leaves_are_constrained_delaunay )
{
	const char* names[] = { "maple", "plane",	"wisteria", "hibiscus",	 "ginkgo",
							"grass", "hickory", "cucumber", "watermelon" };
	for ( size_t k = 0; k < sizeof( names ) / sizeof( names[0] ); ++k )
	{
		char path[256], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", names[k] );
		sere_leaf_source leaf;
		cr_assert_eq( sere_leaf_source_load( path, &leaf, err, sizeof( err ) ), 0, "%s", err );
		sere_sample_params params = { .point_count = 700, .boundary_count = 90, .seed = 2, .candidates = 0 };
		sere_samples samples;
		cr_assert_eq( sere_sample_leaf( &leaf.file.shape, &params, &samples ), SERE_OK, "%s", names[k] );
		sere_cdt_input in = { samples.x,		   samples.y,
							  samples.point_count, samples.boundary_count,
							  samples.segments,	   samples.segment_count };
		sere_triangulation t;
		cr_assert_eq( sere_triangulate( &in, &t ), SERE_OK, "%s", names[k] );
		cr_expect_eq( t.triangle_count, 2 * samples.point_count - samples.boundary_count - 2, "%s", names[k] );
		check_cdt( names[k], &in, &t, 1 );
		sere_triangulation_destroy( &t );
		sere_samples_destroy( &samples );
		sere_leaf_source_destroy( &leaf );
	}
}
