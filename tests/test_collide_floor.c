/* The floors of the collision search (sere_collide_record_search, sere_collide_touch_search) and
 * of a served pass (sere_collide_record_served, sere_collide_touch_served): the recording search
 * or pass does what a plain one does, and the floor replays it whole, counting what the record
 * counts and leaving the positions, velocities, contacts and candidate list as they were. */
#include "collide_sheet.h"
#include "solve/bvh.h"
#include "solve/collide.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* The contacts of the last detection, both kinds, copied. */
typedef struct found
{
	int32_t count, edge_count;
	sere_contact* contacts;
	sere_edge_contact* edges;
} found;

static found found_copy( const sere_collide* c )
{
	found f;
	const sere_contact* contacts = sere_collide_contacts( c, &f.count );
	const sere_edge_contact* edges = sere_collide_edge_contacts( c, &f.edge_count );
	f.contacts = malloc( sizeof( sere_contact ) * (size_t) ( f.count + 1 ) );
	f.edges = malloc( sizeof( sere_edge_contact ) * (size_t) ( f.edge_count + 1 ) );
	memcpy( f.contacts, contacts, sizeof( sere_contact ) * (size_t) f.count );
	memcpy( f.edges, edges, sizeof( sere_edge_contact ) * (size_t) f.edge_count );
	return f;
}

/* Whether the last detection's contacts are f's, bit for bit and in order. */
static bool found_same( const sere_collide* c, const found* f )
{
	int32_t count, edge_count;
	const sere_contact* contacts = sere_collide_contacts( c, &count );
	const sere_edge_contact* edges = sere_collide_edge_contacts( c, &edge_count );
	return count == f->count && edge_count == f->edge_count &&
		   memcmp( contacts, f->contacts, sizeof( sere_contact ) * (size_t) count ) == 0 &&
		   memcmp( edges, f->edges, sizeof( sere_edge_contact ) * (size_t) edge_count ) == 0;
}

static void found_free( found* f )
{
	free( f->contacts );
	free( f->edges );
}

/* Records the search of the sheet as it is on `threads` threads, then replays it twice (the
 * second time with OpenMP set to one thread: the floor keeps the recorded runs) and checks what
 * each left and counted. */
static void check_floor( collide_sheet* s, float h, int threads, const char* what )
{
	omp_set_num_threads( threads );
	cr_assert_eq( sere_collide_set_threads( s->c, threads ), SERE_OK );
	cr_assert_eq( sere_bvh_refit( s->bvh, s->x, s->y, s->z ), SERE_OK );
	int32_t count;
	sere_collide_drop_list( s->c );
	cr_assert_eq( sere_collide_detect( s->c, s->bvh, s->x, s->y, s->z, h, &count ), SERE_OK );
	found plain = found_copy( s->c );
	cr_assert_gt( plain.count, 0, "%s: a shape without contacts tests little", what );

	sere_collide_traffic recorded, replayed;
	cr_assert_eq( sere_collide_record_search( s->c, s->bvh, s->x, s->y, s->z, h, &recorded ), SERE_OK );
	cr_assert( found_same( s->c, &plain ), "%s, %d threads: recording changed what the search finds", what, threads );
	cr_assert_eq( recorded.contacts, (int64_t) plain.count + plain.edge_count );
	/* every node opened leads somewhere, every pair tested was gathered first */
	cr_assert_gt( recorded.nodes, 0 );
	cr_assert_geq( recorded.leaves, recorded.nodes, "%s: %ld triangles from %ld nodes", what, (long) recorded.leaves,
				   (long) recorded.nodes );
	cr_assert_geq( recorded.bound_pairs, recorded.exact_pairs );
	cr_assert_geq( recorded.exact_pairs, recorded.contacts );

	size_t n = (size_t) s->n;
	float* before = malloc( 3 * sizeof( float ) * n );
	memcpy( before, s->x, sizeof( float ) * n );
	memcpy( before + n, s->y, sizeof( float ) * n );
	memcpy( before + 2 * n, s->z, sizeof( float ) * n );
	for ( int pass = 0; pass < 2; ++pass )
	{
		omp_set_num_threads( pass == 0 ? threads : 1 );
		memset( &replayed, 0xff, sizeof( replayed ) );
		cr_assert_eq( sere_collide_touch_search( s->c, s->bvh, s->x, s->y, s->z, &replayed ), SERE_OK );
		cr_assert_eq( replayed.nodes, recorded.nodes, "%s, %d threads: %ld nodes replayed of %ld", what, threads,
					  (long) replayed.nodes, (long) recorded.nodes );
		cr_assert_eq( replayed.leaves, recorded.leaves );
		cr_assert_eq( replayed.bound_pairs, recorded.bound_pairs );
		cr_assert_eq( replayed.exact_pairs, recorded.exact_pairs );
		cr_assert_eq( replayed.contacts, recorded.contacts );
		cr_assert( memcmp( before, s->x, sizeof( float ) * n ) == 0 &&
					   memcmp( before + n, s->y, sizeof( float ) * n ) == 0 &&
					   memcmp( before + 2 * n, s->z, sizeof( float ) * n ) == 0,
				   "%s: the floor moved a vertex", what );
		cr_assert( found_same( s->c, &plain ), "%s, %d threads: the floor changed the contacts", what, threads );
	}
	omp_set_num_threads( threads );
	/* the list the floor rewrote serves the next detection, which finds the same contacts */
	cr_assert_eq( sere_collide_detect( s->c, s->bvh, s->x, s->y, s->z, h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s->c ), 1, "%s: the list no longer serves", what );
	cr_assert( found_same( s->c, &plain ), "%s, %d threads: the list the floor left finds other contacts", what,
			   threads );
	free( before );
	found_free( &plain );
}

