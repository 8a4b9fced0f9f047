/* The multicolor symmetric Gauss–Seidel preconditioner (cg.h: sere_sgs) and the CG it drives
 * (sere_cg_solve_sgs): against a dense reference, its invariants (coloring, symmetry), the
 * tolerance, thread-count determinism, and the osmosis's choice between it and Jacobi. */
#include "drying/model.h"
#include "drying/osmosis.h"
#include "fixture.h"
#include "fixture_cg.h"
#include "ref/osmosis_ref.h"
#include "solve/cg.h"

#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

Test( sgs, coloring_separates_neighbors )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 14, 9 );
	cr_expect_gt( s.g->colors, 1 );
	cr_expect_leq( s.g->colors, SERE_SGS_MAX_COLORS );
	int32_t seen = 0;
	for ( int32_t i = 0; i < s.a->rows; ++i )
	{
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			cr_expect( s.a->col[k] == i || s.g->color[s.a->col[k]] != s.g->color[i], "rows %d and %d share color %d", i,
					   s.a->col[k], s.g->color[i] );
		}
	}
	/* every row has one position, inside its color's chunks */
	for ( int32_t c = 0; c < s.g->colors; ++c )
	{
		for ( int32_t at = s.g->color_chunk[c] * SERE_SELL_C; at < s.g->color_chunk[c + 1] * SERE_SELL_C; ++at )
		{
			if ( s.g->row[at] >= 0 )
			{
				cr_expect_eq( s.g->color[s.g->row[at]], c );
				seen += 1;
			}
		}
	}
	cr_expect_eq( seen, s.a->rows );
	sere_test_cg_system_free( &s );
}

/* Within each window of SERE_SGS_SIGMA positions of a color the rows run from the longest U part
 * to the shortest (ties: the longer L part first), and the layout stores little padding: on this
 * layer 0.9% of the off-diagonal entries, against 3.0% with the rows in their numbering's order
 * (on the maple's T layer 4.2% against 29.5%). */
Test( sgs, layout_sorts_rows_by_length )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 60, 40 );
	const sere_sgs* g = s.g;
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		const int32_t begin = g->color_chunk[c] * SERE_SELL_C, end = g->color_chunk[c + 1] * SERE_SELL_C;
		int32_t previous_u = 0, previous_l = 0;
		for ( int32_t at = begin; at < end && g->row[at] >= 0; ++at )
		{
			int32_t i = g->row[at], nl = 0, nu = 0;
			for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
			{
				nl += g->color[s.a->col[k]] < c;
				nu += g->color[s.a->col[k]] > c;
			}
			if ( ( at - begin ) % SERE_SGS_SIGMA != 0 )
			{
				cr_expect( nu < previous_u || ( nu == previous_u && nl <= previous_l ),
						   "color %d position %d: (U %d, L %d) after (U %d, L %d)", c, at, nu, nl, previous_u,
						   previous_l );
			}
			previous_u = nu, previous_l = nl;
		}
	}
	const int64_t slots = g->upper_ptr[g->chunks], offdiagonal = s.a->nnz - s.a->rows;
	cr_expect_lt( (double) ( slots - offdiagonal ), 0.02 * (double) offdiagonal, "padding %g of the entries",
				  (double) ( slots - offdiagonal ) / (double) offdiagonal );
	sere_test_cg_system_free( &s );
}

/* sere_sgs_apply against M = (D + L) D⁻¹ (D + U) formed densely from the coloring (L: entries
 * toward earlier colors) and solved by Gaussian elimination. */
