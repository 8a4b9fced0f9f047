/* The descent step (solve/vbd.h): a lone spring solved by hand, the reference twin's minimum on a
 * frustrated sheet, the rest state XPBD does not reach there, Chebyshev against plain sweeps,
 * a hub whose rows take several passes, the same bits at every thread count, the ground bound
 * and its push, held particles, the floor leaving positions alone, and the calls that must be
 * refused. */
#include "fixture.h"
#include "ref/vbd_ref.h"
#include "solve/pbd.h"
#include "solve/vbd.h"

#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* α̃ = 0.025 at dt = 0.002, the order of the sheet's inverse masses, as test_pbd_residual.c's */
static sere_vbd_params sheet_params( void )
{
	sere_vbd_params params = sere_vbd_params_default();
	params.compliance = 1e-7f;
	params.tolerance = 1e-7f;
	params.max_iterations = 5000;
	return params;
}

static sere_vbd* sheet_solver( const sere_test_sheet* s, int32_t threads )
{
	sere_vbd* vbd = NULL;
	cr_assert_eq( sere_vbd_create( s->a, s->b, s->count, s->n, &vbd ), SERE_OK );
	cr_assert_eq( sere_vbd_set_rest( vbd, s->rest ), SERE_OK );
	cr_assert_eq( sere_vbd_set_threads( vbd, threads ), SERE_OK );
	return vbd;
}

/* One step of the sheet from its prediction; returns the sweeps. */
static int32_t sheet_step( sere_test_sheet* s, int32_t threads, const sere_vbd_params* params )
{
	sere_vbd* vbd = sheet_solver( s, threads );
	sere_vbd_report report;
	cr_assert_eq( sere_vbd_step( vbd, s->x, s->y, s->z, s->inv_m, params, &report ), SERE_OK );
	cr_assert( !report.hit_cap, "%d sweeps, last move %g", report.iterations, report.max_move );
	sere_vbd_destroy( vbd );
	return report.iterations;
}

/* The largest distance between the sheet's positions and x (3 doubles a particle), in spacings. */
static double spacings_from( const sere_test_sheet* s, const double* x )
{
	double worst = 0.0;
	for ( int32_t i = 0; i < s->n; ++i )
	{
		const double dx = s->x[i] - x[3 * i], dy = s->y[i] - x[3 * i + 1], dz = s->z[i] - x[3 * i + 2];
		worst = fmax( worst, sqrt( dx * dx + dy * dy + dz * dz ) );
	}
	return worst / SERE_TEST_SHEET_SPACING;
}

/* The sheet's positions (prediction: its prediction t*) as 3 doubles a particle, malloc'd. */
static double* sheet_positions( const sere_test_sheet* s, int prediction )
{
	double* x = malloc( sizeof( double ) * 3 * (size_t) s->n );
	cr_assert_not_null( x );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		x[3 * i] = prediction ? s->tx[i] : s->x[i];
		x[3 * i + 1] = prediction ? s->ty[i] : s->y[i];
		x[3 * i + 2] = prediction ? s->tz[i] : s->z[i];
	}
	return x;
}

