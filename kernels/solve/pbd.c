/* _GNU_SOURCE: sched_getaffinity and nanosleep for core/internal/team.h. */
#define _GNU_SOURCE

#include "core/internal/simd.h"
#include "solve/internal/pbd_shared.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* For the block functions: each pass mode gets its own copy of the block loop (project_colors),
 * and GCC's size limits would otherwise leave the block an out-of-line call with its operands
 * in memory. */
#define FORCE_INLINE static inline __attribute__( ( always_inline ) )

/* What one pass over a constraint block does. */
typedef enum block_mode
{
	MODE_GAUSS_SEIDEL, /* project and write both ends */
	MODE_JACOBI,	   /* measure and store the correction per constraint */
	MODE_MEASURE,	   /* measure only */
	MODE_TOUCH,		   /* load and store both ends unchanged (the memory floor) */
} block_mode;

/* What a pass claims items from: a sweep's work lists (bands, then the cuts between them) or
 * every item (the read-only and Jacobi passes). */
typedef enum pass_kind
{
	PASS_SWEEP,
	PASS_ALL,
} pass_kind;

enum
{
	FLAG_ZERO_LENGTH = 1,
	FLAG_NONFINITE = 2,
	FLAG_NEGATIVE_MASS = 4,
};

sere_pbd_params sere_pbd_params_default( void )
{
	sere_pbd_params params = {
		.stiffness = 1.0f,
		.tolerance = 1e-3f,
		.max_iterations = 200,
		.compliance = 0.0f,
		.dt = 0.002f,
		.relaxation = 1.5f,
		.linear_stiffness = 0,
		.warm = 0,
		.chebyshev_rho = 0.0f,
		.chebyshev_delay = 10,
		.stall = 0.0f,
		.ground = -INFINITY,
		.ground_slack = 0.0f,
	};
	return params;
}

void sere_pbd_destroy( sere_pbd* pbd )
{
	if ( pbd == NULL )
	{
		return;
	}
	sere_coloring_destroy( &pbd->coloring );
	sere_free( pbd->segment );
	sere_free( pbd->ia );
	sere_free( pbd->ib );
	sere_free( pbd->source );
	sere_free( pbd->rest );
	sere_free( pbd->lambda );
	sere_free( pbd->weight );
	sere_free( pbd->factor );
	sere_free( pbd->slot );
	sere_free( pbd->particle );
	sere_free( pbd->band_start );
	sere_free( pbd->packed[0] );
	sere_free( pbd->packed[1] );
	sere_free( pbd->push );
	sere_free( pbd->residual_partial );
	sere_free( pbd->history[0] );
	sere_free( pbd->history[1] );
	sere_free( pbd->lambda_history[0] );
	sere_free( pbd->lambda_history[1] );
	sere_free( pbd->adjacency_offset );
	sere_free( pbd->adjacency );
	sere_free( pbd->inv_degree );
	sere_free( pbd->threads );
	sere_free( pbd->counters );
	sere_free( pbd->done );
	sere_free( pbd->barrier );
	sere_free( pbd );
}

const sere_coloring* sere_pbd_coloring( const sere_pbd* pbd )
{
	return &pbd->coloring;
}

sere_pbd_info sere_pbd_get_info( const sere_pbd* pbd )
{
	sere_pbd_info info = {
		.colors = pbd->coloring.color_count,
		.min_batch = pbd->coloring.min_batch,
		.max_batch = pbd->coloring.max_batch,
		.bands = pbd->bands,
		.interface_constraints = pbd->interface_count,
		.lanes = pbd->lanes,
	};
	return info;
}

/* ---------------------------------------------------------------------------------------
 * The constraint block: 16 constraints of one color, no particle twice.
 *
 * Per lane, in this order (the scalar build does the same operations, so both round alike):
 *   d = p_b − p_a, len = √((dx² + dy²) + dz²), C = len − l                    (Jeong Eq. 13)
 *   residual r = C (PBD) or C + α̃λ (XPBD); strain |r|/l
 *   PBD:  f = (k C)/((w_a + w_b) len), 0 when w_a + w_b = 0
 *   XPBD: Δλ = −r/(w_a + w_b + α̃), λ += Δλ, f = r/((w_a + w_b + α̃) len) (= −Δλ/len), both 0
 *         when w_a + w_b + α̃ is not positive
 *   p_a += (w_a f) d, p_b −= (w_b f) d       (Jacobi: store f instead) */

typedef struct block_context
{
	float* packed;
	const int32_t* ia;
	const int32_t* ib;
	const float* rest;
	float* lambda;
	const float* weight;
	float* factor;
	float k, alpha, one;
} block_context;

/* The worst residual and the flags of the lanes a pass has measured. */
typedef struct lane_accum
{
	sere_vf worst;
	sere_vmask zero, nonfinite;
} lane_accum;

FORCE_INLINE lane_accum lane_accum_start( void )
{
	lane_accum acc = { sere_vf_splat( 0.0f ), sere_vmask_none(), sere_vmask_none() };
	return acc;
}

FORCE_INLINE void lane_accum_finish( const lane_accum* acc, float* worst, int32_t* flags )
{
	float w = sere_vf_max_all( acc->worst );
	*worst = w > *worst ? w : *worst;
	*flags |= ( sere_vmask_any( acc->zero ) ? FLAG_ZERO_LENGTH : 0 ) |
			  ( sere_vmask_any( acc->nonfinite ) ? FLAG_NONFINITE : 0 );
}

