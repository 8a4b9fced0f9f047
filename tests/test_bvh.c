#include "fixture.h"
#include "solve/bvh.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define BVH_PI 3.14159265358979323846

/* A jittered grid sheet of width 1 in the plane z = 0 (from the shared plane fixture), with
 * the plane coordinates kept in u, v so deformations can be applied from rest. */
typedef struct bvh_sheet
{
	int32_t n, triangles;
	float *x, *y, *z, *u, *v;
	int32_t* tri;
	float cell;
} bvh_sheet;

static void bvh_sheet_make( bvh_sheet* s, int32_t nx, int32_t ny, uint64_t seed )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, 1.0, (double) ny / nx, 0.4, 0, seed );
	s->n = plane.mesh.point_count;
	s->triangles = plane.mesh.triangle_count;
	s->cell = 1.0f / (float) nx;
	size_t bytes = sizeof( float ) * (size_t) sere_pad( s->n );
	s->x = sere_alloc( bytes ), s->y = sere_alloc( bytes ), s->z = sere_alloc( bytes );
	s->u = sere_alloc( bytes ), s->v = sere_alloc( bytes );
	s->tri = sere_alloc( sizeof( int32_t ) * 3 * (size_t) s->triangles );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		s->u[i] = s->x[i] = (float) plane.x[i];
		s->v[i] = s->y[i] = (float) plane.y[i];
	}
	memcpy( s->tri, plane.tri, sizeof( int32_t ) * 3 * (size_t) s->triangles );
	sere_test_plane_free( &plane );
}

static void bvh_sheet_free( bvh_sheet* s )
{
	sere_free( s->x ), sere_free( s->y ), sere_free( s->z ), sere_free( s->u ), sere_free( s->v );
	sere_free( s->tri );
}

/* The tree over the sheet's triangles as they lie now. */
static sere_bvh* bvh_sheet_tree( const bvh_sheet* s )
{
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( s->tri, s->triangles, s->n, s->x, s->y, s->z, &bvh ), SERE_OK );
	return bvh;
}

static void bvh_sheet_release( bvh_sheet* s, sere_bvh* bvh )
{
	sere_bvh_destroy( bvh );
	bvh_sheet_free( s );
}

/* Smooth bumps of the given amplitude (wavelength a quarter of the sheet) plus per-vertex noise
 * of the given amplitude in all three axes. */
static void bvh_sheet_bump( bvh_sheet* s, double amplitude, double noise, uint64_t seed )
{
	uint64_t state = seed;
	for ( int32_t i = 0; i < s->n; ++i )
	{
		double u = s->u[i], v = s->v[i];
		s->x[i] = (float) ( u + noise * ( sere_test_unit( &state ) - 0.5 ) );
		s->y[i] = (float) ( v + noise * ( sere_test_unit( &state ) - 0.5 ) );
		s->z[i] = (float) ( amplitude * sin( 8.0 * BVH_PI * u ) * sin( 8.0 * BVH_PI * v ) +
							noise * ( sere_test_unit( &state ) - 0.5 ) );
	}
}

/* A sheet of bvh_sheet_make, bumped by bvh_sheet_bump (noise in cells) when amplitude > 0, and
 * the tree over it. */
static sere_bvh* bvh_sheet_start( bvh_sheet* s, int32_t nx, int32_t ny, uint64_t seed, double amplitude,
								  double noise_cells, uint64_t bump_seed )
{
	bvh_sheet_make( s, nx, ny, seed );
	if ( amplitude > 0.0 )
	{
		bvh_sheet_bump( s, amplitude, noise_cells * s->cell, bump_seed );
	}
	return bvh_sheet_tree( s );
}

/* Rolls the sheet around the y axis into a spiral of decreasing radius (a large deformation:
 * far-apart triangles end up next to each other), then twists it about x. */
