/* sere — private to cg.c and cg_sgs.c, not installed and not part of the API: the lane layout of
 * the SELL-C-σ matrices, the workspace, and the step and block-sum helpers both conjugate gradient
 * solvers share. */
#pragma once

#include "core/internal/team.h"
#include "solve/cg.h"

#include <math.h>
#include <omp.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

enum
{
	LANES = SERE_SELL_C,
	CHUNKS_PER_BLOCK = SERE_CG_BLOCK / SERE_SELL_C
};

/* The CG step length α = γ / pᵀAp, or why there is none: a non-finite γ or pᵀAp
 * (SERE_ERR_NONFINITE), or pᵀAp ≤ 0, a matrix that is not SPD (SERE_ERR_NOT_SPD). */
static inline sere_status cg_step_length( double pap, double gamma, double* alpha )
{
	if ( !isfinite( pap ) || !isfinite( gamma ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( !( pap > 0.0 ) )
	{
		return SERE_ERR_NOT_SPD;
	}
	*alpha = gamma / pap;
	return SERE_OK;
}

/* A row and its length (entries, or a key standing for them) for the layouts' sorting windows
 * (SELL-C-σ in cg.c, the SGS colors in cg_sgs.c), ordered by by_length. */
typedef struct row_length
{
	int32_t row, length;
} row_length;

/* Longest first; ties keep row order, so the order is total and rows stay near their neighbours. */
static inline int by_length( const void* left, const void* right )
{
	const row_length *l = left, *r = right;
	if ( l->length != r->length )
	{
		return l->length > r->length ? -1 : 1;
	}
	return l->row < r->row ? -1 : l->row > r->row;
}

/* Row pointers that never decrease and column indices inside the matrix (the caller has checked
 * row_ptr[0] = 0 and row_ptr[rows] = nnz). */
static inline int csr_indices_valid( const sere_csr* a )
{
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		if ( a->row_ptr[i + 1] < a->row_ptr[i] )
		{
			return 0;
		}
	}
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		if ( a->col[k] < 0 || a->col[k] >= a->rows )
		{
			return 0;
		}
	}
	return 1;
}

/* A chunk's sums live in two 4-lane vectors (a vector type, not a double[8]: gcc keeps an
 * array in memory, and every step of the sums then waits on a store and a reload; 4 lanes, one
 * AVX2 register, because gcc lowers wider vector types through memory where they are not
 * native). Values pass through pointers so that no vector crosses a call ABI. */
typedef double half_t __attribute__( ( vector_size( 4 * sizeof( double ) ) ) );
_Static_assert( SERE_SELL_C == 8, "a chunk is two 4-lane vectors" );

typedef struct lanes_t
{
	half_t lo, hi;
} lanes_t;

/* A chunk's 8 lanes of a position-indexed vector (sere_alloc aligns to SERE_ALIGN, chunks start
 * at multiples of 8 doubles): direct vector loads and stores, no copy through the stack. */
static inline lanes_t load_lanes( const double* v )
{
	return ( lanes_t ){ *(const half_t*) v, *(const half_t*) ( v + 4 ) };
}

static inline void store_lanes( double* v, const lanes_t* in )
{
	*(half_t*) v = in->lo;
	*(half_t*) ( v + 4 ) = in->hi;
}

static inline void gather( half_t* out, const double* x, const int32_t* col )
{
	*out = ( half_t ){ x[col[0]], x[col[1]], x[col[2]], x[col[3]] };
}

/* Vectors of the solve, indexed by position (see sere_sell): x and b as permuted in. */
struct sere_cg_workspace
{
	int32_t threads; /* sere_cg_set_threads */
	int32_t capacity;
	int32_t positions; /* vector length: n rounded to chunks, plus a chunk of padding per SGS color */
	int32_t block_capacity;
	double *x, *b, *r, *u, *w, *p, *s, *inv_diag, *t, *z;
	double* partial;			/* 4 sums per block: rᵀr, uᵀw, rᵀu, bᵀb */
	double* chunk_delta;		/* SGS: per chunk, its share of uᵀw */
	sere_spin_barrier* barrier; /* the steps' barrier (team.h) */
};

/* The solution back from layout positions to rows: x_out[row[at]] = x[at] for every position
 * holding a row (row[at] >= 0), at every position of the np. */
static inline void positions_to_rows( const int32_t* row, int32_t np, const double* x, double* x_out, int32_t threads )
{
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t at = 0; at < np; ++at )
	{
		if ( row[at] >= 0 )
		{
			x_out[row[at]] = x[at];
		}
	}
}

