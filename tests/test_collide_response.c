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

/* The default response at thickness h with the given iterations a round and rounds. */
static sere_collide_params response_params( float h, int32_t iterations, int32_t rounds )
{
	sere_collide_params params = sere_collide_params_default();
	params.thickness = h;
	params.iterations = iterations;
	params.rounds = rounds;
	return params;
}

/* The U-fold closer than the thickness: after the response no vertex is closer than the
 * thickness to a non-incident triangle and no two edges are, up to SERE_COLLIDE_TOLERANCE (0.1%:
 * Jacobi averaging approaches the target from below). At gap 0.5h the bend (radius 0.25h) is
 * tighter than the thickness allows, and the edge–edge contacts across it, several on each
 * vertex, open it slowly: 32 iterations a round (16 left 5 of them 0.4% short) and a fourth round
 * (the third's pushes left one new pair). */
Test( collide, response_separates_u_fold )
{
	collide_sheet s;
	float h = collide_sheet_open( &s, 36, 24, 8, 0 );
	sere_collide_params params = response_params( h, 32, 4 );
	const double gaps[] = { 0.8, 0.5 };
	for ( int g = 0; g < 2; ++g )
	{
		collide_sheet_fold( &s, gaps[g] * h );
		memset( s.vx, 0, sizeof( float ) * (size_t) s.n );
		memset( s.vy, 0, sizeof( float ) * (size_t) s.n );
		memset( s.vz, 0, sizeof( float ) * (size_t) s.n );
		float* before = malloc( sizeof( float ) * (size_t) s.n );
		memcpy( before, s.z, sizeof( float ) * (size_t) s.n );
		cr_assert_gt( collide_violations( &s, h, SERE_COLLIDE_TOLERANCE ), s.n );
		sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
		sere_collide_stats stats;
		cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_OK );
		cr_assert_gt( stats.contacts, s.n );
		cr_assert_eq( stats.unresolved, 0 );
		int64_t left = collide_violations( &s, h, SERE_COLLIDE_TOLERANCE );
		cr_assert_eq( left, 0, "gap %gh: %lld pairs still closer than the thickness", gaps[g], (long long) left );
		/* velocities carry the displacement: Δv = Δx / dt, to float rounding of the division */
		for ( int32_t i = 0; i < s.n; ++i )
		{
			float expected = ( s.z[i] - before[i] ) / params.dt;
			cr_assert( fabsf( s.vz[i] - expected ) <= 1e-3f * ( 1.0f + fabsf( expected ) ), "velocity %d", i );
		}
		free( before );
	}
	collide_sheet_release( &s );
}

/* A sheet crumpled through itself cannot be separated by proximity pushes where it truly
 * intersects; the response must still clear almost every contact and report what is left. Its
 * edges pass through each other there, each in several edge–edge contacts sharing vertices.
 * Every contact takes the smallest share among its members (so that it moves no momentum),
 * which clears crowded contacts more slowly than giving each vertex the mean of its own did:
 * with 16 iterations and 3 rounds 6 of 75 vertex–triangle and 41 of 177 edge–edge pairs remain
 * (the per-vertex mean left 5 and 33); 64 iterations and 6 rounds more clear every one. The
 * masses differ from vertex to vertex (1 to 4), and the centre of mass does not move. */