static void bvh_sheet_roll( bvh_sheet* s )
{
	for ( int32_t i = 0; i < s->n; ++i )
	{
		double u = s->u[i], v = s->v[i];
		double angle = 4.0 * BVH_PI * u, radius = 0.2 - 0.15 * u;
		double px = radius * cos( angle ), pz = radius * sin( angle );
		double twist = 1.5 * v;
		s->x[i] = (float) px;
		s->y[i] = (float) ( v * cos( twist ) - pz * sin( twist ) );
		s->z[i] = (float) ( v * sin( twist ) + pz * cos( twist ) );
	}
}

static int bvh_cmp_int( const void* a, const void* b )
{
	int32_t x = *(const int32_t*) a, y = *(const int32_t*) b;
	return ( x > y ) - ( x < y );
}

/* Every query must return exactly the triangles whose box (min/max of the three corners)
 * overlaps the query cube, as a scan over all triangles finds them. */
static void bvh_check_queries( const sere_bvh* bvh, const bvh_sheet* s, uint64_t seed )
{
	int32_t* got = malloc( sizeof( int32_t ) * (size_t) s->triangles );
	int32_t* want = malloc( sizeof( int32_t ) * (size_t) s->triangles );
	uint64_t state = seed;
	for ( int q = 0; q < 400; ++q )
	{
		/* half the queries at vertices (the collision use), half anywhere in the bounds */
		int32_t i = (int32_t) ( sere_test_unit( &state ) * s->n );
		float p[3] = { s->x[i], s->y[i], s->z[i] };
		if ( q % 2 )
		{
			p[0] += (float) ( 0.2 * ( sere_test_unit( &state ) - 0.5 ) );
			p[1] += (float) ( 0.2 * ( sere_test_unit( &state ) - 0.5 ) );
			p[2] += (float) ( 0.2 * ( sere_test_unit( &state ) - 0.5 ) );
		}
		float r = (float) ( 3.0 * s->cell * sere_test_unit( &state ) * sere_test_unit( &state ) );
		int32_t count = sere_bvh_query( bvh, p[0], p[1], p[2], r, got, s->triangles );
		float lo[3] = { p[0] - r, p[1] - r, p[2] - r }, hi[3] = { p[0] + r, p[1] + r, p[2] + r };
		int32_t expected = 0;
		for ( int32_t t = 0; t < s->triangles; ++t )
		{
			const int32_t* v = s->tri + 3 * t;
			float c[3][3] = { { s->x[v[0]], s->x[v[1]], s->x[v[2]] },
							  { s->y[v[0]], s->y[v[1]], s->y[v[2]] },
							  { s->z[v[0]], s->z[v[1]], s->z[v[2]] } };
			bool overlap = true;
			for ( int a = 0; a < 3; ++a )
			{
				float mn = fminf( c[a][0], fminf( c[a][1], c[a][2] ) ),
					  mx = fmaxf( c[a][0], fmaxf( c[a][1], c[a][2] ) );
				overlap = overlap && mn <= hi[a] && mx >= lo[a];
			}
			if ( overlap )
			{
				want[expected++] = t;
			}
		}
		cr_assert_eq( count, expected, "query %d: %d triangles, brute force %d", q, count, expected );
		qsort( got, (size_t) count, sizeof( int32_t ), bvh_cmp_int );
		cr_assert_eq( memcmp( got, want, sizeof( int32_t ) * (size_t) count ), 0, "query %d: different triangles", q );
	}
	free( got );
	free( want );
}

Test( bvh, query_matches_brute_force_after_build_and_refit )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 40, 30, 11, 0.02, 0.3, 5 );
	bvh_check_queries( bvh, &s, 1 );
	/* refit only, after deformations that move triangles far from where the tree put them */
	bvh_sheet_roll( &s );
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	bvh_check_queries( bvh, &s, 2 );
	bvh_sheet_bump( &s, 0.3, 2.0 * s.cell, 9 );
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	bvh_check_queries( bvh, &s, 3 );
	bvh_sheet_release( &s, bvh );
}