/* What the measuring part of a block leaves for the moving part: both ends and the factor f. */
typedef struct part_state
{
	sere_vf ax, ay, az, aw, bx, by, bz, bw, f;
} part_state;

/* Loads both ends of the SERE_LANES constraints at q, each (x, y, z, w) record with one 128-bit
 * load and a transpose in registers (simd.h), and measures them (Jeong Eq. 13): the residual into
 * acc and, unless mode is MODE_MEASURE, the factor f (XPBD: and the multiplier λ; Jacobi: f stored
 * per lane). A lane whose denominator is not positive gets f = 0, its quotient (0/0 or x/0) kept
 * out by the mask. */
FORCE_INLINE part_state measure_part( const block_context* ctx, int32_t q, block_mode mode, int xpbd, lane_accum* acc )
{
	part_state h;
	sere_vf_load_records_at( ctx->packed, ctx->ia + q, &h.ax, &h.ay, &h.az, &h.aw );
	sere_vf_load_records_at( ctx->packed, ctx->ib + q, &h.bx, &h.by, &h.bz, &h.bw );
	const sere_vf zero = sere_vf_splat( 0.0f );
	const sere_vf dx = sere_vf_sub( h.bx, h.ax ), dy = sere_vf_sub( h.by, h.ay ), dz = sere_vf_sub( h.bz, h.az );
	sere_vf len = sere_vf_sqrt( sere_vf_fma( dz, dz, sere_vf_fma( dy, dy, sere_vf_mul( dx, dx ) ) ) );
	sere_vf rest = sere_vf_load( ctx->rest + q );
	sere_vf c = sere_vf_sub( len, rest ); /* Jeong Eq. 13 */
	acc->zero = sere_vmask_or( acc->zero, sere_vf_eq( len, zero ) );
	acc->nonfinite = sere_vmask_or( acc->nonfinite, sere_vf_not_le( len, sere_vf_splat( FLT_MAX ) ) );
	sere_vf wsum = sere_vf_add( h.aw, h.bw );
	sere_vf lambda = zero, alpha = zero, residual = c;
	if ( xpbd )
	{
		alpha = sere_vf_mul( sere_vf_splat( ctx->alpha ), sere_vf_load( ctx->weight + q ) );
		lambda = sere_vf_load( ctx->lambda + q );
		residual = sere_vf_fma( alpha, lambda, c );
	}
	acc->worst = sere_vf_max( acc->worst, sere_vf_div( sere_vf_abs( residual ), rest ) );
	h.f = zero;
	if ( mode == MODE_MEASURE )
	{
		return h;
	}
	if ( xpbd )
	{
		sere_vf denominator = sere_vf_add( wsum, alpha );
		sere_vmask positive = sere_vf_gt( denominator, zero );
		/* Δλ = −r/(w_a + w_b + α̃), subtracted as r/(…): one operation fewer than adding −r/(…) */
		sere_vf_store( ctx->lambda + q,
					   sere_vf_sub( lambda, sere_vf_keep( positive, sere_vf_div( residual, denominator ) ) ) );
		/* f = −Δλ/len as one quotient, r/((w_a + w_b + α̃) len): its own division, beside Δλ's
		 * rather than after it, so the moves wait for one division instead of two (BM_XPBDColored
		 * at one thread: 5% less time a sweep). */
		h.f = sere_vf_keep( positive, sere_vf_div( residual, sere_vf_mul( denominator, len ) ) );
	}
	else
	{
		h.f = sere_vf_keep( sere_vf_gt( wsum, zero ),
							sere_vf_div( sere_vf_mul( sere_vf_splat( ctx->k ), c ), sere_vf_mul( wsum, len ) ) );
	}
	if ( mode == MODE_JACOBI )
	{
		sere_vf_store( ctx->factor + q, h.f );
	}
	return h;
}

/* The moving part: p_a += (w_a f) d, p_b −= (w_b f) d (Jeong Eq. 13), each coordinate one fused
 * multiply-add (one rounding at every width), stored. d = p_b − p_a again, the same operation on
 * the same values as in measure_part, so the same bits; recomputing it keeps three registers fewer
 * alive between the two parts. */
FORCE_INLINE void move_part( const block_context* ctx, int32_t q, const part_state* h )
{
	sere_vf dx = sere_vf_sub( h->bx, h->ax ), dy = sere_vf_sub( h->by, h->ay ), dz = sere_vf_sub( h->bz, h->az );
	sere_vf fa = sere_vf_mul( h->aw, h->f ), fb = sere_vf_mul( h->bw, h->f );
	sere_vf_store_records_at( ctx->packed, ctx->ia + q, sere_vf_fma( fa, dx, h->ax ), sere_vf_fma( fa, dy, h->ay ),
							  sere_vf_fma( fa, dz, h->az ), h->aw );
	sere_vf_store_records_at( ctx->packed, ctx->ib + q, sere_vf_fnma( fb, dx, h->bx ), sere_vf_fnma( fb, dy, h->by ),
							  sere_vf_fnma( fb, dz, h->bz ), h->bw );
}

/* Loads and stores both ends unchanged: times one, opaque to the compiler, so the stores stay.
 * XPBD's floor also loads each constraint's compliance weight and multiplier and stores the
 * multiplier back (λ·1 + w·(1 − 1): the weight's load stays too), the 12 bytes a constraint an
 * XPBD sweep moves beyond PBD's. */
