/* The candidate list (collide_shared.h, SKIN): a detection it serves finds what a search finds,
 * bit for bit, it skips the tree, and it tests only the listed pairs the motion since the listing
 * can have brought within the thickness (list_reach2). */
#include "collide_sheet.h"
#include "ref/collide_ref.h"
#include "solve/bvh.h"
#include "solve/collide.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Asserts that the last detection of c found what a fresh workspace's search finds on the sheet as
 * it is: the same contacts of both kinds, bit for bit, in the same order. */
static void assert_as_searched( collide_sheet* s, sere_bvh* bvh, sere_collide* c, float h, const char* what )
{
	sere_collide* fresh;
	cr_assert_eq( sere_collide_create( bvh, 1 << 16, &fresh ), SERE_OK );
	int32_t fresh_count = -1, n_a, n_b, e_a, e_b;
	cr_assert_eq( sere_collide_detect( fresh, bvh, s->x, s->y, s->z, h, &fresh_count ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( fresh ), 0, "%s: a fresh workspace searches", what );
	const sere_contact* a = sere_collide_contacts( c, &n_a );
	const sere_contact* b = sere_collide_contacts( fresh, &n_b );
	const sere_edge_contact* ea = sere_collide_edge_contacts( c, &e_a );
	const sere_edge_contact* eb = sere_collide_edge_contacts( fresh, &e_b );
	cr_assert( n_a == n_b && e_a == e_b, "%s: %d + %d contacts, search %d + %d", what, n_a, e_a, n_b, e_b );
	/* tolerance 0: the same pairs through the same exact test, in the same order */
	cr_assert( memcmp( a, b, sizeof( sere_contact ) * (size_t) n_a ) == 0, "%s", what );
	cr_assert( memcmp( ea, eb, sizeof( sere_edge_contact ) * (size_t) e_a ) == 0, "%s", what );
	sere_collide_destroy( fresh );
}

/* A detection served by the candidate list (collide.c, SKIN) must find what a search finds: the
 * same contacts of both kinds, bit for bit and in the same order. A crumpled sheet folded through
 * itself moves by a slowly growing amplitude (about 0.1 thickness a step at the folds), drifts by
 * a common translation of 1.2 thicknesses a step (which the list allows for), thins by 0.1% a
 * step, and has its tree rebuilt once midway; a workspace kept across the steps (the list
 * serving most of them) is compared with a fresh one each step (always searching) and with
 * brute force, at 1, 2 and 3 threads. */
Test( collide, listed_detection_equals_search_while_the_sheet_moves )
{
	collide_sheet s;
	collide_sheet_make( &s, 36, 24, 7 );
	float h0 = 0.3f * s.cell;
	for ( int threads = 1; threads <= 3; ++threads )
	{
		omp_set_num_threads( threads );
		collide_sheet_crumple( &s, 0.3, 0.3 * h0, 5 );
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &bvh ), SERE_OK );
		sere_collide* kept;
		cr_assert_eq( sere_collide_create( bvh, 1 << 16, &kept ), SERE_OK );
		int32_t served = 0, searched = 0, most = 0, most_edges = 0;
		for ( int step = 0; step < 40; ++step )
		{
			float h = h0 * powf( 0.999f, (float) step );
			collide_sheet_crumple( &s, 0.3 + 0.0005 * step, 0.3 * h0, 5 );
			for ( int32_t i = 0; i < s.n; ++i )
			{
				s.x[i] += 1.2f * h0 * (float) step, s.y[i] -= 0.7f * h0 * (float) step;
			}
			if ( step == 20 )
			{
				cr_assert_eq( sere_bvh_build( bvh, s.x, s.y, s.z ), SERE_OK );
			}
			cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
			int32_t edges = 0;
			int32_t count = collide_check_pairs( &s, bvh, kept, h, "listed", &edges );
			int32_t uses = sere_collide_list_uses( kept );
			served += uses > 0, searched += uses == 0;
			most = count > most ? count : most;
			most_edges = edges > most_edges ? edges : most_edges;
			char what[64];
			snprintf( what, sizeof( what ), "%d threads, step %d", threads, step );
			assert_as_searched( &s, bvh, kept, h, what );
		}
		cr_assert_gt( most, 50, "the crumple must fold the sheet onto itself" );
		cr_assert_gt( most_edges, 20, "the crumple must bring edges across each other" );
		cr_assert_gt( served, 20, "%d threads: the list must serve most steps (served %d)", threads, served );
		cr_assert_gt( searched, 2, "%d threads: the motion and the rebuild must outgrow the list (searched %d)",
					  threads, searched );
		sere_collide_destroy( kept );
		sere_bvh_destroy( bvh );
	}
	collide_sheet_free( &s );
}