typedef struct bvh_group_hits
{
	uint32_t* lanes; /* per triangle: the lanes reported */
	int32_t calls;
	int32_t repeats;
} bvh_group_hits;

static void bvh_group_visit( void* context, int32_t triangle, uint32_t lanes )
{
	bvh_group_hits* hits = context;
	hits->repeats += hits->lanes[triangle] != 0;
	hits->lanes[triangle] = lanes;
	hits->calls += 1;
}

/* A group of count boxes around SERE_BVH_WIDTH consecutive vertices from a random first one
 * (returned), each of a random radius up to radius_cells cells. */
static int32_t bvh_group_near( const bvh_sheet* s, sere_bvh_group* group, int count, double radius_cells,
							   uint64_t* state )
{
	group->count = count;
	int32_t base = (int32_t) ( sere_test_unit( state ) * ( s->n - SERE_BVH_WIDTH ) );
	for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		int32_t i = base + k;
		float r = (float) ( radius_cells * s->cell * sere_test_unit( state ) );
		group->lo_x[k] = s->x[i] - r, group->lo_y[k] = s->y[i] - r, group->lo_z[k] = s->z[i] - r;
		group->hi_x[k] = s->x[i] + r, group->hi_y[k] = s->y[i] + r, group->hi_z[k] = s->z[i] + r;
	}
	return base;
}

/* A group query reports each triangle once, with exactly the lanes whose box overlaps the
 * triangle's box; unused lanes and lanes with a NaN bound report nothing. */
Test( bvh, group_query_matches_brute_force )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 40, 30, 12, 0.05, 0.5, 2 );
	uint32_t* lanes = calloc( (size_t) s.triangles, sizeof( uint32_t ) );
	uint64_t state = 9;
	for ( int g = 0; g < 200; ++g )
	{
		/* boxes around nearby vertices (a group's usual shape), one of them NaN now and then */
		sere_bvh_group group;
		bvh_group_near( &s, &group, 1 + g % SERE_BVH_WIDTH, 2.0, &state );
		if ( g % 5 == 0 )
		{
			group.hi_y[g % group.count] = NAN;
		}
		memset( lanes, 0, sizeof( uint32_t ) * (size_t) s.triangles );
		bvh_group_hits hits = { lanes, 0, 0 };
		sere_bvh_query_group( bvh, &group, bvh_group_visit, &hits );
		cr_assert_eq( hits.repeats, 0, "group %d: a triangle reported twice", g );
		for ( int32_t t = 0; t < s.triangles; ++t )
		{
			const int32_t* v = s.tri + 3 * t;
			float lo[3], hi[3];
			const float* c[3] = { s.x, s.y, s.z };
			for ( int a = 0; a < 3; ++a )
			{
				lo[a] = fminf( c[a][v[0]], fminf( c[a][v[1]], c[a][v[2]] ) );
				hi[a] = fmaxf( c[a][v[0]], fmaxf( c[a][v[1]], c[a][v[2]] ) );
			}
			uint32_t expected = 0;
			for ( int k = 0; k < group.count; ++k )
			{
				bool overlap = lo[0] <= group.hi_x[k] && hi[0] >= group.lo_x[k] && lo[1] <= group.hi_y[k] &&
							   hi[1] >= group.lo_y[k] && lo[2] <= group.hi_z[k] && hi[2] >= group.lo_z[k];
				expected |= (uint32_t) overlap << k;
			}
			cr_assert_eq( lanes[t], expected, "group %d triangle %d: lanes %x, brute force %x", g, t, lanes[t],
						  expected );
		}
	}
	free( lanes );
	bvh_sheet_release( &s, bvh );
}

typedef struct bvh_visit_log
{
	int32_t* triangle;
	uint32_t* lanes;
	int32_t count;
	int32_t capacity;
} bvh_visit_log;

static void bvh_log_visit( void* context, int32_t triangle, uint32_t lanes )
{
	bvh_visit_log* log = context;
	if ( log->count < log->capacity )
	{
		log->triangle[log->count] = triangle, log->lanes[log->count] = lanes;
	}
	log->count += 1;
}

