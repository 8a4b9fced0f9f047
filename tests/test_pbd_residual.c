/* The XPBD step's residuals (Macklin et al. 2016 Eqs. 8–9, sere_pbd_step_residual) and its
 * multipliers (sere_pbd_multipliers): against a lone spring solved by hand, against the reference
 * twin on a frustrated sheet, across thread counts, and the calls that must be refused. */
#include "ref/pbd_ref.h"
#include "solve/pbd.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

typedef struct sheet
{
	int32_t n, count;
	float *x, *y, *z, *inv_m;
	float *tx, *ty, *tz; /* the prediction the projection starts from */
	int32_t *a, *b;
	float* rest;
} sheet;

static void add_spring( sheet* s, int32_t i, int32_t j, float scale )
{
	float dx = s->x[j] - s->x[i], dy = s->y[j] - s->y[i], dz = s->z[j] - s->z[i];
	s->a[s->count] = i, s->b[s->count] = j;
	s->rest[s->count] = scale * sqrtf( dx * dx + dy * dy + dz * dz );
	s->count += 1;
}

/* An nx × ny sheet of spacing 0.05, waved in z, with structural springs at their length and the
 * springs of one diagonal at 0.8 of theirs: no shape meets them all, so the multipliers stay large
 * and the springs turn during the step, the case where h grows (docs/DESIGN.md §8). Inverse masses
 * 1..3 so that M matters. */
static sheet make_sheet( int32_t nx, int32_t ny )
{
	sheet s = { 0 };
	s.n = nx * ny;
	float** columns[] = { &s.x, &s.y, &s.z, &s.inv_m, &s.tx, &s.ty, &s.tz };
	for ( size_t k = 0; k < sizeof( columns ) / sizeof( columns[0] ); ++k )
	{
		*columns[k] = calloc( (size_t) s.n, sizeof( float ) );
	}
	s.a = calloc( 3 * (size_t) s.n, sizeof( int32_t ) );
	s.b = calloc( 3 * (size_t) s.n, sizeof( int32_t ) );
	s.rest = calloc( 3 * (size_t) s.n, sizeof( float ) );
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t p = j * nx + i;
			s.x[p] = 0.05f * (float) i, s.y[p] = 0.05f * (float) j;
			s.z[p] = 0.01f * sinf( 0.7f * (float) i ) * cosf( 0.5f * (float) j );
			s.inv_m[p] = 1.0f + (float) ( ( i + 2 * j ) % 3 );
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t p = j * nx + i;
			if ( i + 1 < nx )
			{
				add_spring( &s, p, p + 1, 1.0f );
			}
			if ( j + 1 < ny )
			{
				add_spring( &s, p, p + nx, 1.0f );
			}
			if ( i + 1 < nx && j + 1 < ny )
			{
				add_spring( &s, p, p + nx + 1, 0.8f );
			}
		}
	}
	memcpy( s.tx, s.x, sizeof( float ) * (size_t) s.n );
	memcpy( s.ty, s.y, sizeof( float ) * (size_t) s.n );
	memcpy( s.tz, s.z, sizeof( float ) * (size_t) s.n );
	return s;
}

static void free_sheet( sheet* s )
{
	free( s->x ), free( s->y ), free( s->z ), free( s->inv_m ), free( s->tx ), free( s->ty ), free( s->tz );
	free( s->a ), free( s->b ), free( s->rest );
}

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
	sheet s = make_sheet( 48, 40 );
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
	free_sheet( &s );
}

/* The step's energy E = ½‖x − x̃‖²_M + Σ C²/(2α̃) (Macklin et al. 2016: XPBD's step is derived from
 * its minimum) and a reference minimizer for it: Gauss–Seidel over the particles, each moved by a
 * Newton step on its own 3 × 3 block (inertia plus its springs, the bending part of a spring's
 * Hessian kept only when stretched, so that the block stays positive definite), in double. */
typedef struct energy
{
	const sheet* s;
	double stiffness; /* 1/α̃ */
	int32_t *offset, *spring;
} energy;

static energy energy_of( const sheet* s, double alpha_tilde )
{
	energy e = { s, 1.0 / alpha_tilde, calloc( (size_t) s->n + 1, sizeof( int32_t ) ),
				 malloc( sizeof( int32_t ) * 2 * (size_t) s->count ) };
	for ( int32_t k = 0; k < s->count; ++k )
	{
		e.offset[s->a[k] + 1] += 1, e.offset[s->b[k] + 1] += 1;
	}
	for ( int32_t i = 0; i < s->n; ++i )
	{
		e.offset[i + 1] += e.offset[i];
	}
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) s->n );
	memcpy( fill, e.offset, sizeof( int32_t ) * (size_t) s->n );
	for ( int32_t k = 0; k < s->count; ++k )
	{
		e.spring[fill[s->a[k]]++] = k, e.spring[fill[s->b[k]]++] = k;
	}
	free( fill );
	return e;
}

