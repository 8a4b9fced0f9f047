/* Self-collision on the shipped leaves (the case): random smooth deformations and a
 * crumple of real leaf meshes; the BVH must find exactly the brute-force pair sets, vertex–triangle
 * and edge–edge. */
#include "collide_sheet.h"
#include "drying/model.h"
#include "read/leafload.h"
#include "ref/collide_ref.h"
#include "solve/collide.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct pair
{
	int32_t v, t;
} pair;

/* The edge–edge contacts of the last detection equal the brute-force pair set exactly (with the
 * rest positions rx, ry, rz the workspace was given, or NULL); returns their count. */
static int32_t check_edge_pairs( const sere_collide* collide, const float* x, const float* y, const float* z,
								 const float* rx, const float* ry, const float* rz, const int32_t* tri,
								 int32_t triangles, float thickness, const char* what )
{
	int32_t listed;
	const sere_edge_contact* contacts = sere_collide_edge_contacts( collide, &listed );
	int64_t capacity = 1 << 20;
	int32_t* expected = malloc( sizeof( int32_t ) * 4 * (size_t) capacity );
	int64_t brute =
		sere_collide_ref_edge_pairs( x, y, z, rx, ry, rz, tri, triangles, thickness, expected, NULL, capacity );
	cr_assert_leq( brute, capacity );
	cr_expect_eq( listed, brute, "%s: BVH %d edge pairs, brute force %lld", what, listed, (long long) brute );
	int32_t* found = malloc( sizeof( int32_t ) * 4 * (size_t) ( listed + 1 ) );
	for ( int32_t c = 0; c < listed; ++c )
	{
		found[4 * c] = contacts[c].a0, found[4 * c + 1] = contacts[c].a1;
		found[4 * c + 2] = contacts[c].b0, found[4 * c + 3] = contacts[c].b1;
	}
	qsort( found, (size_t) listed, 4 * sizeof( int32_t ), collide_cmp_quad );
	for ( int32_t c = 0; c < listed && c < brute; ++c )
	{
		cr_assert( collide_cmp_quad( found + 4 * c, expected + 4 * c ) == 0, "%s: edge pair %d differs", what, c );
	}
	free( found );
	free( expected );
	return listed;
}

