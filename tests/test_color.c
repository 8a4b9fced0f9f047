/* Constraint coloring for parallel Gauss–Seidel (Sec. 5.2). */
#include "solve/color.h"

#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

typedef struct graph
{
	int32_t n, count;
	int32_t *a, *b;
} graph;

static void graph_add( graph* g, int32_t i, int32_t j )
{
	g->a[g->count] = i;
	g->b[g->count] = j;
	g->count += 1;
}

/* The connectivity of a triangle–Voronoi double layer (Sec. 3.2) on an nx × ny cell grid:
 * T springs on triangle edges, V springs across interior edges, 3 L springs per triangle. */
static graph double_layer( int32_t nx, int32_t ny )
{
	const int32_t nt = ( nx + 1 ) * ( ny + 1 ), f = 2 * nx * ny;
	graph g = { nt + f, 0, malloc( sizeof( int32_t ) * (size_t) ( 3 * nt + 5 * f ) ),
				malloc( sizeof( int32_t ) * (size_t) ( 3 * nt + 5 * f ) ) }; /* T ≤ 3N, V ≤ 1.5F, L = 3F */
	for ( int32_t j = 0; j <= ny; ++j )
	{
		for ( int32_t i = 0; i <= nx; ++i )
		{
			int32_t v = j * ( nx + 1 ) + i;
			if ( i < nx )
			{
				graph_add( &g, v, v + 1 );
			}
			if ( j < ny )
			{
				graph_add( &g, v, v + nx + 1 );
			}
			if ( i < nx && j < ny )
			{
				graph_add( &g, v, v + nx + 2 );
			}
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t v00 = j * ( nx + 1 ) + i, v10 = v00 + 1, v01 = v00 + nx + 1, v11 = v01 + 1;
			int32_t t0 = nt + 2 * ( j * nx + i ), t1 = t0 + 1;
			graph_add( &g, t0, t1 );
			if ( j > 0 )
			{
				graph_add( &g, nt + 2 * ( ( j - 1 ) * nx + i ) + 1, t0 );
			}
			if ( i > 0 )
			{
				graph_add( &g, nt + 2 * ( j * nx + i - 1 ), t1 );
			}
			graph_add( &g, v00, t0 ), graph_add( &g, v10, t0 ), graph_add( &g, v11, t0 );
			graph_add( &g, v00, t1 ), graph_add( &g, v11, t1 ), graph_add( &g, v01, t1 );
		}
	}
	return g;
}

static void graph_free( graph* g )
{
	free( g->a ), free( g->b );
}

Test( color, every_color_is_an_independent_set_on_a_large_mesh )
{
	/* 150 × 100 cells: 45 151 particles, 180 000 springs (three and a half maples). */
	graph g = double_layer( 150, 100 );
	sere_coloring c;
	cr_assert_eq( sere_coloring_create( g.a, g.b, g.count, g.n, &c ), SERE_OK );
	int32_t* stamp = malloc( sizeof( int32_t ) * (size_t) g.n );
	int32_t* seen = calloc( (size_t) g.count, sizeof( int32_t ) );
	for ( int32_t i = 0; i < g.n; ++i )
	{
		stamp[i] = -1;
	}
	cr_assert_eq( c.offsets[0], 0 );
	cr_assert_eq( c.offsets[c.color_count], g.count );
	int32_t smallest = g.count, largest = 0;
	for ( int32_t color = 0; color < c.color_count; ++color )
	{
		int32_t size = c.offsets[color + 1] - c.offsets[color];
		smallest = size < smallest ? size : smallest;
		largest = size > largest ? size : largest;
		for ( int32_t k = c.offsets[color]; k < c.offsets[color + 1]; ++k )
		{
			int32_t s = c.order[k];
			cr_assert_eq( c.color[s], color );
			cr_assert( k == c.offsets[color] || c.order[k - 1] < s, "ascending within a color" );
			cr_assert_neq( stamp[g.a[s]], color, "color %d meets particle %d twice", color, g.a[s] );
			cr_assert_neq( stamp[g.b[s]], color, "color %d meets particle %d twice", color, g.b[s] );
			stamp[g.a[s]] = color;
			stamp[g.b[s]] = color;
			seen[s] += 1;
		}
	}
	for ( int32_t s = 0; s < g.count; ++s )
	{
		cr_assert_eq( seen[s], 1, "spring %d colored %d times", s, seen[s] );
	}
	cr_expect_eq( c.min_batch, smallest );
	cr_expect_eq( c.max_batch, largest );
	/* Greedy edge coloring never needs more than 2Δ − 1 colors (Δ: max particle degree). */
	int32_t* degree = calloc( (size_t) g.n, sizeof( int32_t ) );
	int32_t max_degree = 0;
	for ( int32_t s = 0; s < g.count; ++s )
	{
		max_degree = ++degree[g.a[s]] > max_degree ? degree[g.a[s]] : max_degree;
		max_degree = ++degree[g.b[s]] > max_degree ? degree[g.b[s]] : max_degree;
	}
	cr_expect_leq( c.color_count, 2 * max_degree - 1 );
	cr_expect_geq( c.color_count, max_degree );
	/* Least-used choice and rebalancing even out the batches: within 1% on this mesh. */
	cr_expect_leq( largest - smallest, largest / 100, "batches %d..%d", smallest, largest );
	free( stamp ), free( seen ), free( degree );
	sere_coloring_destroy( &c );
	graph_free( &g );
}

