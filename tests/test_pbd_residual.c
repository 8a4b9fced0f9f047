/* The XPBD step's residuals (Macklin et al. 2016 Eqs. 8–9, sere_pbd_step_residual) and its
 * multipliers (sere_pbd_multipliers): against a lone spring solved by hand, against the reference
 * twin on a frustrated sheet, across thread counts, and the calls that must be refused. */
#include "fixture.h"
#include "ref/pbd_ref.h"
#include "ref/vbd_ref.h"
#include "solve/pbd.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

typedef sere_test_sheet sheet;

static sere_pbd_params step_params( void )
{
	sere_pbd_params params = sere_pbd_params_default();
	params.compliance = 1e-7f; /* α̃ = 0.025 at dt = 0.002, the order of the inverse masses */
	params.tolerance = 1e-5f;
	params.max_iterations = 5000;
	return params;
}

/* One XPBD step of the sheet at `threads` threads; the residuals into *out, the multipliers into
 * lambda (count floats) when not NULL. */
static void sheet_step( sheet* s, int32_t threads, sere_pbd_residuals* out, float* lambda )
{
	sere_pbd* pbd = NULL;
	cr_assert_eq( sere_pbd_create( s->a, s->b, s->count, s->n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, s->rest ), SERE_OK );
	cr_assert_eq( sere_pbd_set_threads( pbd, threads ), SERE_OK );
	sere_pbd_params params = step_params();
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, s->x, s->y, s->z, s->inv_m, &params, &report ), SERE_OK );
	cr_assert( !report.hit_cap, "%d sweeps, residual %g", report.iterations, report.max_strain );
	cr_assert_eq( sere_pbd_step_residual( pbd, s->x, s->y, s->z, s->tx, s->ty, s->tz, s->inv_m, out ), SERE_OK );
	if ( lambda != NULL )
	{
		cr_assert_eq( sere_pbd_multipliers( pbd, lambda ), SERE_OK );
	}
	sere_pbd_destroy( pbd );
}

Test( pbd_residual, lone_spring_meets_both_conditions )
{
	/* x = (0, 2), rest 1, w = 1 + 1, α̃ = 2: the step ends at C = C0 α̃/(w + α̃) = 0.5 with
	 * λ = −C/α̃ = −0.25, each end moved by 0.25 along the spring, which keeps its direction: h = 0
	 * but for float rounding of positions near 1 (1e-7 a coordinate). */
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 1.0f, 1.0f };
	float x[2] = { 0.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	const float tx[2] = { 0.0f, 2.0f };
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( &a, &b, 1, 2, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, &rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	params.dt = 0.01f;
	params.compliance = 2.0f * params.dt * params.dt;
	params.tolerance = 1e-6f;
	params.max_iterations = 10;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	float lambda = 0.0f;
	cr_assert_eq( sere_pbd_multipliers( pbd, &lambda ), SERE_OK );
	cr_expect_float_eq( lambda, -0.25f, 1e-6f );
	sere_pbd_residuals r;
	cr_assert_eq( sere_pbd_step_residual( pbd, x, y, z, tx, y, z, inv_m, &r ), SERE_OK );
	cr_expect_eq( r.particles, 2 );
	/* both ends moved 0.25 under unit mass, and the multiplier's force on each is 0.25 */
	cr_expect( fabs( r.inertia - 0.25 * sqrt( 2.0 ) ) < 1e-6, "inertia %g", r.inertia );
	cr_expect( fabs( r.constraint - 0.25 * sqrt( 2.0 ) ) < 1e-6, "constraint %g", r.constraint );
	cr_expect( r.primal < 1e-6, "primal %g", r.primal );
	sere_pbd_destroy( pbd );
}

Test( pbd_residual, matches_the_reference_twin_on_a_frustrated_sheet )
{
	/* 48 × 40 particles: more than one band, so bands and cuts sum in the workspace's order */
	sheet s = sere_test_sheet_make( 48, 40 );
	float* lambda = calloc( (size_t) s.count, sizeof( float ) );
	sere_pbd_residuals r;
	sheet_step( &s, 2, &r, lambda );
	sere_ref_particle* now = calloc( (size_t) s.n, sizeof( *now ) );
	sere_ref_particle* before = calloc( (size_t) s.n, sizeof( *before ) );
	sere_ref_spring* springs = calloc( (size_t) s.count, sizeof( *springs ) );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		now[i] = ( sere_ref_particle ){ s.x[i], s.y[i], s.z[i], s.inv_m[i] };
		before[i] = ( sere_ref_particle ){ s.tx[i], s.ty[i], s.tz[i], s.inv_m[i] };
	}
	for ( int32_t k = 0; k < s.count; ++k )
	{
		springs[k] = ( sere_ref_spring ){ s.a[k], s.b[k], s.rest[k] };
	}
	double twin[3];
	int32_t counted = sere_pbd_ref_step_residual( now, before, s.n, springs, lambda, s.count, twin );
	cr_expect_eq( r.particles, counted );
	cr_expect_eq( counted, s.n );
	/* The same float inputs summed in double in another order (springs against each particle's
	 * lane order): a relative 1e-12 covers the reordering of about 10 terms a particle. */
	const double got[3] = { r.primal, r.inertia, r.constraint };
	for ( int k = 0; k < 3; ++k )
	{
		cr_expect( fabs( got[k] - twin[k] ) <= 1e-12 * twin[k], "norm %d: %.17g against the twin's %.17g", k, got[k],
				   twin[k] );
	}
	/* The case the measure exists for: converged to g < 1e-5 l, the step still leaves an h that is a
	 * visible share of the multipliers' forces, while a lone spring leaves none (above). */
	cr_expect( r.primal > 1e-2 * r.constraint, "primal %g, constraint %g", r.primal, r.constraint );
	free( now ), free( before ), free( springs ), free( lambda );
	sere_test_sheet_free( &s );
}