/* sere_collide_resolve refits the tree only for a detection that searches it: over a sheet
 * crumpling step by step, a step the candidate list serves leaves the tree's nodes as they were,
 * a step that searches refits them, and every step's contacts are the brute-force sets. The
 * vertices are pinned (inverse mass 0), so the response moves nothing and the next step's
 * positions are the crumple's alone. */
Test( collide, resolve_refits_the_tree_only_when_it_searches )
{
	collide_sheet s;
	collide_sheet_make( &s, 36, 24, 7 );
	float h = 0.3f * s.cell;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.inv_m[i] = 0.0f;
	}
	/* the tree is made on the flat sheet: the first step searches and refits (or rebuilds) it */
	collide_sheet_tree( &s, 1 << 16 );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	int32_t node_count;
	sere_bvh_nodes( s.bvh, &node_count );
	size_t bytes = sizeof( sere_bvh_node ) * (size_t) node_count;
	sere_bvh_node* before = malloc( bytes );
	int64_t capacity = 1 << 16;
	int32_t *rv = malloc( sizeof( int32_t ) * capacity ), *rt = malloc( sizeof( int32_t ) * capacity );
	int32_t* found = malloc( 2 * sizeof( int32_t ) * capacity );
	int32_t served = 0, searched = 0;
	for ( int step = 0; step < 30; ++step )
	{
		collide_sheet_crumple( &s, 0.3 + 0.0005 * step, 0.3 * h, 5 );
		memcpy( before, sere_bvh_nodes( s.bvh, &node_count ), bytes );
		sere_collide_stats stats;
		cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_OK );
		bool kept = memcmp( before, sere_bvh_nodes( s.bvh, &node_count ), bytes ) == 0;
		bool listed = sere_collide_list_uses( s.c ) > 0;
		served += listed, searched += !listed;
		cr_assert_eq( kept, listed, "step %d: the list %s and the tree was %s", step,
					  listed ? "served" : "did not serve", kept ? "left as it was" : "refit" );
		int32_t count;
		const sere_contact* contacts = sere_collide_contacts( s.c, &count );
		int64_t brute = sere_collide_ref_pairs( s.x, s.y, s.z, s.n, s.tri, s.triangles, h, rv, rt, capacity );
		cr_assert_eq( count, brute, "step %d: %d contacts, brute force %lld", step, count, (long long) brute );
		for ( int32_t k = 0; k < count; ++k )
		{
			found[2 * k] = contacts[k].vertex, found[2 * k + 1] = contacts[k].triangle;
		}
		qsort( found, (size_t) count, 2 * sizeof( int32_t ), collide_cmp_pair );
		for ( int32_t k = 0; k < count; ++k )
		{
			cr_assert( found[2 * k] == rv[k] && found[2 * k + 1] == rt[k], "step %d, pair %d", step, k );
		}
		collide_check_edge_pairs( s.x, s.y, s.z, s.tri, s.triangles, s.c, h, "resolve" );
	}
	cr_assert_gt( served, 10, "the list must serve most steps (served %d)", served );
	cr_assert_gt( searched, 1, "the crumple must outgrow the list (searched %d)", searched );
	free( before ), free( rv ), free( rt ), free( found );
	collide_sheet_release( &s );
}

/* The list's radius at its bound: a U-fold whose halves face each other at 1.47 thicknesses (a
 * fresh workspace's first list has a skin of 0.25 thickness, so it lists pairs up to 1.5
 * thicknesses apart) closes to 0.99 thickness by moving every vertex 0.24 thickness at most
 * (z ↦ d + z (gap − 2d) / gap): the list must serve that detection and hold every pair that has
 * come within the thickness, both kinds, as the fresh search and brute force find them. */
Test( collide, list_holds_pairs_brought_within_the_thickness_by_the_skin )
{
	collide_sheet s;
	float h = 0.3f * collide_sheet_make( &s, 36, 24, 7 ), gap = 1.47f * h, d = 0.24f * h;
	collide_sheet_fold( &s, gap );
	collide_sheet_tree( &s, 1 << 16 );
	int32_t before = -1;
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &before ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s.c ), 0 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] = d + s.z[i] * ( gap - 2.0f * d ) / gap;
	}
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	int32_t edges = 0;
	int32_t count = collide_check_pairs( &s, s.bvh, s.c, h, "closed fold", &edges );
	cr_assert_eq( sere_collide_list_uses( s.c ), 1, "the list must serve a move within its skin" );
	cr_assert_gt( count, 10 * ( before + 10 ), "closing the fold must bring the halves within the thickness" );
	cr_assert_gt( edges, 100 );
	assert_as_searched( &s, s.bvh, s.c, h, "closed fold" );
	collide_sheet_release( &s );
}

