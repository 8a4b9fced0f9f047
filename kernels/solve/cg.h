/* sere — sparse matrices (CSR, SELL-C-σ) and conjugate gradient for any SPD matrix, Jacobi- or
 * multicolor-SGS-preconditioned. Knows nothing of leaves: another solver can hand it its own
 * matrix. */
#pragma once

#include "core/base.h"

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

/* y = A x over fixed row blocks on `threads` threads (core/base.h; each y_i is one sequential
 * sum: the same bits for every count). */
void sere_csr_spmv( const sere_csr* a, const double* x, double* y, int32_t threads );

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
	int32_t threads;	/* sere_sell_set_threads: update and product (0 at create, core/base.h) */
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

/* y = A x over chunks; bitwise equal to sere_csr_spmv on the CSR sell was built from. */
void sere_sell_spmv( const sere_sell* a, const double* x, double* y );

/* The threads sere_sell_update and sere_sell_spmv run with (core/base.h; SERE_ERR_ARGUMENT above
 * SERE_MAX_THREADS). A solve runs with its workspace's count instead. */
sere_status sere_sell_set_threads( sere_sell* sell, int32_t threads );

typedef struct sere_cg_workspace sere_cg_workspace;

/* Scratch for systems of up to n rows, for sere_cg_solve and sere_cg_solve_sgs; nothing is
 * allocated per solve. */
sere_status sere_cg_create( int32_t n, sere_cg_workspace** out );
void sere_cg_destroy( sere_cg_workspace* workspace );

/* The threads the solves on this workspace run with (core/base.h: 0, the initial count, is
 * OpenMP's count at each solve; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_cg_set_threads( sere_cg_workspace* workspace, int32_t threads );

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

/* Multicolor symmetric Gauss–Seidel (SGS), the stronger preconditioner for stiff systems (the
 * plane tree's Voronoi layer at λ = 100, where Jacobi PCG needs about 100 iterations a frame).
 *
 * Rows are colored greedily in row order (each takes the smallest color none of its earlier
 * neighbors holds), so no two rows of one color share an entry. With rows ordered by color,
 * A = L + D + U, L holding the entries toward earlier colors, and the preconditioner is
 * M = (D + L) D⁻¹ (D + U), symmetric and positive definite for SPD A. A Gauss–Seidel sweep then
 * runs color by color, and the rows of a color all at once (in parallel, each row one
 * sequential sum): the same bits for any thread count.
 *
 * Storage: positions are grouped by color (rows sorted by length within windows of
 * SERE_SGS_SIGMA positions, so a chunk's lanes are about as long), each color padded to whole
 * chunks of SERE_SELL_C lanes (padding lanes have row −1, diagonal 1 and no entries); a chunk's L
 * and U entries are two SELL slot ranges (lane fastest, entries in CSR order, padded with 0),
 * columns named by position. One value array holds L's slots, then U's, then the diagonal per position; slot[k]
 * says where CSR entry k lives, so a caller that refills values per step writes them there
 * (or calls sere_sgs_update). */
#define SERE_SGS_MAX_COLORS 32
/* Rows are sorted by length within windows of this many positions of a color (cg_sgs.c). The
 * padding of the maple's T layout, unsorted / σ = 64 / 256 / 512: 29.5% / 9.9% / 4.2% / 2.9%; its
 * SGS-PCG (BM_PCG, 1 thread, two rounds) 147–152 / 129–131 / 127–129 / 129–131 µs, the plane
 * tree's multigrid PCG 1517–1598 / 1376 / 1333–1362 / 1333–1373 µs. */
#define SERE_SGS_SIGMA 256

typedef struct sere_sgs
{
	int32_t rows, nnz;
	int32_t colors;
	int32_t chunks;		  /* positions = chunks · SERE_SELL_C */
	int32_t* color_chunk; /* color c holds chunks [color_chunk[c], color_chunk[c+1]) */
	int32_t* color;		  /* per row, its color */
	int32_t* row;		  /* per position, its row; −1 for padding */
	int32_t* lower_ptr;	  /* per chunk, its L slots [lower_ptr[c], lower_ptr[c+1]) */
	int32_t* upper_ptr;	  /* per chunk, its U slots, offset by lower_ptr[chunks] into col and val */
	int32_t* col;		  /* per slot, the column's position */
	double* val;		  /* L slots, U slots, then the diagonal per position */
	int32_t* slot;		  /* per CSR entry, its index into val */
	int32_t threads;	  /* sere_sgs_set_threads: update and apply (0 at create, core/base.h) */
} sere_sgs;

/* Builds the coloring, layout and values of a. SERE_ERR_ARGUMENT for an empty matrix, a column
 * out of range, a row without its diagonal or with it twice, a pattern that is not symmetric
 * (two rows of one color would then share an entry), or more than SERE_SGS_MAX_COLORS colors
 * (a row with more than 31 neighbors can force that). */