Test( collide, response_on_crumpled_sheet_is_bounded_and_moves_no_momentum )
{
	collide_sheet s;
	float h = 0.3f * collide_sheet_make( &s, 36, 24, 9 );
	collide_sheet_crumple( &s, 0.4, 0.3 * h, 13 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.inv_m[i] = 1.0f / (float) ( 1 + i % 4 );
	}
	double moment[3] = { 0.0, 0.0, 0.0 }, mass = 0.0;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		moment[0] += s.x[i] / s.inv_m[i], moment[1] += s.y[i] / s.inv_m[i], moment[2] += s.z[i] / s.inv_m[i];
		mass += 1.0 / s.inv_m[i];
	}
	collide_sheet_tree( &s, 0 );
	sere_collide_params params = response_params( h, 16, 3 );
	int64_t initial[2] = { collide_violations_of( &s, h, SERE_COLLIDE_TOLERANCE, false ),
						   collide_violations_of( &s, h, SERE_COLLIDE_TOLERANCE, true ) };
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_OK );
	int64_t left[2] = { collide_violations_of( &s, h, SERE_COLLIDE_TOLERANCE, false ),
						collide_violations_of( &s, h, SERE_COLLIDE_TOLERANCE, true ) };
	cr_log_info( "crumpled: %lld and %lld violations before, %lld and %lld after, %d unresolved reported",
				 (long long) initial[0], (long long) initial[1], (long long) left[0], (long long) left[1],
				 stats.unresolved );
	cr_assert_gt( initial[0], 50 );
	cr_assert_gt( initial[1], 50 );
	cr_assert_leq( left[0] * 10, initial[0], "more than a tenth of the vertex–triangle contacts remain" );
	cr_assert_leq( left[1] * 4, initial[1], "more than a quarter of the edge–edge contacts remain" );
	params.iterations = 64;
	params.rounds = 6;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_OK );
	cr_assert_eq( stats.unresolved, 0 );
	cr_assert_eq( collide_violations( &s, h, SERE_COLLIDE_TOLERANCE ), 0 );
	double after[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t i = 0; i < s.n; ++i )
	{
		cr_assert( isfinite( s.x[i] ) && isfinite( s.y[i] ) && isfinite( s.z[i] ) && isfinite( s.vz[i] ) );
		after[0] += s.x[i] / s.inv_m[i], after[1] += s.y[i] / s.inv_m[i], after[2] += s.z[i] / s.inv_m[i];
	}
	/* Each contact's pushes sum to zero momentum exactly; what is left is float rounding of
	 * positions near 1 (6e-8) over a few thousand moved vertices of mass up to 4, summed:
	 * 1e-6 of the total mass, against a centroid motion of ~1e-4 cell when the shares differed. */
	for ( int k = 0; k < 3; ++k )
	{
		cr_assert_float_eq( after[k] / mass, moment[k] / mass, 1e-6, "axis %d: the centre of mass moved by %g", k,
							( after[k] - moment[k] ) / mass );
	}
	collide_sheet_release( &s );
}

/* Jeong Eq. 14 in both modes: ĥ measured before the collision pass (Algorithm 1 line 14), or the rest
 * thickness h. */