Test( sgs, apply_matches_dense_reference )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 10, 7 );
	double *lower = calloc( (size_t) s.n * s.n, sizeof( double ) ),
		   *upper = calloc( (size_t) s.n * s.n, sizeof( double ) );
	double *m = calloc( (size_t) s.n * s.n, sizeof( double ) ), *d = calloc( s.n, sizeof( double ) );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			int32_t j = s.a->col[k];
			if ( j == i )
			{
				d[i] = s.a->val[k];
				lower[(size_t) i * s.n + i] = upper[(size_t) i * s.n + i] = s.a->val[k];
			}
			else if ( s.g->color[j] < s.g->color[i] )
			{
				lower[(size_t) i * s.n + j] = s.a->val[k];
			}
			else
			{
				upper[(size_t) i * s.n + j] = s.a->val[k];
			}
		}
	}
	for ( int32_t i = 0; i < s.n; ++i )
	{
		for ( int32_t j = 0; j < s.n; ++j )
		{
			double sum = 0.0;
			for ( int32_t k = 0; k < s.n; ++k )
			{
				sum += lower[(size_t) i * s.n + k] / d[k] * upper[(size_t) k * s.n + j];
			}
			m[(size_t) i * s.n + j] = sum;
		}
	}
	double *r = malloc( sizeof( double ) * s.n ), *z = malloc( sizeof( double ) * s.n ),
		   *ref = malloc( sizeof( double ) * s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		r[i] = sin( 0.7 * i ) + 0.2;
	}
	cr_assert_eq( sere_sgs_apply( s.g, r, z ), SERE_OK );
	cr_assert_eq( sere_dense_ref_solve( m, r, ref, s.n ), SERE_OK );
	double largest, worst = sere_test_worst_difference( z, ref, s.n, &largest );
	/* Two triangular sweeps against a pivoted dense solve of the product: both backward stable,
	 * M's condition number here is about 10² (diagonally dominant rows), so they agree to
	 * ~1e-14 of the solution; 1e-11 leaves room and is far below a wrong sweep (O(1)). */
	cr_expect_leq( worst, 1e-11 * largest, "SGS differs from the dense solve by %g of %g", worst, largest );
	free( lower ), free( upper ), free( m ), free( d ), free( r ), free( z ), free( ref );
	sere_test_cg_system_free( &s );
}

/* M⁻¹ is symmetric: xᵀM⁻¹y = yᵀM⁻¹x, and positive: xᵀM⁻¹x > 0. */
Test( sgs, preconditioner_is_symmetric_positive )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 30, 20 );
	double *x = malloc( sizeof( double ) * s.n ), *y = malloc( sizeof( double ) * s.n );
	double *mx = malloc( sizeof( double ) * s.n ), *my = malloc( sizeof( double ) * s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		x[i] = sin( 1.7 * i + 0.3 );
		y[i] = cos( 0.9 * i );
	}
	cr_assert_eq( sere_sgs_apply( s.g, x, mx ), SERE_OK );
	cr_assert_eq( sere_sgs_apply( s.g, y, my ), SERE_OK );
	double gap, norm;
	const double xmx = sere_test_symmetry( x, y, mx, my, s.n, &gap, &norm );
	/* As HPCG's symmetry test: the two sums agree to the rounding of the sweeps and the sums,
	 * a few ulps per term, far below 1e-12 of their size (an unsymmetric M, e.g. one sweep
	 * only, differs by O(1) of it). */
	cr_expect_leq( fabs( gap ), 1e-12 * norm, "xᵀM⁻¹y − yᵀM⁻¹x = %.17g of %.17g", gap, norm );
	cr_expect_gt( xmx, 0.0 );
	free( x ), free( y ), free( mx ), free( my );
	sere_test_cg_system_free( &s );
}

/* The solve reaches the tolerance on the true residual (checked here independently), in fewer
 * iterations than Jacobi on a stiff system, bit-identically at 1, 2 and 3 threads, and agrees
 * with the Jacobi PCG's solution to what the tolerance permits. */
