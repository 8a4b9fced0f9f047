/* The aggregation multigrid preconditioner (cg.h: sere_amg) and the CG it drives
 * (sere_cg_solve_amg): its levels, symmetry and positivity, convergence against SGS on stiff
 * systems, thread-count determinism, the smallest matrices, bad input, and the osmosis building
 * the levels only when a step needs them.
 * _GNU_SOURCE: the private amg_shared.h (the levels' Galerkin sums) reaches internal/team.h. */
#define _GNU_SOURCE

#include "fixture.h"
#include "fixture_cg.h"
#include "solve/internal/amg_shared.h"

#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static sere_amg* amg_on( const sere_test_cg_system* s )
{
	sere_amg* m = NULL;
	cr_assert_eq( sere_amg_create( s->a, s->g, &m ), SERE_OK );
	cr_assert_eq( sere_amg_update( m ), SERE_OK );
	return m;
}

/* A grid leaf's model and its triangle layer's osmosis workspace (the layer whose multigrid the
 * test below builds). */
static sere_osmosis* grid_t_layer( sere_model* model )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, 60, 40, 3.0, 2.0, 0.3, 1, 5 );
	sere_layer_params layer = sere_layer_params_default();
	cr_assert_eq( sere_model_from_triangles( &plane.mesh, &layer, model ), SERE_OK );
	sere_test_plane_free( &plane );
	sere_osmosis* o = NULL;
	cr_assert_eq( sere_osmosis_create( 0, model->triangle_particles, model->s.a, model->s.b, model->t_springs, &o ),
				  SERE_OK );
	return o;
}

static sere_status model_step( sere_osmosis* o, sere_model* model, const sere_osmosis_params* params,
							   sere_osmosis_report* report )
{
	return sere_osmosis_step( o, model->p.x, model->p.y, model->p.z, model->p.tau, model->p.M, model->p.w, model->p.m,
							  params, report );
}

/* The multigrid's levels are built only when a step first needs an iteration with them
 * (osmosis.c): a stiff layer (λ = 2000: Σ|a_ij|/a_ii near 0.9995, past SERE_OSMOSIS_AMG_ABOVE;
 * the plane tree's 100 gives 0.988 on this coarse grid) whose first step starts at its answer
 * (uniform concentration, no loss: A c = b for c = w/M) takes no iteration; its next step, from
 * a dry patch, builds the levels then and solves to the tolerance, to what a fresh workspace
 * solving the same step finds (as osmosis/extrapolated_start_saves_iterations_not_accuracy
 * compares them). */
Test( amg, osmosis_builds_the_levels_when_first_needed )
{
	sere_model kept_model, fresh_model;
	sere_osmosis* kept = grid_t_layer( &kept_model );
	sere_osmosis* fresh = grid_t_layer( &fresh_model );
	const int32_t n = kept_model.triangle_particles;
	for ( int32_t i = 0; i < n; ++i )
	{
		kept_model.p.w[i] = 0.8 * kept_model.p.M[i];
	}
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = 2000.0;
	params.water_rate = 0.0;
	sere_osmosis_report report;
	cr_assert_eq( model_step( kept, &kept_model, &params, &report ), SERE_OK );
	cr_expect_eq( report.preconditioner, SERE_OSMOSIS_AMG, "offdiag %g", report.offdiag );
	cr_expect_eq( report.iterations, 0 );
	cr_expect_leq( report.residual, params.tolerance );
	for ( int32_t i = 0; i < n; ++i )
	{
		const double x = kept_model.p.x[i], y = kept_model.p.y[i];
		kept_model.p.w[i] =
			( x - 1.5 ) * ( x - 1.5 ) + ( y - 1.0 ) * ( y - 1.0 ) < 0.25 ? 0.1 * kept_model.p.M[i] : kept_model.p.w[i];
		kept_model.p.m[i] = kept_model.p.M[i] + kept_model.p.w[i];
		fresh_model.p.w[i] = kept_model.p.w[i], fresh_model.p.m[i] = kept_model.p.m[i];
	}
	params.water_rate = -0.1;
	cr_assert_eq( model_step( kept, &kept_model, &params, &report ), SERE_OK );
	cr_expect_eq( report.preconditioner, SERE_OSMOSIS_AMG );
	cr_expect_gt( report.iterations, 0 );
	cr_expect_leq( report.residual, params.tolerance );
	sere_osmosis_report fresh_report;
	cr_assert_eq( model_step( fresh, &fresh_model, &params, &fresh_report ), SERE_OK );
	/* both at ‖r‖ ≤ 1e-10 ‖b‖ from different guesses: 1e-6 of the largest water content is far
	 * above what those residuals allow and far below a wrong solve */
	double worst = 0.0, largest = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		worst = fmax( worst, fabs( kept_model.p.w[i] - fresh_model.p.w[i] ) );
		largest = fmax( largest, fabs( fresh_model.p.w[i] ) );
	}
	cr_expect_leq( worst, 1e-6 * largest, "water differs by %g (largest %g)", worst, largest );
	sere_osmosis_destroy( kept );
	sere_osmosis_destroy( fresh );
	sere_model_destroy( &kept_model );
	sere_model_destroy( &fresh_model );
}

