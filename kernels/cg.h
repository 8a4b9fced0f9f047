/* sere — sparse matrices (CSR, SELL-C-σ) and Jacobi-preconditioned conjugate gradient for any
 * SPD matrix. Knows nothing of leaves: another solver can hand it its own matrix. */
#pragma once

#include "base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Compressed sparse rows, the interchange format: row i holds entries [row_ptr[i], row_ptr[i+1])
 * of col and val. */
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

/* SELL-C-σ (Kreutzer et al. 2014): rows are cut into chunks of SERE_SELL_C rows stored column by
 * column, so one SIMD lane runs one row and a chunk's rows advance together (no per-row loop exit
 * to mispredict, no chain of dependent adds per row). Inside windows of σ rows the rows are
 * sorted by decreasing length so that a chunk's rows are about as long and little padding is
 * stored.
 *
 * Each lane takes its row's entries in CSR order and then padding (value 0, the row's last
 * column), so y_i is the same sequence of operations as the CSR row sum followed by additions of
 * 0·x_j = ±0 to a sum that is never −0: sere_sell_spmv is bitwise equal to sere_csr_spmv for
 * finite x.
 *
 * The layout depends only on the CSR pattern, which for a simulation is usually fixed while the
 * values change every step (the osmosis matrix does): build it once with sere_sell_create, then
 * either copy new values in with sere_sell_update (one pass over the entries) or, cheaper, write
 * each value where slot says while assembling it (the osmosis does).
 *
 * Positions: lane l of chunk c is position c·SERE_SELL_C + l. The CG runs in that order (its
 * vectors indexed by position, local_col naming columns by position), so a chunk's products are
 * one contiguous vector store and every vector sweep is contiguous; it permutes b and x in and x
 * out once per solve. */
#define SERE_SELL_C 8

typedef struct sere_sell
{
	int32_t rows;		/* as the CSR it was built from */
	int32_t nnz;		/* CSR entries, without padding */
	int32_t sigma;		/* sorting window, in rows */
	int32_t chunks;		/* ⌈rows / SERE_SELL_C⌉ */
	int32_t* chunk_ptr; /* chunk c holds slots [chunk_ptr[c], chunk_ptr[c+1]): its width times SERE_SELL_C */
	int32_t* row;		/* lane l of chunk c runs row row[c·SERE_SELL_C + l]; −1 past the last row */
	int32_t* col;		/* per slot, lane fastest */
	double* val;		/* per slot; 0 in padding */
	int32_t* slot;		/* per CSR entry k: the slot holding it, val[slot[k]] */
	int32_t* local_col; /* per slot, the column as a position in the layout's row order (below) */
	int32_t* diagonal;	/* per position, the slot of the row's diagonal entry; −1 if it has none */
} sere_sell;

/* Builds the layout and values of a. σ is a multiple of SERE_SELL_C that divides SERE_CG_BLOCK
 * (8, 16, ..., 512), so that windows never straddle a CG block: a block's positions are then its
 * own rows, and its sums do not depend on how blocks are shared among threads.
 * SERE_SELL_SIGMA: on the maple osmosis matrices σ = 8 pads the T layer by 21%, σ = 64 by 4% and
 * σ = 512 by 0.7%; 64 and 512 time within the machine's noise. SERE_ERR_ARGUMENT for another σ,
 * an empty matrix, a column out of range, or a row holding its diagonal entry twice (the CG reads
 * the diagonal from one slot). */
#define SERE_SELL_SIGMA 64
sere_status sere_sell_create( const sere_csr* a, int32_t sigma, sere_sell** out );
void sere_sell_destroy( sere_sell* sell );

/* Copies a's values into sell. a must have the pattern sell was built from: rows and nnz are
 * checked, and every entry's column against its slot (SERE_ERR_ARGUMENT, values then undefined). */
sere_status sere_sell_update( sere_sell* sell, const sere_csr* a );

/* y = A x, OpenMP over chunks; bitwise equal to sere_csr_spmv on the CSR sell was built from. */
void sere_sell_spmv( const sere_sell* a, const double* x, double* y );

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
 * SERE_ERR_NO_CONVERGE at the cap (x then holds the last iterate). b = 0 gives x = 0.
 *
 * The matrix is SELL because the solve is a sequence of products with one matrix: the layout
 * pays for itself within one solve, and the caller keeps it across solves (sere_sell_update).
 * The recurrence is Chronopoulos and Gear's: one product per iteration (with the preconditioned
 * residual, gathering one vector) yields both sums the step needs, so an iteration is two sweeps
 * and two barriers. Its iterates equal the textbook PCG's in exact arithmetic and differ only by
 * rounding (tests compare the two). */
sere_status sere_cg_solve( sere_cg_workspace* workspace, const sere_sell* a, const double* b, double* x,
						   double tolerance, int32_t max_iterations, sere_cg_result* result );

#ifdef __cplusplus
}
#endif
