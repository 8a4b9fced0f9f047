#include "collide_sheet.h"
#include "fixture.h"
#include "mesh/measure.h"
#include "ref/collide_ref.h"
#include "solve/bvh.h"
#include "solve/collide.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Point j of points gets coordinates uniform in [−half[j], half[j]], drawn axis by axis (the x
 * of every point, then the y, then the z). */
static void random_points( uint64_t* state, int count, float* const points[], const double half[] )
{
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = 0; j < count; ++j )
		{
			points[j][i] = (float) ( 2.0 * half[j] * sere_test_unit( state ) - half[j] );
		}
	}
}

Test( collide, closest_point_matches_double_reference )
{
	uint64_t state = 4;
	for ( int k = 0; k < 20000; ++k )
	{
		float a[3], b[3], c[3], p[3];
		random_points( &state, 4, ( float* const[] ){ a, b, c, p }, ( const double[] ){ 1.0, 1.0, 1.0, 1.5 } );
		if ( k % 10 == 1 )
		{
			/* slivers and fully degenerate triangles: c on the line ab, or all three equal */
			double t = sere_test_unit( &state );
			for ( int i = 0; i < 3; ++i )
			{
				c[i] = (float) ( a[i] + t * ( b[i] - a[i] ) );
				b[i] = k % 20 == 1 ? a[i] : b[i];
			}
		}
		float w[3];
		float d2 = sere_closest_point_triangle( p, a, b, c, w );
		double pd[3] = { p[0], p[1], p[2] }, ad[3] = { a[0], a[1], a[2] }, bd[3] = { b[0], b[1], b[2] },
			   cd[3] = { c[0], c[1], c[2] };
		double ref = sere_collide_ref_distance2( pd, ad, bd, cd );
		/* coordinates within 1.5: a few dozen float operations keep the distance within 1e-5 */
		cr_assert( fabs( sqrt( d2 ) - sqrt( ref ) ) < 1e-5, "case %d: %g vs %g", k, sqrt( d2 ), sqrt( ref ) );
		cr_assert( w[0] >= 0.0f && w[1] >= 0.0f && w[2] >= 0.0f, "case %d: negative weight", k );
		cr_assert( fabsf( w[0] + w[1] + w[2] - 1.0f ) < 1e-6f, "case %d: weights sum %g", k, w[0] + w[1] + w[2] );
		double q[3], e = 0.0;
		for ( int i = 0; i < 3; ++i )
		{
			q[i] = w[0] * ad[i] + w[1] * bd[i] + w[2] * cd[i];
			e += ( pd[i] - q[i] ) * ( pd[i] - q[i] );
		}
		cr_assert( fabs( sqrt( e ) - sqrt( ref ) ) < 1e-5, "case %d: weights point %g away", k, sqrt( e ) );
	}
}

Test( collide, pairs_match_brute_force_on_random_deformations )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 5, 1 << 16 );
	cr_assert_eq( collide_check_pairs( &s, s.bvh, s.c, h, "flat", NULL ), 0 );
	/* noise of 3 cells in every axis: neighbourhoods interpenetrate, many contacts beyond the
	 * vertices joined by an edge (which do not count) */
	for ( uint64_t seed = 1; seed <= 3; ++seed )
	{
		uint64_t state = seed;
		for ( int32_t i = 0; i < s.n; ++i )
		{
			s.x[i] = (float) ( s.u[i] + 3.0 * s.cell * ( sere_test_unit( &state ) - 0.5 ) );
			s.y[i] = (float) ( s.v[i] + 3.0 * s.cell * ( sere_test_unit( &state ) - 0.5 ) );
			s.z[i] = (float) ( 3.0 * s.cell * ( sere_test_unit( &state ) - 0.5 ) );
		}
		/* refit only: the tree was built on the flat sheet */
		cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
		int32_t edges = 0;
		int32_t refit = collide_check_pairs( &s, s.bvh, s.c, h, "noise, refit", &edges );
		cr_assert_gt( refit, 100, "refit found %d", refit );
		cr_assert_gt( edges, 100, "refit found %d edge pairs", edges );
		cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
		cr_assert_eq( collide_check_pairs( &s, s.bvh, s.c, h, "noise, rebuilt", NULL ), refit );
		collide_sheet_flat( &s );
		cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
	}
	collide_sheet_release( &s );
}

Test( collide, pairs_match_brute_force_on_u_fold )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 6, 1 << 16 );
	/* below the thickness the halves touch everywhere: about every vertex is in contact */
	collide_sheet_fold( &s, 0.8 * h );
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	int32_t near_edges = 0;
	int32_t near = collide_check_pairs( &s, s.bvh, s.c, h, "fold 0.8h, refit", &near_edges );
	cr_assert_gt( near, s.n );
	/* the halves' edges cross over each other in projection, about two per edge */
	cr_assert_gt( near_edges, s.n / 2 );
	cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
	collide_check_pairs( &s, s.bvh, s.c, h, "fold 0.8h, rebuilt", NULL );
	/* above it only the tight bend itself (radius 0.6h) is closer than h */
	collide_sheet_fold( &s, 1.2 * h );
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	int32_t far_edges = 0;
	int32_t far = collide_check_pairs( &s, s.bvh, s.c, h, "fold 1.2h", &far_edges );
	cr_assert_lt( far, near / 20 );
	cr_assert_lt( far_edges, near_edges / 20 );
	int32_t count;
	const sere_contact* contacts = sere_collide_contacts( s.c, &count );
	for ( int32_t k = 0; k < count; ++k )
	{
		const int32_t* v = s.tri + 3 * contacts[k].triangle;
		cr_assert( fabs( s.u[contacts[k].vertex] - 0.5 ) < 2.0 * s.cell && fabs( s.u[v[0]] - 0.5 ) < 2.0 * s.cell,
				   "contact away from the bend" );
	}
	const sere_edge_contact* edge_contacts = sere_collide_edge_contacts( s.c, &count );
	for ( int32_t k = 0; k < count; ++k )
	{
		cr_assert( fabs( s.u[edge_contacts[k].a0] - 0.5 ) < 2.0 * s.cell &&
					   fabs( s.u[edge_contacts[k].b0] - 0.5 ) < 2.0 * s.cell,
				   "edge contact away from the bend" );
	}
	collide_sheet_release( &s );
}