Test( collide, voronoi_restore_eq14 )
{
	collide_sheet s;
	collide_sheet_make( &s, 20, 16, 10 );
	collide_sheet_crumple( &s, 0.1, 0.0, 3 );
	int32_t n = s.n, f = s.triangles;
	uint64_t state = 2;
	/* Voronoi particles scattered around their triangles, velocities random */
	for ( int32_t i = 0; i < n + f; ++i )
	{
		s.vx[i] = (float) ( sere_test_unit( &state ) - 0.5 );
		s.vy[i] = (float) ( sere_test_unit( &state ) - 0.5 );
		s.vz[i] = (float) ( sere_test_unit( &state ) - 0.5 );
	}
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = s.tri + 3 * t;
		s.x[n + t] =
			( s.x[v[0]] + s.x[v[1]] + s.x[v[2]] ) / 3.0f + (float) ( 0.01 * ( sere_test_unit( &state ) - 0.5 ) );
		s.y[n + t] =
			( s.y[v[0]] + s.y[v[1]] + s.y[v[2]] ) / 3.0f + (float) ( 0.01 * ( sere_test_unit( &state ) - 0.5 ) );
		s.z[n + t] =
			( s.z[v[0]] + s.z[v[1]] + s.z[v[2]] ) / 3.0f + (float) ( 0.02 * ( sere_test_unit( &state ) - 0.5 ) );
	}
	float* h_hat = malloc( sizeof( float ) * (size_t) f );
	double* h_ref = malloc( sizeof( double ) * (size_t) f );
	cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, h_hat, 0 ), SERE_OK );
	sere_collide_ref_measure_h( s.x, s.y, s.z, s.tri, f, n, h_ref );
	for ( int32_t t = 0; t < f; ++t )
	{
		/* offsets of 0.01 with unit-size coordinates: float error ~1e-7 × |x| */
		cr_assert( fabs( h_hat[t] - h_ref[t] ) < 1e-6, "ĥ %d: %g vs %g", t, h_hat[t], h_ref[t] );
	}

	/* the layer moves (a collision pass would), then both modes restore */
	for ( int32_t i = 0; i < n; ++i )
	{
		s.z[i] += (float) ( 0.002 * sin( 9.0 * s.u[i] ) );
	}
	float* rest = malloc( sizeof( float ) * (size_t) f );
	for ( int32_t t = 0; t < f; ++t )
	{
		rest[t] = t % 3 == 0 ? -0.06f : 0.01f; /* signed, as h_vein and h_surf of Table 2 */
	}
	const float* modes[2] = { h_hat, rest };
	size_t all = (size_t) ( n + f );
	double *dx = malloc( sizeof( double ) * all ), *dy = malloc( sizeof( double ) * all ),
		   *dz = malloc( sizeof( double ) * all ), *dvx = malloc( sizeof( double ) * all ),
		   *dvy = malloc( sizeof( double ) * all ), *dvz = malloc( sizeof( double ) * all ),
		   *dh = malloc( sizeof( double ) * (size_t) f );
	for ( int m = 0; m < 2; ++m )
	{
		for ( size_t i = 0; i < all; ++i )
		{
			dx[i] = s.x[i], dy[i] = s.y[i], dz[i] = s.z[i], dvx[i] = s.vx[i], dvy[i] = s.vy[i], dvz[i] = s.vz[i];
		}
		for ( int32_t t = 0; t < f; ++t )
		{
			dh[t] = modes[m][t];
		}
		cr_assert_eq( sere_collide_restore_voronoi( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, modes[m], 0 ),
					  SERE_OK );
		sere_collide_ref_restore_voronoi( dx, dy, dz, dvx, dvy, dvz, s.tri, f, n, dh );
		for ( int32_t t = 0; t < f; ++t )
		{
			int32_t i = n + t;
			/* position: centroid + h n in float against double, coordinates ≤ 1.5 and |h| ≤ 0.06:
			 * a few ulps of the coordinates (2e-7) */
			cr_assert( fabs( s.x[i] - dx[i] ) < 1e-6 && fabs( s.y[i] - dy[i] ) < 1e-6 && fabs( s.z[i] - dz[i] ) < 1e-6,
					   "mode %d: particle %d off Jeong Eq. 14", m, t );
			/* velocity: the corner mean, three additions and a division in float */
			cr_assert( fabs( s.vx[i] - dvx[i] ) < 1e-6 && fabs( s.vy[i] - dvy[i] ) < 1e-6 &&
						   fabs( s.vz[i] - dvz[i] ) < 1e-6,
					   "mode %d: velocity %d is not the corner mean", m, t );
		}
		/* measuring again gives back the thickness used (the particle sits on the normal line) */
		float* again = malloc( sizeof( float ) * (size_t) f );
		cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, again, 0 ), SERE_OK );
		for ( int32_t t = 0; t < f; ++t )
		{
			cr_assert( fabsf( again[t] - modes[m][t] ) < 1e-6f, "mode %d: %d measures %g, restored %g", m, t, again[t],
					   modes[m][t] );
		}
		free( again );
	}
	free( dx ), free( dy ), free( dz ), free( dvx ), free( dvy ), free( dvz ), free( dh );
	free( rest );
	free( h_hat );
	free( h_ref );
	collide_sheet_free( &s );
}

/* Runs one collision pass (three rounds) plus the Voronoi restore with the given thread count
 * and returns the state as one buffer, the first detection's contacts of each kind, and (when
 * edges is not NULL) a copy of the last detection's edge–edge contacts (*edge_count of them). */