/* The largest distance between two position sets, in grid spacings (0.05). */
static double spacings_apart( const double* x, const double* y, int32_t n )
{
	double worst = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		double dx = x[3 * i] - y[3 * i], dy = x[3 * i + 1] - y[3 * i + 1], dz = x[3 * i + 2] - y[3 * i + 2];
		worst = fmax( worst, sqrt( dx * dx + dy * dy + dz * dz ) );
	}
	return worst / SERE_TEST_SHEET_SPACING;
}

Test( pbd_residual, a_large_residual_marks_an_answer_away_from_the_energy_minimum )
{
	/* On the lone spring above h = 0 and the XPBD answer is E's minimum (C = C0 α̃/(w + α̃) is
	 * where dE/dδ = 0 for ends moved by ±δ). On the frustrated sheet h stays a large share of the
	 * multipliers' forces, and the answer is neither a stationary point of E nor near the minimum
	 * a descent from the prediction reaches (docs/DESIGN.md §8, "What the step leaves
	 * unbalanced"). */
	sheet s = sere_test_sheet_make( 24, 20 );
	sere_pbd_residuals r;
	sheet_step( &s, 1, &r, NULL );
	double* stiffness = malloc( sizeof( double ) * (size_t) s.count );
	for ( int32_t k = 0; k < s.count; ++k )
	{
		stiffness[k] = 0.002 * 0.002 / step_params().compliance; /* 1/α̃ */
	}
	const sere_vbd_ref_problem problem = { s.n, s.count, s.tx, s.ty, s.tz, s.inv_m, s.a, s.b, s.rest, stiffness };
	double* xpbd = malloc( sizeof( double ) * 3 * (size_t) s.n );
	double* minimum = malloc( sizeof( double ) * 3 * (size_t) s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		xpbd[3 * i] = s.x[i], xpbd[3 * i + 1] = s.y[i], xpbd[3 * i + 2] = s.z[i];
		minimum[3 * i] = s.tx[i], minimum[3 * i + 1] = s.ty[i], minimum[3 * i + 2] = s.tz[i];
	}
	cr_assert_geq( sere_vbd_ref_descend( &problem, minimum, 1e-9, 20000 ), 0 );
	double gradient = sere_vbd_ref_gradient( &problem, xpbd ), apart = spacings_apart( xpbd, minimum, s.n );
	cr_log_info( "h/force %g, |grad E| %g, %g spacings", r.primal / r.constraint, gradient, apart );
	cr_expect_gt( r.primal, 0.3 * r.constraint );
	cr_expect_gt( gradient, 1e-2, "the XPBD answer's largest |dE/dx_i| is %g", gradient );
	cr_expect_gt( apart, 0.5, "%g spacings from the minimum", apart );
	free( xpbd ), free( minimum ), free( stiffness );
	sere_test_sheet_free( &s );
}