Test( vbd, lone_spring_lands_on_the_minimum_by_hand )
{
	/* End 0 held at the origin, end 1 predicted at 2 with m = 1, rest 1, k = dt²/α = 3: along the
	 * spring E = ½ (r − 2)² + 3/2 (r − 1)² is least at r = (2 + 3)/4 = 1.25, and one Newton step
	 * on that parabola lands there; the second sweep moves nothing and stops. */
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 0.0f, 1.0f };
	float x[2] = { 0.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	sere_vbd* vbd;
	cr_assert_eq( sere_vbd_create( &a, &b, 1, 2, &vbd ), SERE_OK );
	cr_assert_eq( sere_vbd_set_rest( vbd, &rest ), SERE_OK );
	sere_vbd_params params = sere_vbd_params_default();
	params.dt = 0.01f;
	params.compliance = params.dt * params.dt / 3.0f;
	sere_vbd_report report;
	cr_assert_eq( sere_vbd_step( vbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	/* float: dt²/α rounds to 3 within 1e-7 relative, so r within a few 1e-7 */
	cr_expect_float_eq( x[1], 1.25f, 1e-6f );
	cr_expect( x[0] == 0.0f && y[1] == 0.0f && z[1] == 0.0f, "held end %g, off the line %g %g", x[0], y[1], z[1] );
	cr_expect_eq( report.iterations, 2 );
	cr_expect( !report.hit_cap );
	sere_vbd_destroy( vbd );
}

/* The twin's problem for the sheet s under params, with its stiffnesses in *stiffness (freed by
 * the caller). */
static sere_vbd_ref_problem twin_problem( const sere_test_sheet* s, const sere_vbd_params* params, double** stiffness )
{
	*stiffness = malloc( sizeof( double ) * (size_t) s->count );
	cr_assert_not_null( *stiffness );
	for ( int32_t k = 0; k < s->count; ++k )
	{
		( *stiffness )[k] = (double) params->dt * params->dt / params->compliance;
	}
	return ( sere_vbd_ref_problem ){ s->n, s->count, s->tx, s->ty, s->tz, s->inv_m, s->a, s->b, s->rest, *stiffness };
}

Test( vbd, reaches_the_twins_minimum_where_it_is_unique )
{
	/* Every spring at 0.9 of its length: all stay stretched, where (|d| − l)² is convex, so E has
	 * one minimum, which the twin reaches sweeping the particles one by one in double to a
	 * gradient of 1e-9. The colored SIMD sweeps in float stop at moves of 1e-7 (2e-6 spacings),
	 * but they contract slowly here (hundreds of sweeps, a factor ρ near 0.99 each), so the stop
	 * leaves them about move/(1 − ρ) = 1e-5 (2e-4 spacings) short: within 1e-3 spacings. */
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	for ( int32_t k = 0; k < s.count; ++k )
	{
		const int32_t a = s.a[k], b = s.b[k];
		const float dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
		s.rest[k] = 0.9f * sqrtf( dx * dx + dy * dy + dz * dz );
	}
	sere_vbd_params params = sheet_params();
	sheet_step( &s, 2, &params );
	double* stiffness;
	const sere_vbd_ref_problem problem = twin_problem( &s, &params, &stiffness );
	double* twin = sheet_positions( &s, 1 );
	cr_assert_geq( sere_vbd_ref_descend( &problem, twin, 1e-9, 20000 ), 0 );
	const double apart = spacings_from( &s, twin );
	cr_log_info( "descent against the twin: %g spacings", apart );
	cr_expect_lt( apart, 1e-3 );
	free( stiffness ), free( twin );
	sere_test_sheet_free( &s );
}

Test( vbd, stops_where_the_twin_measures_no_force_on_a_frustrated_sheet )
{
	/* The frustrated sheet has several minima (its waves can buckle either way), and sweeping in
	 * another order may end in another one; what the twin can check is that the answer is a
	 * stationary point of E: its largest |∂E/∂x_i|, summed in double, is at the float rounding of
	 * the forces that cancel there (forces of order 1: 1e-4), where XPBD's answer leaves 0.107
	 * (test_pbd_residual.c). */
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	sere_vbd_params params = sheet_params();
	sheet_step( &s, 2, &params );
	double* stiffness;
	const sere_vbd_ref_problem problem = twin_problem( &s, &params, &stiffness );
	double* x = sheet_positions( &s, 0 );
	const double gradient = sere_vbd_ref_gradient( &problem, x );
	cr_log_info( "largest |dE/dx_i| at the descent's answer: %g", gradient );
	cr_expect_lt( gradient, 1e-4 );
	free( stiffness ), free( x );
	sere_test_sheet_free( &s );
}

Test( vbd, rests_where_the_xpbd_step_leaves_forces_unbalanced )
{
	/* On the same sheet XPBD converged to g < 1e-5 l leaves h at 0.59 of the multipliers' forces
	 * (test_pbd_residual.c); the descent's answer is a rest state of E: its gradient is the float
	 * rounding of the forces that cancel in it, 1e-3 of them at most. */
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	sere_vbd_params params = sheet_params();
	sheet_step( &s, 1, &params );
	sere_vbd* vbd = sheet_solver( &s, 1 );
	sere_vbd_residuals r;
	cr_assert_eq( sere_vbd_step_residual( vbd, s.x, s.y, s.z, s.tx, s.ty, s.tz, s.inv_m, &params, &r ), SERE_OK );
	cr_log_info( "descent: h/force %g (%g over %g)", r.primal / r.constraint, r.primal, r.constraint );
	cr_expect_eq( r.particles, s.n );
	cr_expect_gt( r.constraint, 0.0 );
	cr_expect_lt( r.primal, 1e-3 * r.constraint );
	/* the measure sees what XPBD leaves: its answer from the same prediction */
	sere_test_sheet xpbd = sere_test_sheet_make( 24, 20 );
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( xpbd.a, xpbd.b, xpbd.count, xpbd.n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, xpbd.rest ), SERE_OK );
	sere_pbd_params step = sere_pbd_params_default();
	step.compliance = params.compliance, step.tolerance = 1e-5f, step.max_iterations = 5000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, xpbd.x, xpbd.y, xpbd.z, xpbd.inv_m, &step, &report ), SERE_OK );
	cr_assert_eq(
		sere_vbd_step_residual( vbd, xpbd.x, xpbd.y, xpbd.z, xpbd.tx, xpbd.ty, xpbd.tz, xpbd.inv_m, &params, &r ),
		SERE_OK );
	cr_log_info( "XPBD: h/force %g", r.primal / r.constraint );
	cr_expect_gt( r.primal, 0.1 * r.constraint );
	sere_pbd_destroy( pbd );
	sere_vbd_destroy( vbd );
	sere_test_sheet_free( &xpbd );
	sere_test_sheet_free( &s );
}