static float* collide_run_pass( int threads, void ( *shape )( collide_sheet* ), bool history, int32_t* contacts_out,
								int32_t* edge_contacts_out, sere_edge_contact** edges, int32_t* edge_count )
{
	collide_sheet s;
	collide_sheet_make( &s, 36, 24, 12 );
	shape( &s );
	int32_t n = s.n, f = s.triangles;
	/* start-of-step positions: the shape moved off the sheet by up to half the thickness, so
	 * some contacts keep their detection side and others take the opposite one */
	float* start = malloc( sizeof( float ) * 3 * (size_t) n );
	for ( int32_t i = 0; i < n; ++i )
	{
		start[i] = s.x[i], start[n + i] = s.y[i];
		start[2 * n + i] = s.z[i] + 0.15f * s.cell * sinf( 0.7f * (float) i );
	}
	float* h = malloc( sizeof( float ) * (size_t) f );
	for ( int32_t t = 0; t < f; ++t )
	{
		h[t] = 0.01f;
	}
	omp_set_num_threads( threads );
	collide_sheet_tree( &s, 0 );
	sere_collide_params params = sere_collide_params_default();
	params.thickness = 0.3f * s.cell;
	params.rounds = 3;
	sere_collide_state state = { s.x, s.y, s.z, s.vx, s.vy, s.vz, s.inv_m, NULL, NULL, NULL };
	if ( history )
	{
		state.x0 = start, state.y0 = start + n, state.z0 = start + 2 * n;
	}
	sere_collide_stats stats;
	cr_assert_eq( sere_collide_resolve( s.c, s.bvh, &state, &params, &stats ), SERE_OK );
	cr_assert_eq( sere_collide_restore_voronoi( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, 0 ), SERE_OK );
	*contacts_out = stats.contacts;
	*edge_contacts_out = stats.edge_contacts;
	if ( edges != NULL )
	{
		const sere_edge_contact* listed = sere_collide_edge_contacts( s.c, edge_count );
		*edges = malloc( sizeof( sere_edge_contact ) * (size_t) ( *edge_count + 1 ) );
		memcpy( *edges, listed, sizeof( sere_edge_contact ) * (size_t) *edge_count );
	}
	free( start );
	size_t all = (size_t) ( n + f );
	float* out = malloc( sizeof( float ) * 6 * all );
	const float* arrays[6] = { s.x, s.y, s.z, s.vx, s.vy, s.vz };
	for ( int k = 0; k < 6; ++k )
	{
		memcpy( out + (size_t) k * all, arrays[k], sizeof( float ) * all );
	}
	free( h );
	collide_sheet_release( &s );
	return out;
}

/* Three threads as well as two: the detection lists, the gather lists (a counting sort split
 * over threads) and the response's share of vertices (cut by gather work) all depend on the
 * team size, the result must not. */
Test( collide, identical_with_one_two_and_three_threads )
{
	void ( *shapes[2] )( collide_sheet* ) = { collide_shape_fold, collide_shape_crumple };
	int saved = omp_get_max_threads();
	for ( int run = 0; run < 4; ++run )
	{
		int k = run % 2;
		bool history = run >= 2;
		int32_t c[3], e[3], listed[3];
		sere_edge_contact* edges[3];
		float* result[3];
		for ( int t = 0; t < 3; ++t )
		{
			result[t] = collide_run_pass( t + 1, shapes[k], history, c + t, e + t, edges + t, listed + t );
		}
		collide_sheet probe;
		collide_sheet_make( &probe, 36, 24, 12 );
		size_t bytes = sizeof( float ) * 6 * (size_t) ( probe.n + probe.triangles );
		collide_sheet_free( &probe );
		/* the fold's contacts exceed the sequential-response threshold (512 of both kinds),
		 * exercising the parallel response; the crumple's (about 130 and 360) stay below it */
		cr_assert_gt( c[0], k == 0 ? 512 : 20, "shape %d: %d contacts", k, c[0] );
		cr_assert_gt( e[0], k == 0 ? 512 : 20, "shape %d: %d edge contacts", k, e[0] );
		for ( int t = 1; t < 3; ++t )
		{
			cr_assert_eq( c[0], c[t] );
			cr_assert_eq( e[0], e[t] );
			cr_assert_eq( listed[0], listed[t] );
			cr_assert_eq( memcmp( edges[0], edges[t], sizeof( sere_edge_contact ) * (size_t) listed[0] ), 0,
						  "shape %d, history %d: 1 and %d threads list different edge contacts", k, history, t + 1 );
			cr_assert_eq( memcmp( result[0], result[t], bytes ), 0, "shape %d, history %d: 1 and %d threads differ", k,
						  history, t + 1 );
		}
		if ( history )
		{
			/* the start-of-step sides disagree with some detection sides, so the push differs */
			int32_t c0, e0;
			float* plain = collide_run_pass( 1, shapes[k], false, &c0, &e0, NULL, NULL );
			cr_assert_neq( memcmp( result[0], plain, bytes ), 0, "shape %d: start-of-step sides changed nothing", k );
			free( plain );
		}
		for ( int t = 0; t < 3; ++t )
		{
			free( result[t] );
			free( edges[t] );
		}
	}
	omp_set_num_threads( saved );
}