Test( collide, pairs_match_brute_force_on_crumpled_sheet )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 7, 1 << 16 );
	const double amplitudes[] = { 0.05, 0.2, 0.4 };
	int32_t most = 0, most_edges = 0;
	for ( int k = 0; k < 3; ++k )
	{
		collide_sheet_crumple( &s, amplitudes[k], 0.3 * h, 11 + (uint64_t) k );
		cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
		int32_t edges = 0;
		int32_t refit = collide_check_pairs( &s, s.bvh, s.c, h, "crumpled, refit", &edges );
		cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
		cr_assert_eq( collide_check_pairs( &s, s.bvh, s.c, h, "crumpled, rebuilt", NULL ), refit );
		most = refit > most ? refit : most;
		most_edges = edges > most_edges ? edges : most_edges;
		collide_sheet_flat( &s );
		cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
	}
	cr_assert_gt( most, 50, "the strongest crumple must fold the sheet onto itself" );
	cr_assert_gt( most_edges, 50, "the strongest crumple must bring edges across each other" );
	collide_sheet_release( &s );
}

/* Slivers and collapsed triangles take closest_point's nearest-edge fallback, which the
 * eight-wide test hands back to the scalar code: pairs and weights must still be exact. */
Test( collide, pairs_match_brute_force_with_degenerate_triangles )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 9, 1 << 16 );
	collide_sheet_fold( &s, 0.8 * h );
	/* on the upper half, put a corner of every fifth triangle on the midpoint of the other two
	 * (zero area), or a millionth of a cell beside it (a sliver) */
	int32_t collapsed = 0;
	for ( int32_t t = 0; t < s.triangles; t += 5 )
	{
		const int32_t* v = s.tri + 3 * t;
		if ( s.u[v[0]] < 0.6 || s.u[v[1]] < 0.6 || s.u[v[2]] < 0.6 )
		{
			continue;
		}
		float offset = ( collapsed & 1 ) ? 1e-6f * s.cell : 0.0f;
		s.x[v[2]] = 0.5f * ( s.x[v[0]] + s.x[v[1]] ) + offset;
		s.y[v[2]] = 0.5f * ( s.y[v[0]] + s.y[v[1]] );
		s.z[v[2]] = 0.5f * ( s.z[v[0]] + s.z[v[1]] );
		collapsed += 1;
	}
	cr_assert_gt( collapsed, 50 );
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	int32_t near = collide_check_pairs( &s, s.bvh, s.c, h, "fold with collapsed triangles", NULL );
	cr_assert_gt( near, s.n / 2 );
	/* some contact must lie on a collapsed triangle for the fallback to have been exercised */
	int32_t count, on_degenerate = 0;
	const sere_contact* contacts = sere_collide_contacts( s.c, &count );
	for ( int32_t k = 0; k < count; ++k )
	{
		const int32_t* v = s.tri + 3 * contacts[k].triangle;
		float ab[3] = { s.x[v[1]] - s.x[v[0]], s.y[v[1]] - s.y[v[0]], s.z[v[1]] - s.z[v[0]] };
		float ac[3] = { s.x[v[2]] - s.x[v[0]], s.y[v[2]] - s.y[v[0]], s.z[v[2]] - s.z[v[0]] };
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float area2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
		on_degenerate += area2 <= 1e-6f * ab2 * ab2;
	}
	cr_assert_gt( on_degenerate, 0, "no contact on a collapsed triangle: the fallback was not exercised" );
	collide_sheet_release( &s );
}

/* One vertex over the middle of a triangle, everything else far away: a single contact whose
 * solution is known in closed form. */
Test( collide, single_contact_shared_by_inverse_mass )
{
	/* triangle 0 = (0, 1, 2) in z = 0; triangle 1 = (3, 4, 5) holds the vertex 3 above it */
	float x[6] = { 0.0f, 1.0f, 0.0f, 1.0f / 3.0f, 5.0f, 5.0f };
	float y[6] = { 0.0f, 0.0f, 1.0f, 1.0f / 3.0f, 5.0f, 6.0f };
	float z[6] = { 0.0f, 0.0f, 0.0f, 0.02f, 5.0f, 5.0f };
	float vx[6] = { 0 }, vy[6] = { 0 }, vz[6] = { 0 };
	float inv_m[6] = { 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f };
	int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 6, x, y, z, &bvh ), SERE_OK );
	sere_collide* c;
	cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.05f;
	params.dt = 0.01f;
	params.rounds = 1;
	sere_collide_state state = { x, y, z, vx, vy, vz, inv_m, NULL, NULL, NULL };
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( c, bvh, &state, &params, &stats ), SERE_OK );
	cr_assert_eq( stats.contacts, 1 );
	cr_assert_eq( stats.unresolved, 0 );
	/* W = w_p + Σ w_k b_k² = 1 + 3 (1/3)² = 4/3, λ = (0.05 − 0.02) / W = 0.0225: the vertex rises
	 * by λ, each corner sinks by λ / 3, and the gap becomes exactly the thickness. One contact
	 * converges in one iteration; float rounding of the weights and sqrt stays below 1e-7. */
	cr_assert_float_eq( z[3], 0.02f + 0.0225f, 1e-7f );
	for ( int k = 0; k < 3; ++k )
	{
		cr_assert_float_eq( z[k], -0.0075f, 1e-7f );
		cr_assert_float_eq( vz[k], -0.0075f / 0.01f, 1e-5f );
		cr_assert( x[k] == ( k == 1 ? 1.0f : 0.0f ) && y[k] == ( k == 2 ? 1.0f : 0.0f ), "moved off the normal" );
	}
	cr_assert_float_eq( vz[3], 0.0225f / 0.01f, 1e-5f );
	cr_assert_float_eq( z[3] - z[0], 0.05f, 1e-7f );
	cr_assert( vz[4] == 0.0f && vz[5] == 0.0f && z[4] == 5.0f, "bystanders moved" );

	/* pinned triangle: the vertex alone takes the whole push */
	z[0] = z[1] = z[2] = 0.0f, z[3] = 0.02f;
	inv_m[0] = inv_m[1] = inv_m[2] = 0.0f;
	cr_assert_eq( sere_collide_resolve( c, bvh, &state, &params, &stats ), SERE_OK );
	cr_assert_float_eq( z[3], 0.05f, 1e-7f );
	cr_assert( z[0] == 0.0f && z[1] == 0.0f && z[2] == 0.0f, "a pinned corner moved" );
	sere_collide_destroy( c );
	sere_bvh_destroy( bvh );
}