Test( collide_leaf, bvh_equals_brute_force_on_deformed_leaves )
{
	const char* names[] = { "maple", "hickory", "ginkgo" };
	for ( size_t k = 0; k < sizeof( names ) / sizeof( names[0] ); ++k )
	{
		char path[128], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", names[k] );
		sere_leaf_source leaf;
		cr_assert_eq( sere_leaf_source_load( path, &leaf, err, sizeof( err ) ), 0, "%s", err );
		sere_build_params params = sere_build_params_default();
		params.point_count = 900;
		params.boundary_count = sere_boundary_for_points( sere_shape_area( &leaf.file.shape ),
														  sere_shape_perimeter( &leaf.file.shape ), 900 );
		sere_model m;
		cr_assert_eq( sere_model_build( &leaf.file.shape, &params, &m, NULL ), SERE_OK );
		int32_t n = m.triangle_particles;
		float* x = m.p.x;
		float* y = m.p.y;
		float* z = m.p.z;
		float umin = m.u[0], umax = m.u[0];
		for ( int32_t i = 1; i < n; ++i )
		{
			umin = fminf( umin, m.u[i] ), umax = fmaxf( umax, m.u[i] );
		}
		float* rest[3] = { malloc( sizeof( float ) * n ), malloc( sizeof( float ) * n ),
						   calloc( (size_t) n, sizeof( float ) ) };
		for ( int32_t i = 0; i < n; ++i )
		{
			rest[0][i] = m.u[i], rest[1][i] = m.v[i];
		}
		for ( int shape = 0; shape < 3; ++shape )
		{
			/* 0: gentle waves; 1: a roll about the midrib; 2: a crumple with vertex noise */
			for ( int32_t i = 0; i < n; ++i )
			{
				float u = m.u[i], v = m.v[i];
				if ( shape == 0 )
					x[i] = u, y[i] = v, z[i] = 0.03f * sinf( 9.0f * u ) * cosf( 7.0f * v );
				else if ( shape == 1 )
				{
					/* rolls the blade two turns around the y axis on a spiral whose turns lie
					 * 0.006 apart, closer than the thickness: layers of the roll touch */
					float angle = 4.0f * 3.14159265f * ( u - umin ) / ( umax - umin );
					float r = 0.05f + 0.006f * angle / ( 2.0f * 3.14159265f );
					x[i] = r * sinf( angle ), y[i] = v, z[i] = -r * cosf( angle );
				}
				else
				{
					float noise = sinf( 12.9898f * i ) * 43758.5453f;
					noise -= floorf( noise );
					x[i] = 0.6f * u + 0.05f * sinf( 11.0f * v );
					y[i] = 0.6f * v + 0.05f * sinf( 13.0f * u );
					z[i] = 0.08f * sinf( 8.0f * u + 5.0f * v ) + 0.004f * ( noise - 0.5f );
				}
			}
			sere_bvh* bvh;
			cr_assert_eq( sere_bvh_create( m.tri, m.triangle_count, n, x, y, z, &bvh ), SERE_OK );
			sere_collide* collide;
			cr_assert_eq( sere_collide_create( bvh, 64 * n, &collide ), SERE_OK );
			const float thickness = 0.01f;
			int32_t count = 0;
			cr_assert_eq( sere_collide_detect( collide, bvh, x, y, z, thickness, &count ), SERE_OK );
			int32_t listed = 0;
			const sere_contact* contacts = sere_collide_contacts( collide, &listed );
			pair* found = malloc( sizeof( pair ) * ( listed + 1 ) );
			for ( int32_t c = 0; c < listed; ++c )
			{
				found[c] = ( pair ){ contacts[c].vertex, contacts[c].triangle };
			}
			int64_t capacity = 64 * (int64_t) n;
			int32_t* rv = malloc( sizeof( int32_t ) * capacity );
			int32_t* rt = malloc( sizeof( int32_t ) * capacity );
			int64_t brute = sere_collide_ref_pairs( x, y, z, n, m.tri, m.triangle_count, thickness, rv, rt, capacity );
			cr_assert_leq( brute, capacity );
			pair* expected = malloc( sizeof( pair ) * ( brute + 1 ) );
			for ( int64_t c = 0; c < brute; ++c )
			{
				expected[c] = ( pair ){ rv[c], rt[c] };
			}
			qsort( found, (size_t) listed, sizeof( pair ), collide_cmp_pair );
			qsort( expected, (size_t) brute, sizeof( pair ), collide_cmp_pair );
			cr_expect_eq( listed, brute, "%s shape %d: BVH %d pairs, brute force %lld", names[k], shape, listed,
						  (long long) brute );
			for ( int32_t c = 0; c < listed && c < brute; ++c )
			{
				cr_assert( found[c].v == expected[c].v && found[c].t == expected[c].t, "%s shape %d: pair %d differs",
						   names[k], shape, c );
			}
			char what[64];
			snprintf( what, sizeof( what ), "%s shape %d", names[k], shape );
			int32_t edges =
				check_edge_pairs( collide, x, y, z, NULL, NULL, NULL, m.tri, m.triangle_count, thickness, what );
			/* again with the flat leaf (u, v, 0) as the rest state: pairs that close at rest drop out */
			cr_assert_eq( sere_collide_set_rest( collide, rest[0], rest[1], rest[2] ), SERE_OK );
			cr_assert_eq( sere_collide_detect( collide, bvh, x, y, z, thickness, &count ), SERE_OK );
			snprintf( what, sizeof( what ), "%s shape %d, with rest", names[k], shape );
			int32_t rest_edges = check_edge_pairs( collide, x, y, z, rest[0], rest[1], rest[2], m.tri, m.triangle_count,
												   thickness, what );
			cr_assert_leq( rest_edges, edges );
			if ( shape == 1 )
			{
				cr_expect_gt( brute, 0, "%s: the roll should bring layers into contact", names[k] );
				cr_expect_gt( edges, 0, "%s: the roll should bring edges across each other", names[k] );
				cr_expect_gt( rest_edges, 0, "%s: the roll's layers are far apart at rest and still count", names[k] );
			}
			free( found ), free( expected ), free( rv ), free( rt );
			sere_collide_destroy( collide );
			sere_bvh_destroy( bvh );
		}
		free( rest[0] ), free( rest[1] ), free( rest[2] );
		sere_model_destroy( &m );
		sere_leaf_source_destroy( &leaf );
	}
}

/* The crumpled shipped maple at a thickness that brings thousands of vertex–triangle and
 * edge–edge pairs together (past the parallel response's threshold, with vertices in dozens of
 * contacts): the contact lists, the pushed positions and the velocities are bitwise the same for
 * 1, 2 and 3 threads, and the lists are still the brute-force pair sets. */