/* A sheet with Voronoi particles off their places, random velocities and masses in [0.5, 2]. */
static void conserving_sheet( collide_sheet* s, uint64_t seed )
{
	collide_sheet_make( s, 36, 24, seed );
	int32_t n = s->n, f = s->triangles;
	uint64_t state = seed;
	for ( int32_t i = 0; i < n; ++i )
	{
		s->z[i] = (float) ( 0.05 * sin( 7.0 * s->u[i] + 3.0 * s->v[i] ) );
	}
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = s->tri + 3 * t;
		s->x[n + t] =
			( s->x[v[0]] + s->x[v[1]] + s->x[v[2]] ) / 3.0f + (float) ( 0.01 * ( sere_test_unit( &state ) - 0.5 ) );
		s->y[n + t] =
			( s->y[v[0]] + s->y[v[1]] + s->y[v[2]] ) / 3.0f + (float) ( 0.01 * ( sere_test_unit( &state ) - 0.5 ) );
		s->z[n + t] = ( s->z[v[0]] + s->z[v[1]] + s->z[v[2]] ) / 3.0f + (float) ( 0.02 * sere_test_unit( &state ) );
	}
	for ( int32_t i = 0; i < n + f; ++i )
	{
		s->vx[i] = (float) ( sere_test_unit( &state ) - 0.5 );
		s->vy[i] = (float) ( sere_test_unit( &state ) - 0.5 );
		s->vz[i] = (float) ( sere_test_unit( &state ) - 0.5 );
		s->inv_m[i] = (float) ( 1.0 / ( 0.5 + 1.5 * sere_test_unit( &state ) ) );
	}
}

/* Jeong Eq. 14 only where the collision response moved a corner and left the Voronoi particle on the
 * wrong side of its triangle (Sec. 5.3): those are put back on the normal line at h with the
 * velocity change Δx/Δt, every other Voronoi particle stays bit for bit. */