/* The query above a floor is the plain group query with the triangles whose corners all lie at
 * or below the floor left out, the rest visited in the same order with the same lanes (the edge
 * search's contact order depends on it); also after a rebuild for moved positions. */
Test( bvh, group_query_above_is_the_plain_query_filtered_in_order )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 40, 30, 12, 0.05, 0.5, 2 );
	int32_t capacity = s.triangles;
	bvh_visit_log plain = { malloc( sizeof( int32_t ) * (size_t) capacity ),
							malloc( sizeof( uint32_t ) * (size_t) capacity ), 0, capacity };
	bvh_visit_log above = { malloc( sizeof( int32_t ) * (size_t) capacity ),
							malloc( sizeof( uint32_t ) * (size_t) capacity ), 0, capacity };
	uint64_t state = 5;
	for ( int g = 0; g < 400; ++g )
	{
		if ( g == 200 )
		{
			bvh_sheet_roll( &s );
			cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
		}
		sere_bvh_group group;
		int32_t base = bvh_group_near( &s, &group, 1 + g % SERE_BVH_WIDTH, 3.0, &state );
		/* below every index, around the group's own, and above every index */
		int32_t floor = g % 3 == 0 ? -1 : ( g % 3 == 1 ? base + g % 7 : s.n - 1 );
		plain.count = above.count = 0;
		sere_bvh_query_group( bvh, &group, bvh_log_visit, &plain );
		sere_bvh_query_group_above( bvh, &group, floor, bvh_log_visit, &above );
		cr_assert_leq( plain.count, capacity );
		int32_t kept = 0;
		for ( int32_t k = 0; k < plain.count; ++k )
		{
			const int32_t* v = s.tri + 3 * plain.triangle[k];
			if ( v[0] > floor || v[1] > floor || v[2] > floor )
			{
				cr_assert_lt( kept, above.count, "group %d: visit %d missing", g, k );
				cr_assert_eq( above.triangle[kept], plain.triangle[k], "group %d: visit %d", g, kept );
				cr_assert_eq( above.lanes[kept], plain.lanes[k], "group %d: visit %d", g, kept );
				kept += 1;
			}
		}
		cr_assert_eq( above.count, kept, "group %d: %d visits, %d expected", g, above.count, kept );
	}
	free( plain.triangle ), free( plain.lanes ), free( above.triangle ), free( above.lanes );
	bvh_sheet_release( &s, bvh );
}

/* Refit boxes are exact: a triangle lane is the min/max of its corners, a node lane the union of
 * the child's lanes; so they contain everything below them whatever the deformation. Also the
 * structure: each triangle in exactly one lane, children after their parent. */