/* Each level has at most 4/5 of the rows of the one before, and the last is small enough to be
 * factored: the coarsening stops where cg.h says. */
Test( amg, levels_shrink_to_a_dense_level )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 60, 40 );
	sere_amg* m = amg_on( &s );
	const int32_t levels = sere_amg_levels( m );
	cr_expect_geq( levels, 3, "%d levels for %d rows", levels, s.n );
	cr_expect_eq( sere_amg_rows( m, 0 ), s.n );
	for ( int32_t l = 1; l < levels; ++l )
	{
		cr_expect_leq( 5 * sere_amg_rows( m, l ), 4 * sere_amg_rows( m, l - 1 ), "level %d: %d rows after %d", l,
					   sere_amg_rows( m, l ), sere_amg_rows( m, l - 1 ) );
		cr_expect_gt( sere_amg_rows( m, l ), 0 );
	}
	cr_expect_leq( sere_amg_rows( m, levels - 1 ), SERE_AMG_DENSE_ROWS );
	cr_expect_eq( sere_amg_rows( m, levels ), 0 );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

/* The finest level's Galerkin sums (sere_amg_refresh adds val[sum_from[q]] into the coarse
 * entry sum_to[t]): every fine entry a_ij is summed exactly once, into a target whose entries all
 * join the same pair of aggregates (those of rows i and j), no two targets join the same pair, and
 * within a target the entries come in (min(i, j), max(i, j), i) order, which makes the coarse
 * matrix bitwise symmetric. Integers only: exact. */