Test( sgs, cg_converges_deterministically, .timeout = 60 )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 60, 40 );
	sere_sell* sell;
	sere_cg_workspace* w;
	cr_assert_eq( sere_sell_create( s.a, SERE_SELL_SIGMA, &sell ), SERE_OK );
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	double* x[3];
	double* jacobi = malloc( sizeof( double ) * s.n );
	sere_cg_result result[3], jacobi_result;
	const double tolerance = 1e-10;
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		x[t] = malloc( sizeof( double ) * s.n );
		for ( int32_t i = 0; i < s.n; ++i )
		{
			x[t][i] = 0.1 * cos( 0.02 * i ); /* warm start */
		}
		cr_assert_eq( sere_cg_solve_sgs( w, s.g, s.b, x[t], tolerance, 5000, &result[t] ), SERE_OK );
		cr_expect_leq( result[t].residual, tolerance );
	}
	for ( int t = 1; t < 3; ++t )
	{
		cr_expect_eq( result[t].iterations, result[0].iterations );
		cr_expect_eq( memcmp( &result[t].residual, &result[0].residual, sizeof( double ) ), 0 );
		cr_expect_eq( memcmp( x[t], x[0], sizeof( double ) * s.n ), 0, "%d threads differ from 1", t + 1 );
	}
	/* The reported residual is the true one: recomputed here with the CSR product, it agrees to
	 * the rounding of the two computations of r = s.b − Ax, which may sum a row in different orders
	 * (another compiler vectorizes them differently). Component i of a computed r is off by at
	 * most k ε (Σ_j |a_ij x_j| + |b_i|) for a row of k − 1 entries (the standard bound on a
	 * recursive sum), so the two relative residuals differ by at most twice that norm over ‖s.b‖.
	 * At 1e-10 the cancellation in s.b − Ax is deep: this bound, not a fixed fraction of the
	 * residual, is what rounding allows. */
	double check = sere_test_relative_residual( s.a, s.b, x[0] );
	double bound2 = 0.0, bb = 0.0;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double row = fabs( s.b[i] );
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			row += fabs( s.a->val[k] * x[0][s.a->col[k]] );
		}
		double k_eps = (double) ( s.a->row_ptr[i + 1] - s.a->row_ptr[i] + 1 ) * DBL_EPSILON;
		bound2 += ( k_eps * row ) * ( k_eps * row );
		bb += s.b[i] * s.b[i];
	}
	double bound = 2.0 * sqrt( bound2 / bb );
	cr_expect_leq( fabs( check - result[0].residual ), bound, "reported %g, recomputed %g, rounding bound %g",
				   result[0].residual, check, bound );
	cr_expect_leq( check, tolerance + bound, "the recomputed residual %g misses the tolerance", check );
	omp_set_num_threads( 2 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		jacobi[i] = 0.1 * cos( 0.02 * i );
	}
	cr_assert_eq( sere_cg_solve( w, sell, s.b, jacobi, tolerance, 5000, &jacobi_result ), SERE_OK );
	/* SGS must save at least a third of the iterations: PCG iterations go with √κ, and SGS
	 * divides κ of a diffusion-dominated system by about 4 (BM_PCG, plane tree: 579 → 289). */
	cr_expect_lt( 3 * result[0].iterations, 2 * jacobi_result.iterations, "SGS %d iterations, Jacobi %d",
				  result[0].iterations, jacobi_result.iterations );
	/* Both solutions have relative residual ≤ 1e-10; their difference is bounded by
	 * κ(A) · 2e-10 relative, with κ(A) ≲ 10⁴ on this system: 1e-5 of the solution's size. */
	double largest, worst = sere_test_worst_difference( x[0], jacobi, s.n, &largest );
	cr_expect_leq( worst, 1e-5 * largest, "SGS and Jacobi solutions differ by %g of %g", worst, largest );
	free( x[0] ), free( x[1] ), free( x[2] ), free( jacobi );
	sere_cg_destroy( w );
	sere_sell_destroy( sell );
	sere_test_cg_system_free( &s );
}

/* From x = +0 the solve skips the products of its start (A x and L̃ᵀ x are +0): it must take the
 * bits of the full path, which a start from x = −0 still runs (its products come out +0 too, so
 * the two solves meet exactly from there on), at 1 and 2 threads. */
Test( sgs, cold_start_takes_the_full_paths_bits, .timeout = 60 )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 60, 40 );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	double* x[2][2];
	sere_cg_result result[2][2];
	for ( int t = 0; t < 2; ++t )
	{
		omp_set_num_threads( t + 1 );
		for ( int sign = 0; sign < 2; ++sign )
		{
			x[t][sign] = malloc( sizeof( double ) * s.n );
			for ( int32_t i = 0; i < s.n; ++i )
			{
				x[t][sign][i] = sign ? -0.0 : 0.0;
			}
			cr_assert_eq( sere_cg_solve_sgs( w, s.g, s.b, x[t][sign], 1e-10, 5000, &result[t][sign] ), SERE_OK );
		}
		cr_expect_gt( result[t][0].iterations, 1 );
		cr_expect_eq( result[t][0].iterations, result[t][1].iterations );
		cr_expect_eq( memcmp( &result[t][0].residual, &result[t][1].residual, sizeof( double ) ), 0 );
		cr_expect_eq( memcmp( x[t][0], x[t][1], sizeof( double ) * s.n ), 0, "%d threads: +0 and −0 starts differ",
					  t + 1 );
	}
	cr_expect_eq( memcmp( x[1][0], x[0][0], sizeof( double ) * s.n ), 0 );
	cr_expect_leq( result[0][0].residual, 1e-10 );
	for ( int t = 0; t < 2; ++t )
	{
		free( x[t][0] ), free( x[t][1] );
	}
	sere_cg_destroy( w );
	sere_test_cg_system_free( &s );
}