/* Builds the tree and a collide workspace on the two triangles (0, 1, 2) and (3, 4, 5) and
 * resolves once, with the start-of-step positions x0, y0, z0 unless x0 is NULL; the caller
 * destroys *bvh and *c. */
static sere_collide_stats resolve_two( float* x, float* y, float* z, float* vx, float* vy, float* vz, float* inv_m,
									   const float* x0, const float* y0, const float* z0,
									   const sere_collide_params* params, sere_bvh** bvh, sere_collide** c )
{
	static const int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	cr_assert_eq( sere_bvh_create( tri, 2, 6, x, y, z, bvh ), SERE_OK );
	cr_assert_eq( sere_collide_create( *bvh, 0, c ), SERE_OK );
	sere_collide_state state = { x, y, z, vx, vy, vz, inv_m, NULL, NULL, NULL };
	if ( x0 != NULL )
	{
		state.x0 = x0, state.y0 = y0, state.z0 = z0;
	}
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( *c, *bvh, &state, params, &stats ), SERE_OK );
	return stats;
}

/* A vertex the step carried through a triangle: detection finds it below, 0.02 under the
 * plane; at the start of the step it was 0.03 above. Without the start-of-step positions the
 * push continues downward (the gap becomes −thickness); with them it goes back up to
 * +thickness. W = 4/3 as above: λ = (0.05 + 0.02) / W = 0.0525, the vertex rises by λ and each
 * corner sinks by λ / 3. Tolerance 1e-7: float rounding of one exact push. */
Test( collide, start_of_step_side_returns_a_vertex_through_a_triangle )
{
	float inv_m[6] = { 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f };
	float x0[6] = { 0.0f, 1.0f, 0.0f, 1.0f / 3.0f, 5.0f, 5.0f };
	float y0[6] = { 0.0f, 0.0f, 1.0f, 1.0f / 3.0f, 5.0f, 6.0f };
	float z0[6] = { 0.0f, 0.0f, 0.0f, 0.03f, 5.0f, 5.0f };
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.05f;
	params.dt = 0.01f;
	for ( int history = 0; history < 2; ++history )
	{
		float x[6], y[6], z[6], vx[6] = { 0 }, vy[6] = { 0 }, vz[6] = { 0 };
		memcpy( x, x0, sizeof( x ) ), memcpy( y, y0, sizeof( y ) ), memcpy( z, z0, sizeof( z ) );
		z[3] = -0.02f;
		sere_bvh* bvh;
		sere_collide* c;
		sere_collide_stats stats =
			resolve_two( x, y, z, vx, vy, vz, inv_m, history ? x0 : NULL, y0, z0, &params, &bvh, &c );
		cr_assert_eq( stats.contacts, 1 );
		cr_assert_eq( stats.unresolved, 0 );
		int32_t count;
		const sere_contact* contact = sere_collide_contacts( c, &count );
		cr_assert_eq( contact[0].side, history ? 1.0f : -1.0f, "history %d: side %g", history, contact[0].side );
		float gap = z[3] - z[0];
		cr_assert_float_eq( gap, history ? 0.05f : -0.05f, 1e-7f, "history %d: gap %g", history, gap );
		if ( history )
		{
			cr_assert_float_eq( z[3], -0.02f + 0.0525f, 1e-7f );
			cr_assert_float_eq( z[0], -0.0175f, 1e-7f );
		}
		sere_collide_destroy( c );
		sere_bvh_destroy( bvh );
	}
}