Test( collide_floor, replays_the_recorded_search )
{
	int saved = omp_get_max_threads();
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 5, 1 << 16 );
	for ( int threads = 1; threads <= 3; ++threads )
	{
		collide_shape_crumple( &s );
		check_floor( &s, h, threads, "crumpled" );
		collide_shape_fold( &s );
		check_floor( &s, h, threads, "folded" );
	}
	/* with rest positions, the exact edge test reads them too */
	collide_sheet_flat( &s );
	cr_assert_eq( sere_collide_set_rest( s.c, s.x, s.y, s.z ), SERE_OK );
	collide_shape_crumple( &s );
	check_floor( &s, h, 2, "crumpled, rest positions" );
	omp_set_num_threads( saved );
	collide_sheet_release( &s );
}

Test( collide_floor, rejects_what_it_cannot_replay )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 16, 12, 3, 1 << 14 );
	collide_shape_crumple( &s );
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	sere_collide_traffic traffic;
	int32_t count;
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, &traffic ), SERE_ERR_ARGUMENT,
				  "no record yet" );
	cr_assert_eq( sere_collide_record_search( NULL, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, -h, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_touch_search( NULL, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_search( s.c, NULL, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, NULL, s.z, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_OK );

	/* a detection since the record: its contacts and list are no longer the recorded ones */
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );

	/* more threads, or a rebuilt tree */
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_set_threads( s.c, 4 ), SERE_OK );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_OK );
	cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );

	/* a search that fails keeps no record */
	s.x[3] = NAN;
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_ERR_NONFINITE );
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );
	collide_sheet_release( &s );
}

/* The sheet's positions and velocities, copied (6 rows of n). */
static float* motion_copy( const collide_sheet* s )
{
	size_t n = (size_t) s->n;
	float* copy = malloc( 6 * sizeof( float ) * n );
	const float* rows[6] = { s->x, s->y, s->z, s->vx, s->vy, s->vz };
	for ( int r = 0; r < 6; ++r )
	{
		memcpy( copy + (size_t) r * n, rows[r], sizeof( float ) * n );
	}
	return copy;
}

static void motion_restore( collide_sheet* s, const float* copy )
{
	size_t n = (size_t) s->n;
	float* rows[6] = { s->x, s->y, s->z, s->vx, s->vy, s->vz };
	for ( int r = 0; r < 6; ++r )
	{
		memcpy( rows[r], copy + (size_t) r * n, sizeof( float ) * n );
	}
}