/* The blocks a thread of a team takes in a pass over a layout's vectors: those whose first chunk
 * lies in the thread's share of some color, the chunks its own sweeps take (lo[k] to hi[k] for
 * color k). A pass over the vectors then meets, in its own cache, the values the same thread's
 * sweeps wrote: with the blocks split in halves instead, about half of every vector a step
 * writes crossed between the cores every step, and two threads were slower than one on the
 * leaves' systems (docs/PERFORMANCE.md). Which thread sums a block never changes its bits. */
typedef struct owned_blocks
{
	int32_t colors;
	int32_t lo[SERE_SGS_MAX_COLORS], hi[SERE_SGS_MAX_COLORS];
} owned_blocks;

static inline owned_blocks blocks_of_thread( const sere_sgs* g, int tid, int team )
{
	owned_blocks own;
	own.colors = g->colors;
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		int32_t first, last;
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], tid, team, &first, &last );
		own.lo[c] = ( first + CHUNKS_PER_BLOCK - 1 ) / CHUNKS_PER_BLOCK;
		own.hi[c] = ( last + CHUNKS_PER_BLOCK - 1 ) / CHUNKS_PER_BLOCK;
	}
	return own;
}

/* The first of own's blocks after blk (blk = −1: its first), or −1 past its last. The ranges
 * ascend, so this is the walk in block order; a step looks at no more than the colors. */
static inline int32_t owned_block_next( const owned_blocks* own, int32_t blk )
{
	for ( int32_t c = 0; c < own->colors; ++c )
	{
		if ( own->lo[c] < own->hi[c] && own->hi[c] > blk + 1 )
		{
			return own->lo[c] > blk + 1 ? own->lo[c] : blk + 1;
		}
	}
	return -1;
}

static inline int32_t block_end( int32_t blk, int32_t n )
{
	return ( blk + 1 ) * SERE_CG_BLOCK < n ? ( blk + 1 ) * SERE_CG_BLOCK : n;
}

/* Row i's entries of b_in and x_in into position at, zeros for a padding lane (i < 0); nonzero
 * when either is not finite. */
static inline int load_position( int32_t i, const double* b_in, const double* x_in, double* b, double* x, int32_t at )
{
	b[at] = i >= 0 ? b_in[i] : 0.0;
	x[at] = i >= 0 ? x_in[i] : 0.0;
	return !isfinite( b[at] ) || !isfinite( x[at] );
}

/* A solve's state between its parallel regions: every thread of a region holds the same values
 * (they take the same decisions from the same block sums), and the master publishes them at the
 * region's end. */
typedef struct cg_state
{
	int32_t it;
	double alpha_prev, gamma_prev, rel, b_norm;
	double delta; /* the SGS solve's uᵀw for the next step (sgs_product_sums) */
	int status, done, met, bad_diagonal, nonfinite;
} cg_state;

/* The SGS layout's chunk kernels (sere_sgs, cg.h), for its CG (cg_sgs.c) and the multigrid
 * levels that smooth with it (cg_amg.c). */

/* Sum over a chunk's slots [begin, end) of val · x[col], lane by lane in slot order; with touch
 * (the multigrid's floor, amg_shared.h), val + x[col]: the same loads and gathers, an add where it
 * multiplies. Inlined with a constant flag, so neither pays for the other. */
static inline void chunk_pass( const int32_t* col, const double* val, int32_t begin, int32_t end, const double* x,
							   bool touch, lanes_t* out )
{
	half_t lo = { 0.0 }, hi = { 0.0 }, xlo, xhi;
	for ( int32_t s = begin; s < end; s += LANES )
	{
		gather( &xlo, x, col + s );
		gather( &xhi, x, col + s + 4 );
		half_t vlo = *(const half_t*) ( val + s ), vhi = *(const half_t*) ( val + s + 4 );
		lo += touch ? vlo + xlo : vlo * xlo;
		hi += touch ? vhi + xhi : vhi * xhi;
	}
	out->lo = lo;
	out->hi = hi;
}

static inline void chunk_sum( const int32_t* col, const double* val, int32_t begin, int32_t end, const double* x,
							  lanes_t* out )
{
	chunk_pass( col, val, begin, end, x, false, out );
}