FORCE_INLINE void touch_part( const block_context* ctx, int32_t q, int xpbd )
{
	sere_vf ax, ay, az, aw, bx, by, bz, bw;
	sere_vf_load_records_at( ctx->packed, ctx->ia + q, &ax, &ay, &az, &aw );
	sere_vf_load_records_at( ctx->packed, ctx->ib + q, &bx, &by, &bz, &bw );
	const sere_vf one = sere_vf_splat( ctx->one );
	if ( xpbd )
	{
		sere_vf lambda = sere_vf_load( ctx->lambda + q ), weight = sere_vf_load( ctx->weight + q );
		sere_vf_store( ctx->lambda + q,
					   sere_vf_add( sere_vf_mul( lambda, one ), sere_vf_mul( weight, sere_vf_sub( one, one ) ) ) );
	}
	sere_vf_store_records_at( ctx->packed, ctx->ia + q, sere_vf_mul( ax, one ), sere_vf_mul( ay, one ),
							  sere_vf_mul( az, one ), aw );
	sere_vf_store_records_at( ctx->packed, ctx->ib + q, sere_vf_mul( bx, one ), sere_vf_mul( by, one ),
							  sere_vf_mul( bz, one ), bw );
}

/* Lanes [first, last) of one color of one item, a multiple of LANES, in parts of SERE_LANES.
 *
 * Gauss–Seidel is software-pipelined by one part: the next part is measured before this one
 * moves. Measuring (loads, transposes, √, two divisions) is a dependency chain of some 60 cycles
 * and a part's moves wait at its end; issued in program order they filled the out-of-order
 * window (llvm-mca's Zen 3 model: the 64-entry floating-point scheduler full most of the time),
 * so a core worked on about one part at a time. Measured one part ahead, a part's moves find f
 * ready. On the maple at one thread this took an AVX2 sweep from 2.2 to 1.8 times its floor
 * (sere_pbd_touch_sweeps) and an AVX-512 sweep from 1.6 to 1.3 (CPU time). All lanes of one
 * color share no particle, so reading the next part before this one is stored reads the same
 * values, and every width (16, 8 or 4 lanes a part) gives the same bits. */
FORCE_INLINE void project_segment( const block_context* ctx, int32_t first, int32_t last, block_mode mode, int xpbd,
								   lane_accum* acc )
{
	if ( mode != MODE_GAUSS_SEIDEL )
	{
		for ( int32_t q = first; q < last; q += SERE_LANES )
		{
			if ( mode == MODE_TOUCH )
			{
				touch_part( ctx, q, xpbd );
			}
			else
			{
				measure_part( ctx, q, mode, xpbd, acc );
			}
		}
		return;
	}
	if ( first == last )
	{
		return;
	}
	part_state current = measure_part( ctx, first, mode, xpbd, acc );
	for ( int32_t q = first; q + SERE_LANES < last; q += SERE_LANES )
	{
		part_state next = measure_part( ctx, q + SERE_LANES, mode, xpbd, acc );
		move_part( ctx, q, &current );
		current = next;
	}
	move_part( ctx, last - SERE_LANES, &current );
}

/* ---------------------------------------------------------------------------------------
 * Threads: work claiming and the barrier. */

/* Waits until item `item` has been projected in sweep `number` of this call. */
static void wait_done( sere_pbd* pbd, int32_t item, int32_t number )
{
	sere_wait wait = SERE_WAIT_START;
	while ( atomic_load_explicit( &pbd->done[item].value, memory_order_acquire ) < number )
	{
		sere_wait_step( &wait );
	}
}

/* Publishes this thread's result of a pass, waits for all, and returns the combined result
 * (the same on every thread, so all take the same branch next). Max is exact in any order. */
static void exchange( sere_pbd* pbd, int t, int threads, int* parity, float* worst, int32_t* flags )
{
	pbd->threads[t].worst[*parity] = *worst;
	pbd->threads[t].flags[*parity] = *flags;
	sere_spin_barrier_wait( pbd->barrier, threads );
	float all_worst = 0.0f;
	int32_t all_flags = 0;
	for ( int u = 0; u < threads; ++u )
	{
		float w = pbd->threads[u].worst[*parity];
		all_worst = w > all_worst ? w : all_worst;
		all_flags |= pbd->threads[u].flags[*parity];
	}
	*parity ^= 1;
	*worst = all_worst;
	*flags = all_flags;
}

/* Thread u's work list in a pass. In a sweep: its share of the bands [r0, r1), then the cuts
 * c ∈ [r0, min(r1, R − 1)) below them (cut c joins bands c and c + 1), the even ones before
 * the odd ones. In any other pass: its share of all items. Either way it starts with what it
 * packed, so the records are in its own cache. */
typedef struct work_list
{
	int32_t first, count;		 /* bands (a sweep) or items (any other pass) */
	int32_t cut_first, cut_last; /* a sweep's cuts */
	int32_t length;
} work_list;

static work_list work_of( const sere_pbd* pbd, pass_kind kind, int u, int threads )
{
	work_list w = { 0, 0, 0, 0, 0 };
	const int32_t n = kind == PASS_SWEEP ? pbd->bands : pbd->items;
	w.first = (int32_t) ( (int64_t) n * u / threads );
	w.count = (int32_t) ( (int64_t) n * ( u + 1 ) / threads ) - w.first;
	w.length = w.count;
	if ( kind == PASS_SWEEP && w.count > 0 )
	{
		const int32_t end = w.first + w.count;
		w.cut_first = w.first;
		w.cut_last = end < pbd->bands - 1 ? end : pbd->bands - 1;
		w.length += w.cut_last - w.cut_first;
	}
	return w;
}