Test( vbd, chebyshev_reaches_the_same_minimum_in_fewer_sweeps )
{
	/* A descent has one answer near the prediction, so extrapolating the sweeps changes how fast
	 * it is reached and not where: both stop at moves of 1e-7, within 1e-3 spacings of each
	 * other (XPBD's plain and Chebyshev answers on this sheet are 0.48 spacings apart, DESIGN §8). */
	sere_test_sheet plain = sere_test_sheet_make( 24, 20 ), fast = sere_test_sheet_make( 24, 20 );
	sere_vbd_params params = sheet_params();
	const int32_t plain_sweeps = sheet_step( &plain, 1, &params );
	params.chebyshev_rho = 0.8f;
	const int32_t fast_sweeps = sheet_step( &fast, 1, &params );
	double* x = sheet_positions( &plain, 0 );
	const double apart = spacings_from( &fast, x );
	cr_log_info( "plain %d sweeps, Chebyshev %d, %g spacings apart", plain_sweeps, fast_sweeps, apart );
	cr_expect_lt( apart, 1e-3 );
	cr_expect_lt( fast_sweeps, plain_sweeps );
	free( x );
	sere_test_sheet_free( &plain ), sere_test_sheet_free( &fast );
}

/* One frame of a drying sheet: rest lengths 0.2% shorter a frame, the prediction the last answer
 * dropped by g dt², one step; returns its sweeps. */
static int32_t drying_frame( sere_vbd* vbd, sere_test_sheet* s, const sere_vbd_params* params, int frame, float* rest )
{
	for ( int32_t k = 0; k < s->count; ++k )
	{
		rest[k] = s->rest[k] * ( 1.0f - 0.002f * (float) frame );
	}
	cr_assert_eq( sere_vbd_set_rest( vbd, rest ), SERE_OK );
	const float drop = 9.8f * params->dt * params->dt;
	for ( int32_t i = 0; i < s->n; ++i )
	{
		s->z[i] -= s->inv_m[i] > 0.0f ? drop : 0.0f;
	}
	sere_vbd_report report;
	cr_assert_eq( sere_vbd_step( vbd, s->x, s->y, s->z, s->inv_m, params, &report ), SERE_OK );
	cr_assert( !report.hit_cap, "frame %d: %d sweeps", frame, report.iterations );
	return report.iterations;
}

