/* The ground plane inside the projection (sere_pbd_params.ground): the same bits as the loop a
 * caller would write around it (project, put the particles below the ground onto it, go on
 * with the same multipliers while that pushed more than the slack), at any thread count, where
 * every round's confirming measure passes (the kernel grounds before it measures, so a round
 * whose measure would fail is grounded earlier than the loop grounds it); and a converged
 * strain measured on the positions returned. The stall rule (sere_pbd_project_stalling) runs
 * inside the same call, so it keeps these bits too. */
#include "solve/pbd.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

enum
{
	NX = 48,
	NY = 32,
	N = NX * NY,
	MAX_SPRINGS = 4 * N
};

/* A sheet lying just above the ground with its springs shortened by 3% in a band across it,
 * so that the step pulls it together and pushes parts of it under the ground; x, y, z are the
 * predicted positions (the whole sheet moved down, as gravity would). */
typedef struct ground_sheet
{
	float x[N], y[N], z[N], inv_m[N];
	int32_t a[MAX_SPRINGS], b[MAX_SPRINGS];
	float rest[MAX_SPRINGS];
	int32_t count;
} ground_sheet;

static void sheet_spring( ground_sheet* s, int32_t i, int32_t j )
{
	float dx = s->x[j] - s->x[i], dy = s->y[j] - s->y[i], dz = s->z[j] - s->z[i];
	float length = sqrtf( dx * dx + dy * dy + dz * dz );
	float band = fabsf( 0.5f * ( s->x[i] + s->x[j] ) - 0.5f * NX * 0.02f ) < 0.15f ? 0.97f : 1.0f;
	s->a[s->count] = i, s->b[s->count] = j, s->rest[s->count] = band * length;
	s->count += 1;
}

static void sheet_make( ground_sheet* s )
{
	memset( s, 0, sizeof( *s ) );
	for ( int32_t j = 0; j < NY; ++j )
	{
		for ( int32_t i = 0; i < NX; ++i )
		{
			int32_t k = j * NX + i;
			s->x[k] = 0.02f * (float) i, s->y[k] = 0.02f * (float) j;
			/* a gentle wave, so the sheet bends one way or the other where it is squeezed */
			s->z[k] = 0.002f * sinf( 0.4f * (float) i ) * cosf( 0.3f * (float) j ) - 0.001f;
			s->inv_m[k] = 1.0f + (float) ( k % 3 );
		}
	}
	for ( int32_t j = 0; j < NY; ++j )
	{
		for ( int32_t i = 0; i < NX; ++i )
		{
			int32_t k = j * NX + i;
			if ( i + 1 < NX )
			{
				sheet_spring( s, k, k + 1 );
			}
			if ( j + 1 < NY )
			{
				sheet_spring( s, k, k + NX );
			}
			if ( i + 1 < NX && j + 1 < NY )
			{
				sheet_spring( s, k, k + NX + 1 );
				sheet_spring( s, k + 1, k + NX );
			}
		}
	}
}

static sere_pbd_params sheet_params( void )
{
	sere_pbd_params params = sere_pbd_params_default();
	params.compliance = 1e-6f;
	params.dt = 0.002f;
	params.tolerance = 1e-3f;
	params.max_iterations = 400;
	return params;
}

static const float GROUND = 0.0f, SLACK = 1e-6f;

/* The caller's loop the kernel replaces; returns the rounds (projection calls) it took. */
static int32_t loop_step( ground_sheet* s, sere_pbd* pbd, float* push, sere_pbd_report* total )
{
	sere_pbd_params params = sheet_params();
	int32_t left = params.max_iterations, rounds = 0;
	memset( total, 0, sizeof( *total ) );
	while ( left > 0 )
	{
		params.max_iterations = left;
		sere_pbd_report report;
		cr_assert_eq( sere_pbd_project( pbd, s->x, s->y, s->z, s->inv_m, &params, &report ), SERE_OK );
		rounds += 1, left -= report.iterations;
		total->iterations += report.iterations, total->max_strain = report.max_strain;
		float pushed = 0.0f;
		for ( int32_t i = 0; i < N; ++i )
		{
			float depth = fmaxf( GROUND - s->z[i], 0.0f );
			s->z[i] += depth, push[i] += depth;
			pushed = fmaxf( pushed, depth );
		}
		total->hit_cap = report.hit_cap || pushed > SLACK;
		if ( !report.hit_cap && pushed <= SLACK )
		{
			break;
		}
		params.warm = 1;
	}
	return rounds;
}