/* The j-th item of a list. */
static int32_t work_item( const sere_pbd* pbd, const work_list* w, int32_t j )
{
	if ( j < w->count )
	{
		return w->first + j;
	}
	j -= w->count;
	const int32_t first_even = ( w->cut_first + 1 ) & ~1;
	const int32_t evens = ( w->cut_last - first_even + 1 ) / 2;
	const int32_t cut = j < evens ? first_even + 2 * j : ( w->cut_first | 1 ) + 2 * ( j - evens );
	return pbd->bands + cut;
}

/* Before cut c of sweep `number`, what it reads must be final: bands c and c + 1 and, for an
 * odd c, the even cuts c − 1 and c + 1 that share its bands. Together with the exchange that
 * ends each sweep this keeps the order of one thread (bands, even cuts, odd cuts) for every
 * pair of items that share a particle, so the result does not depend on the threads, while
 * a sweep has one barrier instead of one per group. */
static void wait_cut_inputs( sere_pbd* pbd, int32_t cut, int32_t number )
{
	const int32_t bands = pbd->bands;
	wait_done( pbd, cut, number );
	wait_done( pbd, cut + 1, number );
	if ( cut & 1 )
	{
		wait_done( pbd, bands + cut - 1, number );
		if ( cut + 1 < bands - 1 )
		{
			wait_done( pbd, bands + cut + 1, number );
		}
	}
}

/* One item, color after color (all lanes of one block have one color), with its own copy of
 * the loop for each mode: with mode and xpbd constant the branches leave the loop and the
 * accumulator stays in registers. The context is copied too: stores through its float pointers
 * could otherwise alias it, and every block reloaded its pointers. */
FORCE_INLINE void project_colors( const block_context* ctx, const int32_t* segment, int32_t colors, block_mode mode,
								  int xpbd, lane_accum* acc )
{
	const block_context local_ctx = *ctx;
	lane_accum local = *acc;
	for ( int32_t c = 0; c < colors; ++c )
	{
		project_segment( &local_ctx, segment[c], segment[c + 1], mode, xpbd, &local );
	}
	*acc = local;
}

/* segment: the item's colors + 1 lane offsets. */
static void project_item( const block_context* ctx, const int32_t* segment, int32_t colors, block_mode mode, int xpbd,
						  lane_accum* acc )
{
	switch ( mode )
	{
		case MODE_GAUSS_SEIDEL:
			xpbd ? project_colors( ctx, segment, colors, MODE_GAUSS_SEIDEL, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_GAUSS_SEIDEL, 0, acc );
			break;
		case MODE_JACOBI:
			xpbd ? project_colors( ctx, segment, colors, MODE_JACOBI, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_JACOBI, 0, acc );
			break;
		case MODE_MEASURE:
			xpbd ? project_colors( ctx, segment, colors, MODE_MEASURE, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_MEASURE, 0, acc );
			break;
		case MODE_TOUCH:
			xpbd ? project_colors( ctx, segment, colors, MODE_TOUCH, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_TOUCH, 0, acc );
			break;
	}
}

/* Thread t takes the items of its own list in order, then helps the other threads with
 * theirs, so a thread on a slower core does less. Which thread projects an item never changes
 * the result (wait_cut_inputs). A thread that waits on a cut holds only an odd cut or an even
 * one waiting on bands, and owners take their lists in order (bands, even, odd), so some
 * thread can always go on. `number` is the sweep of this call (a PASS_SWEEP). */
static void run_pass( sere_pbd* pbd, const block_context* ctx, pass_kind kind, int parity, int32_t number,
					  block_mode mode, int xpbd, int t, int threads, float* worst, int32_t* flags )
{
	/* The other parity's counters are idle until the exchange that ends this pass. */
	atomic_store_explicit( &pbd->counters[( 1 - parity ) * MAX_THREADS + t].value, 0, memory_order_relaxed );
	const int32_t colors = pbd->colors;
	lane_accum acc = lane_accum_start();
	for ( int v = 0; v < threads; ++v )
	{
		const int u = ( t + v ) % threads;
		const work_list w = work_of( pbd, kind, u, threads );
		atomic_int* next = &pbd->counters[parity * MAX_THREADS + u].value;
		for ( ;; )
		{
			int32_t j = atomic_fetch_add_explicit( next, 1, memory_order_relaxed );
			if ( j >= w.length )
			{
				break;
			}
			const int32_t item = kind == PASS_SWEEP ? work_item( pbd, &w, j ) : w.first + j;
			if ( kind == PASS_SWEEP && item >= pbd->bands )
			{
				wait_cut_inputs( pbd, item - pbd->bands, number );
			}
			project_item( ctx, pbd->segment + item * colors, colors, mode, xpbd, &acc );
			if ( kind == PASS_SWEEP )
			{
				atomic_store_explicit( &pbd->done[item].value, number, memory_order_release );
			}
		}
	}
	lane_accum_finish( &acc, worst, flags );
}

