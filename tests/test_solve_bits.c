/* Stored bits of the solvers in kernels/solve (PBD projection, collision pass, BVH): an FNV-1a
 * 64 hash of their outputs on fixture sheets, checked at every SIMD width (make test-widths).
 * The hashes were taken from commit 002e313, native (AVX-512) build, before the per-ISA bodies
 * were rewritten once over the lane layer (kernels/core/internal/simd.h); the AVX2 and portable
 * builds of that commit gave the same values. Lane-wise IEEE arithmetic without FMA is what lets
 * one value hold at every width. The PBD projection's hash was taken again at the commit that
 * made the XPBD factor one quotient (f = r/((w_a + w_b + α̃) len) instead of −Δλ/len: rounding
 * only), at all three widths. */
#include "core/internal/simd.h"
#include "fixture.h"
#include "solve/bvh.h"
#include "solve/collide.h"
#include "solve/pbd.h"
#include "solve/vbd.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BITS_BASIS 0xcbf29ce484222325ull

static uint64_t fnv1a( uint64_t h, const void* data, size_t bytes )
{
	const unsigned char* p = data;
	for ( size_t i = 0; i < bytes; ++i )
	{
		h = ( h ^ p[i] ) * 0x100000001b3ull;
	}
	return h;
}

/* A crumpled fixture sheet: the rest plane (u, v, 0), the crumpled positions x, y, z, and the
 * unique triangle edges as distance constraints a–b. */
typedef struct bits_sheet
{
	int32_t n, triangles, edges;
	double *u, *v;
	int32_t *tri, *a, *b;
	float *x, *y, *z, *inv_m, *rest;
} bits_sheet;

static int bits_cmp_edge( const void* p, const void* q )
{
	const int64_t *s = p, *t = q;
	return ( *s > *t ) - ( *s < *t );
}

static void bits_edges( bits_sheet* s )
{
	int64_t* key = malloc( sizeof( int64_t ) * 3 * (size_t) s->triangles );
	for ( int32_t t = 0; t < s->triangles; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			int64_t i = s->tri[3 * t + k], j = s->tri[3 * t + ( k + 1 ) % 3];
			key[3 * t + k] = i < j ? i * s->n + j : j * s->n + i;
		}
	}
	qsort( key, 3 * (size_t) s->triangles, sizeof( int64_t ), bits_cmp_edge );
	s->a = malloc( sizeof( int32_t ) * 3 * (size_t) s->triangles );
	s->b = malloc( sizeof( int32_t ) * 3 * (size_t) s->triangles );
	s->rest = malloc( sizeof( float ) * 3 * (size_t) s->triangles );
	s->edges = 0;
	for ( int32_t k = 0; k < 3 * s->triangles; ++k )
	{
		if ( k > 0 && key[k] == key[k - 1] )
		{
			continue;
		}
		int32_t i = (int32_t) ( key[k] / s->n ), j = (int32_t) ( key[k] % s->n );
		double du = s->u[j] - s->u[i], dv = s->v[j] - s->v[i];
		s->a[s->edges] = i, s->b[s->edges] = j;
		s->rest[s->edges] = (float) sqrt( du * du + dv * dv );
		s->edges += 1;
	}
	free( key );
}

static void bits_sheet_make( bits_sheet* s, int32_t nx, double amplitude, uint64_t seed )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, nx, 1.0, 1.0, 0.2, 0, seed );
	free( plane.veins );
	s->n = plane.mesh.point_count;
	s->triangles = plane.mesh.triangle_count;
	s->u = plane.x, s->v = plane.y, s->tri = plane.tri;
	size_t bytes = sizeof( float ) * (size_t) sere_pad( s->n );
	float** arrays[] = { &s->x, &s->y, &s->z, &s->inv_m };
	for ( int k = 0; k < 4; ++k )
	{
		*arrays[k] = sere_alloc( bytes );
	}
	sere_test_crumple field;
	sere_test_crumple_make( &field, amplitude, seed );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		sere_test_crumple_point( &field, s->u[i], s->v[i], 0.3 / nx, s->x + i, s->y + i, s->z + i );
		s->inv_m[i] = i % 97 == 0 ? 0.0f : 1.0f / ( 0.5f + (float) ( i % 5 ) * 0.25f );
	}
	bits_edges( s );
}

static void bits_sheet_free( bits_sheet* s )
{
	float* arrays[] = { s->x, s->y, s->z, s->inv_m };
	for ( int k = 0; k < 4; ++k )
	{
		sere_free( arrays[k] );
	}
	free( s->u ), free( s->v ), free( s->tri ), free( s->a ), free( s->b ), free( s->rest );
}