/* Twenty frames of a drying sheet: every frame its rest lengths shrink by 0.2% and its prediction
 * is the last answer dropped by g dt². A warm start begins each frame's sweeps where the last
 * frame's correction points; the answer is the same descent's (within 1e-3 spacings of the cold
 * start's every frame, where the tolerance of 1e-7 is 2e-6 spacings and the sweeps contract
 * slowly), in fewer sweeps once the sheet has left its frustrated start (frames 10–19; the first
 * frames' corrections are that start's relaxation, which does not recur), and the same bits at 1
 * and 2 threads. The first frame has no correction: the cold start's bits. */
Test( vbd, a_warm_start_reaches_the_cold_answer_in_fewer_sweeps )
{
	sere_test_sheet cold = sere_test_sheet_make( 24, 20 ), warm = sere_test_sheet_make( 24, 20 ),
					other = sere_test_sheet_make( 24, 20 );
	sere_vbd *cold_vbd = sheet_solver( &cold, 1 ), *warm_vbd = sheet_solver( &warm, 1 ),
			 *other_vbd = sheet_solver( &other, 2 );
	float* rest = malloc( sizeof( float ) * (size_t) cold.count );
	cr_assert_not_null( rest );
	sere_vbd_params params = sheet_params(), warm_params = sheet_params();
	warm_params.warm_start = 1;
	int32_t cold_sweeps = 0, warm_sweeps = 0;
	double worst = 0.0;
	const size_t bytes = sizeof( float ) * (size_t) cold.n;
	for ( int frame = 0; frame < 20; ++frame )
	{
		const int32_t c = drying_frame( cold_vbd, &cold, &params, frame, rest );
		const int32_t w = drying_frame( warm_vbd, &warm, &warm_params, frame, rest );
		drying_frame( other_vbd, &other, &warm_params, frame, rest );
		cr_expect( memcmp( warm.x, other.x, bytes ) == 0 && memcmp( warm.y, other.y, bytes ) == 0 &&
					   memcmp( warm.z, other.z, bytes ) == 0,
				   "frame %d: 2 threads differ from 1", frame );
		double* x = sheet_positions( &cold, 0 );
		const double apart = spacings_from( &warm, x );
		free( x );
		if ( frame == 0 )
		{
			cr_expect_eq( w, c, "no correction yet: the cold start's sweeps" );
			cr_expect_eq( memcmp( warm.z, cold.z, bytes ), 0, "no correction yet: the cold start's bits" );
		}
		cold_sweeps += frame >= 10 ? c : 0, warm_sweeps += frame >= 10 ? w : 0;
		worst = fmax( worst, apart );
		/* the next frame starts both from the cold answer, so each frame compares one step */
		memcpy( warm.x, cold.x, bytes ), memcpy( warm.y, cold.y, bytes ), memcpy( warm.z, cold.z, bytes );
		memcpy( other.x, cold.x, bytes ), memcpy( other.y, cold.y, bytes ), memcpy( other.z, cold.z, bytes );
	}
	cr_log_info( "frames 10-19: cold %d sweeps, warm %d; at most %g spacings apart", cold_sweeps, warm_sweeps, worst );
	cr_expect_lt( worst, 1e-3 );
	cr_expect_lt( warm_sweeps, cold_sweeps * 3 / 4 );
	/* a particle held now that was free (and corrected) before stays where it is given */
	const int32_t held = warm.n / 2;
	warm.inv_m[held] = 0.0f;
	const float where[3] = { warm.x[held], warm.y[held], warm.z[held] };
	drying_frame( warm_vbd, &warm, &warm_params, 20, rest );
	cr_expect( warm.x[held] == where[0] && warm.y[held] == where[1] && warm.z[held] == where[2],
			   "held particle moved to (%g, %g, %g)", (double) warm.x[held], (double) warm.y[held],
			   (double) warm.z[held] );
	free( rest );
	sere_vbd_destroy( cold_vbd ), sere_vbd_destroy( warm_vbd ), sere_vbd_destroy( other_vbd );
	sere_test_sheet_free( &cold ), sere_test_sheet_free( &warm ), sere_test_sheet_free( &other );
}