/* Caller's arrays into records. Thread t writes the records of the bands it starts the
 * band phase with, in slot order: whole cache lines that no other thread writes (written in
 * the caller's order, the two threads' records shared lines, and at 2 threads the false
 * sharing cost more than the rest of a call), and that this thread then reads first. Every
 * value is checked once, on the records just written. */
static int32_t pack( sere_pbd* pbd, const float* px, const float* py, const float* pz, const float* inv_m, int t,
					 int threads )
{
	const int32_t first = pbd->band_start[(int64_t) pbd->bands * t / threads];
	const int32_t last = pbd->band_start[(int64_t) pbd->bands * ( t + 1 ) / threads];
	const int32_t* particle = pbd->particle;
	float* packed = pbd->packed[0];
	for ( int32_t s = first; s < last; ++s )
	{
		const int32_t i = particle[s];
		float* record = packed + 4 * s;
		record[0] = px[i], record[1] = py[i], record[2] = pz[i], record[3] = inv_m[i];
	}
	/* Flags as 0/1 per record, combined after: this form vectorizes (a flag-valued select per
	 * value did not, and cost twice the packing). */
	int32_t nonfinite = 0, negative = 0;
#pragma omp simd reduction( | : nonfinite, negative )
	for ( int32_t s = first; s < last; ++s )
	{
		const float* record = packed + 4 * s;
		nonfinite |= !( fabsf( record[0] ) <= FLT_MAX ) | !( fabsf( record[1] ) <= FLT_MAX ) |
					 !( fabsf( record[2] ) <= FLT_MAX ) | !( fabsf( record[3] ) <= FLT_MAX );
		negative |= record[3] < 0.0f;
	}
	return ( nonfinite ? FLAG_NONFINITE : 0 ) | ( negative ? FLAG_NEGATIVE_MASS : 0 );
}

static void unpack( const float* packed, const int32_t* slot, int32_t n, float* px, float* py, float* pz, int t,
					int threads )
{
	int32_t first, last;
	sere_team_share( 0, n, t, threads, &first, &last );
	for ( int32_t i = first; i < last; ++i )
	{
		const float* record = packed + 4 * slot[i];
		px[i] = record[0], py[i] = record[1], pz[i] = record[2];
	}
}

/* Jacobi: every particle of thread t's share moves from its old record to a new one by
 * ω/n_i · w_i Σ f_q (p_other − p_i) over its constraints q, summed in lane order (both ends
 * of a constraint move along their own d, which is how −w_b f d reads from b's side).
 *
 * Out of line and on a cache line of its own: inlined, its gather loop sat wherever the code
 * linked before this file left it, and one placement cost the Jacobi sweep 16% (CPU time, one
 * thread, the maple) against another with the same instructions. */
static __attribute__( ( noinline, aligned( 64 ) ) ) void jacobi_apply( sere_pbd* pbd, const float* old, float* next,
																	   float omega, int t, int threads )
{
	int32_t first, last;
	sere_team_share( 0, pbd->particle_count, t, threads, &first, &last );
	const float* factor = pbd->factor;
	const int32_t* adjacency = pbd->adjacency;
	for ( int32_t s = first; s < last; ++s )
	{
		const float* p = old + 4 * s;
		float sx = 0.0f, sy = 0.0f, sz = 0.0f;
		for ( int32_t e = pbd->adjacency_offset[s]; e < pbd->adjacency_offset[s + 1]; ++e )
		{
			float f = factor[adjacency[2 * e]];
			const float* o = old + adjacency[2 * e + 1];
			sx += f * ( o[0] - p[0] ), sy += f * ( o[1] - p[1] ), sz += f * ( o[2] - p[2] );
		}
		float scale = ( omega * pbd->inv_degree[s] ) * p[3];
		float* n = next + 4 * s;
		n[0] = p[0] + scale * sx, n[1] = p[1] + scale * sy, n[2] = p[2] + scale * sz, n[3] = p[3];
	}
}

static sere_status status_of( int32_t flags )
{
	if ( flags & FLAG_NEGATIVE_MASS )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( flags & FLAG_ZERO_LENGTH )
	{
		return SERE_ERR_GEOMETRY;
	}
	return flags & FLAG_NONFINITE ? SERE_ERR_NONFINITE : SERE_OK;
}

typedef enum solver
{
	SOLVER_GAUSS_SEIDEL,
	SOLVER_JACOBI,
	SOLVER_TOUCH,
} solver;

typedef struct solve_setup
{
	solver kind;
	float k, alpha, omega, tolerance;
	float stall; /* sere_pbd_params.stall; 0: no stall rule */
	int32_t max_iterations;
	int xpbd, warm;
	float ground, slack; /* the ground plane z ≥ ground (−∞: none) and the push a converged round may leave */
	float rho;			 /* Chebyshev ρ, 0: off */
	int32_t delay;		 /* Chebyshev: plain sweeps before the first extrapolation */
} solve_setup;

typedef struct solve_result
{
	int32_t iterations, flags;
	float strain;
	int converged, stalled;
} solve_result;

/* One thread's part of sweep `number` of a Gauss–Seidel (or touch) call; returns the
 * combined result of the sweep. */
static void sweep( sere_pbd* pbd, const block_context* ctx, block_mode mode, int xpbd, int t, int threads, int* parity,
				   int32_t number, float* worst, int32_t* flags )
{
	run_pass( pbd, ctx, PASS_SWEEP, *parity, number, mode, xpbd, t, threads, worst, flags );
	exchange( pbd, t, threads, parity, worst, flags );
}

