#include "collide_sheet.h"

#include "fixture.h"
#include "ref/collide_ref.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#define COLLIDE_PI 3.14159265358979323846

float collide_sheet_make( collide_sheet* s, int32_t nx, int32_t ny, uint64_t seed )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, 1.0, (double) ny / nx, 0.2, 0, seed );
	s->n = plane.mesh.point_count;
	s->triangles = plane.mesh.triangle_count;
	s->cell = 1.0f / (float) nx;
	s->bvh = NULL;
	s->c = NULL;
	size_t bytes = sizeof( float ) * (size_t) sere_pad( s->n + s->triangles );
	float** arrays[] = { &s->x, &s->y, &s->z, &s->vx, &s->vy, &s->vz, &s->inv_m };
	for ( int k = 0; k < 7; ++k )
	{
		*arrays[k] = sere_alloc( bytes );
	}
	s->u = plane.x;
	s->v = plane.y;
	s->tri = plane.tri;
	free( plane.veins );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		s->x[i] = (float) s->u[i];
		s->y[i] = (float) s->v[i];
		s->inv_m[i] = 1.0f;
	}
	return s->cell;
}

void collide_sheet_free( collide_sheet* s )
{
	float* arrays[] = { s->x, s->y, s->z, s->vx, s->vy, s->vz, s->inv_m };
	for ( int k = 0; k < 7; ++k )
	{
		sere_free( arrays[k] );
	}
	free( s->u );
	free( s->v );
	free( s->tri );
}

void collide_sheet_tree( collide_sheet* s, int32_t capacity )
{
	cr_assert_eq( sere_bvh_create( s->tri, s->triangles, s->n, s->x, s->y, s->z, &s->bvh ), SERE_OK );
	cr_assert_eq( sere_collide_create( s->bvh, capacity, &s->c ), SERE_OK );
}

float collide_sheet_open( collide_sheet* s, int32_t nx, int32_t ny, uint64_t seed, int32_t capacity )
{
	collide_sheet_make( s, nx, ny, seed );
	collide_sheet_tree( s, capacity );
	return 0.3f * s->cell;
}

void collide_sheet_release( collide_sheet* s )
{
	sere_collide_destroy( s->c );
	sere_bvh_destroy( s->bvh );
	collide_sheet_free( s );
}

void collide_sheet_flat( collide_sheet* s )
{
	for ( int32_t i = 0; i < s->n; ++i )
	{
		s->x[i] = (float) s->u[i], s->y[i] = (float) s->v[i], s->z[i] = 0.0f;
	}
}

void collide_sheet_fold( collide_sheet* s, double gap )
{
	double r = 0.5 * gap, a = 0.5 * ( 1.0 - COLLIDE_PI * r );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		double u = s->u[i];
		if ( u <= a )
		{
			s->x[i] = (float) u, s->z[i] = 0.0f;
		}
		else if ( u <= a + COLLIDE_PI * r )
		{
			s->x[i] = (float) ( a + r * sin( ( u - a ) / r ) );
			s->z[i] = (float) ( r - r * cos( ( u - a ) / r ) );
		}
		else
		{
			s->x[i] = (float) ( a - ( u - a - COLLIDE_PI * r ) ), s->z[i] = (float) gap;
		}
		s->y[i] = (float) s->v[i];
	}
}

void collide_sheet_crumple( collide_sheet* s, double amplitude, double noise, uint64_t seed )
{
	sere_test_crumple field;
	sere_test_crumple_make( &field, amplitude, seed );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		sere_test_crumple_point( &field, s->u[i], s->v[i], noise, s->x + i, s->y + i, s->z + i );
	}
}

int collide_cmp_pair( const void* a, const void* b )
{
	const int32_t *p = a, *q = b;
	if ( p[0] != q[0] )
	{
		return p[0] < q[0] ? -1 : 1;
	}
	return ( p[1] > q[1] ) - ( p[1] < q[1] );
}

int collide_cmp_quad( const void* a, const void* b )
{
	const int32_t *p = a, *q = b;
	for ( int k = 0; k < 4; ++k )
	{
		if ( p[k] != q[k] )
		{
			return p[k] < q[k] ? -1 : 1;
		}
	}
	return 0;
}

int32_t collide_check_edge_pairs( const float* x, const float* y, const float* z, const int32_t* tri, int32_t triangles,
								  sere_collide* c, float h, const char* what )
{
	int64_t capacity = 1 << 20;
	int32_t* ends = malloc( sizeof( int32_t ) * 4 * (size_t) capacity );
	float* weights = malloc( sizeof( float ) * 2 * (size_t) capacity );
	int64_t expected =
		sere_collide_ref_edge_pairs( x, y, z, NULL, NULL, NULL, tri, triangles, h, ends, weights, capacity );
	cr_assert_leq( expected, capacity );
	int32_t count;
	const sere_edge_contact* contacts = sere_collide_edge_contacts( c, &count );
	cr_assert_eq( count, expected, "%s: BVH finds %d edge pairs, brute force %lld", what, count, (long long) expected );
	int32_t* found = malloc( sizeof( int32_t ) * 4 * (size_t) ( count + 1 ) );
	for ( int32_t k = 0; k < count; ++k )
	{
		const sere_edge_contact* e = contacts + k;
		found[4 * k] = e->a0, found[4 * k + 1] = e->a1, found[4 * k + 2] = e->b0, found[4 * k + 3] = e->b1;
		cr_assert( e->a0 < e->a1 && e->b0 < e->b1 && e->a0 < e->b0, "%s: edge contact %d not in order", what, k );
		float p0[3] = { x[e->a0], y[e->a0], z[e->a0] }, p1[3] = { x[e->a1], y[e->a1], z[e->a1] };
		float q0[3] = { x[e->b0], y[e->b0], z[e->b0] }, q1[3] = { x[e->b1], y[e->b1], z[e->b1] }, w[2];
		float d2 = sere_closest_points_segments( p0, p1, q0, q1, w );
		cr_assert( e->s == w[0] && e->t == w[1] && e->distance == sqrtf( d2 ),
				   "%s: edge contact %d: (%.9g %.9g) at %.9g, scalar (%.9g %.9g) at %.9g", what, k, e->s, e->t,
				   e->distance, w[0], w[1], sqrtf( d2 ) );
		cr_assert( e->distance < h && e->s > 0.0f && e->s < 1.0f && e->t > 0.0f && e->t < 1.0f, "%s: edge contact %d",
				   what, k );
	}
	qsort( found, (size_t) count, 4 * sizeof( int32_t ), collide_cmp_quad );
	for ( int32_t k = 0; k < count; ++k )
	{
		cr_assert( collide_cmp_quad( found + 4 * k, ends + 4 * k ) == 0, "%s: edge pair %d differs", what, k );
	}
	free( found );
	free( ends );
	free( weights );
	return count;
}