Test( vbd, a_hub_with_more_springs_than_a_pass_reaches_the_twins_minimum )
{
	/* One free particle tied by 40 springs to held ones at uneven angles and heights: its block
	 * takes its rows in passes of 16 (vbd.c), so the hub's gradient and block are summed over
	 * three passes, the last one short. All springs stretched (rest 0.4 of a rim at radius 1
	 * to 1.4), so E is convex and has one minimum, which the twin reaches in double to a gradient
	 * of 1e-9. The springs are not balanced by a subset of them: the second pass left out moves
	 * the hub 0.5 from the twin's, one row left out of each pass 0.014. Float's rounding leaves
	 * the descent within 1e-5 (it lands 5e-8 away). */
	enum
	{
		RIM = 40,
		N = RIM + 1
	};
	float x[N], y[N], z[N], tx[N], ty[N], tz[N], inv_m[N], rest[RIM];
	double stiffness[RIM], twin[3 * N]; /* the twin's k = dt²/α, and its positions */
	int32_t a[RIM], b[RIM];
	for ( int32_t k = 0; k < RIM; ++k )
	{
		const float angle = 6.2831853f * ( (float) k + 0.3f * sinf( 1.7f * (float) k ) ) / RIM;
		const float radius = 1.0f + 0.4f * (float) ( ( k * 7 ) % 5 ) / 4.0f;
		x[k + 1] = radius * cosf( angle ), y[k + 1] = radius * sinf( angle ), z[k + 1] = 0.2f * cosf( 3.0f * angle );
		inv_m[k + 1] = 0.0f;
		a[k] = 0, b[k] = k + 1, rest[k] = 0.4f, stiffness[k] = 1.0;
	}
	x[0] = 0.3f, y[0] = -0.2f, z[0] = 0.1f, inv_m[0] = 1.0f;
	memcpy( tx, x, sizeof( x ) ), memcpy( ty, y, sizeof( y ) ), memcpy( tz, z, sizeof( z ) );
	sere_vbd* vbd;
	cr_assert_eq( sere_vbd_create( a, b, RIM, N, &vbd ), SERE_OK );
	cr_assert_eq( sere_vbd_set_rest( vbd, rest ), SERE_OK );
	sere_vbd_params params = sere_vbd_params_default();
	params.dt = 0.01f, params.compliance = 1e-4f, params.tolerance = 1e-7f; /* k = dt²/α = 1 */
	sere_vbd_report report;
	cr_assert_eq( sere_vbd_step( vbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	cr_assert( !report.hit_cap );
	for ( int32_t i = 0; i < N; ++i )
	{
		twin[3 * i] = tx[i], twin[3 * i + 1] = ty[i], twin[3 * i + 2] = tz[i];
	}
	const sere_vbd_ref_problem problem = { N, RIM, tx, ty, tz, inv_m, a, b, rest, stiffness };
	cr_assert_geq( sere_vbd_ref_descend( &problem, twin, 1e-9, 1000 ), 0 );
	const double apart = sqrt( ( x[0] - twin[0] ) * ( x[0] - twin[0] ) + ( y[0] - twin[1] ) * ( y[0] - twin[1] ) +
							   ( z[0] - twin[2] ) * ( z[0] - twin[2] ) );
	cr_log_info( "hub: (%g, %g, %g) against the twin's (%g, %g, %g)", x[0], y[0], z[0], twin[0], twin[1], twin[2] );
	cr_expect_lt( apart, 1e-5 );
	sere_vbd_destroy( vbd );
}

Test( vbd, same_bits_at_every_thread_count )
{
	/* 48 × 40: every color has blocks for more than one thread; Chebyshev and the ground on. Moves
	 * of 1e-7 are below this sheet's float floor; 1e-6 converges. */
	sere_vbd_params params = sheet_params();
	params.tolerance = 1e-6f;
	params.chebyshev_rho = 0.8f;
	params.ground = 0.0f;
	sere_test_sheet one = sere_test_sheet_make( 48, 40 );
	sheet_step( &one, 1, &params );
	for ( int32_t threads = 2; threads <= 3; ++threads )
	{
		sere_test_sheet other = sere_test_sheet_make( 48, 40 );
		sheet_step( &other, threads, &params );
		const size_t bytes = sizeof( float ) * (size_t) one.n;
		cr_expect( memcmp( one.x, other.x, bytes ) == 0 && memcmp( one.y, other.y, bytes ) == 0 &&
					   memcmp( one.z, other.z, bytes ) == 0,
				   "%d threads differ from 1", threads );
		sere_test_sheet_free( &other );
	}
	sere_test_sheet_free( &one );
}

Test( vbd, the_ground_bounds_the_step_and_reports_its_push )
{
	/* The sheet predicted 0.02 below the ground z = 0 with its waves of ±0.01: every particle
	 * ends on or above it, held ones excepted, and those the ground held report a push; a call
	 * without ground reports none. */
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] -= 0.02f, s.tz[i] -= 0.02f;
	}
	s.inv_m[0] = 0.0f;
	sere_vbd* vbd = sheet_solver( &s, 2 );
	sere_vbd_params params = sheet_params();
	params.ground = 0.0f;
	sere_vbd_report report;
	const float held = s.z[0];
	cr_assert_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	float* push = calloc( (size_t) s.n, sizeof( float ) );
	cr_assert_eq( sere_vbd_ground_push( vbd, push ), SERE_OK );
	int32_t pushed = 0;
	for ( int32_t i = 1; i < s.n; ++i )
	{
		cr_expect_geq( s.z[i], 0.0f, "particle %d at %g", i, s.z[i] );
		cr_expect_geq( push[i], 0.0f );
		pushed += push[i] > 0.0f;
		cr_expect( push[i] == 0.0f || s.z[i] == 0.0f, "particle %d pushed %g but at %g", i, push[i], s.z[i] );
	}
	cr_expect_eq( s.z[0], held );
	cr_expect_eq( push[0], 0.0f );
	cr_expect_gt( pushed, s.n / 2, "%d of %d pushed", pushed, s.n );
	params.ground = -INFINITY;
	memset( push, 0, sizeof( float ) * (size_t) s.n );
	cr_assert_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	cr_assert_eq( sere_vbd_ground_push( vbd, push ), SERE_OK );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		cr_expect_eq( push[i], 0.0f );
	}
	free( push );
	sere_vbd_destroy( vbd );
	sere_test_sheet_free( &s );
}