Test( amg, galerkin_sums_group_and_order_the_fine_entries )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 30, 20 );
	sere_amg* m = amg_on( &s );
	const amg_level* L = &m->level[0];
	const sere_sgs* g = s.g;
	const int32_t nnz = s.a->nnz, np = g->chunks * SERE_SELL_C;
	int32_t* position = malloc( sizeof( int32_t ) * s.n );
	int32_t* row_of = malloc( sizeof( int32_t ) * nnz );
	int32_t* seen = calloc( (size_t) nnz, sizeof( int32_t ) );
	/* the aggregates are the next level's positions (or the dense level's rows) */
	const int32_t next_np = m->levels > 1 ? m->level[1].np : m->dense_rows;
	int32_t* pair_target = malloc( sizeof( int32_t ) * (size_t) next_np * (size_t) next_np );
	cr_assert( position && row_of && seen && pair_target );
	for ( int32_t at = 0; at < np; ++at )
	{
		if ( g->row[at] >= 0 )
		{
			position[g->row[at]] = at;
		}
	}
	/* the slots hold every entry once (the layout's own contract); map each back to its entry */
	const int32_t slots = g->upper_ptr[g->chunks] + np;
	int32_t* slot_entry = malloc( sizeof( int32_t ) * slots );
	for ( int32_t q = 0; q < slots; ++q )
	{
		slot_entry[q] = -1;
	}
	for ( int32_t i = 0; i < s.n; ++i )
	{
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			slot_entry[g->slot[k]] = k;
			row_of[k] = i;
		}
	}
	for ( size_t q = 0; q < (size_t) next_np * (size_t) next_np; ++q )
	{
		pair_target[q] = -1;
	}
	cr_assert_eq( L->sum_ptr[0], 0 );
	cr_assert_eq( L->sum_ptr[L->targets], nnz, "%d entries summed of %d", L->sum_ptr[L->targets], nnz );
	for ( int32_t t = 0; t < L->targets; ++t )
	{
		cr_assert_lt( L->sum_ptr[t], L->sum_ptr[t + 1], "target %d is empty", t );
		cr_expect( t == 0 || L->sum_to[t] > L->sum_to[t - 1], "targets out of order at %d", t );
		int32_t ci = -1, cj = -1, low0 = -1, high0 = -1, row0 = -1;
		for ( int32_t q = L->sum_ptr[t]; q < L->sum_ptr[t + 1]; ++q )
		{
			const int32_t k = slot_entry[L->sum_from[q]];
			cr_assert_geq( k, 0, "slot %d holds no entry", L->sum_from[q] );
			seen[k] += 1;
			const int32_t i = row_of[k], j = s.a->col[k];
			const int32_t low = i < j ? i : j, high = i < j ? j : i;
			const int32_t pi = L->coarse_at[position[i]], pj = L->coarse_at[position[j]];
			if ( q == L->sum_ptr[t] )
			{
				ci = pi, cj = pj;
				cr_assert( pi >= 0 && pi < next_np && pj >= 0 && pj < next_np, "aggregates %d, %d", pi, pj );
				cr_expect_eq( pair_target[(size_t) pi * next_np + pj], -1, "aggregates %d, %d summed in two targets",
							  pi, pj );
				pair_target[(size_t) pi * next_np + pj] = t;
			}
			else
			{
				cr_expect( pi == ci && pj == cj, "target %d joins (%d, %d) and (%d, %d)", t, ci, cj, pi, pj );
				const bool ascending =
					low > low0 || ( low == low0 && ( high > high0 || ( high == high0 && i > row0 ) ) );
				cr_expect( ascending, "target %d: (%d, %d, %d) after (%d, %d, %d)", t, low, high, i, low0, high0,
						   row0 );
			}
			low0 = low, high0 = high, row0 = i;
		}
	}
	for ( int32_t k = 0; k < nnz; ++k )
	{
		cr_expect_eq( seen[k], 1, "entry %d summed %d times", k, seen[k] );
	}
	free( position ), free( row_of ), free( seen ), free( pair_target ), free( slot_entry );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

/* xᵀBy = yᵀBx and xᵀBx > 0 for the V-cycle B: CG needs both. */
Test( amg, preconditioner_is_symmetric_positive )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 30, 20 );
	sere_amg* m = amg_on( &s );
	double *x = malloc( sizeof( double ) * s.n ), *y = malloc( sizeof( double ) * s.n );
	double *bx = malloc( sizeof( double ) * s.n ), *by = malloc( sizeof( double ) * s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		x[i] = sin( 1.7 * i + 0.3 );
		y[i] = cos( 0.9 * i ) + 0.5; /* a smooth part too: the coarse levels carry it */
	}
	cr_assert_eq( sere_amg_apply( m, x, bx ), SERE_OK );
	cr_assert_eq( sere_amg_apply( m, y, by ), SERE_OK );
	double gap, norm, unused;
	const double xbx = sere_test_symmetry( x, y, bx, by, s.n, &gap, &norm );
	const double yby = sere_test_symmetry( y, x, by, bx, s.n, &unused, &unused );
	/* The sweeps are adjoint and the coarse matrices bitwise symmetric, so the two sums differ by
	 * rounding only: each level's sweeps and sums add a few ulps per term, which the coarse
	 * solves of this nearly singular system (κ ≈ 10³) carry into the result; 1e-10 of the sum's
	 * size leaves room for that, while a V-cycle without its backward sweep (not symmetric)
	 * differs by O(1) of it. */
	cr_expect_leq( fabs( gap ), 1e-10 * norm, "xᵀBy − yᵀBx = %.17g of %.17g", gap, norm );
	cr_expect_gt( xbx, 0.0 );
	cr_expect_gt( yby, 0.0 );
	free( x ), free( y ), free( bx ), free( by );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

