/* A 2D Poisson problem solved with sere's conjugate gradient (solve/cg.h): the start of any
 * solver that hands sere its own sparse SPD matrix. It includes only the CG's header, by its
 * room, as a program that wants one kernel does.
 *
 * −Δu = f on the unit square with u = 0 on the boundary, on an N×N grid of interior points and
 * the 5-point stencil (h = 1/(N+1)). With f = 2 [x(1−x) + y(1−y)] the solution is
 * u = x(1−x) y(1−y), and since the stencil's second differences are exact on quadratics, the
 * discrete solution is u sampled at the grid points: any error left is the solver's. The program
 * checks the relative residual (recomputed here with the CSR product, not taken from the
 * solver) and the error against u, and exits non-zero when a check fails.
 *
 *   cc poisson.c $(pkg-config --cflags --libs sere) -o poisson && ./poisson */
#include <solve/cg.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N 100 /* interior points per side: 10⁴ unknowns, 49600 nonzeros */
/* Threads for every kernel call, said at the call (0 would take OpenMP's count). */
#define THREADS 2

int main( void )
{
	const int32_t n = N * N;
	const double h = 1.0 / ( N + 1 );

	/* The matrix in CSR, the interchange format: row i·N + j couples point (i, j) to its four
	 * neighbours inside the grid (4/h² on the diagonal, −1/h² off it; boundary values are 0). */
	sere_csr a = { .rows = n };
	a.row_ptr = malloc( sizeof( int32_t ) * ( (size_t) n + 1 ) );
	a.col = malloc( sizeof( int32_t ) * 5 * (size_t) n );
	a.val = malloc( sizeof( double ) * 5 * (size_t) n );
	double* b = malloc( sizeof( double ) * (size_t) n );
	double* u = malloc( sizeof( double ) * (size_t) n );
	double* x = calloc( (size_t) n, sizeof( double ) ); /* CG starts from x: here 0 */
	double* ax = malloc( sizeof( double ) * (size_t) n );
	if ( !a.row_ptr || !a.col || !a.val || !b || !u || !x || !ax )
	{
		fprintf( stderr, "poisson: out of memory\n" );
		return 1;
	}
	const double off = -1.0 / ( h * h ), diagonal = 4.0 / ( h * h );
	int32_t k = 0;
	for ( int32_t i = 0; i < N; ++i )
	{
		for ( int32_t j = 0; j < N; ++j )
		{
			const int32_t row = i * N + j;
			a.row_ptr[row] = k;
			if ( i > 0 )
			{
				a.col[k] = row - N, a.val[k++] = off;
			}
			if ( j > 0 )
			{
				a.col[k] = row - 1, a.val[k++] = off;
			}
			a.col[k] = row, a.val[k++] = diagonal;
			if ( j < N - 1 )
			{
				a.col[k] = row + 1, a.val[k++] = off;
			}
			if ( i < N - 1 )
			{
				a.col[k] = row + N, a.val[k++] = off;
			}
			const double px = ( i + 1 ) * h, py = ( j + 1 ) * h;
			b[row] = 2.0 * ( px * ( 1.0 - px ) + py * ( 1.0 - py ) );
			u[row] = px * ( 1.0 - px ) * py * ( 1.0 - py );
		}
	}
	a.row_ptr[n] = k;
	a.nnz = k;

	/* CG runs on the SELL-C-σ layout of the matrix, built once per sparsity pattern (a solver
	 * whose values change keeps it and calls sere_sell_update), with a workspace made once. */
	sere_sell* sell = NULL;
	sere_cg_workspace* cg = NULL;
	sere_cg_result result = { 0 };
	const double tolerance = 1e-10;
	sere_status status = sere_sell_create( &a, SERE_SELL_SIGMA, &sell );
	if ( status == SERE_OK )
	{
		status = sere_cg_create( n, &cg );
	}
	if ( status == SERE_OK )
	{
		status = sere_cg_set_threads( cg, THREADS );
	}
	if ( status == SERE_OK )
	{
		status = sere_cg_solve( cg, sell, b, x, tolerance, 10 * N, &result );
	}
	if ( status != SERE_OK )
	{
		fprintf( stderr, "poisson: FAIL %s\n", sere_status_text( status ) );
		return 1;
	}

	/* The checks, computed here. */
	sere_csr_spmv( &a, x, ax, THREADS );
	double rr = 0.0, bb = 0.0, error = 0.0, size = 0.0;
	for ( int32_t row = 0; row < n; ++row )
	{
		rr += ( b[row] - ax[row] ) * ( b[row] - ax[row] );
		bb += b[row] * b[row];
		error = fmax( error, fabs( x[row] - u[row] ) );
		size = fmax( size, fabs( u[row] ) );
	}
	const double residual = sqrt( rr / bb );
	printf( "poisson: sere %s (%s), %d unknowns, %d nonzeros\n", sere_version(), sere_simd_path(), n, a.nnz );
	printf( "poisson: CG %d iterations, relative residual %.3g (solver), %.3g (recomputed)\n", result.iterations,
			result.residual, residual );
	printf( "poisson: max |x - u| = %.3g (max |u| = %.4g)\n", error, size );

	int failed = 0;
	if ( !( residual <= 10 * tolerance ) )
	{
		fprintf( stderr, "poisson: FAIL relative residual %.3g above %.3g\n", residual, 10 * tolerance );
		failed = 1;
	}
	/* κ(A) ≈ 4/(π h)² ≈ 4·10³: a residual of 1e-10 bounds the relative error by about 4e-7. */
	if ( !( error <= 1e-6 * size ) )
	{
		fprintf( stderr, "poisson: FAIL max error %.3g against the known solution\n", error );
		failed = 1;
	}
	sere_cg_destroy( cg );
	sere_sell_destroy( sell );
	free( a.row_ptr ), free( a.col ), free( a.val ), free( b ), free( u ), free( x ), free( ax );
	puts( failed ? "poisson: FAILED" : "poisson: ok" );
	return failed;
}