sere_status sere_sgs_create( const sere_csr* a, sere_sgs** out );
void sere_sgs_destroy( sere_sgs* sgs );

/* Copies a's values (a must have the pattern sgs was built from; rows and nnz are checked). */
sere_status sere_sgs_update( sere_sgs* sgs, const sere_csr* a );

/* z = M⁻¹ r in the row numbering (a forward then a backward sweep); for tests and callers with
 * their own Krylov method. SERE_ERR_NOT_SPD for a diagonal entry that is not positive. */
sere_status sere_sgs_apply( const sere_sgs* sgs, const double* r, double* z );

/* The threads sere_sgs_update and sere_sgs_apply run with (core/base.h; SERE_ERR_ARGUMENT above
 * SERE_MAX_THREADS). sere_cg_solve_sgs runs with its workspace's count instead. */
sere_status sere_sgs_set_threads( sere_sgs* sgs, int32_t threads );

/* sere_cg_solve preconditioned with M (same arguments, tolerance and result: the relative
 * residual ||b − A x||₂ / ||b||₂, checked on the true residual before the solve returns).
 *
 * Eisenstat's (1981) form: with L̃ = D + L, CG runs on E = L̃⁻¹ A L̃⁻ᵀ (SPD, as L̃ᵀ = D + U)
 * with D as its preconditioner (u = D r̂: CG on D^½ E D^½ = C⁻¹ A C⁻ᵀ for M = C Cᵀ,
 * C = L̃ D^−½), for ŷ = L̃ᵀ x and right-hand side L̃⁻¹ b. Since A = L̃ + L̃ᵀ − D,
 * E u = t + L̃⁻¹ (u − D t) with t = L̃⁻ᵀ u: one backward and one forward sweep, which together
 * read every entry of A once, the same traffic as the Jacobi PCG's one product. The iterates are
 * those of PCG on A with M in exact arithmetic. The loop stops on the transformed residual
 * L̃⁻¹ (b − A x); the true residual is then computed, and if it is still above tolerance (their
 * ratio is bounded by the norms of L̃ and its inverse) the solve restarts from that x, with the
 * transformed target halved at each restart, for as long as a restart halves the true residual.
 * (Below the rounding floor of b − A x, near 1e-14 relative on diffusion-dominated rows, it
 * stalls: the solve then returns SERE_OK if the recursive residual met its target, as the
 * Jacobi path, which checks only that one, would, and reports the true residual.)
 *
 * SSOR with ω > 1 was measured worse on these systems (plane tree V: 289 iterations at ω = 1,
 * 332 at 1.4, 488 at 1.8), as usual for multicolor orderings, so M is plain SGS. */
sere_status sere_cg_solve_sgs( sere_cg_workspace* workspace, const sere_sgs* sgs, const double* b, double* x,
							   double tolerance, int32_t max_iterations, sere_cg_result* result );

/* ‖b − A x‖ / ‖b‖ of a guess x, A in the SGS layout's values, into *relative (the true residual
 * a solve from x would start with, the same sums at any thread count); +∞ when b = 0 and A x is
 * not. x is not changed. For a caller who wants to know whether a guess already meets a
 * tolerance before it builds a stronger preconditioner (the osmosis, before the multigrid).
 * SERE_ERR_ARGUMENT as sere_cg_solve_sgs, SERE_ERR_NONFINITE for a non-finite b or x. */
sere_status sere_cg_residual_sgs( sere_cg_workspace* workspace, const sere_sgs* sgs, const double* b, const double* x,
								  double* relative );

/* The floor of `iterations` steps of sere_cg_solve_sgs (benchmarks): each step's update pass over
 * the positions and its backward and forward sweeps over every entry, the same loads, gathers and
 * stores at the same barriers, with an add where the step multiplies, divides or multiplies and
 * adds. The solve's start, restarts and true residuals are not in it. Writes only the workspace's
 * scratch vectors, from zero: a solve after it gives the same bits. SERE_ERR_ARGUMENT as
 * sere_cg_solve_sgs. */
sere_status sere_cg_touch_sgs( sere_cg_workspace* workspace, const sere_sgs* sgs, int32_t iterations );