Test( collide, restore_moved_applies_eq14_only_where_collisions_moved )
{
	collide_sheet s, before;
	conserving_sheet( &s, 21 );
	conserving_sheet( &before, 21 );
	int32_t n = s.n, f = s.triangles;
	const float dt = 0.002f;
	float* h = malloc( sizeof( float ) * (size_t) f );
	uint8_t* moved = calloc( (size_t) n, 1 );
	for ( int32_t t = 0; t < f; ++t )
	{
		h[t] = t % 3 == 0 ? -0.06f : 0.01f;
	}
	/* nothing moved: nothing is touched, bit for bit (no velocity from nowhere) */
	cr_assert_eq( sere_collide_restore_voronoi_moved( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, moved, dt, 0 ),
				  SERE_OK );
	cr_expect_eq( memcmp( s.z, before.z, sizeof( float ) * (size_t) ( n + f ) ), 0 );
	cr_expect_eq( memcmp( s.vz, before.vz, sizeof( float ) * (size_t) ( n + f ) ), 0 );
	for ( int32_t i = 0; i < n; i += 7 )
	{
		moved[i] = 1;
	}
	/* which side of its triangle each Voronoi particle is on before the restore */
	float* side = malloc( sizeof( float ) * (size_t) f );
	cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, side, 0 ), SERE_OK );
	cr_assert_eq( sere_collide_restore_voronoi_moved( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, moved, dt, 0 ),
				  SERE_OK );
	float* again = malloc( sizeof( float ) * (size_t) f );
	cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, again, 0 ), SERE_OK );
	int32_t restored = 0;
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = s.tri + 3 * t;
		int32_t i = n + t;
		/* the conserving sheet puts the Voronoi particles near +z of their triangles: on the side
		 * h puts them for most with h = 0.01, through the triangle for most with h = -0.06 */
		if ( ( moved[v[0]] | moved[v[1]] | moved[v[2]] ) && !( side[t] * h[t] > 0.0f ) )
		{
			restored += 1;
			/* on the normal line at h: float rounding of unit-size coordinates */
			cr_assert( fabsf( again[t] - h[t] ) < 1e-6f, "%d measures %g, restored %g", t, again[t], h[t] );
			/* Δv = Δx/Δt; the quotient amplifies the coordinates' rounding (1e-7) by 1/dt */
			float expected = before.vz[i] + ( s.z[i] - before.z[i] ) / dt;
			cr_assert( fabsf( s.vz[i] - expected ) < 1e-3f * ( 1.0f + fabsf( expected ) ), "velocity %d: %g, not %g", t,
					   s.vz[i], expected );
		}
		else
		{
			cr_assert( s.x[i] == before.x[i] && s.y[i] == before.y[i] && s.z[i] == before.z[i] &&
						   s.vz[i] == before.vz[i],
					   "triangle %d: no moved corner, or its Voronoi particle on its side, but it changed", t );
		}
	}
	cr_assert( restored > 0 && restored < f, "%d of %d triangles restored", restored, f );
	cr_expect_eq( sere_collide_restore_voronoi_moved( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, NULL, dt, 0 ),
				  SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_collide_restore_voronoi_moved( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, moved, 0.0f, 0 ),
				  SERE_ERR_ARGUMENT );
	free( again );
	free( side );
	free( moved );
	free( h );
	collide_sheet_free( &before );
	collide_sheet_free( &s );
}

Test( collide, restore_moved_is_deterministic )
{
	float* result[2];
	for ( int threads = 1; threads <= 2; ++threads )
	{
		omp_set_num_threads( threads );
		collide_sheet s;
		conserving_sheet( &s, 33 );
		int32_t n = s.n, f = s.triangles;
		float* h = malloc( sizeof( float ) * (size_t) f );
		uint8_t* moved = calloc( (size_t) n, 1 );
		for ( int32_t t = 0; t < f; ++t )
		{
			h[t] = t % 2 == 0 ? 0.01f : -0.01f; /* half of them through their triangle */
		}
		for ( int32_t i = 0; i < n; i += 3 )
		{
			moved[i] = 1;
		}
		cr_assert_eq(
			sere_collide_restore_voronoi_moved( s.x, s.y, s.z, s.vx, s.vy, s.vz, s.tri, f, n, h, moved, 0.002f, 0 ),
			SERE_OK );
		collide_sheet fresh;
		conserving_sheet( &fresh, 33 );
		cr_assert_neq( memcmp( fresh.z + n, s.z + n, sizeof( float ) * (size_t) f ), 0, "nothing was restored" );
		collide_sheet_free( &fresh );
		result[threads - 1] = malloc( sizeof( float ) * 4 * (size_t) ( n + f ) );
		memcpy( result[threads - 1], s.x, sizeof( float ) * (size_t) ( n + f ) );
		memcpy( result[threads - 1] + n + f, s.y, sizeof( float ) * (size_t) ( n + f ) );
		memcpy( result[threads - 1] + 2 * ( n + f ), s.z, sizeof( float ) * (size_t) ( n + f ) );
		memcpy( result[threads - 1] + 3 * ( n + f ), s.vz, sizeof( float ) * (size_t) ( n + f ) );
		if ( threads == 2 )
		{
			cr_expect_eq( memcmp( result[0], result[1], sizeof( float ) * 4 * (size_t) ( n + f ) ), 0,
						  "1 and 2 threads differ" );
		}
		free( moved );
		free( h );
		collide_sheet_free( &s );
	}
	free( result[0] ), free( result[1] );
}