Test( bvh, refit_boxes_exact_and_structure )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 50, 40, 3, 0.0, 0.0, 0 );
	bvh_sheet_roll( &s );
	bvh_sheet_bump( &s, 0.1, 0.5 * s.cell, 4 );
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	int32_t nodes;
	const sere_bvh_node* node = sere_bvh_nodes( bvh, &nodes );
	cr_assert( nodes >= 1 && nodes <= s.triangles - 1 );
	int32_t* seen = calloc( (size_t) s.triangles, sizeof( int32_t ) );
	for ( int32_t i = 0; i < nodes; ++i )
	{
		for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
		{
			int32_t c = node[i].child[k];
			float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
			if ( c == SERE_BVH_EMPTY )
			{
				continue;
			}
			if ( c >= 0 )
			{
				cr_assert( c > i && c < nodes, "child %d of node %d", c, i );
				for ( int j = 0; j < SERE_BVH_WIDTH; ++j )
				{
					lo[0] = fminf( lo[0], node[c].min_x[j] ), hi[0] = fmaxf( hi[0], node[c].max_x[j] );
					lo[1] = fminf( lo[1], node[c].min_y[j] ), hi[1] = fmaxf( hi[1], node[c].max_y[j] );
					lo[2] = fminf( lo[2], node[c].min_z[j] ), hi[2] = fmaxf( hi[2], node[c].max_z[j] );
				}
			}
			else
			{
				int32_t t = ~c;
				cr_assert( t >= 0 && t < s.triangles );
				seen[t] += 1;
				for ( int r = 0; r < 3; ++r )
				{
					int32_t v = s.tri[3 * t + r];
					lo[0] = fminf( lo[0], s.x[v] ), hi[0] = fmaxf( hi[0], s.x[v] );
					lo[1] = fminf( lo[1], s.y[v] ), hi[1] = fmaxf( hi[1], s.y[v] );
					lo[2] = fminf( lo[2], s.z[v] ), hi[2] = fmaxf( hi[2], s.z[v] );
				}
			}
			/* min and max are exact in float: equality, no tolerance */
			cr_assert( node[i].min_x[k] == lo[0] && node[i].max_x[k] == hi[0] && node[i].min_y[k] == lo[1] &&
						   node[i].max_y[k] == hi[1] && node[i].min_z[k] == lo[2] && node[i].max_z[k] == hi[2],
					   "node %d lane %d is not the exact box of its child", i, k );
		}
	}
	for ( int32_t t = 0; t < s.triangles; ++t )
	{
		cr_assert_eq( seen[t], 1, "triangle %d in %d lanes", t, seen[t] );
	}
	/* a 2000-triangle sheet in 8-wide nodes: log8(2000) ≈ 3.7, a sound SAH tree stays shallow */
	cr_expect_leq( sere_bvh_depth( bvh ), 8 );
	free( seen );
	bvh_sheet_release( &s, bvh );
}

Test( bvh, quality_ratio_grows_with_deformation_and_triggers_rebuild )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 40, 40, 8, 0.0, 0.0, 0 );
	/* the same sums over the same boxes: exactly 1 */
	cr_assert_eq( sere_bvh_quality_ratio( bvh ), 1.0 );
	cr_assert( !sere_bvh_needs_rebuild( bvh, SERE_BVH_REBUILD_RATIO ) );
	const double amplitudes[] = { 0.005, 0.02, 0.05, 0.1, 0.2 };
	double previous = 1.0;
	for ( int k = 0; k < 5; ++k )
	{
		bvh_sheet_bump( &s, amplitudes[k], 0.0, 1 );
		cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
		double ratio = sere_bvh_quality_ratio( bvh );
		cr_assert_gt( ratio, previous, "amplitude %g: ratio %g not above %g", amplitudes[k], ratio, previous );
		cr_assert_eq( sere_bvh_needs_rebuild( bvh, SERE_BVH_REBUILD_RATIO ), ratio > SERE_BVH_REBUILD_RATIO );
		previous = ratio;
	}
	cr_assert_gt( previous, SERE_BVH_REBUILD_RATIO, "the largest bumps must call for a rebuild" );

	/* a small deformation refits only; the large one rebuilds and the ratio is 1 again */
	bool rebuilt = true;
	bvh_sheet_bump( &s, 0.005, 0.0, 1 );
	cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
	bvh_sheet_bump( &s, 0.006, 0.0, 1 );
	cr_assert_eq( sere_bvh_update( bvh, s.x, s.y, s.z, SERE_BVH_REBUILD_RATIO, &rebuilt ), SERE_OK );
	cr_assert( !rebuilt );
	bvh_sheet_bump( &s, 0.2, 0.0, 1 );
	cr_assert_eq( sere_bvh_update( bvh, s.x, s.y, s.z, SERE_BVH_REBUILD_RATIO, &rebuilt ), SERE_OK );
	cr_assert( rebuilt );
	cr_assert_eq( sere_bvh_quality_ratio( bvh ), 1.0 );
	bvh_sheet_release( &s, bvh );
}