Test( collide_leaf, crumpled_maple_identical_for_one_two_and_three_threads )
{
	sere_leaf_source leaf;
	char err[1024];
	cr_assert_eq( sere_leaf_source_load( "data/leaves/maple.leaf", &leaf, err, sizeof( err ) ), 0, "%s", err );
	sere_build_params params = sere_build_params_default();
	params.point_count = 1500;
	params.boundary_count =
		sere_boundary_for_points( sere_shape_area( &leaf.file.shape ), sere_shape_perimeter( &leaf.file.shape ), 1500 );
	sere_model m;
	cr_assert_eq( sere_model_build( &leaf.file.shape, &params, &m, NULL ), SERE_OK );
	int32_t n = m.triangle_particles, f = m.triangle_count;
	float* rest[3] = { malloc( sizeof( float ) * n ), malloc( sizeof( float ) * n ), malloc( sizeof( float ) * n ) };
	for ( int32_t i = 0; i < n; ++i )
	{
		float u = m.u[i], v = m.v[i];
		float noise = sinf( 12.9898f * i ) * 43758.5453f;
		noise -= floorf( noise );
		rest[0][i] = 0.5f * u + 0.05f * sinf( 11.0f * v );
		rest[1][i] = 0.5f * v + 0.05f * sinf( 13.0f * u );
		rest[2][i] = 0.08f * sinf( 8.0f * u + 5.0f * v ) + 0.004f * ( noise - 0.5f );
	}
	const float thickness = 0.02f;
	int saved = omp_get_max_threads();
	float* first = NULL;
	sere_contact* first_contacts = NULL;
	sere_edge_contact* first_edges = NULL;
	int32_t first_count = 0, first_edge_count = 0;
	size_t bytes = sizeof( float ) * 6 * (size_t) n;
	for ( int threads = 1; threads <= 3; ++threads )
	{
		omp_set_num_threads( threads );
		float* state = calloc( 6 * (size_t) n, sizeof( float ) );
		float* inv_m = malloc( sizeof( float ) * n );
		for ( int32_t i = 0; i < n; ++i )
		{
			state[i] = rest[0][i], state[n + i] = rest[1][i], state[2 * n + i] = rest[2][i];
			inv_m[i] = 1.0f + (float) ( i % 3 );
		}
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( m.tri, f, n, state, state + n, state + 2 * n, &bvh ), SERE_OK );
		sere_collide* collide;
		cr_assert_eq( sere_collide_create( bvh, 64 * n, &collide ), SERE_OK );
		int32_t count = 0;
		cr_assert_eq( sere_collide_detect( collide, bvh, state, state + n, state + 2 * n, thickness, &count ),
					  SERE_OK );
		int32_t listed;
		const sere_contact* contacts = sere_collide_contacts( collide, &listed );
		cr_assert_gt( listed, 2000, "%d contacts", listed );
		if ( threads == 1 )
		{
			int64_t capacity = 64 * (int64_t) n;
			int32_t* rv = malloc( sizeof( int32_t ) * capacity );
			int32_t* rt = malloc( sizeof( int32_t ) * capacity );
			int64_t brute =
				sere_collide_ref_pairs( state, state + n, state + 2 * n, n, m.tri, f, thickness, rv, rt, capacity );
			cr_assert_eq( listed, brute, "BVH %d pairs, brute force %lld", listed, (long long) brute );
			free( rv ), free( rt );
			first_count = listed;
			first_contacts = malloc( sizeof( sere_contact ) * (size_t) listed );
			memcpy( first_contacts, contacts, sizeof( sere_contact ) * (size_t) listed );
			first_edge_count = check_edge_pairs( collide, state, state + n, state + 2 * n, NULL, NULL, NULL, m.tri, f,
												 thickness, "crumpled maple" );
			cr_assert_gt( first_edge_count, 1000, "%d edge contacts", first_edge_count );
			first_edges = malloc( sizeof( sere_edge_contact ) * (size_t) first_edge_count );
			memcpy( first_edges, sere_collide_edge_contacts( collide, &listed ),
					sizeof( sere_edge_contact ) * (size_t) first_edge_count );
		}
		else
		{
			cr_assert_eq( listed, first_count );
			cr_assert_eq( memcmp( contacts, first_contacts, sizeof( sere_contact ) * (size_t) listed ), 0,
						  "%d threads: contact list differs", threads );
			const sere_edge_contact* edges = sere_collide_edge_contacts( collide, &listed );
			cr_assert_eq( listed, first_edge_count );
			cr_assert_eq( memcmp( edges, first_edges, sizeof( sere_edge_contact ) * (size_t) listed ), 0,
						  "%d threads: edge contact list differs", threads );
		}
		sere_collide_params p = sere_collide_params_default();
		p.thickness = thickness;
		sere_collide_state s = { state,			state + n, state + 2 * n, state + 3 * n, state + 4 * n,
								 state + 5 * n, inv_m,	   NULL,		  NULL,			 NULL };
		cr_assert_eq( sere_collide_respond( collide, bvh, &s, &p, NULL ), SERE_OK );
		if ( threads == 1 )
		{
			first = state;
		}
		else
		{
			cr_assert_eq( memcmp( state, first, bytes ), 0, "%d threads: response differs", threads );
			free( state );
		}
		free( inv_m );
		sere_collide_destroy( collide );
		sere_bvh_destroy( bvh );
	}
	omp_set_num_threads( saved );
	free( first ), free( first_contacts ), free( first_edges );
	free( rest[0] ), free( rest[1] ), free( rest[2] );
	sere_model_destroy( &m );
	sere_leaf_source_destroy( &leaf );
}