Test( collide, closest_segments_match_double_reference )
{
	uint64_t state = 8;
	int32_t inside = 0;
	for ( int k = 0; k < 20000; ++k )
	{
		float p0[3], p1[3], q0[3], q1[3];
		random_points( &state, 4, ( float* const[] ){ p0, p1, q0, q1 }, ( const double[] ){ 1.0, 1.0, 1.0, 1.0 } );
		/* parallel segments (overlapping or not), and segments of zero length */
		bool parallel = k % 10 == 1, point = k % 20 == 3 || k % 20 == 5;
		if ( parallel )
		{
			double scale = 2.0 * sere_test_unit( &state ) - 1.0;
			for ( int i = 0; i < 3; ++i )
			{
				q1[i] = (float) ( q0[i] + scale * ( p1[i] - p0[i] ) );
			}
		}
		for ( int i = 0; i < 3 && point; ++i )
		{
			( k % 20 == 3 ? q1 : p1 )[i] = ( k % 20 == 3 ? q0 : p0 )[i];
		}
		float w[2];
		float d2 = sere_closest_points_segments( p0, p1, q0, q1, w );
		double a0[3] = { p0[0], p0[1], p0[2] }, a1[3] = { p1[0], p1[1], p1[2] };
		double b0[3] = { q0[0], q0[1], q0[2] }, b1[3] = { q1[0], q1[1], q1[2] };
		double ref = sere_collide_ref_segment_distance2( a0, a1, b0, b1 );
		/* coordinates within 1: a few dozen float operations keep the distance within 1e-5 */
		cr_assert( fabs( sqrt( d2 ) - sqrt( ref ) ) < 1e-5, "case %d: %g vs %g", k, sqrt( d2 ), sqrt( ref ) );
		cr_assert( w[0] >= 0.0f && w[0] <= 1.0f && w[1] >= 0.0f && w[1] <= 1.0f, "case %d: weights out of [0, 1]", k );
		double e = 0.0;
		for ( int i = 0; i < 3; ++i )
		{
			double d = ( a0[i] + w[0] * ( a1[i] - a0[i] ) ) - ( b0[i] + w[1] * ( b1[i] - b0[i] ) );
			e += d * d;
		}
		cr_assert( fabs( sqrt( e ) - sqrt( ref ) ) < 1e-5, "case %d: weights' points %g apart", k, sqrt( e ) );
		bool interior = w[0] > 0.0f && w[0] < 1.0f && w[1] > 0.0f && w[1] < 1.0f;
		cr_assert( !( interior && ( parallel || point ) ), "case %d: parallel or point segments closest inside", k );
		inside += interior;
	}
	cr_assert_gt( inside, 2000, "%d pairs closest inside both: the skew case must be exercised", inside );
}

/* Two triangles meeting edge through edge, every vertex far from the other triangle: edge (0, 1)
 * along x and edge (3, 4) along y cross at the origin, the triangles standing on them in the
 * planes y = 0 (up) and x = 0 (down). At the start of the step edge (0, 1) was 0.6h above; the
 * step carried it to 0.4h below, through the other triangle (two crossings). Only the edge–edge
 * contact sees it. With the start-of-step positions its side is the one it came from: the closest
 * points are the midpoints (s = t = 1/2), W = 4 (1/2)² = 1, λ = h + 0.4h = 1.4h, each end of
 * (0, 1) rises by λ/2 and each end of (3, 4) sinks by λ/2, and the edges end exactly h apart,
 * (0, 1) above, with no crossing. Without them the push continues downward to h below.
 * Tolerance 1e-7: float rounding of one exact push. */
Test( collide, edge_contact_pushes_crossing_edges_back_to_their_side )
{
	const float h = 0.05f, below = -0.4f * h;
	int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	float inv_m[6] = { 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f };
	float x0[6] = { -1.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f };
	float y0[6] = { 0.0f, 0.0f, 0.0f, -1.0f, 1.0f, 0.0f };
	float z0[6] = { 0.6f * h, 0.6f * h, 1.0f + 0.6f * h, 0.0f, 0.0f, -1.0f };
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	for ( int history = 0; history < 2; ++history )
	{
		float x[6], y[6], z[6], vx[6] = { 0 }, vy[6] = { 0 }, vz[6] = { 0 };
		memcpy( x, x0, sizeof( x ) ), memcpy( y, y0, sizeof( y ) ), memcpy( z, z0, sizeof( z ) );
		z[0] = z[1] = below, z[2] = 1.0f + below;
		int64_t crossings = 0;
		cr_assert_eq( sere_crossings_count_once( x, y, z, 6, tri, 2, &crossings, 0 ), SERE_OK );
		cr_assert_eq( crossings, 2 );
		sere_bvh* bvh;
		sere_collide* c;
		sere_collide_stats stats =
			resolve_two( x, y, z, vx, vy, vz, inv_m, history ? x0 : NULL, y0, z0, &params, &bvh, &c );
		cr_assert_eq( stats.contacts, 0, "no vertex is near the other triangle" );
		cr_assert_eq( stats.edge_contacts, 1 );
		cr_assert_eq( stats.unresolved, 0 );
		int32_t count;
		const sere_edge_contact* e = sere_collide_edge_contacts( c, &count );
		cr_assert( e->a0 == 0 && e->a1 == 1 && e->b0 == 3 && e->b1 == 4 && e->s == 0.5f && e->t == 0.5f );
		cr_assert_eq( e->side, history ? 1.0f : -1.0f, "history %d: side %g", history, e->side );
		float push = 0.5f * ( history ? h - below : -h - below );
		for ( int k = 0; k < 2; ++k )
		{
			cr_assert_float_eq( z[k], below + push, 1e-7f, "history %d: end %d at %g", history, k, z[k] );
			cr_assert_float_eq( z[3 + k], -push, 1e-7f, "history %d: end %d at %g", history, 3 + k, z[3 + k] );
			cr_assert_float_eq( vz[k], push / params.dt, 1e-4f );
		}
		cr_assert_float_eq( z[0] - z[3], history ? h : -h, 1e-7f );
		cr_assert( z[2] == 1.0f + below && z[5] == -1.0f && x[0] == -1.0f && y[3] == -1.0f, "other coordinates moved" );
		float p0[3] = { x[0], y[0], z[0] }, p1[3] = { x[1], y[1], z[1] };
		float q0[3] = { x[3], y[3], z[3] }, q1[3] = { x[4], y[4], z[4] }, w[2];
		cr_assert_float_eq( sqrtf( sere_closest_points_segments( p0, p1, q0, q1, w ) ), h, 1e-7f );
		cr_assert_eq( sere_crossings_count_once( x, y, z, 6, tri, 2, &crossings, 0 ), SERE_OK );
		cr_assert_eq( crossings, history ? 0 : 2, "history %d: %lld crossings", history, (long long) crossings );
		sere_collide_destroy( c );
		sere_bvh_destroy( bvh );
	}
}