/* The pairs a served pass tests of its list (collide_shared.h, list_reach2): only those the motion
 * since the listing can have brought within the thickness. On the U-fold of the test above, the
 * halves 1.47 thicknesses apart: served where the list was made, the pass tests what is within
 * the thickness there (in the bend), not the pairs across the flat halves; after every vertex
 * moved 0.05 thickness it still does not (1.47 − 0.1 is beyond 1 + 0.1); after the fold
 * closed to 0.99 thickness by moves of 0.24 it tests the pairs across, and finds the contacts a
 * search finds. The counts are the recorded pass's exact tests (sere_collide_record_served). */
Test( collide, served_pass_tests_only_pairs_the_motion_can_bring_within_the_thickness )
{
	collide_sheet s;
	float h = 0.3f * collide_sheet_make( &s, 36, 24, 7 ), gap = 1.47f * h;
	collide_sheet_fold( &s, gap );
	collide_sheet_tree( &s, 1 << 16 );
	size_t n = (size_t) s.n;
	for ( size_t i = 0; i < n; ++i )
	{
		s.inv_m[i] = 0.0f;
	}
	sere_collide_traffic search, still, nudged, closed;
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, &search ), SERE_OK );
	cr_assert_gt( search.exact_pairs, 1000, "the search lists the pairs across the fold" );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	float* z0 = malloc( sizeof( float ) * n );
	memcpy( z0, s.z, sizeof( float ) * n );
	float moves[3] = { 0.0f, 0.05f * h, 0.24f * h };
	sere_collide_traffic* traffic[3] = { &still, &nudged, &closed };
	for ( int k = 0; k < 3; ++k )
	{
		float d = moves[k];
		for ( size_t i = 0; i < n; ++i )
		{
			s.z[i] = d + z0[i] * ( gap - 2.0f * d ) / gap;
		}
		cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, traffic[k] ), SERE_OK,
					  "the list serves a move of %g thickness", (double) ( d / h ) );
		/* a served pass leaves the tree as it was: the search needs it refit */
		cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
		char what[32];
		snprintf( what, sizeof( what ), "move %d", k );
		assert_as_searched( &s, s.bvh, s.c, h, what );
	}
	cr_assert_eq( sere_collide_list_uses( s.c ), 3 );
	cr_assert_lt( still.exact_pairs * 4, search.exact_pairs, "unmoved: %ld of %ld listed pairs tested",
				  (long) still.exact_pairs, (long) search.exact_pairs );
	/* a wider reach only adds pairs; across the flat halves it adds none */
	cr_assert_geq( nudged.exact_pairs, still.exact_pairs );
	cr_assert_lt( nudged.exact_pairs * 4, search.exact_pairs, "moved 0.05: %ld of %ld listed pairs tested",
				  (long) nudged.exact_pairs, (long) search.exact_pairs );
	cr_assert_gt( closed.exact_pairs, still.exact_pairs + 1000, "closed: %ld pairs tested", (long) closed.exact_pairs );
	cr_assert_leq( closed.exact_pairs, search.exact_pairs );
	cr_assert_gt( closed.contacts, 100, "closing the fold must bring the halves within the thickness" );
	free( z0 );
	collide_sheet_release( &s );
}

/* A sliver under a served pass (list_reach2): a vertex 1.1997 thicknesses above a triangle 3
 * thicknesses long and 0.0014 wide (sin² of its corner angle 2⁻¹⁹, just above the degenerate
 * 2⁻²⁰), which moves 0.1 thickness towards it while the vertex moves 0.1 towards the triangle.
 * The listing's exact test puts the vertex 1.20197 away (its closest point lands off along the
 * sliver), beyond the 1.2015 a served pass after a move of 0.1 must test; the true distance is
 * 1.1997, and the list keeps 0 for a sliver (list_reach2). After the move the pair is a contact
 * (0.9997): the served pass must find it, as the search does. Coordinates as found by a search
 * over random slivers (thickness 1); the vertex's triangle reaches away from the sliver. */
