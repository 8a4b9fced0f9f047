/* sere — private to cg_amg.c and cg_amg_touch.c, not installed: the multigrid's levels and the
 * team a V-cycle runs with. */
#pragma once

#include "solve/internal/cg_shared.h"

/* Levels with fewer positions than this run on the team's first thread while the others wait:
 * their sweeps take a few µs, less than the barriers a shared level would cross (one per color
 * and sweep). */
#define AMG_SHARED_POSITIONS 4096

typedef struct amg_level
{
	const sere_sgs* g; /* the layout: the caller's at level 0, `own` above */
	sere_sgs* own;
	int32_t np; /* positions */
	/* Toward the next level (the dense one past the last sgs level): */
	int32_t* coarse_at;	 /* per position, its aggregate's position there; −1 for padding */
	int32_t* member_ptr; /* per position there, its members member[member_ptr[P] .. member_ptr[P + 1]) */
	int32_t* member;	 /* positions here, ascending within an aggregate */
	int32_t targets;	 /* Galerkin sums: the value at sum_to[t] there is the sum of val[sum_from[q]] */
	int32_t *sum_to, *sum_ptr, *sum_from; /* here over q in [sum_ptr[t], sum_ptr[t + 1]) */
	double *x, *b, *r, *inv_diag;		  /* per position */
} amg_level;

struct sere_amg
{
	int32_t levels; /* sgs levels */
	amg_level level[SERE_AMG_MAX_LEVELS];
	int32_t dense_rows; /* the dense level past the last sgs level; 0 when there is none */
	double *dense, *factor, *dense_b, *dense_x;
	int32_t threads;
	/* sere_amg_update only marks the coarse levels stale; the next V-cycle refreshes them (a
	 * solve that starts converged never pays for it: the plane tree's triangle layer, most
	 * frames). coarse_bad: the last refresh found a coarse level that is not SPD. */
	int updated, stale, coarse_bad;
	sere_spin_barrier* barrier;
};

/* The threads of a V-cycle: tid of team, meeting at barrier. */
typedef struct amg_team
{
	int tid, team;
	sere_spin_barrier* barrier;
} amg_team;

/* What a V-cycle needs: the finest level's D⁻¹ from the sgs's current values (every call: the
 * caller refills them every step), and when an update asked for it the coarse values (Galerkin
 * sums level by level), their D⁻¹ and the dense level's factor. */
sere_status sere_amg_refresh( sere_amg* m, int32_t threads );

/* Restriction Pᵀ r of level l into bc (the next level's b, or the dense level's), by every thread
 * of t: each aggregate's sum over its members, in position order; ends at a barrier. */
static inline void amg_restrict( const sere_amg* m, int32_t l, double* bc, amg_team t )
{
	const amg_level* L = &m->level[l];
	const int32_t next_np = l + 1 == m->levels ? m->dense_rows : m->level[l + 1].np;
	int32_t first, last;
	sere_team_share( 0, next_np, t.tid, t.team, &first, &last );
	for ( int32_t at = first; at < last; ++at )
	{
		double sum = 0.0;
		for ( int32_t q = L->member_ptr[at]; q < L->member_ptr[at + 1]; ++q )
		{
			sum += L->r[L->member[q]];
		}
		bc[at] = sum;
	}
	sere_spin_barrier_wait( t.barrier, t.team );
}

/* The floor's chunk_sum (cg_shared.h, chunk_pass): the same value loads and gathers, an add where
 * it multiplies. */
static inline void chunk_touch( const int32_t* col, const double* val, int32_t begin, int32_t end, const double* x,
								lanes_t* out )
{
	chunk_pass( col, val, begin, end, x, true, out );
}

/* The floor of chunk ch of a sweep over the lower rows or (full) the whole rows: in, D⁻¹ and the
 * rows' entries read, out stored, adds only. */
static inline void sweep_touch( const sere_sgs* g, bool full, int32_t ch, const double* inv_diag, const double* in,
								double* out )
{
	lanes_t lo, up = { { 0.0 }, { 0.0 } }, v = load_lanes( in + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	chunk_touch( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], out, &lo );
	if ( full )
	{
		chunk_touch( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], out, &up );
	}
	v.lo = v.lo + lo.lo + up.lo + inv.lo;
	v.hi = v.hi + lo.hi + up.hi + inv.hi;
	store_lanes( out + ch * LANES, &v );
}

/* x = B_l b on level l (both by position), by every thread of t; ends at a barrier. touch: the
 * floor instead (sere_cg_touch_amg): the same passes over the same arrays at the same barriers,
 * an add where the cycle multiplies, divides or multiplies and adds. */
void sere_amg_cycle( const sere_amg* m, int32_t l, const double* b, double* x, amg_team t, bool touch );