/* The solve reaches the tolerance on the true residual (recomputed here), with the same bits at
 * 1, 2 and 3 threads, in fewer iterations than SGS on a stiff system, and agrees with the SGS
 * solution to what the tolerance permits. */
static void converges_against_sgs( double lambda, int32_t nx, int32_t ny, int32_t fewer_by )
{
	sere_test_cg_system s;
	s.b = sere_test_v_system( &s.model, nx, ny, lambda, &s.o, &s.report );
	s.a = sere_osmosis_matrix( s.o );
	s.n = s.a->rows;
	cr_assert_eq( sere_sgs_create( s.a, &s.g ), SERE_OK );
	sere_amg* m = amg_on( &s );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	const double tolerance = 1e-10;
	double *x[3], *sgs = malloc( sizeof( double ) * s.n );
	sere_cg_result result[3], sgs_result;
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		x[t] = calloc( (size_t) s.n, sizeof( double ) );
		cr_assert_eq( sere_cg_solve_amg( w, m, s.b, x[t], tolerance, 1000, &result[t] ), SERE_OK );
		cr_expect_leq( result[t].residual, tolerance );
	}
	for ( int t = 1; t < 3; ++t )
	{
		cr_expect_eq( result[t].iterations, result[0].iterations );
		cr_expect_eq( memcmp( x[t], x[0], sizeof( double ) * s.n ), 0, "%d threads differ from 1", t + 1 );
	}
	/* The reported residual is the true one: the CSR product's recomputation agrees to the
	 * rounding of b − Ax, which at 1e-10 cancels ten digits: 1e-4 of it is far above that
	 * rounding and far below the factor a wrong report would be off by. */
	double check = sere_test_relative_residual( s.a, s.b, x[0] );
	cr_expect_leq( fabs( check - result[0].residual ), 1e-4 * result[0].residual + 1e-15, "reported %g, recomputed %g",
				   result[0].residual, check );
	omp_set_num_threads( 2 );
	memset( sgs, 0, sizeof( double ) * s.n );
	cr_assert_eq( sere_cg_solve_sgs( w, s.g, s.b, sgs, tolerance, 5000, &sgs_result ), SERE_OK );
	cr_expect_lt( fewer_by * result[0].iterations, sgs_result.iterations, "lambda %g: multigrid %d, SGS %d", lambda,
				  result[0].iterations, sgs_result.iterations );
	/* Two solutions of relative residual ≤ 1e-10 differ by at most κ(A) · 2e-10 relative, κ(A) ≲
	 * 10⁵ here (1 / (1 − q) with q ≤ 0.99999): 1e-4 of the solution's size. */
	double largest, worst = sere_test_worst_difference( x[0], sgs, s.n, &largest );
	cr_expect_leq( worst, 1e-4 * largest, "multigrid and SGS solutions differ by %g of %g", worst, largest );
	free( x[0] ), free( x[1] ), free( x[2] ), free( sgs );
	sere_cg_destroy( w );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

/* λ = 100 (q = 0.990): the multigrid must at least halve SGS's iterations; λ = 2000 (q = 0.9995),
 * where SGS's iterations grow with √κ and the multigrid's barely do, divide them by four. */
Test( amg, cg_converges_deterministically, .timeout = 60 )
{
	converges_against_sgs( 100.0, 60, 40, 2 );
	converges_against_sgs( 2000.0, 60, 40, 4 );
}