/* p = h = ω (p − h) + h over [first, last): the extrapolated iterate, kept as the history
 * (with ω = 1, p is copied). */
static void extrapolate_range( float* restrict p, float* restrict h, int32_t first, int32_t last, float omega )
{
	if ( omega == 1.0f )
	{
		memcpy( h + first, p + first, sizeof( float ) * (size_t) ( last - first ) );
		return;
	}
	for ( int32_t s = first; s < last; ++s )
	{
		float n = omega * ( p[s] - h[s] ) + h[s];
		p[s] = n, h[s] = n;
	}
}

/* Chebyshev semi-iteration (Wang 2015): x_{k+1} = ω_{k+1} (x̂_{k+1} − x_{k−1}) + x_{k−1},
 * x̂_{k+1} the sweep's result in the records, x_{k−1} in history[*older]; with XPBD the same
 * combination of the multipliers, so each position stays the inertia anchor plus the
 * multipliers' corrections (Δx = M⁻¹ ∇Cᵀ Δλ is linear in Δλ for fixed gradients). ω = 1 only
 * records x_{k+1} = x̂_{k+1} (ω (x̂ − x) + x would round it). The new iterate overwrites
 * x_{k−1}, which becomes x_k for the next sweep. Thread t takes its share of the floats; a
 * barrier follows, since any thread may project any item next. */
static void extrapolate( sere_pbd* pbd, float omega, int xpbd, int* older, int t, int threads )
{
	int32_t first, last;
	sere_team_share( 0, 4 * pbd->slot_count, t, threads, &first, &last );
	extrapolate_range( pbd->packed[0], pbd->history[*older], first, last, omega );
	if ( xpbd )
	{
		sere_team_share( 0, pbd->lanes, t, threads, &first, &last );
		extrapolate_range( pbd->lambda, pbd->lambda_history[*older], first, last, omega );
	}
	*older ^= 1;
	sere_spin_barrier_wait( pbd->barrier, threads );
}

/* The ground between rounds: thread t's share of the particles below z = ground put onto it,
 * each push added to the particle's total; then the largest push of all shares, combined. */
static float ground_pass( sere_pbd* pbd, float ground, int t, int threads, int* parity )
{
	int32_t first, last;
	sere_team_share( 0, pbd->particle_count, t, threads, &first, &last );
	float* packed = pbd->packed[0];
	float largest = 0.0f;
	for ( int32_t s = first; s < last; ++s )
	{
		float depth = ground - packed[4 * s + 2];
		depth = depth > 0.0f ? depth : 0.0f;
		packed[4 * s + 2] += depth;
		pbd->push[s] += depth;
		largest = depth > largest ? depth : largest;
	}
	/* as run_pass does: the counters of the pass after the exchange start from zero */
	atomic_store_explicit( &pbd->counters[( 1 - *parity ) * MAX_THREADS + t].value, 0, memory_order_relaxed );
	int32_t none = 0;
	exchange( pbd, t, threads, parity, &largest, &none );
	return largest;
}

/* Gauss–Seidel sweeps until converged (and verified) or the cap; runs on every thread. With a
 * ground, a sweep below the tolerance is followed by the ground pass, and the sweeps go on from
 * the same multipliers (a new round, Chebyshev restarted) until it moves no particle beyond the
 * slack; only then does the read-only pass confirm the residual, on the positions returned. */
static solve_result gauss_seidel( sere_pbd* pbd, const block_context* ctx, const solve_setup* setup, int t, int threads,
								  int* parity )
{
	solve_result result = { 0, 0, 0.0f, 0, 0 };
	const block_mode mode = setup->kind == SOLVER_TOUCH ? MODE_TOUCH : MODE_GAUSS_SEIDEL;
	const int ground = setup->ground > -INFINITY;
	float window_strain = INFINITY; /* the stall rule's: the last window's last sweep */
	/* Chebyshev weights (Wang 2015), the same sequence on every thread. */
	const double rho2 = (double) setup->rho * (double) setup->rho;
	double omega = 1.0;
	int older = 0;
	int32_t round_start = 0;
	while ( result.iterations < setup->max_iterations )
	{
		float worst = 0.0f;
		int32_t flags = 0;
		sweep( pbd, ctx, mode, setup->xpbd, t, threads, parity, result.iterations + 1, &worst, &flags );
		result.iterations += 1, result.flags = flags, result.strain = worst;
		if ( flags != 0 )
		{
			break;
		}
		/* The floor runs its sweeps to the cap, exchanges included. */
		if ( setup->kind != SOLVER_TOUCH && worst < setup->tolerance )
		{
			if ( ground && ground_pass( pbd, setup->ground, t, threads, parity ) > setup->slack )
			{
				round_start = result.iterations, older = 0;
				continue;
			}
			/* Residuals were taken before each projection; check the positions left. */
			worst = 0.0f;
			run_pass( pbd, ctx, PASS_ALL, *parity, 0, MODE_MEASURE, setup->xpbd, t, threads, &worst, &flags );
			exchange( pbd, t, threads, parity, &worst, &flags );
			result.flags = flags;
			if ( flags != 0 )
			{
				break;
			}
			if ( worst < setup->tolerance )
			{
				result.strain = worst;
				result.converged = 1;
				break;
			}
			if ( ground )
			{
				round_start = result.iterations, older = 0;
				continue;
			}
		}
		/* The stall rule, inside the one call so that the multipliers and the Chebyshev
		 * sequence go on as without it; a stall in the last window is the cap. */
		if ( setup->stall > 0.0f && result.iterations % SERE_PBD_STALL_WINDOW == 0 &&
			 result.iterations < setup->max_iterations )
		{
			if ( result.strain > ( 1.0f - setup->stall ) * window_strain )
			{
				result.stalled = 1;
				break;
			}
			window_strain = result.strain;
		}
		const int32_t k = result.iterations - round_start;
		if ( setup->rho > 0.0f && result.iterations < setup->max_iterations )
		{
			omega = k <= setup->delay		? 1.0
					: k == setup->delay + 1 ? 2.0 / ( 2.0 - rho2 )
											: 4.0 / ( 4.0 - rho2 * omega );
			/* Sweep k's record is read two sweeps on, and only by an extrapolation (k + 2 >
			 * delay): the plain sweeps before the delay's last two need none, nor its barrier
			 * (the wisteria's 90 would copy its records and multipliers every sweep). */
			if ( k + 2 > setup->delay )
			{
				extrapolate( pbd, (float) omega, setup->xpbd, &older, t, threads );
			}
			else
			{
				older ^= 1;
			}
		}
	}
	/* At the cap or a stall the returned positions meet the ground too, unless the last round
	 * just did. */
	if ( ground && !result.converged && result.flags == 0 && round_start != result.iterations )
	{
		ground_pass( pbd, setup->ground, t, threads, parity );
	}
	return result;
}