/* Two triangles meeting at vertex 0 only, crossed like an X: edge (1, 2) of one passes 0.2h
 * from edge (3, 4) of the other, inside both, while the edges out of vertex 0 touch there (at
 * distance 0). Only the pair sharing no vertex is a contact: two edges meeting at a vertex are
 * closest at it, whatever their angle, and never a contact. */
Test( collide, edges_sharing_a_vertex_are_not_contacts )
{
	const float h = 0.05f;
	int32_t tri[6] = { 0, 1, 2, 0, 3, 4 };
	float x[5] = { 0.0f, 1.0f, 1.0f, 1.0f + 0.2f * h, 1.0f + 0.2f * h };
	float y[5] = { 0.0f, -0.5f, 0.5f, 0.0f, 0.0f };
	float z[5] = { 0.0f, 0.0f, 0.0f, -0.5f, 0.5f };
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 5, x, y, z, &bvh ), SERE_OK );
	sere_collide* c;
	cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
	int32_t count = -1;
	cr_assert_eq( sere_collide_detect( c, bvh, x, y, z, h, &count ), SERE_OK );
	cr_assert_eq( count, 0 );
	const sere_edge_contact* e = sere_collide_edge_contacts( c, &count );
	cr_assert_eq( count, 1 );
	cr_assert( e->a0 == 1 && e->a1 == 2 && e->b0 == 3 && e->b1 == 4, "(%d %d)-(%d %d)", e->a0, e->a1, e->b0, e->b1 );
	cr_assert_float_eq( e->distance, 0.2f * h, 1e-7f );
	/* the edges out of vertex 0 are within the thickness of each other, closest at the vertex */
	int32_t out[4] = { 1, 2, 3, 4 };
	for ( int i = 0; i < 2; ++i )
	{
		for ( int j = 2; j < 4; ++j )
		{
			float p0[3] = { x[0], y[0], z[0] }, p1[3] = { x[out[i]], y[out[i]], z[out[i]] };
			float q1[3] = { x[out[j]], y[out[j]], z[out[j]] }, w[2];
			cr_assert( sere_closest_points_segments( p0, p1, p0, q1, w ) < h * h && w[0] == 0.0f && w[1] == 0.0f );
		}
	}
	int64_t brute = sere_collide_ref_edge_pairs( x, y, z, NULL, NULL, NULL, tri, 2, h, &count, NULL, 0 );
	cr_assert_eq( brute, 1 );
	sere_collide_destroy( c );
	sere_bvh_destroy( bvh );
}

/* A hinge: triangles (0, 1, 2) and (1, 3, 2) share edge (1, 2), so vertex 3 is joined by an
 * edge to two corners of the first. Flat, with the second triangle thinner than the thickness,
 * vertex 3 is within it of the first across the shared edge, closest there: no contact (pushing
 * it would buckle the sheet). Folded shut like a book, vertex 3 lies over the first triangle's
 * face, 0.4h above it: a contact, pushed to exactly h (W = 1 + 0.4² + 2 · 0.3², as in
 * single_contact_shared_by_inverse_mass). Unchecked, the fold would carry the vertex through the
 * face, as it did at the base of the maple at 800 points. */
Test( collide, neighbour_over_a_folded_face_is_a_contact )
{
	const float h = 0.05f;
	int32_t tri[6] = { 0, 1, 2, 1, 3, 2 };
	float inv_m[4] = { 1.0f, 1.0f, 1.0f, 1.0f };
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	for ( int folded = 0; folded < 2; ++folded )
	{
		float x[4] = { 0.0f, 1.0f, 0.0f, folded ? 0.3f : 0.52f };
		float y[4] = { 0.0f, 0.0f, 1.0f, folded ? 0.3f : 0.52f };
		float z[4] = { 0.0f, 0.0f, 0.0f, folded ? 0.4f * h : 0.0f };
		float vx[4] = { 0 }, vy[4] = { 0 }, vz[4] = { 0 };
		float p[3] = { x[3], y[3], z[3] }, a[3] = { 0.0f, 0.0f, 0.0f }, b[3] = { 1.0f, 0.0f, 0.0f };
		float cc[3] = { 0.0f, 1.0f, 0.0f }, w[3];
		cr_assert_lt( sere_closest_point_triangle( p, a, b, cc, w ), h * h );
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( tri, 2, 4, x, y, z, &bvh ), SERE_OK );
		sere_collide* c;
		cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
		sere_collide_state state = { x, y, z, vx, vy, vz, inv_m, NULL, NULL, NULL };
		sere_collide_stats stats;
		cr_assert_eq( sere_collide_resolve( c, bvh, &state, &params, &stats ), SERE_OK );
		cr_assert_eq( stats.contacts, folded, "folded %d: %d contacts", folded, stats.contacts );
		cr_assert_eq( stats.edge_contacts, 0 );
		int64_t left =
			sere_collide_ref_pairs( x, y, z, 4, tri, 2, h * ( 1.0f - SERE_COLLIDE_TOLERANCE ), NULL, NULL, 0 );
		cr_assert_eq( left, 0, "folded %d: a pair is left closer than the thickness", folded );
		if ( folded )
		{
			float gap = z[3] - ( 0.4f * z[0] + 0.3f * z[1] + 0.3f * z[2] );
			cr_assert_float_eq( gap, h, 1e-7f, "gap %g", gap );
			cr_assert_float_eq( z[3], 0.4f * h + 0.6f * h / ( 1.0f + 0.16f + 0.18f ), 1e-7f );
		}
		else
		{
			cr_assert( z[3] == 0.0f && vz[3] == 0.0f, "a flat neighbour was pushed" );
		}
		sere_collide_destroy( c );
		sere_bvh_destroy( bvh );
	}
}