/* The floor (sere_cg_touch_sgs) writes only scratch: a solve after it, at 1 and 2 threads, gives
 * the bits of a solve before it; it refuses bad input as the solve does. */
Test( sgs, touch_leaves_the_solve_unchanged, .timeout = 60 )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 40, 30 );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	sere_cg_result before_result, after_result;
	double* before = calloc( (size_t) s.n, sizeof( double ) );
	double* after = calloc( (size_t) s.n, sizeof( double ) );
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_cg_solve_sgs( w, s.g, s.b, before, 1e-10, 5000, &before_result ), SERE_OK );
	cr_assert_gt( before_result.iterations, 1 );
	for ( int t = 1; t <= 2; ++t )
	{
		omp_set_num_threads( t );
		cr_assert_eq( sere_cg_touch_sgs( w, s.g, before_result.iterations ), SERE_OK );
		memset( after, 0, sizeof( double ) * (size_t) s.n );
		omp_set_num_threads( 1 );
		cr_assert_eq( sere_cg_solve_sgs( w, s.g, s.b, after, 1e-10, 5000, &after_result ), SERE_OK );
		cr_expect_eq( after_result.iterations, before_result.iterations );
		cr_expect_eq( memcmp( after, before, sizeof( double ) * (size_t) s.n ), 0, "touching at %d threads", t );
	}
	cr_expect_eq( sere_cg_touch_sgs( NULL, s.g, 1 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_touch_sgs( w, NULL, 1 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_touch_sgs( w, s.g, -1 ), SERE_ERR_ARGUMENT );
	sere_cg_workspace* small;
	cr_assert_eq( sere_cg_create( 4, &small ), SERE_OK );
	cr_expect_eq( sere_cg_touch_sgs( small, s.g, 1 ), SERE_ERR_ARGUMENT, "a workspace too small for the system" );
	omp_set_num_threads( 2 );
	free( before ), free( after );
	sere_cg_destroy( small );
	sere_cg_destroy( w );
	sere_test_cg_system_free( &s );
}

/* The coloring's smallest cases take their own paths through the solve (the last color's
 * backward rows ride in the update loop only when there are two colors or more, and color 0's
 * backward and forward rows share one loop): a diagonal matrix (one color, M = A, so one step
 * solves it) and tridiag(−1, 2.5, −1) (a path: two colors), each solved at 1, 2 and 3 threads
 * with the same bits, the true residual within the tolerance, and the solution within what the
 * tolerance and κ ≤ 4.5 / 0.5 = 9 allow of the exact one (the diagonal's b / d; Thomas's
 * elimination for the path, whose own rounding is near 1e-15). */
Test( sgs, one_and_two_colors_solve )
{
	enum
	{
		N = 1000
	};
	static int32_t row_ptr[N + 1], col[3 * N];
	static double val[3 * N], b[N], exact[N], x[3][N], c_prime[N];
	for ( int colors = 1; colors <= 2; ++colors )
	{
		int32_t nnz = 0;
		for ( int32_t i = 0; i < N; ++i )
		{
			row_ptr[i] = nnz;
			if ( colors == 2 && i > 0 )
			{
				col[nnz] = i - 1, val[nnz++] = -1.0;
			}
			col[nnz] = i, val[nnz++] = colors == 2 ? 2.5 : 1.0 + 0.5 * ( i % 7 );
			if ( colors == 2 && i + 1 < N )
			{
				col[nnz] = i + 1, val[nnz++] = -1.0;
			}
			b[i] = sin( 0.05 * i ) + 0.2;
		}
		row_ptr[N] = nnz;
		sere_csr a = { N, nnz, row_ptr, col, val };
		if ( colors == 1 )
		{
			for ( int32_t i = 0; i < N; ++i )
			{
				exact[i] = b[i] / val[i];
			}
		}
		else
		{
			/* Thomas: forward elimination, back substitution */
			double d_prime = 0.0;
			for ( int32_t i = 0; i < N; ++i )
			{
				double m = 2.5 - ( i > 0 ? -1.0 * c_prime[i - 1] : 0.0 );
				c_prime[i] = -1.0 / m;
				d_prime = ( b[i] - ( i > 0 ? -1.0 * exact[i - 1] : 0.0 ) ) / m;
				exact[i] = d_prime;
			}
			for ( int32_t i = N - 2; i >= 0; --i )
			{
				exact[i] -= c_prime[i] * exact[i + 1];
			}
		}
		sere_sgs* g = NULL;
		sere_cg_workspace* w = NULL;
		cr_assert_eq( sere_sgs_create( &a, &g ), SERE_OK );
		cr_assert_eq( g->colors, colors );
		cr_assert_eq( sere_cg_create( N, &w ), SERE_OK );
		const double tolerance = 1e-10;
		sere_cg_result result[3];
		for ( int t = 0; t < 3; ++t )
		{
			omp_set_num_threads( t + 1 );
			memset( x[t], 0, sizeof( x[t] ) );
			cr_assert_eq( sere_cg_solve_sgs( w, g, b, x[t], tolerance, 1000, &result[t] ), SERE_OK );
			cr_expect_eq( memcmp( x[t], x[0], sizeof( x[0] ) ), 0, "%d colors: %d threads differ from 1", colors,
						  t + 1 );
			cr_expect_eq( result[t].iterations, result[0].iterations );
		}
		if ( colors == 1 )
		{
			cr_expect_eq( result[0].iterations, 1, "M = A takes one step, took %d", result[0].iterations );
		}
		else
		{
			/* CG's bound with κ ≤ 9 even without a preconditioner: ½ √κ ln(2 / tolerance) ≈ 36 */
			cr_expect_leq( result[0].iterations, 36, "two colors took %d iterations", result[0].iterations );
		}
		cr_expect_leq( sere_test_relative_residual( &a, b, x[0] ), tolerance );
		double largest, worst = sere_test_worst_difference( x[0], exact, N, &largest );
		/* relative error ≤ κ · relative residual in the 2-norm; in the max norm a factor √N more */
		cr_expect_leq( worst, 9.0 * tolerance * sqrt( (double) N ) * largest, "%d colors: off by %g of %g", colors,
					   worst, largest );
		sere_cg_destroy( w );
		sere_sgs_destroy( g );
	}
}

Test( sgs, rejects_bad_patterns_and_matrices )
{
	/* 3 × 3: row 2 lacks its diagonal; then an unsymmetric pattern; then a negative diagonal */
	int32_t row_ptr[] = { 0, 2, 4, 5 }, col[] = { 0, 1, 0, 1, 0 };
	double val[] = { 2.0, -1.0, -1.0, 2.0, -1.0 };
	sere_csr a = { 3, 5, row_ptr, col, val };
	sere_sgs* g = NULL;
	cr_expect_eq( sere_sgs_create( &a, &g ), SERE_ERR_ARGUMENT );
	int32_t row_ptr2[] = { 0, 2, 3, 5 }, col2[] = { 0, 2, 1, 1, 2 };
	double val2[] = { 2.0, -1.0, 2.0, -1.0, 2.0 };
	sere_csr b = { 3, 5, row_ptr2, col2, val2 }; /* (0,2) and (2,1) without (2,0) and (1,2) */
	cr_expect_eq( sere_sgs_create( &b, &g ), SERE_ERR_ARGUMENT );
	int32_t row_ptr3[] = { 0, 2, 4 }, col3[] = { 0, 1, 0, 1 };
	double val3[] = { -2.0, 1.0, 1.0, 2.0 };
	sere_csr c = { 2, 4, row_ptr3, col3, val3 };
	cr_assert_eq( sere_sgs_create( &c, &g ), SERE_OK );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( 2, &w ), SERE_OK );
	double rhs[2] = { 1.0, 1.0 }, x[2] = { 0.0, 0.0 };
	sere_cg_result result;
	cr_expect_eq( sere_cg_solve_sgs( w, g, rhs, x, 1e-8, 10, &result ), SERE_ERR_NOT_SPD );
	cr_expect_eq( sere_sgs_apply( g, rhs, x ), SERE_ERR_NOT_SPD );
	sere_cg_destroy( w );
	sere_sgs_destroy( g );
}