Test( bvh, quality_ratio_ignores_uniform_shrinking )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 30, 30, 2, 0.05, 0.2, 3 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.x[i] *= 0.6f, s.y[i] *= 0.6f, s.z[i] *= 0.6f;
	}
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	/* a drying leaf shrinking by 40% keeps its tree: areas all scale by 0.36, the ratio moves
	 * only by float rounding of the scaled coordinates (relative 1e-6 per coordinate) */
	cr_assert_float_eq( sere_bvh_quality_ratio( bvh ), 1.0, 1e-4 );
	bvh_sheet_release( &s, bvh );
}

Test( bvh, build_and_refit_identical_with_one_and_two_threads )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 60, 40, 6, 0.0, 0.0, 0 );
	bvh_sheet_roll( &s );
	int32_t nodes;
	const sere_bvh_node* node = sere_bvh_nodes( bvh, &nodes );
	sere_bvh_node* first = malloc( sizeof( sere_bvh_node ) * (size_t) nodes );
	int saved = omp_get_max_threads();
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	memcpy( first, node, sizeof( sere_bvh_node ) * (size_t) nodes );
	double ratio = sere_bvh_quality_ratio( bvh );
	omp_set_num_threads( 2 );
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	cr_assert_eq( memcmp( first, node, sizeof( sere_bvh_node ) * (size_t) nodes ), 0 );
	cr_assert_eq( sere_bvh_quality_ratio( bvh ), ratio );

	/* and a rebuild of the rolled sheet */
	cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
	node = sere_bvh_nodes( bvh, &nodes );
	sere_bvh_node* second = malloc( sizeof( sere_bvh_node ) * (size_t) nodes );
	memcpy( second, node, sizeof( sere_bvh_node ) * (size_t) nodes );
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
	omp_set_num_threads( saved );
	int32_t nodes_again;
	node = sere_bvh_nodes( bvh, &nodes_again );
	cr_assert_eq( nodes_again, nodes );
	cr_assert_eq( memcmp( second, node, sizeof( sere_bvh_node ) * (size_t) nodes ), 0 );
	free( first );
	free( second );
	bvh_sheet_release( &s, bvh );
}

Test( bvh, nonfinite_positions_are_refused )
{
	bvh_sheet s;
	sere_bvh* bvh = bvh_sheet_start( &s, 10, 10, 1, 0.0, 0.0, 0 );
	int32_t nodes;
	const sere_bvh_node* node = sere_bvh_nodes( bvh, &nodes );
	sere_bvh_node* before = malloc( sizeof( sere_bvh_node ) * (size_t) nodes );
	memcpy( before, node, sizeof( sere_bvh_node ) * (size_t) nodes );
	s.y[37] = NAN;
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_ERR_NONFINITE );
	cr_assert_eq( memcmp( before, node, sizeof( sere_bvh_node ) * (size_t) nodes ), 0, "boxes changed on error" );
	cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_ERR_NONFINITE );
	bool rebuilt;
	cr_assert_eq( sere_bvh_update( bvh, s.x, s.y, s.z, 1.5, &rebuilt ), SERE_ERR_NONFINITE );
	sere_bvh* other = bvh; /* non-null, so the test sees create clear it */
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &other ), SERE_ERR_NONFINITE );
	cr_assert_null( other );
	s.y[37] = s.v[37];
	s.z[5] = INFINITY;
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_ERR_NONFINITE );
	/* a NaN query finds nothing rather than everything */
	int32_t out[4];
	cr_assert_eq( sere_bvh_query( bvh, NAN, 0.5f, 0.0f, 0.1f, out, 4 ), 0 );
	free( before );
	bvh_sheet_release( &s, bvh );
}