Test( collide, nonfinite_inputs_are_refused )
{
	collide_sheet s;
	collide_sheet_make( &s, 12, 10, 1 );
	collide_shape_fold( &s );
	int32_t n = s.n, f = s.triangles;
	cr_assert_eq( sere_bvh_create( s.tri, f, n, s.x, s.y, s.z, &s.bvh ), SERE_OK );
	cr_assert_eq( sere_collide_create( s.bvh, 0, &s.c ), SERE_OK );
	size_t bytes = sizeof( float ) * (size_t) ( n + f );
	float* saved = malloc( 3 * bytes );
	memcpy( saved, s.x, bytes ), memcpy( saved + n + f, s.y, bytes ), memcpy( saved + 2 * ( n + f ), s.z, bytes );

	s.x[7] = NAN;
	int32_t count = 0;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, 0.01f, &count ), SERE_ERR_NONFINITE );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.3f * s.cell;
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_NONFINITE );
	s.x[7] = saved[7];
	cr_assert( memcmp( saved, s.x, bytes ) == 0 && memcmp( saved + n + f, s.y, bytes ) == 0 &&
				   memcmp( saved + 2 * ( n + f ), s.z, bytes ) == 0,
			   "positions changed on error" );

	/* a NaN velocity on a vertex in contact */
	s.vz[0] = INFINITY;
	bool touched = false;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, params.thickness, &count ), SERE_OK );
	const sere_contact* contacts = sere_collide_contacts( s.c, &count );
	for ( int32_t k = 0; k < count; ++k )
	{
		touched = touched || contacts[k].vertex == 0 || s.tri[3 * contacts[k].triangle] == 0 ||
				  s.tri[3 * contacts[k].triangle + 1] == 0 || s.tri[3 * contacts[k].triangle + 2] == 0;
	}
	cr_assert( touched, "vertex 0 should be in contact in the fold" );
	cr_assert_eq( sere_collide_respond( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_NONFINITE );
	cr_assert( memcmp( saved + 2 * ( n + f ), s.z, bytes ) == 0, "positions changed on error" );
	s.vz[0] = 0.0f;

	/* a NaN start-of-step position of a vertex in contact; x0 without y0 and z0 */
	float* start = malloc( sizeof( float ) * (size_t) n );
	memcpy( start, s.z, sizeof( float ) * (size_t) n );
	start[0] = NAN;
	sere_collide_state history = state;
	history.x0 = s.x, history.y0 = s.y, history.z0 = start;
	const sere_contact* listed = sere_collide_contacts( s.c, &count );
	float* sides = malloc( sizeof( float ) * (size_t) count );
	for ( int32_t k = 0; k < count; ++k )
	{
		sides[k] = listed[k].side;
	}
	/* the start of the step mirrored: every side it gives is the opposite of detection's */
	for ( int32_t i = 1; i < n; ++i )
	{
		start[i] = -s.z[i];
	}
	cr_assert_eq( sere_collide_respond( s.c, s.bvh, &history, &params, NULL ), SERE_ERR_NONFINITE );
	cr_assert( memcmp( saved + 2 * ( n + f ), s.z, bytes ) == 0, "positions changed on error" );
	for ( int32_t k = 0; k < count; ++k )
	{
		cr_assert_eq( listed[k].side, sides[k], "contact %d: side rewritten on error", k );
	}
	free( sides );
	history.y0 = NULL;
	cr_assert_eq( sere_collide_respond( s.c, s.bvh, &history, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &history, &params, NULL ), SERE_ERR_ARGUMENT );
	free( start );
	s.vz[0] = INFINITY;

	/* Jeong Eq. 14 with a NaN thickness or velocity writes nothing */
	float* h = malloc( sizeof( float ) * (size_t) f );
	for ( int32_t t = 0; t < f; ++t )
	{
		h[t] = 0.01f;
	}
	h[3] = NAN;
	s.vz[0] = 0.0f;
	cr_assert_eq( sere_collide_restore_voronoi( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, 0 ),
				  SERE_ERR_NONFINITE );
	h[3] = 0.01f;
	s.vy[5] = NAN;
	cr_assert_eq( sere_collide_restore_voronoi( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, 0 ),
				  SERE_ERR_NONFINITE );
	cr_assert( memcmp( saved + n, s.x + n, sizeof( float ) * (size_t) f ) == 0, "Voronoi particles written on error" );
	s.vy[5] = 0.0f;
	/* a corner at or past voronoi_first would be overwritten while read */
	cr_assert_eq( sere_collide_restore_voronoi( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n - 1, h, 0 ),
				  SERE_ERR_ARGUMENT );
	s.z[2] = NAN;
	cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, h, 0 ), SERE_ERR_NONFINITE );
	for ( int32_t t = 0; t < f; ++t )
	{
		cr_assert( isfinite( h[t] ), "measure_h wrote a non-finite ĥ" );
	}
	free( h );
	free( saved );
	collide_sheet_release( &s );
}