Test( collide, served_pass_keeps_a_sliver_the_motion_brings_within_the_thickness )
{
	const float then[4][3] = { { -0x0p+0f, 0x0p+0f, 0x0p+0f },
							   { -0x1.7250d2p+0f, 0x1.70ce2p-2f, 0x1.4d3cd4p+1f },
							   { -0x1.6c3df6p+0f, 0x1.69d43cp-2f, 0x1.46ef2ap+1f },
							   { -0x1.d6f334p-2f, -0x1.12f808p+0f, 0x1.fb23fap-1f } };
	const float now[4][3] = { { 0x0p+0f, -0x1.95bc6p-4f, 0x1.c10a9ap-7f },
							  { -0x1.7250d2p+0f, 0x1.0b5f0ap-2f, 0x1.4efddep+1f },
							  { -0x1.6c3df6p+0f, 0x1.046524p-2f, 0x1.48b036p+1f },
							  { -0x1.d6f334p-2f, -0x1.f33882p-1f, 0x1.f41fdp-1f } };
	/* the sliver's normal side the vertex is on: the sliver moved 0.1 along it */
	float up[3];
	for ( int r = 0; r < 3; ++r )
	{
		up[r] = ( now[0][r] - then[0][r] ) / 0.1f;
	}
	float x[2][6], y[2][6], z[2][6];
	for ( int k = 0; k < 2; ++k )
	{
		const float( *at )[3] = k == 0 ? then : now;
		for ( int i = 0; i < 4; ++i )
		{
			x[k][i] = at[i][0], y[k][i] = at[i][1], z[k][i] = at[i][2];
		}
		/* the vertex's triangle: two more corners 2 along `up` from it, 1 to either side */
		for ( int i = 4; i < 6; ++i )
		{
			float side = i == 4 ? 1.0f : -1.0f;
			x[k][i] = at[3][0] + 2.0f * up[0] + side, y[k][i] = at[3][1] + 2.0f * up[1];
			z[k][i] = at[3][2] + 2.0f * up[2];
		}
	}
	const int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	float h = 1.0f;
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 6, x[0], y[0], z[0], &bvh ), SERE_OK );
	sere_collide *kept, *fresh;
	cr_assert_eq( sere_collide_create( bvh, 64, &kept ), SERE_OK );
	cr_assert_eq( sere_collide_create( bvh, 64, &fresh ), SERE_OK );
	int32_t count = -1, fresh_count = -1;
	cr_assert_eq( sere_collide_detect( kept, bvh, x[0], y[0], z[0], h, &count ), SERE_OK );
	cr_assert_eq( count, 0, "1.2 thicknesses apart at the listing" );
	cr_assert_eq( sere_bvh_refit( bvh, x[1], y[1], z[1] ), SERE_OK );
	cr_assert_eq( sere_collide_detect( kept, bvh, x[1], y[1], z[1], h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( kept ), 1, "the list serves a move of 0.1 thickness" );
	cr_assert_eq( sere_collide_detect( fresh, bvh, x[1], y[1], z[1], h, &fresh_count ), SERE_OK );
	cr_assert_eq( fresh_count, 1, "the search finds the vertex within the thickness of the sliver" );
	int32_t n_kept, n_fresh;
	const sere_contact* a = sere_collide_contacts( kept, &n_kept );
	const sere_contact* b = sere_collide_contacts( fresh, &n_fresh );
	cr_assert_eq( n_kept, n_fresh, "the served pass found %d contacts, the search %d", n_kept, n_fresh );
	/* tolerance 0: the same pair through the same exact test */
	cr_assert( memcmp( a, b, sizeof( sere_contact ) * (size_t) n_kept ) == 0 );
	sere_collide_destroy( kept );
	sere_collide_destroy( fresh );
	sere_bvh_destroy( bvh );
}

/* Scales the sheet's triangle layer by `scale` about the middle of its box. */
static void scale_sheet( collide_sheet* s, float scale )
{
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	float* axis[3] = { s->x, s->y, s->z };
	for ( int r = 0; r < 3; ++r )
	{
		for ( int32_t i = 0; i < s->n; ++i )
		{
			lo[r] = axis[r][i] < lo[r] ? axis[r][i] : lo[r];
			hi[r] = axis[r][i] > hi[r] ? axis[r][i] : hi[r];
		}
		float middle = 0.5f * ( lo[r] + hi[r] );
		for ( int32_t i = 0; i < s->n; ++i )
		{
			axis[r][i] = middle + scale * ( axis[r][i] - middle );
		}
	}
}