Test( vbd, the_floor_moves_nothing )
{
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	sere_vbd* vbd = sheet_solver( &s, 2 );
	cr_assert_eq( sere_vbd_touch_sweeps( vbd, s.x, s.y, s.z, s.inv_m, 3 ), SERE_OK );
	const size_t bytes = sizeof( float ) * (size_t) s.n;
	cr_expect( memcmp( s.x, s.tx, bytes ) == 0 && memcmp( s.y, s.ty, bytes ) == 0 && memcmp( s.z, s.tz, bytes ) == 0 );
	cr_expect_eq( sere_vbd_touch_sweeps( vbd, s.x, s.y, s.z, s.inv_m, 0 ), SERE_ERR_ARGUMENT );
	const sere_vbd_info info = sere_vbd_get_info( vbd );
	cr_expect_eq( info.springs, 2 * s.count );
	cr_expect_geq( info.entries, info.springs );
	cr_expect_geq( info.colors, 2 );
	sere_vbd_destroy( vbd );
	sere_test_sheet_free( &s );
}

Test( vbd, refuses_bad_input_and_leaves_the_positions )
{
	sere_test_sheet s = sere_test_sheet_make( 8, 6 );
	sere_vbd* vbd = NULL;
	int32_t self[2] = { 3, 3 }, outside[2] = { 0, 48 };
	cr_expect_eq( sere_vbd_create( self, self + 1, 1, s.n, &vbd ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_vbd_create( outside, outside + 1, 1, s.n, &vbd ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_vbd_create( s.a, s.b, s.count, s.n, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_vbd_create( s.a, s.b, s.count, s.n, &vbd ), SERE_OK );
	sere_vbd_params params = sheet_params();
	sere_vbd_report report;
	/* no rest lengths yet, then a bad one */
	cr_expect_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	/* each bad length, in the lanes' body and in the last spring (a loop's remainder) */
	const float bad_length[4] = { 0.0f, -0.05f, NAN, INFINITY };
	const int32_t where[2] = { 5, s.count - 1 };
	for ( int w = 0; w < 2; ++w )
	{
		for ( int k = 0; k < 4; ++k )
		{
			const float kept = s.rest[where[w]];
			s.rest[where[w]] = bad_length[k];
			cr_expect_eq( sere_vbd_set_rest( vbd, s.rest ), SERE_ERR_GEOMETRY, "length %g at spring %d", bad_length[k],
						  where[w] );
			s.rest[where[w]] = kept;
		}
	}
	cr_assert_eq( sere_vbd_set_rest( vbd, s.rest ), SERE_OK );
	float* weight = malloc( sizeof( float ) * (size_t) s.count );
	for ( int32_t k = 0; k < s.count; ++k )
	{
		weight[k] = 1.0f;
	}
	weight[2] = 0.0f;
	cr_expect_eq( sere_vbd_set_compliance_weights( vbd, weight ), SERE_ERR_ARGUMENT );
	const sere_vbd_params good = params;
	sere_vbd_params bad[7] = { good, good, good, good, good, good, good };
	bad[0].compliance = 0.0f, bad[1].dt = 0.0f, bad[2].tolerance = 0.0f;
	bad[3].max_iterations = 0, bad[4].chebyshev_rho = 1.0f, bad[5].chebyshev_delay = 1;
	bad[6].warm_start = 2;
	for ( int k = 0; k < 7; ++k )
	{
		cr_expect_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &bad[k], &report ), SERE_ERR_ARGUMENT, "case %d", k );
	}
	cr_expect_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, NULL ), SERE_ERR_ARGUMENT );
	/* refused input leaves every position as it was */
	const size_t bytes = sizeof( float ) * (size_t) s.n;
	s.inv_m[7] = -1.0f;
	cr_expect_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	s.inv_m[7] = 1.0f;
	s.y[9] = NAN;
	cr_expect_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_ERR_NONFINITE );
	s.y[9] = s.ty[9];
	cr_expect( memcmp( s.x, s.tx, bytes ) == 0 && memcmp( s.y, s.ty, bytes ) == 0 && memcmp( s.z, s.tz, bytes ) == 0 );
	cr_expect_eq( sere_vbd_set_threads( vbd, SERE_MAX_THREADS + 1 ), SERE_ERR_ARGUMENT );
	free( weight );
	sere_vbd_destroy( vbd );
	sere_test_sheet_free( &s );
}