static bool motion_same( const collide_sheet* s, const float* copy )
{
	size_t n = (size_t) s->n;
	const float* rows[6] = { s->x, s->y, s->z, s->vx, s->vy, s->vz };
	bool same = true;
	for ( int r = 0; r < 6; ++r )
	{
		same = same && memcmp( rows[r], copy + (size_t) r * n, sizeof( float ) * n ) == 0;
	}
	return same;
}

/* On the sheet as it is, at rest, on `threads` threads: a search lists the pairs, a plain served
 * pass (sere_collide_resolve) runs from there, then the recorded one from the same start must do
 * what it did, bit for bit; the floor replays it twice (the second time with OpenMP at one thread)
 * and must count what the record counts and leave the contacts, positions, velocities and list as
 * they were. With history, the response takes its sides from the start-of-step positions. */
static void check_served_floor( collide_sheet* s, float h, int threads, bool history, const char* what )
{
	omp_set_num_threads( threads );
	cr_assert_eq( sere_collide_set_threads( s->c, threads ), SERE_OK );
	cr_assert_eq( sere_bvh_refit( s->bvh, s->x, s->y, s->z ), SERE_OK );
	size_t n = (size_t) s->n;
	memset( s->vx, 0, sizeof( float ) * n ), memset( s->vy, 0, sizeof( float ) * n );
	memset( s->vz, 0, sizeof( float ) * n );
	int32_t count;
	sere_collide_drop_list( s->c );
	cr_assert_eq( sere_collide_detect( s->c, s->bvh, s->x, s->y, s->z, h, &count ), SERE_OK );
	found searched = found_copy( s->c );
	cr_assert_gt( searched.count, 0, "%s: a shape without contacts tests little", what );
	float* start = motion_copy( s );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	/* room for the fold's response to stop before its last iteration (at 30), the crumple's not */
	params.iterations = 40;
	sere_collide_state state = { s->x, s->y, s->z, s->vx, s->vy, s->vz, s->inv_m, NULL, NULL, NULL };
	if ( history )
	{
		state.x0 = start, state.y0 = start + n, state.z0 = start + 2 * n;
	}

	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( s->c, s->bvh, &state, &params, &stats ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s->c ), 1, "%s: the list must serve the pass", what );
	cr_assert_gt( stats.iterations, 0, "%s: a response of one evaluation tests little", what );
	found plain = found_copy( s->c );
	float* pushed = motion_copy( s );

	motion_restore( s, start );
	sere_collide_traffic recorded, replayed;
	cr_assert_eq( sere_collide_record_served( s->c, s->bvh, &state, &params, &recorded ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s->c ), 2 );
	cr_assert( found_same( s->c, &plain ), "%s, %d threads: recording changed the contacts", what, threads );
	cr_assert( motion_same( s, pushed ), "%s, %d threads: recording changed the pushes", what, threads );
	int64_t contacts = (int64_t) plain.count + plain.edge_count;
	cr_assert_eq( recorded.nodes + recorded.leaves + recorded.bound_pairs, 0, "%s: a served pass walks no tree", what );
	cr_assert_eq( recorded.contacts, contacts );
	cr_assert_geq( recorded.exact_pairs, recorded.contacts );
	cr_assert_eq( recorded.evaluated, contacts * ( stats.iterations + 1 ), "%s: %ld evaluated", what,
				  (long) recorded.evaluated );
	/* four gather entries a contact */
	cr_assert_eq( recorded.gathered, 4 * contacts * stats.iterations );

	for ( int pass = 0; pass < 2; ++pass )
	{
		omp_set_num_threads( pass == 0 ? threads : 1 );
		memset( &replayed, 0xff, sizeof( replayed ) );
		cr_assert_eq( sere_collide_touch_served( s->c, s->bvh, &state, &replayed ), SERE_OK );
		cr_assert( memcmp( &replayed, &recorded, sizeof( recorded ) ) == 0,
				   "%s, %d threads: replayed %ld pairs, %ld evaluations, %ld entries of %ld, %ld, %ld", what, threads,
				   (long) replayed.exact_pairs, (long) replayed.evaluated, (long) replayed.gathered,
				   (long) recorded.exact_pairs, (long) recorded.evaluated, (long) recorded.gathered );
		cr_assert( motion_same( s, pushed ), "%s, %d threads: the floor moved a vertex", what, threads );
		cr_assert( found_same( s->c, &plain ), "%s, %d threads: the floor changed the contacts", what, threads );
	}
	omp_set_num_threads( threads );
	/* the list the floor left serves the start again, with the search's contacts */
	motion_restore( s, start );
	cr_assert_eq( sere_collide_detect( s->c, s->bvh, s->x, s->y, s->z, h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s->c ), 3, "%s: the list no longer serves", what );
	cr_assert( found_same( s->c, &searched ), "%s, %d threads: the list the floor left finds other contacts", what,
			   threads );
	free( start ), free( pushed );
	found_free( &searched ), found_free( &plain );
}