static void kernel_step( ground_sheet* s, sere_pbd* pbd, float* push, sere_pbd_report* report, int32_t cap )
{
	sere_pbd_params params = sheet_params();
	params.ground = GROUND, params.ground_slack = SLACK;
	params.max_iterations = cap;
	cr_assert_eq( sere_pbd_project( pbd, s->x, s->y, s->z, s->inv_m, &params, report ), SERE_OK );
	cr_assert_eq( sere_pbd_ground_push( pbd, push ), SERE_OK );
}

static sere_pbd* sheet_solver( const ground_sheet* s, int32_t threads )
{
	sere_pbd* pbd = NULL;
	cr_assert_eq( sere_pbd_create( s->a, s->b, s->count, N, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, s->rest ), SERE_OK );
	cr_assert_eq( sere_pbd_set_threads( pbd, threads ), SERE_OK );
	return pbd;
}

Test( pbd_ground, the_same_bits_as_the_loop_around_the_projection )
{
	static ground_sheet loop, inside;
	static float push_loop[N], push_inside[N];
	sheet_make( &loop );
	sere_pbd* pbd = sheet_solver( &loop, 1 );
	sere_pbd_report by_loop, by_kernel;
	int32_t rounds = loop_step( &loop, pbd, push_loop, &by_loop );
	sere_pbd_destroy( pbd );
	/* the case the kernel's rounds exist for: the ground pushed back after a converged round */
	cr_assert_geq( rounds, 2, "%d rounds, %d sweeps, cap %d, strain %g", rounds, by_loop.iterations, by_loop.hit_cap,
				   by_loop.max_strain );
	cr_assert( !by_loop.hit_cap, "the loop reached the cap (%d sweeps)", by_loop.iterations );
	for ( int32_t threads = 1; threads <= 3; ++threads )
	{
		sheet_make( &inside );
		memset( push_inside, 0, sizeof( push_inside ) );
		pbd = sheet_solver( &inside, threads );
		kernel_step( &inside, pbd, push_inside, &by_kernel, sheet_params().max_iterations );
		sere_pbd_destroy( pbd );
		cr_expect_eq( by_kernel.iterations, by_loop.iterations, "%d threads", threads );
		cr_expect_eq( by_kernel.hit_cap, 0, "%d threads", threads );
		cr_expect_eq( memcmp( &by_kernel.max_strain, &by_loop.max_strain, sizeof( float ) ), 0 );
		cr_expect_eq( memcmp( inside.x, loop.x, sizeof( loop.x ) ), 0, "%d threads: x", threads );
		cr_expect_eq( memcmp( inside.y, loop.y, sizeof( loop.y ) ), 0, "%d threads: y", threads );
		cr_expect_eq( memcmp( inside.z, loop.z, sizeof( loop.z ) ), 0, "%d threads: z", threads );
		cr_expect_eq( memcmp( push_inside, push_loop, sizeof( push_loop ) ), 0, "%d threads: push", threads );
	}
}

Test( pbd_ground, at_the_cap_the_positions_still_meet_the_ground )
{
	static ground_sheet s;
	static float push[N];
	sheet_make( &s );
	sere_pbd* pbd = sheet_solver( &s, 0 );
	sere_pbd_report report;
	kernel_step( &s, pbd, push, &report, 3 );
	sere_pbd_destroy( pbd );
	cr_expect_eq( report.iterations, 3 );
	cr_expect( report.hit_cap );
	int32_t below = 0, pushed = 0;
	for ( int32_t i = 0; i < N; ++i )
	{
		below += s.z[i] < GROUND;
		pushed += push[i] > 0.0f;
	}
	cr_expect_eq( below, 0, "%d particles under the ground", below );
	cr_expect_gt( pushed, 0, "the ground pushed nothing: the test does not reach it" );
}

/* The ground comes before the read-only pass that confirms convergence, so a converged report
 * (with the strain it gives) describes the positions returned, ground pushes included: the
 * paper's PBD (no compliance, so the residual is |C/l| of the positions alone), a slack the
 * first round's pushes stay within, and the largest |C/l| of the returned positions recomputed
 * with the kernel's operations in its order (sqrt((dx² + dy²) + dz²), then |len − l| / l: the
 * same bits). Measured before the ground, as the kernel once did, the strain was that of
 * positions it then changed. */