/* Jacobi sweeps, alternating the two record buffers; *front ends on the one holding the
 * result. */
static solve_result jacobi( sere_pbd* pbd, block_context* ctx, const solve_setup* setup, int t, int threads,
							int* parity, int* front )
{
	solve_result result = { 0, 0, 0.0f, 0, 0 };
	while ( result.iterations < setup->max_iterations )
	{
		float worst = 0.0f;
		int32_t flags = 0;
		ctx->packed = pbd->packed[*front];
		run_pass( pbd, ctx, PASS_ALL, *parity, 0, MODE_JACOBI, setup->xpbd, t, threads, &worst, &flags );
		exchange( pbd, t, threads, parity, &worst, &flags );
		result.iterations += 1, result.flags = flags, result.strain = worst;
		/* Measured on the positions as they are: converged means exactly that. */
		if ( flags != 0 || worst < setup->tolerance )
		{
			result.converged = flags == 0;
			break;
		}
		jacobi_apply( pbd, pbd->packed[*front], pbd->packed[1 - *front], setup->omega, t, threads );
		*front = 1 - *front;
		sere_spin_barrier_wait( pbd->barrier, threads );
	}
	return result;
}

/* stalled: set when the stall rule stopped the sweeps (NULL: not asked). */
static sere_status solve( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, const solve_setup* setup,
						  sere_pbd_report* report, int* stalled )
{
	int requested = sere_team_for( pbd->thread_count );
	requested = requested < 1 ? 1 : requested > MAX_THREADS ? MAX_THREADS : requested;
	solve_result outcome = { 0, 0, 0.0f, 0, 0 };
	/* One parallel region per call; inside it every thread follows the same control flow,
	 * driven by values combined in exchange(). */
#pragma omp parallel num_threads( requested )
	{
		const int t = omp_get_thread_num(), threads = omp_get_num_threads();
		block_context ctx = {
			.packed = pbd->packed[0],
			.ia = pbd->ia,
			.ib = pbd->ib,
			.rest = pbd->rest,
			.lambda = pbd->lambda,
			.weight = pbd->weight,
			.factor = pbd->factor,
			.k = setup->k,
			.alpha = setup->alpha,
			.one = pbd->one,
		};
		int parity = 0, front = 0;
		float worst = 0.0f;
		int32_t flags = pack( pbd, px, py, pz, inv_m, t, threads );
		if ( setup->xpbd && !setup->warm )
		{
			int32_t first, last;
			sere_team_share( 0, pbd->lanes, t, threads, &first, &last );
			memset( pbd->lambda + first, 0, sizeof( float ) * (size_t) ( last - first ) );
		}
		{
			int32_t first, last;
			sere_team_share( 0, pbd->particle_count, t, threads, &first, &last );
			memset( pbd->push + first, 0, sizeof( float ) * (size_t) ( last - first ) );
		}
		/* Work lists from their start; no item projected yet in this call. The exchange below
		 * publishes both before any pass. */
		atomic_store_explicit( &pbd->counters[t].value, 0, memory_order_relaxed );
		atomic_store_explicit( &pbd->counters[MAX_THREADS + t].value, 0, memory_order_relaxed );
		for ( int32_t item = t; item < pbd->items; item += threads )
		{
			atomic_store_explicit( &pbd->done[item].value, 0, memory_order_relaxed );
		}
		exchange( pbd, t, threads, &parity, &worst, &flags );
		solve_result result = { 0, flags, 0.0f, 0, 0 };
		if ( flags == 0 )
		{
			result = setup->kind == SOLVER_JACOBI ? jacobi( pbd, &ctx, setup, t, threads, &parity, &front )
												  : gauss_seidel( pbd, &ctx, setup, t, threads, &parity );
		}
		if ( result.flags == 0 )
		{
			unpack( pbd->packed[front], pbd->slot, pbd->particle_count, px, py, pz, t, threads );
		}
		if ( t == 0 )
		{
			outcome = result;
		}
	}
	pbd->multipliers_valid = setup->xpbd && setup->kind != SOLVER_TOUCH && outcome.flags == 0;
	report->iterations = outcome.iterations;
	report->max_strain = outcome.strain;
	report->hit_cap = !outcome.converged && !outcome.stalled;
	if ( stalled != NULL )
	{
		*stalled = outcome.stalled;
	}
	return status_of( outcome.flags );
}