/* Coarse levels that lag the fine values (no update after the matrix changed) leave B symmetric
 * positive definite: the solve still meets the tolerance on the changed matrix, with the same bits
 * at 1 to 3 threads; an update then changes the coarse levels (other bits) and does not need more
 * iterations. The change: every diagonal entry grows by 20% (a drying step changes them by 10⁻³). */
Test( amg, lagging_coarse_levels_still_solve, .timeout = 60 )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 60, 40 );
	sere_amg* m = amg_on( &s );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	sere_cg_result result;
	double* x = calloc( (size_t) s.n, sizeof( double ) );
	cr_assert_eq( sere_cg_solve_amg( w, m, s.b, x, 1e-10, 1000, &result ), SERE_OK );
	sere_csr changed = *s.a;
	changed.val = malloc( sizeof( double ) * (size_t) s.a->nnz );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			changed.val[k] = s.a->val[k] * ( s.a->col[k] == i ? 1.2 : 1.0 );
		}
	}
	cr_assert_eq( sere_sgs_update( s.g, &changed ), SERE_OK );
	double *lagging[3], *followed = calloc( (size_t) s.n, sizeof( double ) );
	int32_t lagging_iterations = 0;
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		lagging[t] = calloc( (size_t) s.n, sizeof( double ) );
		cr_assert_eq( sere_cg_solve_amg( w, m, s.b, lagging[t], 1e-10, 1000, &result ), SERE_OK );
		cr_expect_leq( sere_test_relative_residual( &changed, s.b, lagging[t] ), 2e-10,
					   "the changed matrix's residual (the solve's 1e-10 and its rounding)" );
		lagging_iterations = t == 0 ? result.iterations : lagging_iterations;
		cr_expect_eq( result.iterations, lagging_iterations );
		cr_expect_eq( memcmp( lagging[t], lagging[0], sizeof( double ) * s.n ), 0, "%d threads differ", t + 1 );
	}
	omp_set_num_threads( 2 );
	cr_assert_eq( sere_amg_update( m ), SERE_OK );
	cr_assert_eq( sere_cg_solve_amg( w, m, s.b, followed, 1e-10, 1000, &result ), SERE_OK );
	cr_expect_neq( memcmp( followed, lagging[0], sizeof( double ) * s.n ), 0, "the update changed nothing" );
	cr_expect_leq( result.iterations, lagging_iterations );
	free( x ), free( followed ), free( changed.val );
	free( lagging[0] ), free( lagging[1] ), free( lagging[2] );
	sere_cg_destroy( w );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

/* The smallest cases take their own paths: a diagonal matrix does not coarsen (every aggregate a
 * single row: one level, B = D⁻¹ = A⁻¹, one step solves it); a 1 × 1 matrix; a path
 * tridiag(−1, 2.05, −1) of 500 rows (aggregates of three, down to a dense level; κ ≈ 80) solved
 * to 1e-12 with the same bits at 1–3 threads and within κ · 1e-12 of Thomas's solution. */