Test( pbd_ground, a_converged_strain_is_that_of_the_returned_positions )
{
	static ground_sheet s;
	static float push[N];
	sheet_make( &s );
	/* a flat sheet just under the ground with one particle lower still, every spring at its
	 * rest length: the first sweep converges, and the ground pass after it lifts the sheet and
	 * shortens the springs of the low particle (a strain of 0.5%, within the tolerance), which
	 * only a measure after the ground sees */
	for ( int32_t i = 0; i < N; ++i )
	{
		s.z[i] = i == N / 2 + NX / 2 ? -0.003f : -0.001f;
	}
	for ( int32_t k = 0; k < s.count; ++k )
	{
		float dx = s.x[s.b[k]] - s.x[s.a[k]], dy = s.y[s.b[k]] - s.y[s.a[k]], dz = s.z[s.b[k]] - s.z[s.a[k]];
		s.rest[k] = sqrtf( ( dx * dx + dy * dy ) + dz * dz );
	}
	sere_pbd* pbd = sheet_solver( &s, 0 );
	sere_pbd_params params = sheet_params();
	params.compliance = 0.0f;
	params.ground = GROUND, params.ground_slack = 0.01f;
	params.tolerance = 1e-2f;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	cr_assert_eq( sere_pbd_ground_push( pbd, push ), SERE_OK );
	sere_pbd_destroy( pbd );
	cr_assert( !report.hit_cap, "%d sweeps, strain %g", report.iterations, report.max_strain );
	float pushed = 0.0f, worst = 0.0f;
	for ( int32_t i = 0; i < N; ++i )
	{
		pushed = fmaxf( pushed, push[i] );
	}
	cr_assert_gt( pushed, 0.0f, "the ground pushed nothing: the test does not reach it" );
	for ( int32_t k = 0; k < s.count; ++k )
	{
		float dx = s.x[s.b[k]] - s.x[s.a[k]], dy = s.y[s.b[k]] - s.y[s.a[k]], dz = s.z[s.b[k]] - s.z[s.a[k]];
		float len = sqrtf( ( dx * dx + dy * dy ) + dz * dz );
		worst = fmaxf( worst, fabsf( len - s.rest[k] ) / s.rest[k] );
	}
	cr_expect_gt( worst, 1e-3f, "the ground changed no spring length: the test does not reach it" );
	cr_expect_lt( worst, params.tolerance );
	cr_expect_eq( memcmp( &worst, &report.max_strain, sizeof( float ) ), 0, "returned positions %.9g, reported %.9g",
				  worst, report.max_strain );
}

