/* sere — a CSR sparse matrix and Jacobi-preconditioned conjugate gradient for any SPD matrix.
 * Knows nothing of leaves: another solver can hand it its own matrix. */
#pragma once

#include "base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Compressed sparse rows: row i holds entries [row_ptr[i], row_ptr[i+1]) of col and val. */
typedef struct sere_csr
{
	int32_t rows;
	int32_t nnz;
	int32_t* row_ptr;
	int32_t* col;
	double* val;
} sere_csr;

/* y = A x, OpenMP over fixed row blocks (each y_i is one sequential sum: deterministic). */
void sere_csr_spmv( const sere_csr* a, const double* x, double* y );

/* Dot products sum fixed blocks of SERE_CG_BLOCK entries, then the block sums in block order,
 * so the result is bitwise the same for any thread count. */
#define SERE_CG_BLOCK 512

typedef struct sere_cg_workspace sere_cg_workspace;

/* Scratch for systems of up to n rows; nothing is allocated per solve. */
sere_status sere_cg_create( int32_t n, sere_cg_workspace** out );
void sere_cg_destroy( sere_cg_workspace* workspace );

typedef struct sere_cg_result
{
	int32_t iterations;
	double residual; /* ||b − A x||₂ / ||b||₂ (unpreconditioned, as Eigen reports it) */
} sere_cg_result;

/* Solves A x = b for SPD A starting from x (warm start). Stops when the relative residual is
 * at most tolerance or after max_iterations. SERE_ERR_NOT_SPD when a diagonal entry or a
 * curvature pᵀAp is not positive (indefinite or singular A), SERE_ERR_NONFINITE on NaN/inf,
 * SERE_ERR_NO_CONVERGE at the cap (x then holds the last iterate). b = 0 gives x = 0. */
sere_status sere_cg_solve( sere_cg_workspace* workspace, const sere_csr* a, const double* b, double* x,
						   double tolerance, int32_t max_iterations, sere_cg_result* result );

#ifdef __cplusplus
}
#endif