Test( collide, capacity_overflow_is_reported_and_reserve_fixes_it )
{
	collide_sheet s;
	collide_sheet_make( &s, 20, 16, 2 );
	collide_shape_fold( &s );
	collide_sheet_tree( &s, 16 );
	float* saved = malloc( sizeof( float ) * (size_t) s.n );
	memcpy( saved, s.z, sizeof( float ) * (size_t) s.n );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.3f * s.cell;
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_ERR_CAPACITY );
	/* the capacity holds each kind: the larger count is what it must grow to */
	int32_t needed = stats.contacts > stats.edge_contacts ? stats.contacts : stats.edge_contacts;
	cr_assert_gt( stats.contacts, 16 );
	cr_assert_gt( stats.edge_contacts, 16 );
	cr_assert_eq( memcmp( saved, s.z, sizeof( float ) * (size_t) s.n ), 0, "positions changed on overflow" );
	int32_t listed;
	sere_collide_contacts( s.c, &listed );
	cr_assert_eq( listed, 0 );
	sere_collide_edge_contacts( s.c, &listed );
	cr_assert_eq( listed, 0 );
	cr_assert_eq( sere_collide_reserve( s.c, needed ), SERE_OK );
	int32_t found;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, params.thickness, &found ), SERE_OK );
	cr_assert_eq( found, stats.contacts );
	sere_collide_edge_contacts( s.c, &listed );
	cr_assert_eq( listed, stats.edge_contacts );
	free( saved );
	collide_sheet_release( &s );
}

Test( collide, bad_arguments_are_refused )
{
	collide_sheet s;
	collide_sheet_make( &s, 6, 6, 1 );
	cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &s.bvh ), SERE_OK );
	cr_assert_eq( sere_collide_create( s.bvh, -1, &s.c ), SERE_ERR_ARGUMENT );
	cr_assert_null( s.c );
	cr_assert_eq( sere_collide_create( s.bvh, 0, &s.c ), SERE_OK );
	int32_t count;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, 0.0f, &count ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, NAN, &count ), SERE_ERR_ARGUMENT );
	sere_collide_params params = sere_collide_params_default();
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	params.dt = 0.0f;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	params = sere_collide_params_default();
	params.rounds = 0;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	/* a workspace made for another mesh */
	sere_bvh* other;
	int32_t one[3] = { 0, 1, 2 };
	cr_assert_eq( sere_bvh_create( one, 1, 3, s.x, s.y, s.z, &other ), SERE_OK );
	cr_assert_eq( sere_collide_detect( s.c, other, s.x, s.y, s.z, 0.01f, &count ), SERE_ERR_ARGUMENT );
	sere_bvh_destroy( other );
	collide_sheet_release( &s );
}

/* A flat sheet and a thickness of 3/4 of a cell: every vertex is closer than that to triangles
 * it is not a corner of (across the far edge of its own triangles), but all of them have a
 * corner joined to it by an edge, so no contact may be reported. */
/* A strip of two triangles (0, 1, 2) and (1, 3, 2): its long edges (0, 1) and (2, 3) share no
 * vertex. Here it is 0.5h wide with a slight twist, so that the two are closest in their middles,
 * within the thickness: an edge–edge contact, pushed apart (one up, one down). With rest positions
 * where the strip is as narrow (sere_collide_set_rest), the two are neighbours in the sheet: no
 * contact and no push (the Table 1 maple's petiole buzzed so). With rest positions where it is
 * 2h wide, the strip has been squeezed: a contact again. The brute-force twin agrees each time. */
Test( collide, edges_closer_than_the_thickness_at_rest_are_not_contacts )
{
	const float h = 0.05f, twist = 0.05f * h;
	int32_t tri[6] = { 0, 1, 2, 1, 3, 2 };
	float inv_m[4] = { 1.0f, 1.0f, 1.0f, 1.0f };
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	const float narrow[4] = { 0.0f, 0.0f, 0.5f * h, 0.5f * h }, wide[4] = { 0.0f, 0.0f, 2.0f * h, 2.0f * h };
	const float rest_x[4] = { 0.0f, 1.0f, 0.0f, 1.0f }, rest_z[4] = { 0.0f, 0.0f, 0.0f, 0.0f };
	for ( int rest = 0; rest < 3; ++rest )
	{
		/* rest 0: no rest positions; 1: rest as narrow as now; 2: rest twice the thickness wide */
		float x[4] = { 0.0f, 1.0f, 0.0f, 1.0f }, y[4] = { 0.0f, 0.0f, 0.5f * h, 0.5f * h };
		float z[4] = { 0.0f, 0.0f, -twist, twist };
		float x0[4], y0[4], z0[4];
		memcpy( x0, x, sizeof( x ) ), memcpy( y0, y, sizeof( y ) ), memcpy( z0, z, sizeof( z ) );
		float vx[4] = { 0 }, vy[4] = { 0 }, vz[4] = { 0 };
		float p0[3] = { x[0], y[0], z[0] }, p1[3] = { x[1], y[1], z[1] };
		float q0[3] = { x[2], y[2], z[2] }, q1[3] = { x[3], y[3], z[3] }, weights[2];
		float d2 = sere_closest_points_segments( p0, p1, q0, q1, weights );
		cr_assert( d2 < h * h && weights[0] > 0.0f && weights[0] < 1.0f && weights[1] > 0.0f && weights[1] < 1.0f,
				   "the long edges must be closest inside both, within the thickness (%g, s %g, t %g)", sqrtf( d2 ),
				   weights[0], weights[1] );
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( tri, 2, 4, x, y, z, &bvh ), SERE_OK );
		sere_collide* c;
		cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
		const float* rest_y = rest == 2 ? wide : narrow;
		if ( rest > 0 )
		{
			cr_assert_eq( sere_collide_set_rest( c, rest_x, rest_y, rest_z ), SERE_OK );
		}
		int32_t count = -1;
		cr_assert_eq( sere_collide_detect( c, bvh, x, y, z, h, &count ), SERE_OK );
		const sere_edge_contact* e = sere_collide_edge_contacts( c, &count );
		int32_t expected = rest == 1 ? 0 : 1;
		cr_assert_eq( count, expected, "rest %d: %d edge contacts", rest, count );
		if ( expected )
		{
			cr_assert( e->a0 == 0 && e->a1 == 1 && e->b0 == 2 && e->b1 == 3, "(%d %d)-(%d %d)", e->a0, e->a1, e->b0,
					   e->b1 );
		}
		int32_t ends[4];
		cr_assert_eq( sere_collide_ref_edge_pairs( x, y, z, rest ? rest_x : NULL, rest ? rest_y : NULL,
												   rest ? rest_z : NULL, tri, 2, h, ends, NULL, 1 ),
					  expected );
		sere_collide_state state = { x, y, z, vx, vy, vz, inv_m, NULL, NULL, NULL };
		sere_collide_stats stats;
		cr_assert_eq( sere_collide_resolve( c, bvh, &state, &params, &stats ), SERE_OK );
		bool moved = memcmp( x, x0, sizeof( x ) ) || memcmp( y, y0, sizeof( y ) ) || memcmp( z, z0, sizeof( z ) );
		cr_assert_eq( moved, expected != 0, "rest %d: the response %s", rest,
					  moved ? "moved the strip" : "did nothing" );
		sere_collide_destroy( c );
		sere_bvh_destroy( bvh );
	}
}