Test( vbd, a_tolerance_below_the_rounding_stops_at_the_rounding )
{
	/* Moves of 1e-12 cannot be told from the rounding of coordinates up to 1.15 (1.4e-7 apart):
	 * the stop rises to FLT_EPSILON times the largest coordinate, where the sweeps get within the
	 * cap, and the report says which stop was used. */
	sere_test_sheet s = sere_test_sheet_make( 24, 20 );
	float largest = 0.0f;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		largest = fmaxf( largest, fmaxf( fabsf( s.x[i] ), fmaxf( fabsf( s.y[i] ), fabsf( s.z[i] ) ) ) );
	}
	sere_vbd* vbd = sheet_solver( &s, 1 );
	sere_vbd_params params = sheet_params();
	params.tolerance = 1e-12f;
	sere_vbd_report report;
	cr_assert_eq( sere_vbd_step( vbd, s.x, s.y, s.z, s.inv_m, &params, &report ), SERE_OK );
	cr_expect( !report.hit_cap, "%d sweeps, last move %g", report.iterations, report.max_move );
	cr_expect_eq( report.tolerance, sqrtf( ( FLT_EPSILON * largest ) * ( FLT_EPSILON * largest ) ) );
	cr_expect_leq( report.max_move, report.tolerance );
	sere_vbd_destroy( vbd );
	sere_test_sheet_free( &s );
}