Test( amg, small_and_diagonal_matrices )
{
	enum
	{
		N = 500
	};
	int32_t row_ptr[N + 1], col[3 * N];
	double val[3 * N], b[N], x[3][N], exact[N];
	for ( int32_t i = 0; i < N; ++i )
	{
		row_ptr[i] = i;
		col[i] = i;
		val[i] = 1.0 + 0.01 * i;
		b[i] = sin( 0.3 * i ) + 2.0;
	}
	row_ptr[N] = N;
	sere_csr diagonal = { N, N, row_ptr, col, val };
	sere_sgs* g;
	sere_amg* m;
	sere_cg_workspace* w;
	sere_cg_result result;
	cr_assert_eq( sere_cg_create( N, &w ), SERE_OK );
	cr_assert_eq( sere_sgs_create( &diagonal, &g ), SERE_OK );
	cr_assert_eq( sere_amg_create( &diagonal, g, &m ), SERE_OK );
	cr_expect_eq( sere_amg_levels( m ), 1 );
	cr_assert_eq( sere_amg_update( m ), SERE_OK );
	memset( x[0], 0, sizeof( x[0] ) );
	cr_assert_eq( sere_cg_solve_amg( w, m, b, x[0], 1e-14, 10, &result ), SERE_OK );
	cr_expect_eq( result.iterations, 1 );
	for ( int32_t i = 0; i < N; ++i )
	{
		cr_expect_leq( fabs( x[0][i] - b[i] / val[i] ), 1e-15 * fabs( b[i] / val[i] ), "row %d", i );
	}
	sere_amg_destroy( m ), sere_sgs_destroy( g );

	sere_csr one = { 1, 1, row_ptr, col, val };
	cr_assert_eq( sere_sgs_create( &one, &g ), SERE_OK );
	cr_assert_eq( sere_amg_create( &one, g, &m ), SERE_OK );
	cr_assert_eq( sere_amg_update( m ), SERE_OK );
	x[0][0] = 0.0;
	cr_assert_eq( sere_cg_solve_amg( w, m, b, x[0], 1e-14, 10, &result ), SERE_OK );
	cr_expect_leq( fabs( x[0][0] - b[0] / val[0] ), 1e-15 * fabs( b[0] / val[0] ) );
	sere_amg_destroy( m ), sere_sgs_destroy( g );

	int32_t nnz = 0;
	for ( int32_t i = 0; i < N; ++i )
	{
		row_ptr[i] = nnz;
		for ( int32_t j = i - 1; j <= i + 1; ++j )
		{
			if ( j >= 0 && j < N )
			{
				col[nnz] = j;
				val[nnz++] = j == i ? 2.05 : -1.0;
			}
		}
	}
	row_ptr[N] = nnz;
	sere_csr path = { N, nnz, row_ptr, col, val };
	cr_assert_eq( sere_sgs_create( &path, &g ), SERE_OK );
	cr_assert_eq( sere_amg_create( &path, g, &m ), SERE_OK );
	cr_expect_geq( sere_amg_levels( m ), 3 );
	cr_assert_eq( sere_amg_update( m ), SERE_OK );
	/* Thomas's elimination for the exact solution */
	double c[N], d[N];
	c[0] = -1.0 / 2.05, d[0] = b[0] / 2.05;
	for ( int32_t i = 1; i < N; ++i )
	{
		double den = 2.05 + c[i - 1];
		c[i] = -1.0 / den, d[i] = ( b[i] + d[i - 1] ) / den;
	}
	exact[N - 1] = d[N - 1];
	for ( int32_t i = N - 2; i >= 0; --i )
	{
		exact[i] = d[i] - c[i] * exact[i + 1];
	}
	int32_t iterations = 0;
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		memset( x[t], 0, sizeof( x[t] ) );
		cr_assert_eq( sere_cg_solve_amg( w, m, b, x[t], 1e-12, 200, &result ), SERE_OK );
		cr_expect_leq( result.residual, 1e-12 );
		iterations = t == 0 ? result.iterations : iterations;
		cr_expect_eq( result.iterations, iterations );
		cr_expect_eq( memcmp( x[t], x[0], sizeof( x[0] ) ), 0, "%d threads differ from 1", t + 1 );
	}
	/* Unpreconditioned CG needs about √κ · ln(2 / 1e-12) / 2 ≈ 125 iterations on this path. */
	cr_expect_lt( iterations, 40, "%d iterations", iterations );
	double largest, worst = sere_test_worst_difference( x[0], exact, N, &largest );
	cr_expect_leq( worst, 80.0 * 1e-12 * sqrt( (double) N ) * largest, "off by %g of %g", worst, largest );
	omp_set_num_threads( 2 );
	sere_amg_destroy( m ), sere_sgs_destroy( g );
	sere_cg_destroy( w );
}

/* The floor (sere_cg_touch_amg) writes only scratch: a solve after it, at 1 and 2 threads, gives
 * the bits of a solve before it; it refuses bad input as the solve does. */