Test( color, deterministic )
{
	graph g = double_layer( 40, 30 );
	sere_coloring c1, c2;
	cr_assert_eq( sere_coloring_create( g.a, g.b, g.count, g.n, &c1 ), SERE_OK );
	cr_assert_eq( sere_coloring_create( g.a, g.b, g.count, g.n, &c2 ), SERE_OK );
	cr_expect_eq( c1.color_count, c2.color_count );
	cr_expect_eq( memcmp( c1.offsets, c2.offsets, sizeof( c1.offsets ) ), 0 );
	cr_expect_eq( memcmp( c1.color, c2.color, sizeof( int32_t ) * (size_t) g.count ), 0 );
	cr_expect_eq( memcmp( c1.order, c2.order, sizeof( int32_t ) * (size_t) g.count ), 0 );
	sere_coloring_destroy( &c1 );
	sere_coloring_destroy( &c2 );
	graph_free( &g );
}

Test( color, small_cases_by_hand )
{
	/* A triangle needs three colors; a square two. Springs take the least-used free color,
	 * the lowest on a tie: square 0-1, 1-2, 2-3, 3-0 → 0, 1, 0, 1 (balanced: nothing moves). */
	int32_t ta[3] = { 0, 1, 2 }, tb[3] = { 1, 2, 0 };
	sere_coloring c;
	cr_assert_eq( sere_coloring_create( ta, tb, 3, 3, &c ), SERE_OK );
	cr_expect_eq( c.color_count, 3 );
	cr_expect( c.min_batch == 1 && c.max_batch == 1 );
	sere_coloring_destroy( &c );
	int32_t sa[4] = { 0, 1, 2, 3 }, sb[4] = { 1, 2, 3, 0 };
	cr_assert_eq( sere_coloring_create( sa, sb, 4, 4, &c ), SERE_OK );
	cr_expect_eq( c.color_count, 2 );
	int32_t expected[4] = { 0, 1, 0, 1 };
	cr_expect_eq( memcmp( c.color, expected, sizeof( expected ) ), 0 );
	sere_coloring_destroy( &c );
	/* Two disjoint springs share color 0, then a third meeting both opens color 1; a fourth,
	 * free for both colors, takes the less used one (1). */
	int32_t la[4] = { 0, 2, 1, 4 }, lb[4] = { 1, 3, 2, 5 };
	cr_assert_eq( sere_coloring_create( la, lb, 4, 6, &c ), SERE_OK );
	int32_t balanced[4] = { 0, 0, 1, 1 };
	cr_expect_eq( memcmp( c.color, balanced, sizeof( balanced ) ), 0 );
	sere_coloring_destroy( &c );
}

Test( color, gather_puts_springs_in_color_order )
{
	graph g = double_layer( 30, 20 );
	sere_coloring c;
	cr_assert_eq( sere_coloring_create( g.a, g.b, g.count, g.n, &c ), SERE_OK );
	float* rest = malloc( sizeof( float ) * (size_t) g.count );
	uint8_t* kind = malloc( (size_t) g.count );
	for ( int32_t s = 0; s < g.count; ++s )
	{
		rest[s] = (float) s;
		kind[s] = (uint8_t) ( s % 7 );
	}
	int32_t* a = malloc( sizeof( int32_t ) * (size_t) g.count );
	int32_t* b = malloc( sizeof( int32_t ) * (size_t) g.count );
	float* rest_sorted = malloc( sizeof( float ) * (size_t) g.count );
	uint8_t* kind_sorted = malloc( (size_t) g.count );
	sere_coloring_gather_i32( &c, g.a, a );
	sere_coloring_gather_i32( &c, g.b, b );
	sere_coloring_gather_f32( &c, rest, rest_sorted );
	sere_coloring_gather_u8( &c, kind, kind_sorted );
	int32_t* stamp = malloc( sizeof( int32_t ) * (size_t) g.n );
	for ( int32_t i = 0; i < g.n; ++i )
	{
		stamp[i] = -1;
	}
	for ( int32_t color = 0; color < c.color_count; ++color )
	{
		/* After the reorder a color is a contiguous range of independent springs. */
		for ( int32_t k = c.offsets[color]; k < c.offsets[color + 1]; ++k )
		{
			int32_t s = (int32_t) rest_sorted[k];
			cr_assert( a[k] == g.a[s] && b[k] == g.b[s] && kind_sorted[k] == kind[s] );
			cr_assert( stamp[a[k]] != color && stamp[b[k]] != color );
			stamp[a[k]] = stamp[b[k]] = color;
		}
	}
	free( rest ), free( kind ), free( a ), free( b ), free( rest_sorted ), free( kind_sorted ), free( stamp );
	sere_coloring_destroy( &c );
	graph_free( &g );
}

Test( color, capacity_and_bad_input )
{
	/* A star: every spring meets particle 0, so each needs its own color. */
	int32_t a[65], b[65];
	for ( int32_t s = 0; s < 65; ++s )
	{
		a[s] = 0, b[s] = s + 1;
	}
	sere_coloring c;
	cr_assert_eq( sere_coloring_create( a, b, SERE_MAX_COLORS, 66, &c ), SERE_OK );
	cr_expect_eq( c.color_count, SERE_MAX_COLORS );
	sere_coloring_destroy( &c );
	cr_expect_eq( sere_coloring_create( a, b, 65, 66, &c ), SERE_ERR_CAPACITY );
	cr_expect( c.order == NULL && c.color == NULL && c.color_count == 0, "cleared after a failure" );
	sere_coloring_destroy( &c );
	int32_t self[1] = { 2 }, far[1] = { 66 };
	cr_expect_eq( sere_coloring_create( self, self, 1, 66, &c ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_coloring_create( a, far, 1, 66, &c ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_coloring_create( a, b, 0, 66, &c ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_coloring_create( a, b, 1, 66, NULL ), SERE_ERR_ARGUMENT );
}