Test( bvh, bad_arguments_are_refused )
{
	int32_t tri[6] = { 0, 1, 2, 0, 2, 3 };
	float x[4] = { 0, 1, 1, 0 }, y[4] = { 0, 0, 1, 1 }, z[4] = { 0 };
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 3, x, y, z, &bvh ), SERE_ERR_ARGUMENT ); /* index 3 out of range */
	cr_assert_null( bvh );
	cr_assert_eq( sere_bvh_create( tri, 0, 4, x, y, z, &bvh ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_bvh_create( NULL, 2, 4, x, y, z, &bvh ), SERE_ERR_ARGUMENT );
	tri[4] = -1;
	cr_assert_eq( sere_bvh_create( tri, 2, 4, x, y, z, &bvh ), SERE_ERR_ARGUMENT );
}

Test( bvh, degenerate_meshes )
{
	/* one triangle: the root holds it in lane 0 */
	int32_t one[3] = { 0, 1, 2 };
	float x[4] = { 0, 1, 0, 0 }, y[4] = { 0, 0, 1, 0 }, z[4] = { 0 };
	sere_bvh* bvh;
	int32_t out[64];
	cr_assert_eq( sere_bvh_create( one, 1, 3, x, y, z, &bvh ), SERE_OK );
	cr_assert_eq( sere_bvh_query( bvh, 0.2f, 0.2f, 0.0f, 0.0f, out, 64 ), 1 );
	cr_assert_eq( out[0], 0 );
	cr_assert_eq( sere_bvh_query( bvh, 2.0f, 0.2f, 0.0f, 0.5f, out, 64 ), 0 );
	sere_bvh_destroy( bvh );

	/* every vertex at one point: all box centres coincide, the build still splits to the end */
	bvh_sheet s;
	bvh_sheet_make( &s, 8, 8, 1 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.x[i] = s.y[i] = s.z[i] = 0.25f;
	}
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &bvh ), SERE_OK );
	int32_t* all = malloc( sizeof( int32_t ) * (size_t) s.triangles );
	/* a capacity below the count still reports the full count */
	cr_assert_eq( sere_bvh_query( bvh, 0.25f, 0.25f, 0.25f, 0.0f, out, 64 ), s.triangles );
	cr_assert_eq( sere_bvh_query( bvh, 0.25f, 0.25f, 0.25f, 0.0f, all, s.triangles ), s.triangles );
	qsort( all, (size_t) s.triangles, sizeof( int32_t ), bvh_cmp_int );
	for ( int32_t t = 0; t < s.triangles; ++t )
	{
		cr_assert_eq( all[t], t );
	}
	cr_assert_eq( sere_bvh_quality_ratio( bvh ), 1.0 );
	free( all );
	bvh_sheet_release( &s, bvh );
}

/* The generation names a build: the candidate list of sere_collide trusts it to say the tree's
 * order is unchanged, so a refit must keep it, a build must change it, and two trees never share
 * one. */
Test( bvh, generation_changes_with_builds_only )
{
	bvh_sheet s;
	bvh_sheet_make( &s, 12, 8, 3 );
	sere_bvh *a, *b;
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &a ), SERE_OK );
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &b ), SERE_OK );
	uint64_t first = sere_bvh_generation( a );
	cr_assert_neq( first, 0u );
	cr_assert_neq( sere_bvh_generation( b ), first );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] = 0.1f * s.x[i] * s.x[i];
	}
	cr_assert_eq( sere_bvh_refit( a, s.x, s.y, s.z ), SERE_OK );
	cr_assert_eq( sere_bvh_generation( a ), first );
	bool rebuilt = true;
	cr_assert_eq( sere_bvh_update( a, s.x, s.y, s.z, 1e9, &rebuilt ), SERE_OK );
	cr_assert( !rebuilt );
	cr_assert_eq( sere_bvh_generation( a ), first );
	cr_assert_eq( sere_bvh_build( a, s.x, s.y, s.z ), SERE_OK );
	cr_assert_neq( sere_bvh_generation( a ), first );
	cr_assert_neq( sere_bvh_generation( a ), sere_bvh_generation( b ) );
	sere_bvh_destroy( a );
	sere_bvh_destroy( b );
	bvh_sheet_free( &s );
}