static sere_status check_call( const sere_pbd* pbd, const float* px, const float* py, const float* pz,
							   const float* inv_m, const sere_pbd_params* params, sere_pbd_report* report )
{
	if ( report != NULL )
	{
		memset( report, 0, sizeof( *report ) ); /* a refused call reports nothing done */
	}
	if ( pbd == NULL || px == NULL || py == NULL || pz == NULL || inv_m == NULL || params == NULL || report == NULL ||
		 !( params->stiffness >= 0.0f && params->stiffness <= 1.0f ) || !( params->tolerance > 0.0f ) ||
		 params->max_iterations < 1 || !( params->compliance >= 0.0f && params->compliance <= FLT_MAX ) ||
		 !( params->chebyshev_rho >= 0.0f && params->chebyshev_rho < 1.0f ) || params->chebyshev_delay < 2 ||
		 isnan( params->ground ) || params->ground == INFINITY ||
		 !( params->ground_slack >= 0.0f && params->ground_slack <= FLT_MAX ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( params->compliance > 0.0f )
	{
		float alpha = params->compliance / ( params->dt * params->dt );
		if ( !( params->dt > 0.0f ) || !( alpha <= FLT_MAX ) )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return pbd->rest_valid ? SERE_OK : SERE_ERR_GEOMETRY;
}

static solve_setup setup_of( const sere_pbd_params* params, solver kind )
{
	solve_setup setup = {
		.kind = kind,
		.k = params->stiffness,
		.alpha = params->compliance > 0.0f ? params->compliance / ( params->dt * params->dt ) : 0.0f,
		.omega = params->relaxation,
		.tolerance = params->tolerance,
		.max_iterations = params->max_iterations,
		.xpbd = params->compliance > 0.0f,
		.warm = params->warm,
		.ground = params->ground,
		.slack = params->ground_slack,
		.rho = params->chebyshev_rho,
		.delay = params->chebyshev_delay,
	};
	return setup;
}

sere_status sere_pbd_project( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
							  const sere_pbd_params* params, sere_pbd_report* report )
{
	sere_status status = check_call( pbd, px, py, pz, inv_m, params, report );
	if ( status != SERE_OK )
	{
		return status;
	}
	solve_setup setup = setup_of( params, SOLVER_GAUSS_SEIDEL );
	if ( params->linear_stiffness )
	{
		/* (1 − k')^n = 1 − k after n sweeps. */
		setup.k = (float) ( 1.0 - pow( 1.0 - (double) params->stiffness, 1.0 / (double) params->max_iterations ) );
	}
	return solve( pbd, px, py, pz, inv_m, &setup, report, NULL );
}

sere_status sere_pbd_project_stalling( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									   const sere_pbd_params* params, sere_pbd_report* report, int* stalled )
{
	sere_status status = check_call( pbd, px, py, pz, inv_m, params, report );
	if ( stalled != NULL )
	{
		*stalled = 0;
	}
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( stalled == NULL || !( params->stall >= 0.0f && params->stall < 1.0f ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( params->linear_stiffness )
	{
		return sere_pbd_project( pbd, px, py, pz, inv_m, params, report );
	}
	solve_setup setup = setup_of( params, SOLVER_GAUSS_SEIDEL );
	setup.stall = params->stall;
	return solve( pbd, px, py, pz, inv_m, &setup, report, stalled );
}

sere_status sere_pbd_project_jacobi( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									 const sere_pbd_params* params, sere_pbd_report* report )
{
	sere_status status = check_call( pbd, px, py, pz, inv_m, params, report );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( !( params->relaxation > 0.0f && params->relaxation < 2.0f ) || params->linear_stiffness ||
		 params->chebyshev_rho > 0.0f || params->ground > -INFINITY )
	{
		return SERE_ERR_ARGUMENT;
	}
	solve_setup setup = setup_of( params, SOLVER_JACOBI );
	return solve( pbd, px, py, pz, inv_m, &setup, report, NULL );
}

static sere_status touch_sweeps( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps,
								 int xpbd )
{
	if ( pbd == NULL || px == NULL || py == NULL || pz == NULL || inv_m == NULL || sweeps < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	solve_setup setup = { .kind = SOLVER_TOUCH,
						  .k = 1.0f,
						  .omega = 1.0f,
						  .tolerance = 1.0f,
						  .max_iterations = sweeps,
						  .ground = -INFINITY,
						  .xpbd = xpbd };
	sere_pbd_report report;
	return solve( pbd, px, py, pz, inv_m, &setup, &report, NULL );
}

sere_status sere_pbd_touch_sweeps( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps )
{
	return touch_sweeps( pbd, px, py, pz, inv_m, sweeps, 0 );
}

sere_status sere_pbd_touch_sweeps_xpbd( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
										int32_t sweeps )
{
	return touch_sweeps( pbd, px, py, pz, inv_m, sweeps, 1 );
}

sere_status sere_pbd_touch( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m )
{
	return sere_pbd_touch_sweeps( pbd, px, py, pz, inv_m, 1 );
}