/* Aggregation multigrid (AMG), the strongest preconditioner here, for systems whose smooth errors
 * SGS removes slowly: a diffusion system whose mass term is small beside its couplings (the plane
 * tree's Voronoi layer: Σ_j |a_ij| / a_ii = 0.9999, where SGS-PCG needs 50–150 iterations a
 * frame) is nearly singular on its smoothest vectors, which no sweep moves far.
 *
 * Levels: rows are grouped into aggregates (each row of a fresh group with its neighbors, in row
 * order; leftover rows join their first grouped neighbor), and level l + 1 has one row per
 * aggregate of level l with A_{l+1} = Pᵀ A_l P, P the aggregates' indicator (piecewise constant:
 * an entry of A_{l+1} is the sum of the entries of A_l between two aggregates, so refreshing the
 * values is one summation pass). Coarsening goes on while it shrinks a level to at most 4/5 of
 * its rows; a coarsest level of at most SERE_AMG_DENSE_ROWS rows is factored (Cholesky) and solved
 * exactly. Aggregates follow the pattern only, so they stay valid while the values change.
 *
 * One application is a V-cycle: a forward multicolor Gauss–Seidel sweep from zero, the residual
 * restricted to the next level, its correction scaled by SERE_AMG_OVERCORRECT, a backward sweep.
 * The backward sweep is the forward one's adjoint, so the preconditioner is symmetric; it is
 * positive definite for any positive scaling when the sweeps converge (an A-norm argument: the
 * coarse step never amplifies error, a strictly diagonally dominant or SPD level's sweeps
 * contract), so CG applies. The scaling: unsmoothed aggregates' corrections come out too small,
 * and 1.8 took the plane tree's V system at frame 100 from 18 to 13 iterations from its warm
 * start, 38 to 25 from zero (Braess 1995 uses the same remedy). Every level's sweeps run over the SGS layout (sere_sgs)
 * and every sum in a fixed order: the same bits for any thread count.
 *
 * The finest level's layout and values are the caller's sgs (built from the same a), kept current
 * by the caller; sere_amg_update has the coarse levels follow them. One solve at a time per
 * sere_amg (it holds the coarse levels' vectors). */
#define SERE_AMG_DENSE_ROWS	 64
#define SERE_AMG_OVERCORRECT 1.8
#define SERE_AMG_MAX_LEVELS	 16

typedef struct sere_amg sere_amg;

/* Builds the levels over fine, which must have been built from a (rows and nnz are checked).
 * SERE_ERR_ARGUMENT for a NULL or mismatched argument or an invalid a. */
sere_status sere_amg_create( const sere_csr* a, const sere_sgs* fine, sere_amg** out );
void sere_amg_destroy( sere_amg* amg );

/* Says the coarse levels should follow the fine sgs's values: the next V-cycle (of a solve that
 * needs one, or of sere_amg_apply) recomputes them. Between updates they keep their values while
 * the finest level follows the sgs's current ones (its D⁻¹ is taken at every solve): B stays
 * symmetric positive definite with coarse levels that lag (the argument above holds for any SPD
 * coarse matrices), only weaker as the values drift, so a caller whose matrix drifts slowly may
 * update every few steps (the osmosis does). A V-cycle's call returns SERE_ERR_NOT_SPD for a
 * level with a diagonal entry that is not positive or a coarsest matrix that is not positive
 * definite; the solves and sere_amg_apply return SERE_ERR_ARGUMENT before the first update. */
sere_status sere_amg_update( sere_amg* amg );

/* z = B r (one V-cycle) in the row numbering, for tests and callers with their own Krylov method. */
sere_status sere_amg_apply( sere_amg* amg, const double* r, double* z );

/* Levels (the finest counts), and the rows of level l (0 for l out of range or a NULL amg). */
int32_t sere_amg_levels( const sere_amg* amg );
int32_t sere_amg_rows( const sere_amg* amg, int32_t level );

/* The threads sere_amg_update and sere_amg_apply run with (core/base.h; SERE_ERR_ARGUMENT above
 * SERE_MAX_THREADS). sere_cg_solve_amg runs with its workspace's count instead. */
sere_status sere_amg_set_threads( sere_amg* amg, int32_t threads );

/* The floor of `iterations` steps of sere_cg_solve_amg (benchmarks): the same passes over the
 * same arrays of every level, at the same barriers, with an add where the solve multiplies,
 * divides or multiplies and adds (the dense coarsest solve reads its factor twice). Writes only
 * the workspace's and the levels' scratch vectors, from zero: a solve after it gives the same
 * bits. SERE_ERR_ARGUMENT as sere_cg_solve_amg, or before the first sere_amg_update. */
sere_status sere_cg_touch_amg( sere_cg_workspace* workspace, sere_amg* amg, int32_t iterations );

/* sere_cg_solve preconditioned with one V-cycle of amg (as updated last) per iteration: the same
 * arguments, statuses and result (the reported residual is the true one, computed at the end). */
sere_status sere_cg_solve_amg( sere_cg_workspace* workspace, sere_amg* amg, const double* b, double* x,
							   double tolerance, int32_t max_iterations, sere_cg_result* result );

#ifdef __cplusplus
}
#endif