static uint64_t bits_positions( uint64_t h, const bits_sheet* s )
{
	size_t bytes = sizeof( float ) * (size_t) s->n;
	h = fnv1a( h, s->x, bytes );
	h = fnv1a( h, s->y, bytes );
	return fnv1a( h, s->z, bytes );
}

static uint64_t bits_report( uint64_t h, const sere_pbd_report* r )
{
	h = fnv1a( h, &r->iterations, sizeof( r->iterations ) );
	h = fnv1a( h, &r->max_strain, sizeof( r->max_strain ) );
	return fnv1a( h, &r->hit_cap, sizeof( r->hit_cap ) );
}

/* Gauss–Seidel PBD (Müller 2007 Sec. 3.3), XPBD with warm multipliers and Chebyshev
 * extrapolation (Wang 2015), Jacobi, and the fixed-sweep touch: every body the projection has. */
Test( solvebits, pbd_projection )
{
	bits_sheet s;
	bits_sheet_make( &s, 40, 0.15, 5 );
	sere_pbd* pbd = NULL;
	cr_assert_eq( sere_pbd_create( s.a, s.b, s.edges, s.n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, s.rest ), SERE_OK );
	uint64_t h = BITS_BASIS;
	sere_pbd_report report;

	sere_pbd_params params = sere_pbd_params_default();
	params.tolerance = 1e-7f;
	params.max_iterations = 12;
	params.stiffness = 0.9f;
	cr_assert_eq( sere_pbd_project( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	h = bits_report( bits_positions( h, &s ), &report );

	float* weight = malloc( sizeof( float ) * (size_t) s.edges );
	for ( int32_t q = 0; q < s.edges; ++q )
	{
		weight[q] = 0.5f + (float) ( q % 3 );
	}
	cr_assert_eq( sere_pbd_set_compliance_weights( pbd, weight ), SERE_OK );
	free( weight );
	params = sere_pbd_params_default();
	params.tolerance = 1e-7f;
	params.max_iterations = 30;
	params.compliance = 1e-6f;
	params.dt = 1.0f / 60.0f;
	params.warm = 1;
	params.chebyshev_rho = 0.9f;
	params.chebyshev_delay = 4;
	for ( int call = 0; call < 2; ++call )
	{
		cr_assert_eq( sere_pbd_project( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
		h = bits_report( bits_positions( h, &s ), &report );
	}

	params = sere_pbd_params_default();
	params.tolerance = 1e-7f;
	params.max_iterations = 10;
	cr_assert_eq( sere_pbd_project_jacobi( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	h = bits_report( bits_positions( h, &s ), &report );

	cr_assert_eq( sere_pbd_touch_sweeps( pbd, s.x, s.y, s.z, s.inv_m, 5 ), SERE_OK );
	h = bits_positions( h, &s );
	cr_expect_eq( h, 0x81a89503ad38041bull, "hash %#018llx", (unsigned long long) h );
	sere_pbd_destroy( pbd );
	bits_sheet_free( &s );
}

/* The descent step (solve/vbd.h): plain sweeps, then Chebyshev with the ground and weights, then
 * the floor's sweeps; positions, reports and the ground's reaction. A lane's arithmetic reads
 * only its own particle's springs in adjacency order (the padding rows add zeros), so the
 * blocks' widths do not show in the bits. Taken at the commit that added the descent, native
 * (AVX-512), AVX2 and portable builds alike. */
/* The lane layer's fused multiply-add rounds once at every width: (1 + 2⁻¹³)² − 1 is exactly
 * 2⁻¹² + 2⁻²⁶, which float holds; a multiply rounded before the add loses the 2⁻²⁶. */
Test( solvebits, lane_fma_rounds_once )
{
	const float a = 1.0f + ldexpf( 1.0f, -13 ), exact = ldexpf( 1.0f, -12 ) + ldexpf( 1.0f, -26 );
	_Alignas( 64 ) float out[SERE_LANES], apart[SERE_LANES];
	const sere_vf va = sere_vf_splat( a ), one = sere_vf_splat( 1.0f );
	sere_vf_store( out, sere_vf_fma( va, va, sere_vf_splat( -1.0f ) ) );
	sere_vf_store( apart, sere_vf_sub( sere_vf_mul( va, va ), one ) );
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		cr_expect_eq( out[j], exact, "lane %d: fma %a, exact %a", j, (double) out[j], (double) exact );
		cr_expect_neq( apart[j], exact, "lane %d: the unfused product must round", j );
	}
	sere_vf_store( out, sere_vf_fnma( va, va, one ) );
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		cr_expect_eq( out[j], -exact, "lane %d: fnma %a", j, (double) out[j] );
	}
}

Test( solvebits, vbd_step )
{
	bits_sheet s;
	bits_sheet_make( &s, 40, 0.15, 9 );
	sere_vbd* vbd = NULL;
	cr_assert_eq( sere_vbd_create( s.a, s.b, s.edges, s.n, &vbd ), SERE_OK );
	cr_assert_eq( sere_vbd_set_rest( vbd, s.rest ), SERE_OK );
	uint64_t h = BITS_BASIS;
	sere_vbd_report report;
	sere_vbd_params params = sere_vbd_params_default();
	params.compliance = 1e-6f;
	params.tolerance = 1e-7f;
	params.max_iterations = 25;
	cr_assert_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	h = bits_positions( h, &s );
	h = fnv1a( h, &report, sizeof( report ) );

	float* weight = malloc( sizeof( float ) * (size_t) s.edges );
	for ( int32_t q = 0; q < s.edges; ++q )
	{
		weight[q] = 0.5f + (float) ( q % 3 );
	}
	cr_assert_eq( sere_vbd_set_compliance_weights( vbd, weight ), SERE_OK );
	free( weight );
	params.chebyshev_rho = 0.9f;
	params.chebyshev_delay = 4;
	params.ground = -0.05f;
	cr_assert_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	h = bits_positions( h, &s );
	h = fnv1a( h, &report, sizeof( report ) );
	float* push = calloc( (size_t) s.n, sizeof( float ) );
	cr_assert_eq( sere_vbd_ground_push( vbd, push ), SERE_OK );
	h = fnv1a( h, push, sizeof( float ) * (size_t) s.n );
	free( push );

	cr_assert_eq( sere_vbd_touch_sweeps( vbd, s.x, s.y, s.z, s.inv_m, 5 ), SERE_OK );
	h = bits_positions( h, &s );
	cr_expect_eq( h, 0x84c8c359179edb6aull, "hash %#018llx", (unsigned long long) h );
	sere_vbd_destroy( vbd );
	bits_sheet_free( &s );
}

static int bits_cmp_contact( const void* p, const void* q )
{
	return memcmp( p, q, sizeof( sere_contact ) );
}

static int bits_cmp_edge_contact( const void* p, const void* q )
{
	return memcmp( p, q, sizeof( sere_edge_contact ) );
}

/* The contact lists of a sheet crumpled through itself, sorted (their order is the threads'),
 * then the positions and velocities the full resolve (detect + Jacobi response rounds) leaves. */
Test( solvebits, collision_pass )
{
	bits_sheet s;
	bits_sheet_make( &s, 48, 0.35, 11 );
	float h_cell = 1.0f / 48.0f;
	size_t bytes = sizeof( float ) * (size_t) sere_pad( s.n );
	float *vx = sere_alloc( bytes ), *vy = sere_alloc( bytes ), *vz = sere_alloc( bytes );
	memset( vx, 0, bytes ), memset( vy, 0, bytes ), memset( vz, 0, bytes );
	sere_bvh* bvh = NULL;
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &bvh ), SERE_OK );
	sere_collide* c = NULL;
	cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
	int32_t found = 0;
	cr_assert_eq( sere_collide_detect( c, bvh, s.x, s.y, s.z, 0.3f * h_cell, &found ), SERE_OK );
	int32_t count = 0, edge_count = 0;
	const sere_contact* contacts = sere_collide_contacts( c, &count );
	const sere_edge_contact* edges = sere_collide_edge_contacts( c, &edge_count );
	cr_assert_gt( count, 50, "the crumple must fold the sheet onto itself" );
	cr_assert_gt( edge_count, 0 );
	sere_contact* sorted = malloc( sizeof( sere_contact ) * (size_t) count );
	memcpy( sorted, contacts, sizeof( sere_contact ) * (size_t) count );
	qsort( sorted, (size_t) count, sizeof( sere_contact ), bits_cmp_contact );
	sere_edge_contact* sorted_edges = malloc( sizeof( sere_edge_contact ) * (size_t) edge_count );
	memcpy( sorted_edges, edges, sizeof( sere_edge_contact ) * (size_t) edge_count );
	qsort( sorted_edges, (size_t) edge_count, sizeof( sere_edge_contact ), bits_cmp_edge_contact );
	uint64_t h = fnv1a( BITS_BASIS, sorted, sizeof( sere_contact ) * (size_t) count );
	h = fnv1a( h, sorted_edges, sizeof( sere_edge_contact ) * (size_t) edge_count );
	free( sorted );
	free( sorted_edges );

	sere_collide_state state = { s.x, s.y, s.z, vx, vy, vz, s.inv_m, NULL, NULL, NULL };
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.3f * h_cell;
	params.dt = 1.0f / 60.0f;
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( c, bvh, &state, &params, &stats ), SERE_OK );
	h = bits_positions( h, &s );
	h = fnv1a( h, vx, sizeof( float ) * (size_t) s.n );
	h = fnv1a( h, vy, sizeof( float ) * (size_t) s.n );
	h = fnv1a( h, vz, sizeof( float ) * (size_t) s.n );
	int32_t numbers[5] = { stats.contacts, stats.edge_contacts, stats.unresolved, stats.iterations, stats.rounds };
	h = fnv1a( h, numbers, sizeof( numbers ) );
	cr_expect_eq( h, 0xd271492c98d3f257ull, "hash %#018llx", (unsigned long long) h );
	sere_collide_destroy( c );
	sere_bvh_destroy( bvh );
	sere_free( vx ), sere_free( vy ), sere_free( vz );
	bits_sheet_free( &s );
}

static uint64_t bits_nodes( uint64_t h, const sere_bvh* bvh )
{
	int32_t node_count = 0, triangle_count = 0;
	const sere_bvh_node* nodes = sere_bvh_nodes( bvh, &node_count );
	const int32_t* triangles = sere_bvh_triangles( bvh, &triangle_count );
	h = fnv1a( h, nodes, sizeof( sere_bvh_node ) * (size_t) node_count );
	return fnv1a( h, triangles, sizeof( int32_t ) * (size_t) triangle_count );
}

typedef struct bits_visits
{
	uint64_t h;
} bits_visits;

static void bits_visit_group( void* context, int32_t triangle, uint32_t lanes )
{
	bits_visits* v = context;
	v->h = fnv1a( v->h, &triangle, sizeof( triangle ) );
	v->h = fnv1a( v->h, &lanes, sizeof( lanes ) );
}

static int bits_cmp_int( const void* p, const void* q )
{
	int32_t a = *(const int32_t*) p, b = *(const int32_t*) q;
	return ( a > b ) - ( a < b );
}

/* The tree of a build, of a refit after the sheet moves, and of a rebuild, with the triangles
 * that point, box and group queries find in it. */
Test( solvebits, bvh_build_refit_query )
{
	bits_sheet s;
	bits_sheet_make( &s, 40, 0.3, 17 );
	sere_bvh* bvh = NULL;
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &bvh ), SERE_OK );
	uint64_t h = bits_nodes( BITS_BASIS, bvh );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] += 0.05f * (float) ( s.u[i] * s.v[i] );
		s.x[i] -= 0.02f * (float) s.v[i];
	}
	cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
	h = bits_nodes( h, bvh );
	double ratio = sere_bvh_quality_ratio( bvh );
	h = fnv1a( h, &ratio, sizeof( ratio ) );

	int32_t found[512];
	for ( int32_t i = 0; i < s.n; i += 7 )
	{
		int32_t k = sere_bvh_query( bvh, s.x[i], s.y[i], s.z[i], 0.04f, found, 512 );
		cr_assert_leq( k, 512 );
		qsort( found, (size_t) k, sizeof( int32_t ), bits_cmp_int );
		h = fnv1a( h, &k, sizeof( k ) );
		h = fnv1a( h, found, sizeof( int32_t ) * (size_t) k );
	}
	bits_visits visits = { h };
	for ( int32_t first = 0; first + SERE_BVH_WIDTH <= s.n; first += 37 )
	{
		sere_bvh_group group;
		group.count = SERE_BVH_WIDTH;
		for ( int32_t j = 0; j < SERE_BVH_WIDTH; ++j )
		{
			int32_t i = first + 3 * j < s.n ? first + 3 * j : first;
			group.lo_x[j] = s.x[i] - 0.03f, group.hi_x[j] = s.x[i] + 0.03f;
			group.lo_y[j] = s.y[i] - 0.03f, group.hi_y[j] = s.y[i] + 0.03f;
			group.lo_z[j] = s.z[i] - 0.03f, group.hi_z[j] = s.z[i] + 0.03f;
		}
		sere_bvh_query_group( bvh, &group, bits_visit_group, &visits );
		sere_bvh_query_group_above( bvh, &group, first, bits_visit_group, &visits );
	}
	h = visits.h;
	cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
	h = bits_nodes( h, bvh );
	cr_expect_eq( h, 0x8536890b34f0a081ull, "hash %#018llx", (unsigned long long) h );
	sere_bvh_destroy( bvh );
	bits_sheet_free( &s );
}