/* ∂E/∂x_i into g and, when H is not NULL, its 3 × 3 block into H. */
static void energy_block( const energy* e, const double* x, int32_t i, double g[3], double H[9] )
{
	const sheet* s = e->s;
	const double m = 1.0 / s->inv_m[i], t[3] = { s->tx[i], s->ty[i], s->tz[i] };
	for ( int r = 0; r < 3; ++r )
	{
		g[r] = m * ( x[3 * i + r] - t[r] );
		for ( int c = 0; H != NULL && c < 3; ++c )
		{
			H[3 * r + c] = r == c ? m : 0.0;
		}
	}
	for ( int32_t k = e->offset[i]; k < e->offset[i + 1]; ++k )
	{
		const int32_t j = e->spring[k], o = s->a[j] == i ? s->b[j] : s->a[j];
		double d[3] = { x[3 * i] - x[3 * o], x[3 * i + 1] - x[3 * o + 1], x[3 * i + 2] - x[3 * o + 2] };
		double length = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] ), c = length - s->rest[j];
		double bend = c > 0.0 ? c / length : 0.0;
		for ( int r = 0; r < 3; ++r )
		{
			g[r] += e->stiffness * c * d[r] / length;
			for ( int q = 0; H != NULL && q < 3; ++q )
			{
				double nn = d[r] * d[q] / ( length * length );
				H[3 * r + q] += e->stiffness * ( nn + bend * ( ( r == q ) - nn ) );
			}
		}
	}
}

/* The largest |∂E/∂x_i| over the particles. */
static double energy_gradient( const energy* e, const double* x )
{
	double worst = 0.0;
	for ( int32_t i = 0; i < e->s->n; ++i )
	{
		double g[3];
		energy_block( e, x, i, g, NULL );
		worst = fmax( worst, sqrt( g[0] * g[0] + g[1] * g[1] + g[2] * g[2] ) );
	}
	return worst;
}

/* Descends from x until the largest |∂E/∂x_i| is below 1e-9 (asserted within the sweep cap). */
static void energy_descend( const energy* e, double* x )
{
	for ( int sweep = 0; energy_gradient( e, x ) >= 1e-9; ++sweep )
	{
		cr_assert_lt( sweep, 20000 );
		for ( int32_t i = 0; i < e->s->n; ++i )
		{
			double g[3], H[9];
			energy_block( e, x, i, g, H );
			double c0 = H[4] * H[8] - H[5] * H[7], c1 = H[5] * H[6] - H[3] * H[8], c2 = H[3] * H[7] - H[4] * H[6];
			double det = H[0] * c0 + H[1] * c1 + H[2] * c2;
			double inv[9] = { c0, H[2] * H[7] - H[1] * H[8], H[1] * H[5] - H[2] * H[4],
							  c1, H[0] * H[8] - H[2] * H[6], H[2] * H[3] - H[0] * H[5],
							  c2, H[1] * H[6] - H[0] * H[7], H[0] * H[4] - H[1] * H[3] };
			for ( int r = 0; r < 3; ++r )
			{
				x[3 * i + r] -= ( inv[3 * r] * g[0] + inv[3 * r + 1] * g[1] + inv[3 * r + 2] * g[2] ) / det;
			}
		}
	}
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
	return worst / 0.05;
}

Test( pbd_residual, a_large_residual_marks_an_answer_away_from_the_energy_minimum )
{
	/* On the lone spring above h = 0 and the XPBD answer is E's minimum (C = C0 α̃/(w + α̃) is
	 * where dE/dδ = 0 for ends moved by ±δ). On the frustrated sheet h stays a large share of the
	 * multipliers' forces, and the answer is neither a stationary point of E nor near the minimum
	 * a descent from the prediction reaches (docs/DESIGN.md §8, "What the step leaves
	 * unbalanced"). */
	sheet s = make_sheet( 24, 20 );
	sere_pbd_residuals r;
	sheet_step( &s, 1, &r, NULL );
	energy e = energy_of( &s, step_params().compliance / ( 0.002 * 0.002 ) );
	double* xpbd = malloc( sizeof( double ) * 3 * (size_t) s.n );
	double* minimum = malloc( sizeof( double ) * 3 * (size_t) s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		xpbd[3 * i] = s.x[i], xpbd[3 * i + 1] = s.y[i], xpbd[3 * i + 2] = s.z[i];
		minimum[3 * i] = s.tx[i], minimum[3 * i + 1] = s.ty[i], minimum[3 * i + 2] = s.tz[i];
	}
	energy_descend( &e, minimum );
	double gradient = energy_gradient( &e, xpbd ), apart = spacings_apart( xpbd, minimum, s.n );
	cr_log_info( "h/force %g, |grad E| %g, %g spacings", r.primal / r.constraint, gradient, apart );
	cr_expect_gt( r.primal, 0.3 * r.constraint );
	cr_expect_gt( gradient, 1e-2, "the XPBD answer's largest |dE/dx_i| is %g", gradient );
	cr_expect_gt( apart, 0.5, "%g spacings from the minimum", apart );
	free( xpbd ), free( minimum ), free( e.offset ), free( e.spring );
	free_sheet( &s );
}

Test( pbd_residual, same_bits_at_every_thread_count )
{
	sere_pbd_residuals one, two, three;
	sheet s = make_sheet( 48, 40 );
	sheet_step( &s, 1, &one, NULL );
	free_sheet( &s );
	s = make_sheet( 48, 40 );
	sheet_step( &s, 2, &two, NULL );
	free_sheet( &s );
	s = make_sheet( 48, 40 );
	sheet_step( &s, 3, &three, NULL );
	free_sheet( &s );
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
