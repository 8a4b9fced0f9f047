/* sere — the Markov chain of leaf states (seed 002, Sec. 5, Tang Eq. 5–6): every leaf on a tree is
 * in one of S states, each a pair (texture, deformation) chosen by the caller; once a day a
 * leaf keeps its state or moves to one of the state's successors with probabilities set by the
 * day's temperature and humidity. Millions of leaves are stepped per day with a counter-based
 * random number, so the result depends on (seed, leaf, day) only, never on the thread count.
 *
 * Tang Eq. 5–6 as implemented. With the day's temperature T and humidity H normalized to the
 * corners of the chain, t = clamp((T − cold)/(warm − cold)) and h = clamp((H − dry)/(wet − dry))
 * in [0, 1], the bilinear interpolation of four corner values c is
 *     B(c; t, h) = (1−t)(1−h) c_dry-cold + t(1−h) c_dry-warm + (1−t) h c_wet-cold + t h c_wet-warm.
 * Tang Eq. 5: the probability of keeping state i is P_ii = B(stay_i; t, h), stay_i the state's four
 *        corner values in [0, 1].
 * Tang Eq. 6: each transition i → j carries the seed's four user constants g_ij in [0, 1] (wet-cold,
 *        wet-warm, dry-cold, dry-warm); the leaf leaves i with probability 1 − P_ii, split among
 *        i's successors in proportion to their interpolated constants:
 *            P_ij = (1 − P_ii) B(g_ij; t, h) / Σ_k B(g_ik; t, h).
 *        When every successor's constant interpolates to 0 (or i has none), P_ii = 1.
 * So each row is non-negative and sums to 1 for every T and H; temperatures and humidities
 * beyond the corners act like the nearest corner. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* States are stored as uint8_t per leaf. */
#define SERE_MARKOV_MAX_STATES 64
/* A state's outcomes: itself plus at most SERE_MARKOV_MAX_OUTCOMES − 1 successors. */
#define SERE_MARKOV_MAX_OUTCOMES 8

/* The four extreme environments of Tang Eq. 6, in the order the seed lists them; corner arrays are
 * indexed by these. */
enum
{
	SERE_WET_COLD = 0,
	SERE_WET_WARM = 1,
	SERE_DRY_COLD = 2,
	SERE_DRY_WARM = 3,
};

typedef struct sere_markov_transition
{
	int32_t from, to;
	double weight[4]; /* g_ij at the four corners (Tang Eq. 6), each in [0, 1] */
} sere_markov_transition;

typedef struct sere_markov_chain
{
	int32_t state_count;
	const double* stay; /* 4 per state: P_ii at the four corners (Tang Eq. 5), each in [0, 1] */
	int32_t transition_count;
	const sere_markov_transition* transitions;
	double cold, warm; /* temperatures of the cold and warm corners, cold < warm */
	double dry, wet;   /* humidities of the dry and wet corners, dry < wet */
} sere_markov_chain;

/* SERE_OK for a usable chain; SERE_ERR_NONFINITE for a NaN or infinite value; otherwise
 * SERE_ERR_ARGUMENT: no states or more than SERE_MARKOV_MAX_STATES, a probability outside
 * [0, 1], a state index out of range, a transition from a state to itself, the same transition
 * twice, more successors than SERE_MARKOV_MAX_OUTCOMES − 1, or cold ≥ warm, dry ≥ wet. */
sere_status sere_markov_validate( const sere_markov_chain* chain );

/* The bilinear interpolation B of four corner values (indexed by SERE_WET_COLD ...) at the
 * normalized temperature t and humidity h, both clamped to [0, 1]. */
double sere_markov_bilinear( const double corner[4], double t, double h );

/* The day's transition matrix: P[i * S + j] for S = state_count, rows summing to 1 (Tang Eq. 5–6).
 * Errors as sere_markov_validate, plus SERE_ERR_NONFINITE for a NaN temperature or humidity. */
sere_status sere_markov_matrix( const sere_markov_chain* chain, double temperature, double humidity, double* P );

/* The exact distribution one day later: next_j = Σ_i pi_i P_ij, summed in i order. */
void sere_markov_propagate( const double* P, int32_t state_count, const double* pi, double* next );

/* One day's transitions as sampling tables: for state s, outcome k (0 = stay, then the
 * successors in the order of the chain's transitions) is taken when the leaf's 31-bit uniform u
 * satisfies threshold[s][k−1] ≤ u < threshold[s][k] (threshold[s][−1] = 0). The cumulative
 * probabilities are rounded to multiples of 2⁻³¹; unused slots hold 2³¹, which no u reaches.
 * Rows for s ≥ state_count keep the state, so a bad state never indexes past the table. */
typedef struct sere_markov_day
{
	int32_t state_count;
	uint32_t threshold[256][SERE_MARKOV_MAX_OUTCOMES];
	int32_t target[256][SERE_MARKOV_MAX_OUTCOMES]; /* int32 so SIMD lanes can gather it */
} sere_markov_day;

sere_status sere_markov_day_prepare( const sere_markov_chain* chain, double temperature, double humidity,
									 sere_markov_day* day );

/* The counter-based generator (SplitMix64's output function applied to a key and a counter):
 * sere_random_key mixes the seed with a stream number (the day), sere_random_u64 gives the
 * counter-th 64-bit value of that stream. The value for (seed, stream, counter) is fixed, so any
 * split of the counters among threads draws the same numbers. */
static inline uint64_t sere_mix64( uint64_t z )
{
	z = ( z ^ ( z >> 30 ) ) * 0xBF58476D1CE4E5B9ull;
	z = ( z ^ ( z >> 27 ) ) * 0x94D049BB133111EBull;
	return z ^ ( z >> 31 );
}

static inline uint64_t sere_random_key( uint64_t seed, uint64_t stream )
{
	return sere_mix64( seed ^ sere_mix64( stream + 0x9E3779B97F4A7C15ull ) );
}

static inline uint64_t sere_random_u64( uint64_t key, uint64_t counter )
{
	return sere_mix64( key + counter * 0x9E3779B97F4A7C15ull );
}

/* Advances leaf_count leaves by one day. states[l] belongs to leaf number first_leaf + l, which
 * draws u = the top 31 bits of sere_random_u64(sere_random_key(seed, day_index), first_leaf + l)
 * and takes the outcome of its state's row; so a population may be advanced in one call or in
 * any number of pieces with the same result. counts (state_count entries, may be NULL) receives
 * how many of these leaves are in each state after the step. SERE_ERR_ARGUMENT if a leaf's
 * state is ≥ state_count (such leaves are left as they were, the others advanced) or for a
 * negative leaf_count. */
sere_status sere_markov_advance( const sere_markov_day* day, uint8_t* states, int64_t leaf_count, uint64_t first_leaf,
								 uint64_t seed, int64_t day_index, int64_t* counts, int32_t threads );

/* How many leaves are in each of state_count states; SERE_ERR_ARGUMENT for a state out of
 * range. Both run on `threads` threads (core/base.h; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_markov_count( const uint8_t* states, int64_t leaf_count, int32_t state_count, int64_t* counts,
							   int32_t threads );

#ifdef __cplusplus
}
#endif