Test( pbd_ground, bad_grounds_are_refused_and_leave_the_positions )
{
	static ground_sheet s, before;
	sheet_make( &s );
	before = s;
	sere_pbd* pbd = sheet_solver( &s, 1 );
	sere_pbd_report report;
	const float grounds[] = { NAN, INFINITY, 0.0f, 0.0f };
	const float slacks[] = { 0.0f, 0.0f, -1.0f, NAN };
	for ( int k = 0; k < 4; ++k )
	{
		sere_pbd_params params = sheet_params();
		params.ground = grounds[k], params.ground_slack = slacks[k];
		cr_expect_eq( sere_pbd_project( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_ERR_ARGUMENT, "case %d",
					  k );
	}
	sere_pbd_params params = sheet_params();
	params.ground = GROUND;
	cr_expect_eq( sere_pbd_project_jacobi( pbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_ground_push( pbd, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( memcmp( s.z, before.z, sizeof( s.z ) ), 0 );
	sere_pbd_destroy( pbd );
}

/* The stall rule inside the one call: a call it does not stop returns the projection's bits, with
 * XPBD multipliers, Chebyshev sweeps and the ground all carried through (it once ran the windows
 * as separate calls, each restarting the multipliers and the Chebyshev sequence); a call it stops
 * after k sweeps returns what a projection capped at k returns, without the cap hit. */
Test( pbd_ground, the_stall_rule_keeps_the_projections_bits )
{
	static ground_sheet plain, stalling;
	sere_pbd_params params = sheet_params();
	params.ground = GROUND, params.ground_slack = SLACK;
	params.chebyshev_rho = 0.9f, params.chebyshev_delay = 5;
	params.stall = 1e-6f; /* a window must lower the residual by a millionth */
	sere_pbd_report by_project, by_stalling;
	int stalled = -1;
	for ( int32_t threads = 1; threads <= 2; ++threads )
	{
		sheet_make( &plain ), sheet_make( &stalling );
		sere_pbd* pbd = sheet_solver( &plain, threads );
		cr_assert_eq( sere_pbd_project( pbd, plain.x, plain.y, plain.z, plain.inv_m, &params, &by_project ), SERE_OK );
		cr_assert_eq( sere_pbd_project_stalling( pbd, stalling.x, stalling.y, stalling.z, stalling.inv_m, &params,
												 &by_stalling, &stalled ),
					  SERE_OK );
		sere_pbd_destroy( pbd );
		cr_assert_eq( stalled, 0, "%d threads: the rule stopped the call after %d sweeps", threads,
					  by_stalling.iterations );
		cr_assert_gt( by_project.iterations, 2 * SERE_PBD_STALL_WINDOW, "too few windows to test" );
		cr_expect_eq( by_stalling.iterations, by_project.iterations );
		cr_expect_eq( by_stalling.hit_cap, by_project.hit_cap );
		cr_expect_eq( memcmp( stalling.x, plain.x, sizeof( plain.x ) ), 0, "%d threads: x", threads );
		cr_expect_eq( memcmp( stalling.y, plain.y, sizeof( plain.y ) ), 0, "%d threads: y", threads );
		cr_expect_eq( memcmp( stalling.z, plain.z, sizeof( plain.z ) ), 0, "%d threads: z", threads );
	}

	/* The paper's hard constraints, asked to halve the residual every window: they stall. */
	params = sheet_params();
	params.compliance = 0.0f, params.tolerance = 1e-7f, params.stall = 0.5f;
	sheet_make( &stalling );
	sere_pbd* pbd = sheet_solver( &stalling, 1 );
	cr_assert_eq( sere_pbd_project_stalling( pbd, stalling.x, stalling.y, stalling.z, stalling.inv_m, &params,
											 &by_stalling, &stalled ),
				  SERE_OK );
	cr_assert_eq( stalled, 1, "%d sweeps, residual %g", by_stalling.iterations, by_stalling.max_strain );
	cr_expect_eq( by_stalling.hit_cap, 0 );
	cr_expect_lt( by_stalling.iterations, params.max_iterations );
	cr_expect_eq( by_stalling.iterations % SERE_PBD_STALL_WINDOW, 0 );
	params.max_iterations = by_stalling.iterations;
	sheet_make( &plain );
	cr_assert_eq( sere_pbd_project( pbd, plain.x, plain.y, plain.z, plain.inv_m, &params, &by_project ), SERE_OK );
	cr_expect( by_project.hit_cap );
	cr_expect_eq( memcmp( &by_project.max_strain, &by_stalling.max_strain, sizeof( float ) ), 0 );
	cr_expect_eq( memcmp( stalling.z, plain.z, sizeof( plain.z ) ), 0, "stopped by the rule and by the cap differ" );

	/* Refused: s outside [0, 1), a NULL flag; the positions are left as they were. */
	static ground_sheet before;
	sheet_make( &stalling );
	before = stalling;
	const float stalls[] = { 1.0f, -0.1f, NAN };
	for ( int k = 0; k < 3; ++k )
	{
		params.stall = stalls[k];
		cr_expect_eq( sere_pbd_project_stalling( pbd, stalling.x, stalling.y, stalling.z, stalling.inv_m, &params,
												 &by_stalling, &stalled ),
					  SERE_ERR_ARGUMENT, "stall %g", stalls[k] );
	}
	params.stall = 0.5f;
	cr_expect_eq( sere_pbd_project_stalling( pbd, stalling.x, stalling.y, stalling.z, stalling.inv_m, &params,
											 &by_stalling, NULL ),
				  SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_project_stalling( pbd, stalling.x, stalling.y, stalling.z, stalling.inv_m, NULL,
											 &by_stalling, &stalled ),
				  SERE_ERR_ARGUMENT );
	cr_expect_eq( memcmp( stalling.z, before.z, sizeof( before.z ) ), 0 );
	sere_pbd_destroy( pbd );
}