/* A drying leaf shrinks all over, so its rim moves farther than the skin while no two points come
 * much closer (list_serves takes a uniform scale off the motion). A crumpled sheet folded through
 * itself shrinks by 0.5% a step about its middle: its rim, half a sheet from the middle, moves
 * 0.0025 a step against a skin of 0.0021, so a list allowing only a translation would serve no
 * step. The list must serve most steps, on the same steps at 1 and 2 threads (the scale's sums are
 * taken in block order), and every step must find what a search and brute force find. */
Test( collide, list_serves_a_sheet_that_shrinks_all_over )
{
	collide_sheet s;
	collide_sheet_make( &s, 36, 24, 7 );
	float h = 0.3f * s.cell;
	uint64_t served_steps[2] = { 0, 0 };
	for ( int threads = 1; threads <= 2; ++threads )
	{
		omp_set_num_threads( threads );
		collide_sheet_crumple( &s, 0.3, 0.3 * h, 5 );
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( s.tri, s.triangles, s.n, s.x, s.y, s.z, &bvh ), SERE_OK );
		sere_collide* kept;
		cr_assert_eq( sere_collide_create( bvh, 1 << 16, &kept ), SERE_OK );
		int32_t most = 0;
		for ( int step = 0; step < 40; ++step )
		{
			collide_sheet_crumple( &s, 0.3 + 0.0005 * step, 0.3 * h, 5 );
			scale_sheet( &s, powf( 0.995f, (float) step ) );
			cr_assert_eq( sere_bvh_refit( bvh, s.x, s.y, s.z ), SERE_OK );
			int32_t count = collide_check_pairs( &s, bvh, kept, h, "shrinking", NULL );
			most = count > most ? count : most;
			served_steps[threads - 1] |= (uint64_t) ( sere_collide_list_uses( kept ) > 0 ) << step;
			assert_as_searched( &s, bvh, kept, h, "shrinking" );
		}
		cr_assert_gt( most, 50, "the crumple must fold the sheet onto itself" );
		int served = __builtin_popcountll( served_steps[threads - 1] );
		cr_assert_gt( served, 30, "%d threads: the list must serve most steps of the shrink (served %d of 40)", threads,
					  served );
		sere_collide_destroy( kept );
		sere_bvh_destroy( bvh );
	}
	cr_assert_eq( served_steps[0], served_steps[1], "the same steps served at 1 and 2 threads" );
	collide_sheet_free( &s );
}

/* The scale's bound (list_serves): a U-fold whose halves face each other across `gap` is listed
 * (a fresh workspace's skin is 0.25 thickness: pairs up to 1.5 thicknesses apart), then the whole
 * sheet shrinks by `scale` about its middle, bringing the halves within the thickness. At 1.2
 * thicknesses the pairs across are listed and a shrink by 0.8 keeps every pair left off the list
 * beyond the thickness (0.8 × 1.5 > 1): the list serves, and the served pass must test the pairs
 * across, now 0.96 thickness apart (they were 1.2 thicknesses apart, beyond the thickness plus
 * the residual motion, but within it over the scale). At 1.6 thicknesses the pairs across are
 * left off the list and a shrink by 0.6 brings them to 0.96: the list must not serve. Either way
 * the detection finds what a search and brute force find. The thickness is 0.2 cell, so that the
 * shrunk sheet's triangles stay taller than it. */
Test( collide, list_serves_a_shrink_only_while_pairs_left_off_stay_apart )
{
	const float gaps[2] = { 1.2f, 1.6f }, scales[2] = { 0.8f, 0.6f };
	for ( int k = 0; k < 2; ++k )
	{
		collide_sheet s;
		float h = 0.2f * collide_sheet_make( &s, 36, 24, 7 );
		collide_sheet_fold( &s, gaps[k] * h );
		collide_sheet_tree( &s, 1 << 16 );
		int32_t before = -1;
		cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &before ), SERE_OK );
		cr_assert_eq( sere_collide_list_uses( s.c ), 0 );
		scale_sheet( &s, scales[k] );
		cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
		int32_t count = collide_check_pairs( &s, s.bvh, s.c, h, k == 0 ? "listed across" : "left off", NULL );
		cr_assert_eq( sere_collide_list_uses( s.c ), k == 0 ? 1 : 0, "gap %g, shrink %g: the list must %s",
					  (double) gaps[k], (double) scales[k], k == 0 ? "serve" : "not serve" );
		cr_assert_gt( count, before + 300, "the shrink must bring the halves within the thickness (%d, before %d)",
					  count, before );
		assert_as_searched( &s, s.bvh, s.c, h, k == 0 ? "listed across" : "left off" );
		collide_sheet_release( &s );
	}
}