Test( pbd_residual, same_bits_at_every_thread_count )
{
	sere_pbd_residuals one, two, three;
	sheet s = sere_test_sheet_make( 48, 40 );
	sheet_step( &s, 1, &one, NULL );
	sere_test_sheet_free( &s );
	s = sere_test_sheet_make( 48, 40 );
	sheet_step( &s, 2, &two, NULL );
	sere_test_sheet_free( &s );
	s = sere_test_sheet_make( 48, 40 );
	sheet_step( &s, 3, &three, NULL );
	sere_test_sheet_free( &s );
	const sere_pbd_residuals* other[2] = { &two, &three };
	for ( int k = 0; k < 2; ++k )
	{
		/* bitwise: memcmp of each double (the struct's padding is not compared) */
		cr_expect( memcmp( &one.primal, &other[k]->primal, sizeof( double ) ) == 0 &&
					   memcmp( &one.inertia, &other[k]->inertia, sizeof( double ) ) == 0 &&
					   memcmp( &one.constraint, &other[k]->constraint, sizeof( double ) ) == 0 &&
					   one.particles == other[k]->particles,
				   "primal %.17g against %.17g", one.primal, other[k]->primal );
	}
}

Test( pbd_residual, pinned_and_grounded_particles_are_not_counted )
{
	/* A pinned end takes any force, and the ground's reaction is no multiplier. */
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 0.0f, 1.0f };
	float x[2] = { 0.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { -1.0f, -1.0f };
	const float t[2] = { 0.0f, 2.0f }, zero[2] = { 0.0f, 0.0f }, below[2] = { -1.0f, -1.0f };
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( &a, &b, 1, 2, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, &rest ), SERE_OK );
	sere_pbd_params params = step_params();
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	sere_pbd_residuals r;
	cr_assert_eq( sere_pbd_step_residual( pbd, x, y, z, t, zero, below, inv_m, &r ), SERE_OK );
	cr_expect_eq( r.particles, 1 );
	params.ground = 0.0f;
	x[0] = 0.0f, x[1] = 2.0f, z[0] = -1.0f, z[1] = -1.0f;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	cr_expect( z[1] >= 0.0f, "z %g", z[1] );
	cr_assert_eq( sere_pbd_step_residual( pbd, x, y, z, t, zero, below, inv_m, &r ), SERE_OK );
	cr_expect_eq( r.particles, 0 );
	sere_pbd_destroy( pbd );
}

Test( pbd_residual, refused_without_an_xpbd_step )
{
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 1.0f, 1.0f }, lambda = 0.0f;
	float x[2] = { 0.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( &a, &b, 1, 2, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, &rest ), SERE_OK );
	sere_pbd_residuals r;
	/* no projection yet */
	cr_expect_eq( sere_pbd_step_residual( pbd, x, y, z, x, y, z, inv_m, &r ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_multipliers( pbd, &lambda ), SERE_ERR_ARGUMENT );
	sere_pbd_params params = step_params();
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	cr_expect_eq( sere_pbd_step_residual( pbd, x, y, z, x, y, z, inv_m, &r ), SERE_OK );
	cr_expect_eq( sere_pbd_step_residual( pbd, x, y, z, x, y, z, inv_m, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_step_residual( pbd, x, y, NULL, x, y, z, inv_m, &r ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_step_residual( NULL, x, y, z, x, y, z, inv_m, &r ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_multipliers( pbd, NULL ), SERE_ERR_ARGUMENT );
	/* the paper's PBD has no multipliers; a floor's sweeps leave none that describe the positions */
	params.compliance = 0.0f;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	cr_expect_eq( sere_pbd_step_residual( pbd, x, y, z, x, y, z, inv_m, &r ), SERE_ERR_ARGUMENT );
	params.compliance = 1e-7f;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	cr_assert_eq( sere_pbd_touch_sweeps_xpbd( pbd, x, y, z, inv_m, 2 ), SERE_OK );
	cr_expect_eq( sere_pbd_multipliers( pbd, &lambda ), SERE_ERR_ARGUMENT );
	/* a call refused for its input leaves no multipliers either */
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	x[0] = NAN;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_pbd_multipliers( pbd, &lambda ), SERE_ERR_ARGUMENT );
	sere_pbd_destroy( pbd );
}