/* Chunk ch of a sweep: out = (in − Σ a_ij out_j) / d over the chunk's slots [ptr[ch],
 * ptr[ch + 1]) (L's for the forward sweep, U's for the backward one), and the sums to sum_out
 * when it is not NULL. */
static inline void sweep_chunk( const sere_sgs* g, const int32_t* ptr, int32_t ch, const double* inv_diag,
								const double* in, double* out, double* sum_out )
{
	lanes_t sum, v = load_lanes( in + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	chunk_sum( g->col, g->val, ptr[ch], ptr[ch + 1], out, &sum );
	v.lo = ( v.lo - sum.lo ) * inv.lo;
	v.hi = ( v.hi - sum.hi ) * inv.hi;
	store_lanes( out + ch * LANES, &v );
	if ( sum_out != NULL )
	{
		store_lanes( sum_out + ch * LANES, &sum );
	}
}

/* y = A v for chunk ch: (L v + U v) + D v. U v comes from upper, the sums a backward sweep left
 * over the same v (sweep_chunk's sum_out: the same slots in the same order, so the same bits),
 * when it is not NULL. */
static inline void sgs_chunk_product( const sere_sgs* g, int32_t ch, const double* v, const double* upper, double* y )
{
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	lanes_t lo, up, d = load_lanes( diagonal + ch * LANES ), x = load_lanes( v + ch * LANES );
	chunk_sum( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], v, &lo );
	if ( upper != NULL )
	{
		up = load_lanes( upper + ch * LANES );
	}
	else
	{
		chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], v, &up );
	}
	lo.lo = ( lo.lo + up.lo ) + d.lo * x.lo;
	lo.hi = ( lo.hi + up.hi ) + d.hi * x.hi;
	store_lanes( y + ch * LANES, &lo );
}

/* Σ u_i v_i over [begin, end) (whole chunks) in 8 lanes, then the lanes in a fixed order: a
 * single chain of 10⁴ dependent adds would take longer than a multigrid V-cycle's sweeps, and the
 * lanes keep the sum the same on every SIMD width. */
static inline double dot_lanes( const double* u, const double* v, int32_t begin, int32_t end )
{
	half_t lo = { 0.0 }, hi = { 0.0 };
	for ( int32_t i = begin; i < end; i += LANES )
	{
		lo += *(const half_t*) ( u + i ) * *(const half_t*) ( v + i );
		hi += *(const half_t*) ( u + i + 4 ) * *(const half_t*) ( v + i + 4 );
	}
	return ( ( lo[0] + lo[1] ) + ( lo[2] + lo[3] ) ) + ( ( hi[0] + hi[1] ) + ( hi[2] + hi[3] ) );
}

/* r = b − A x over the blocks [first, last) of an SGS layout and their sums of rᵀr (slot 0).
 * x NULL stands for x = +0 in every position, whose product is +0 exactly (the diagonal is
 * positive), so r = b with the bits the product would give; a non-finite entry, which would have
 * made r NaN here, makes the first sweep's sums NaN instead, and the solve ends on
 * SERE_ERR_NONFINITE all the same. upper, when not NULL, holds U x (sgs_chunk_product). */
static inline void sgs_residual_blocks( const sere_sgs* g, int32_t first, int32_t last, int32_t np, const double* b,
										const double* x, const double* upper, double* r, double* partial )
{
	for ( int32_t blk = first; blk < last; ++blk )
	{
		int32_t chunk_end = ( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
		for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end && x != NULL; ++ch )
		{
			sgs_chunk_product( g, ch, x, upper, r );
		}
		for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
		{
			r[i] = x != NULL ? b[i] - r[i] : b[i];
		}
		partial[4 * blk] = dot_lanes( r, r, blk * SERE_CG_BLOCK, block_end( blk, np ) );
	}
}

/* The end of a step of the preconditioned solves (cg_sgs.c, cg_amg.c): counts it and, from the
 * recursive residual's rᵀr, stops the solve when that is not finite, meets target (‖r‖ ≤ target)
 * or the step is the cap's. Every thread decides the same from the same block sums. */
static inline bool cg_step_done( cg_state* my, double rr, double target, int32_t max_iterations )
{
	my->it += 1;
	if ( !isfinite( rr ) )
	{
		my->status = SERE_ERR_NONFINITE;
		my->done = 1;
		return true;
	}
	if ( sqrt( rr ) <= target || my->it == max_iterations )
	{
		my->met = sqrt( rr ) <= target;
		my->done = 1;
		return true;
	}
	return false;
}