Test( collide_floor, replays_the_served_pass )
{
	int saved = omp_get_max_threads();
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 5, 1 << 16 );
	for ( int threads = 1; threads <= 3; ++threads )
	{
		collide_shape_crumple( &s );
		check_served_floor( &s, h, threads, threads != 2, "crumpled" );
		collide_shape_fold( &s );
		check_served_floor( &s, h, threads, threads == 2, "folded" );
	}
	omp_set_num_threads( saved );
	collide_sheet_release( &s );
}

Test( collide_floor, served_floor_rejects_what_it_cannot_replay )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 16, 12, 3, 1 << 14 );
	collide_shape_fold( &s );
	cr_assert_eq( sere_bvh_refit( s.bvh, s.x, s.y, s.z ), SERE_OK );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.dt = 0.01f;
	float* start = motion_copy( &s );
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	sere_collide_traffic traffic;
	int32_t count;
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, &traffic ), SERE_ERR_ARGUMENT, "no record yet" );

	/* no list yet, or one made for a thinner sheet: the pass would search, and nothing moves */
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, 0.5f * h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert( motion_same( &s, start ), "a refused record moved the sheet" );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );

	/* a list that serves, but arguments resolve refuses, or more than one round */
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &count ), SERE_OK );
	cr_assert_gt( count, 0 );
	sere_collide_state partial = state;
	partial.x0 = s.x;
	cr_assert_eq( sere_collide_record_served( NULL, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_served( s.c, NULL, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, NULL, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &partial, &params, NULL ), SERE_ERR_ARGUMENT );
	params.rounds = 2;
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_ARGUMENT );
	params.rounds = 1;
	cr_assert( motion_same( &s, start ), "a refused record moved the sheet" );
	cr_assert_eq( sere_collide_list_uses( s.c ), 0 );

	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_list_uses( s.c ), 1 );
	cr_assert_eq( sere_collide_touch_served( NULL, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_served( s.c, NULL, &state, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, NULL, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &partial, NULL ), SERE_ERR_ARGUMENT );
	/* each floor replays only its own kind of record */
	cr_assert_eq( sere_collide_touch_search( s.c, s.bvh, s.x, s.y, s.z, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_OK );

	/* a detection since the record, more threads, or a rebuilt tree */
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_set_threads( s.c, 4 ), SERE_OK );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_collide_detect( s.c, s.bvh, s.x, s.y, s.z, h, &count ), SERE_OK );
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_OK );
	cr_assert_eq( sere_bvh_build( s.bvh, s.x, s.y, s.z ), SERE_OK );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );

	/* a search's record is not a served pass's */
	cr_assert_eq( sere_collide_record_search( s.c, s.bvh, s.x, s.y, s.z, h, NULL ), SERE_OK );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );

	/* a pass whose response fails keeps no record */
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_OK );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.vx[i] = NAN;
	}
	cr_assert_eq( sere_collide_record_served( s.c, s.bvh, &state, &params, NULL ), SERE_ERR_NONFINITE );
	cr_assert_eq( sere_collide_touch_served( s.c, s.bvh, &state, NULL ), SERE_ERR_ARGUMENT );
	free( start );
	collide_sheet_release( &s );
}