/* sere_cg_residual_sgs measures a guess as the CSR product does (to rounding), with the same
 * bits at 1, 2 and 3 threads, leaves x alone, gives 0 for the exact answer of b = 0 and +∞
 * for any other x then, and refuses what a solve refuses. */
Test( sgs, residual_of_a_guess )
{
	sere_test_cg_system s;
	sere_test_cg_system_make( &s, 30, 20 );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( s.n, &w ), SERE_OK );
	double *x = malloc( sizeof( double ) * s.n ), *kept = malloc( sizeof( double ) * s.n );
	double *zero = calloc( (size_t) s.n, sizeof( double ) ), *ones = malloc( sizeof( double ) * s.n );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double diagonal = 1.0;
		for ( int32_t k = s.a->row_ptr[i]; k < s.a->row_ptr[i + 1]; ++k )
		{
			diagonal = s.a->col[k] == i ? s.a->val[k] : diagonal;
		}
		x[i] = 0.9 * s.b[i] / diagonal + 1e-3 * sin( 0.7 * i ); /* a rough guess */
		ones[i] = 1.0;
	}
	memcpy( kept, x, sizeof( double ) * s.n );
	double relative[3];
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		sere_cg_set_threads( w, t + 1 );
		cr_assert_eq( sere_cg_residual_sgs( w, s.g, s.b, x, &relative[t] ), SERE_OK );
		cr_expect_eq( memcmp( &relative[t], &relative[0], sizeof( double ) ), 0, "%d threads: %.17g, 1: %.17g", t + 1,
					  relative[t], relative[0] );
	}
	omp_set_num_threads( 2 );
	cr_expect_eq( memcmp( x, kept, sizeof( double ) * s.n ), 0, "x changed" );
	/* the same sums in other orders: this guess's relative residual (about 0.98, from terms of
	 * order 1) agrees to a few ulps, far within 1e-12 of itself */
	const double check = sere_test_relative_residual( s.a, s.b, x );
	cr_expect_gt( check, 1e-6 );
	cr_expect_leq( fabs( relative[0] - check ), 1e-12 * check, "%.17g against the CSR's %.17g", relative[0], check );
	double r;
	cr_expect_eq( sere_cg_residual_sgs( w, s.g, zero, zero, &r ), SERE_OK );
	cr_expect_eq( r, 0.0 );
	cr_expect_eq( sere_cg_residual_sgs( w, s.g, zero, ones, &r ), SERE_OK );
	cr_expect( isinf( r ) );
	kept[3] = NAN;
	cr_expect_eq( sere_cg_residual_sgs( w, s.g, s.b, kept, &r ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_cg_residual_sgs( w, s.g, s.b, x, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_residual_sgs( NULL, s.g, s.b, x, &r ), SERE_ERR_ARGUMENT );
	sere_cg_workspace* small;
	cr_assert_eq( sere_cg_create( 4, &small ), SERE_OK );
	cr_expect_eq( sere_cg_residual_sgs( small, s.g, s.b, x, &r ), SERE_ERR_ARGUMENT );
	sere_cg_destroy( small );
	free( x ), free( kept ), free( zero ), free( ones );
	sere_cg_destroy( w );
	sere_test_cg_system_free( &s );
}

/* The osmosis picks multigrid for the stiffest system, SGS for a stiff one and Jacobi for the
 * easy one, by q (osmosis.h), and each solve meets the tolerance. On this grid λ = 2000 gives
 * q = 0.9995, λ = 100 gives 0.990 and λ = 0.04 gives 0.037. */
Test( sgs, osmosis_picks_by_offdiagonal_ratio )
{
	const double lambdas[3] = { 2000.0, 100.0, 0.04 };
	const sere_osmosis_precond expected[3] = { SERE_OSMOSIS_AMG, SERE_OSMOSIS_SGS, SERE_OSMOSIS_JACOBI };
	for ( int k = 0; k < 3; ++k )
	{
		sere_model model;
		sere_osmosis* o;
		sere_osmosis_report report;
		double* b = sere_test_v_system( &model, 30, 20, lambdas[k], &o, &report );
		sere_osmosis_precond by_q = report.offdiag > SERE_OSMOSIS_AMG_ABOVE	  ? SERE_OSMOSIS_AMG
									: report.offdiag > SERE_OSMOSIS_SGS_ABOVE ? SERE_OSMOSIS_SGS
																			  : SERE_OSMOSIS_JACOBI;
		cr_expect_eq( report.preconditioner, by_q );
		cr_expect_eq( report.preconditioner, expected[k], "lambda %g: q = %g, preconditioner %d", lambdas[k],
					  report.offdiag, report.preconditioner );
		cr_expect_leq( report.residual, sere_osmosis_params_default().tolerance );
		sere_osmosis_destroy( o );
		sere_model_destroy( &model );
		free( b );
	}
}

/* One workspace whose λ changes between steps takes every preconditioner in turn, each step
 * copying a's values into the layout the last one did not write: its matrix (sere_osmosis_matrix,
 * copied from the layout its step wrote) and right-hand side are bitwise those of a fresh
 * workspace's step from the same state (whose first step writes both layouts), and its water
 * agrees with the fresh one's. */
Test( sgs, osmosis_switches_layouts_on_one_workspace )
{
	sere_model model;
	sere_osmosis* kept;
	sere_osmosis_report report, fresh_report;
	double* b = sere_test_v_system( &model, 30, 20, 0.04, &kept, &report );
	cr_assert_eq( report.preconditioner, SERE_OSMOSIS_JACOBI );
	const double lambdas[4] = { 100.0, 2000.0, 0.04, 100.0 };
	const sere_osmosis_precond expected[4] = { SERE_OSMOSIS_SGS, SERE_OSMOSIS_AMG, SERE_OSMOSIS_JACOBI,
											   SERE_OSMOSIS_SGS };
	const int32_t total = model.p.count, first = model.triangle_particles, count = model.triangle_count;
	double *w = malloc( sizeof( double ) * total ), *m = malloc( sizeof( double ) * total );
	for ( int k = 0; k < 4; ++k )
	{
		memcpy( w, model.p.w, sizeof( double ) * total );
		memcpy( m, model.p.m, sizeof( double ) * total );
		sere_osmosis_params params = sere_osmosis_params_default();
		params.lambda_min = params.lambda_max = lambdas[k];
		cr_assert_eq( sere_osmosis_step( kept, model.p.x, model.p.y, model.p.z, model.p.tau, model.p.M, model.p.w,
										 model.p.m, &params, &report ),
					  SERE_OK );
		cr_expect_eq( report.preconditioner, expected[k], "step %d: preconditioner %d", k, report.preconditioner );
		cr_expect_leq( report.residual, params.tolerance );
		sere_osmosis* fresh;
		cr_assert_eq( sere_osmosis_create( first, count, model.s.a + model.t_springs, model.s.b + model.t_springs,
										   model.v_springs, &fresh ),
					  SERE_OK );
		cr_assert_eq( sere_osmosis_step( fresh, model.p.x, model.p.y, model.p.z, model.p.tau, model.p.M, w, m, &params,
										 &fresh_report ),
					  SERE_OK );
		const sere_csr *a = sere_osmosis_matrix( kept ), *fresh_a = sere_osmosis_matrix( fresh );
		cr_expect_eq( memcmp( a->val, fresh_a->val, sizeof( double ) * a->nnz ), 0, "step %d: matrices differ", k );
		cr_expect_eq( memcmp( sere_osmosis_rhs( kept ), sere_osmosis_rhs( fresh ), sizeof( double ) * count ), 0,
					  "step %d: right-hand sides differ", k );
		/* both at ‖r‖ ≤ 1e-10 ‖b‖ from different guesses, κ ≲ 10⁴ (q ≤ 0.9995): 1e-6 of the
		 * largest water content is far above what that allows and far below a wrong solve */
		double largest, worst = sere_test_worst_difference( model.p.w + first, w + first, count, &largest );
		cr_expect_leq( worst, 1e-6 * largest, "step %d: water differs by %g of %g", k, worst, largest );
		sere_osmosis_destroy( fresh );
	}
	free( w ), free( m ), free( b );
	sere_osmosis_destroy( kept );
	sere_model_destroy( &model );
}