int32_t collide_check_pairs( collide_sheet* s, sere_bvh* bvh, sere_collide* c, float h, const char* what,
							 int32_t* edge_count )
{
	int32_t count = -1;
	cr_assert_eq( sere_collide_detect( c, bvh, s->x, s->y, s->z, h, &count ), SERE_OK, "%s", what );
	int64_t capacity = 1 << 20;
	int32_t* rv = malloc( sizeof( int32_t ) * (size_t) capacity );
	int32_t* rt = malloc( sizeof( int32_t ) * (size_t) capacity );
	int64_t expected = sere_collide_ref_pairs( s->x, s->y, s->z, s->n, s->tri, s->triangles, h, rv, rt, capacity );
	cr_assert_eq( count, expected, "%s: BVH finds %d pairs, brute force %lld", what, count, (long long) expected );
	int32_t listed;
	const sere_contact* contacts = sere_collide_contacts( c, &listed );
	cr_assert_eq( listed, count );
	int32_t* pairs = malloc( sizeof( int32_t ) * 2 * (size_t) ( count + 1 ) );
	for ( int32_t k = 0; k < count; ++k )
	{
		pairs[2 * k] = contacts[k].vertex;
		pairs[2 * k + 1] = contacts[k].triangle;
		cr_assert( contacts[k].distance < h, "%s: contact %d at %g", what, k, contacts[k].distance );
		/* Detection tests pairs eight at a time with selects in place of closest_point's
		 * branches, built to give the same bits: weights and distance must equal the scalar
		 * sere_closest_point_triangle exactly (tolerance 0), whichever path a pair took. */
		const int32_t* v = s->tri + 3 * contacts[k].triangle;
		int32_t i = contacts[k].vertex;
		float p[3] = { s->x[i], s->y[i], s->z[i] }, corner[3][3], w[3];
		for ( int r = 0; r < 3; ++r )
		{
			corner[r][0] = s->x[v[r]], corner[r][1] = s->y[v[r]], corner[r][2] = s->z[v[r]];
		}
		float d2 = sere_closest_point_triangle( p, corner[0], corner[1], corner[2], w );
		cr_assert( contacts[k].u == w[0] && contacts[k].v == w[1] && contacts[k].w == w[2] &&
					   contacts[k].distance == sqrtf( d2 ),
				   "%s: contact %d (%d, %d): weights (%.9g %.9g %.9g) at %.9g, scalar (%.9g %.9g %.9g) at %.9g", what,
				   k, i, contacts[k].triangle, contacts[k].u, contacts[k].v, contacts[k].w, contacts[k].distance, w[0],
				   w[1], w[2], sqrtf( d2 ) );
	}
	qsort( pairs, (size_t) count, 2 * sizeof( int32_t ), collide_cmp_pair );
	for ( int32_t k = 0; k < count; ++k )
	{
		cr_assert( pairs[2 * k] == rv[k] && pairs[2 * k + 1] == rt[k], "%s: pair %d differs", what, k );
	}
	free( pairs );
	free( rv );
	free( rt );
	int32_t edges = collide_check_edge_pairs( s->x, s->y, s->z, s->tri, s->triangles, c, h, what );
	if ( edge_count != NULL )
	{
		*edge_count = edges;
	}
	return count;
}

int64_t collide_violations_of( const collide_sheet* s, float h, float tolerance, bool edges )
{
	int32_t dummy;
	float below = h * ( 1.0f - tolerance );
	return edges ? sere_collide_ref_edge_pairs( s->x, s->y, s->z, NULL, NULL, NULL, s->tri, s->triangles, below, &dummy,
												NULL, 0 )
				 : sere_collide_ref_pairs( s->x, s->y, s->z, s->n, s->tri, s->triangles, below, &dummy, &dummy, 0 );
}

void collide_shape_fold( collide_sheet* s )
{
	collide_sheet_fold( s, 0.8 * 0.3 * s->cell );
}

void collide_shape_crumple( collide_sheet* s )
{
	collide_sheet_crumple( s, 0.3, 0.1 * s->cell, 21 );
}

int64_t collide_violations( const collide_sheet* s, float h, float tolerance )
{
	return collide_violations_of( s, h, tolerance, false ) + collide_violations_of( s, h, tolerance, true );
}