Test( amg, touch_leaves_the_solve_unchanged, .timeout = 60 )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 40, 30 );
	sere_amg* m = amg_on( &s );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	sere_cg_result before_result, after_result;
	double* before = calloc( (size_t) s.n, sizeof( double ) );
	double* after = calloc( (size_t) s.n, sizeof( double ) );
	cr_assert_eq( sere_cg_solve_amg( w, m, s.b, before, 1e-10, 1000, &before_result ), SERE_OK );
	for ( int t = 1; t <= 2; ++t )
	{
		omp_set_num_threads( t );
		cr_assert_eq( sere_cg_touch_amg( w, m, before_result.iterations ), SERE_OK );
		memset( after, 0, sizeof( double ) * (size_t) s.n );
		omp_set_num_threads( 1 );
		cr_assert_eq( sere_cg_solve_amg( w, m, s.b, after, 1e-10, 1000, &after_result ), SERE_OK );
		cr_expect_eq( after_result.iterations, before_result.iterations );
		cr_expect_eq( memcmp( after, before, sizeof( double ) * (size_t) s.n ), 0, "touching at %d threads", t );
	}
	cr_expect_eq( sere_cg_touch_amg( NULL, m, 1 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_touch_amg( w, NULL, 1 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_touch_amg( w, m, -1 ), SERE_ERR_ARGUMENT );
	free( before ), free( after );
	sere_cg_destroy( w );
	sere_amg_destroy( m );
	sere_test_cg_system_free( &s );
}

Test( amg, rejects_bad_input )
{
	/* [−2 1; 1 2]: a valid pattern, a negative diagonal */
	int32_t row_ptr[] = { 0, 2, 4 }, col[] = { 0, 1, 0, 1 };
	double val[] = { -2.0, 1.0, 1.0, 2.0 }, b[2] = { 1.0, 1.0 }, x[2] = { 0.0, 0.0 };
	sere_csr a = { 2, 4, row_ptr, col, val };
	sere_sgs *g, *other;
	sere_amg* m = NULL;
	sere_cg_workspace* w;
	sere_cg_result result;
	cr_assert_eq( sere_sgs_create( &a, &g ), SERE_OK );
	cr_assert_eq( sere_cg_create( 2, &w ), SERE_OK );
	cr_expect_eq( sere_amg_create( NULL, g, &m ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_amg_create( &a, NULL, &m ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_amg_create( &a, g, NULL ), SERE_ERR_ARGUMENT );
	int32_t one_ptr[] = { 0, 1 }, one_col[] = { 0 };
	double one_val[] = { 1.0 };
	sere_csr one = { 1, 1, one_ptr, one_col, one_val };
	cr_assert_eq( sere_sgs_create( &one, &other ), SERE_OK );
	cr_expect_eq( sere_amg_create( &a, other, &m ), SERE_ERR_ARGUMENT, "an sgs of another matrix" );
	cr_assert_eq( sere_amg_create( &a, g, &m ), SERE_OK );
	cr_expect_eq( sere_cg_solve_amg( w, m, b, x, 1e-8, 10, &result ), SERE_ERR_ARGUMENT, "before the first update" );
	cr_expect_eq( sere_amg_apply( m, b, x ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_amg_update( m ), SERE_OK );
	cr_expect_eq( sere_cg_solve_amg( w, m, b, x, 1e-8, 10, &result ), SERE_ERR_NOT_SPD );
	cr_expect_eq( sere_amg_apply( m, b, x ), SERE_ERR_NOT_SPD );
	cr_expect_eq( sere_cg_solve_amg( w, m, b, x, -1.0, 10, &result ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_amg_set_threads( m, SERE_MAX_THREADS + 1 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_amg_levels( NULL ), 0 );
	cr_expect_eq( sere_amg_rows( NULL, 0 ), 0 );
	cr_expect_eq( sere_amg_rows( m, -1 ), 0 );
	double nan_b[2] = { NAN, 1.0 };
	cr_expect_eq( sere_cg_solve_amg( w, m, nan_b, x, 1e-8, 10, &result ), SERE_ERR_NONFINITE );
	sere_amg_destroy( m ), sere_sgs_destroy( g ), sere_sgs_destroy( other );
	sere_cg_destroy( w );
}