/* ĥ measured after the pass for the triangles it moved, from the corners saved before it, is
 * sere_collide_measure_h of the layer before the pass bit for bit on those triangles (the leaf
 * relies on it to drop the full measure), and leaves every other entry as it was; the same at
 * one and two threads. */
Test( collide, measure_h_moved_is_measure_h_before_the_pass_where_a_corner_moved )
{
	collide_sheet s;
	conserving_sheet( &s, 45 );
	int32_t n = s.n, f = s.triangles;
	float* before = malloc( sizeof( float ) * (size_t) f );
	cr_assert_eq( sere_collide_measure_h( s.x, s.y, s.z, s.tri, f, n, before, 0 ), SERE_OK );
	float *cx = malloc( sizeof( float ) * (size_t) n ), *cy = malloc( sizeof( float ) * (size_t) n ),
		  *cz = malloc( sizeof( float ) * (size_t) n );
	memcpy( cx, s.x, sizeof( float ) * (size_t) n );
	memcpy( cy, s.y, sizeof( float ) * (size_t) n );
	memcpy( cz, s.z, sizeof( float ) * (size_t) n );
	/* the pass moves every fifth corner, and so changes the heights over the current layer */
	uint8_t* moved = calloc( (size_t) n, 1 );
	for ( int32_t i = 0; i < n; i += 5 )
	{
		moved[i] = 1;
		s.z[i] += 0.01f;
	}
	const float untouched = 123.0f;
	float* h[2];
	int saved = omp_get_max_threads();
	for ( int threads = 1; threads <= 2; ++threads )
	{
		omp_set_num_threads( threads );
		h[threads - 1] = malloc( sizeof( float ) * (size_t) f );
		for ( int32_t t = 0; t < f; ++t )
		{
			h[threads - 1][t] = untouched;
		}
		cr_assert_eq( sere_collide_measure_h_moved( cx, cy, cz, s.x, s.y, s.z, s.tri, f, n, moved, h[threads - 1], 0 ),
					  SERE_OK );
	}
	omp_set_num_threads( saved );
	cr_expect_eq( memcmp( h[0], h[1], sizeof( float ) * (size_t) f ), 0, "1 and 2 threads differ" );
	int32_t measured = 0;
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = s.tri + 3 * t;
		if ( moved[v[0]] | moved[v[1]] | moved[v[2]] )
		{
			measured += 1;
			cr_assert( h[0][t] == before[t], "triangle %d: %a, before the pass %a", t, h[0][t], before[t] );
		}
		else
		{
			cr_assert( h[0][t] == untouched, "triangle %d has no moved corner but was written", t );
		}
	}
	cr_assert( measured > 0 && measured < f, "%d of %d triangles measured", measured, f );

	/* a corner outside the triangle layer, a NULL mask, a NaN corner of a moved triangle */
	int32_t saved_corner = s.tri[0];
	s.tri[0] = n;
	cr_expect_eq( sere_collide_measure_h_moved( cx, cy, cz, s.x, s.y, s.z, s.tri, f, n, moved, h[0], 0 ),
				  SERE_ERR_ARGUMENT );
	s.tri[0] = saved_corner;
	cr_expect_eq( sere_collide_measure_h_moved( cx, cy, cz, s.x, s.y, s.z, s.tri, f, n, NULL, h[0], 0 ),
				  SERE_ERR_ARGUMENT );
	cz[0] = NAN;
	moved[0] = 1;
	cr_expect_eq( sere_collide_measure_h_moved( cx, cy, cz, s.x, s.y, s.z, s.tri, f, n, moved, h[0], 0 ),
				  SERE_ERR_NONFINITE );
	for ( int32_t t = 0; t < f; ++t )
	{
		cr_assert( isfinite( h[0][t] ), "a non-finite ĥ was written at %d", t );
	}
	free( h[0] ), free( h[1] );
	free( moved );
	free( cx ), free( cy ), free( cz );
	free( before );
	collide_sheet_free( &s );
}