/* sere_collide_set_rest refuses a partial set of arrays and non-finite positions (keeping what it
 * had), and forgets the rest positions when given none. */
Test( collide, set_rest_checks_its_input )
{
	const float h = 0.05f;
	int32_t tri[6] = { 0, 1, 2, 1, 3, 2 };
	float x[4] = { 0.0f, 1.0f, 0.0f, 1.0f }, y[4] = { 0.0f, 0.0f, 0.5f * h, 0.5f * h };
	float z[4] = { 0.0f, 0.0f, -0.05f * h, 0.05f * h };
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 4, x, y, z, &bvh ), SERE_OK );
	sere_collide* c;
	cr_assert_eq( sere_collide_create( bvh, 0, &c ), SERE_OK );
	cr_assert_eq( sere_collide_set_rest( NULL, x, y, z ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_set_rest( c, x, NULL, z ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_set_rest( c, x, y, z ), SERE_OK );
	float bad[4] = { 0.0f, NAN, 0.0f, 0.0f };
	cr_assert_eq( sere_collide_set_rest( c, x, bad, z ), SERE_ERR_NONFINITE );
	int32_t count = -1;
	cr_assert_eq( sere_collide_detect( c, bvh, x, y, z, h, &count ), SERE_OK );
	sere_collide_edge_contacts( c, &count );
	cr_assert_eq( count, 0, "the refused call must keep the rest positions" );
	cr_assert_eq( sere_collide_set_rest( c, NULL, NULL, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_detect( c, bvh, x, y, z, h, &count ), SERE_OK );
	sere_collide_edge_contacts( c, &count );
	cr_assert_eq( count, 1, "without rest positions every pair counts" );
	sere_collide_destroy( c );
	sere_bvh_destroy( bvh );
}

Test( collide, neighbours_in_the_sheet_are_not_contacts )
{
	collide_sheet s;
	float h = 0.75f * collide_sheet_make( &s, 30, 20, 9 );
	int64_t close = 0;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		float p[3] = { s.x[i], s.y[i], s.z[i] };
		for ( int32_t t = 0; t < s.triangles; ++t )
		{
			const int32_t* v = s.tri + 3 * t;
			if ( v[0] == i || v[1] == i || v[2] == i )
			{
				continue;
			}
			float a[3] = { s.x[v[0]], s.y[v[0]], s.z[v[0]] }, b[3] = { s.x[v[1]], s.y[v[1]], s.z[v[1]] };
			float c[3] = { s.x[v[2]], s.y[v[2]], s.z[v[2]] }, w[3];
			close += sere_closest_point_triangle( p, a, b, c, w ) < h * h;
		}
	}
	cr_assert_gt( close, s.n / 2, "the sheet must have close non-incident pairs for the test to mean anything" );
	/* Edges sharing no vertex are as close (across a triangle, a vertex to the opposite edge),
	 * but in a flat sheet two edges are closest at an end of one: none is a contact either. */
	int64_t close_edges = 0;
	for ( int32_t t = 0; t < s.triangles; ++t )
	{
		const int32_t* v = s.tri + 3 * t;
		for ( int32_t u = t + 1; u < s.triangles; ++u )
		{
			const int32_t* w = s.tri + 3 * u;
			float p0[3] = { s.x[v[0]], s.y[v[0]], 0.0f }, p1[3] = { s.x[v[1]], s.y[v[1]], 0.0f };
			float q0[3] = { s.x[w[1]], s.y[w[1]], 0.0f }, q1[3] = { s.x[w[2]], s.y[w[2]], 0.0f }, weights[2];
			bool shared = v[0] == w[1] || v[0] == w[2] || v[1] == w[1] || v[1] == w[2];
			close_edges += !shared && sere_closest_points_segments( p0, p1, q0, q1, weights ) < h * h;
		}
	}
	cr_assert_gt( close_edges, s.n / 2 );
	collide_sheet_tree( &s, 1 << 16 );
	int32_t count = -1;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &count ), SERE_OK );
	cr_expect_eq( count, 0, "%d contacts between neighbours in a flat sheet", count );
	sere_collide_edge_contacts( s.c, &count );
	cr_expect_eq( count, 0, "%d edge contacts between neighbours in a flat sheet", count );
	collide_sheet_release( &s );
}
