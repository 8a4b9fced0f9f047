/* sere — private to pbd.c and pbd_build.c, not installed and not part of the API: the solver's
 * layout (particle bands, constraint lanes in colors, per-slot records) and its thread state. */
#pragma once

#include "core/internal/team.h"
#include "solve/pbd.h"

#include <stdatomic.h>

enum
{
	/* Constraints per block: one 512-bit register of floats, a multiple of every lane width
	 * (SERE_LANES: 16, 8 or 4). */
	LANES = 16,
	/* Bands hold at least this many particles, so the constraints joining two bands stay a
	 * small share (on the maple, 8 bands: 6% of the constraints). */
	BAND_PARTICLES = 1600,
	MAX_BANDS = 8,
	/* Particles per block of sere_pbd_step_residual's partial sums: each block is one thread's,
	 * added in block order, so the norms do not depend on the thread count. */
	RESIDUAL_BLOCK = 1024,
	/* Threads past this many are not started (per-thread slots live in the workspace): the one
	 * limit of every kernel (base.h). */
	MAX_THREADS = SERE_MAX_THREADS,
};

/* Per-thread results of a pass, double-buffered by pass parity so a fast thread can publish
 * the next pass's values while a slow one still reads this one's. One cache line each. */
typedef struct thread_slot
{
	_Alignas( 64 ) float worst[2];
	int32_t flags[2];
} thread_slot;

/* A counter alone on its cache line. */
typedef struct padded_counter
{
	_Alignas( 64 ) atomic_int value;
} padded_counter;

struct sere_pbd
{
	int32_t thread_count; /* sere_pbd_set_threads */
	int32_t particle_count, constraint_count;
	sere_coloring coloring;
	int32_t colors;
	int32_t bands, items; /* items: bands 0..R−1, then cut r (bands r, r+1) is item R + r */
	int32_t interface_count;
	int32_t* segment;		   /* items·colors + 1 lane offsets, multiples of LANES: item w, color c */
	int32_t lanes;			   /* segment[items·colors] */
	int32_t *ia, *ib;		   /* per lane: float offset 4·slot of each end */
	int32_t* source;		   /* per lane: the caller's constraint index, −1 for padding */
	float* rest;			   /* per lane; padding lanes keep 1 */
	float* lambda;			   /* per lane, XPBD multipliers */
	float* weight;			   /* per lane, XPBD compliance weight (α_j = α · weight_j); padding keeps 1 */
	float* factor;			   /* per lane, Jacobi: the f of the block below */
	float* push;			   /* per slot: how far the ground pushed the particle up in the last call */
	int32_t* slot;			   /* particle → slot (its place in breadth-first order) */
	int32_t* particle;		   /* slot → particle, for slots < particle_count */
	int32_t* band_start;	   /* bands + 1 slot offsets, multiples of 4 but the last (particle_count) */
	int32_t slot_count;		   /* particles rounded up to 4, then a dummy pair per item */
	float* packed[2];		   /* (x, y, z, w) per slot; Jacobi alternates the two, the others use [0] */
	float* history[2];		   /* Chebyshev: records of the last two iterates, x_{k−1} and x_k */
	float* lambda_history[2];  /* Chebyshev: multipliers of the last two iterates, per lane */
	int32_t* adjacency_offset; /* per slot < particle_count, Jacobi */
	int32_t* adjacency;		   /* pairs (lane, 4·slot of the other end) */
	float* inv_degree;		   /* per slot: 1/n_i, 0 for a particle without constraints */
	float one;				   /* 1.0f, opaque to the compiler so sere_pbd_touch keeps its stores */
	int rest_valid;
	int multipliers_valid;	  /* the last call was an XPBD projection that returned SERE_OK */
	double* residual_partial; /* 4 per RESIDUAL_BLOCK particles: sere_pbd_step_residual's block sums */
	thread_slot* threads;	  /* MAX_THREADS */
	padded_counter* counters; /* 2 × MAX_THREADS: next item of each thread's list, by pass parity */
	padded_counter* done;	  /* per item: the sweep of the current call that last projected it */
	sere_spin_barrier* barrier;
};
