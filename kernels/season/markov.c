/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "season/markov.h"

#include "core/internal/team.h"

#include <math.h>
#include <string.h>

/* 2³¹: the leaves draw 31-bit uniforms, so a threshold of 2³¹ is never reached. */
#define UNIFORM_RANGE 2147483648.0
#define NEVER		  0x80000000u

/* Leaves per block of the advance loop: the block is stepped first (a branch-free loop the
 * compiler vectorizes), then counted. */
#define BLOCK 2048

static int probability( double p )
{
	return p >= 0.0 && p <= 1.0;
}

sere_status sere_markov_validate( const sere_markov_chain* chain )
{
	if ( chain == NULL || chain->state_count < 1 || chain->state_count > SERE_MARKOV_MAX_STATES ||
		 chain->stay == NULL || chain->transition_count < 0 ||
		 ( chain->transition_count > 0 && chain->transitions == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !isfinite( chain->cold ) || !isfinite( chain->warm ) || !isfinite( chain->dry ) || !isfinite( chain->wet ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( !( chain->cold < chain->warm ) || !( chain->dry < chain->wet ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t k = 0; k < 4 * chain->state_count; ++k )
	{
		if ( !isfinite( chain->stay[k] ) )
		{
			return SERE_ERR_NONFINITE;
		}
		if ( !probability( chain->stay[k] ) )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	int32_t successors[SERE_MARKOV_MAX_STATES] = { 0 };
	for ( int32_t e = 0; e < chain->transition_count; ++e )
	{
		const sere_markov_transition* t = chain->transitions + e;
		if ( t->from < 0 || t->from >= chain->state_count || t->to < 0 || t->to >= chain->state_count ||
			 t->from == t->to )
		{
			return SERE_ERR_ARGUMENT;
		}
		for ( int c = 0; c < 4; ++c )
		{
			if ( !isfinite( t->weight[c] ) )
			{
				return SERE_ERR_NONFINITE;
			}
			if ( !probability( t->weight[c] ) )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
		for ( int32_t f = 0; f < e; ++f )
		{
			if ( chain->transitions[f].from == t->from && chain->transitions[f].to == t->to )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
		if ( ++successors[t->from] > SERE_MARKOV_MAX_OUTCOMES - 1 )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return SERE_OK;
}

static double clamp01( double v )
{
	return v < 0.0 ? 0.0 : ( v > 1.0 ? 1.0 : v );
}

double sere_markov_bilinear( const double corner[4], double t, double h )
{
	t = clamp01( t );
	h = clamp01( h );
	double dry = ( 1.0 - t ) * corner[SERE_DRY_COLD] + t * corner[SERE_DRY_WARM];
	double wet = ( 1.0 - t ) * corner[SERE_WET_COLD] + t * corner[SERE_WET_WARM];
	return ( 1.0 - h ) * dry + h * wet;
}

/* Row i of Tang Eq. 5–6: p[0] = P_ii, then p[1..] for i's successors in transition order, whose
 * indices go to to[]; returns the number of outcomes. */
static int32_t row( const sere_markov_chain* chain, int32_t i, double t, double h, double* p, int32_t* to )
{
	double stay = clamp01( sere_markov_bilinear( chain->stay + 4 * i, t, h ) ); /* Tang Eq. 5 */
	int32_t n = 1;
	double total = 0.0;
	to[0] = i;
	for ( int32_t e = 0; e < chain->transition_count; ++e )
	{
		const sere_markov_transition* tr = chain->transitions + e;
		if ( tr->from == i )
		{
			p[n] = clamp01( sere_markov_bilinear( tr->weight, t, h ) );
			to[n] = tr->to;
			total += p[n];
			++n;
		}
	}
	if ( total > 0.0 )
	{
		p[0] = stay;
		for ( int32_t k = 1; k < n; ++k )
		{
			p[k] = ( 1.0 - stay ) * ( p[k] / total ); /* Tang Eq. 6 */
		}
	}
	else
	{
		p[0] = 1.0;
		for ( int32_t k = 1; k < n; ++k )
		{
			p[k] = 0.0;
		}
	}
	return n;
}

static sere_status normalized( const sere_markov_chain* chain, double temperature, double humidity, double* t,
							   double* h )
{
	sere_status status = sere_markov_validate( chain );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( isnan( temperature ) || isnan( humidity ) )
	{
		return SERE_ERR_NONFINITE;
	}
	*t = clamp01( ( temperature - chain->cold ) / ( chain->warm - chain->cold ) );
	*h = clamp01( ( humidity - chain->dry ) / ( chain->wet - chain->dry ) );
	return SERE_OK;
}

sere_status sere_markov_matrix( const sere_markov_chain* chain, double temperature, double humidity, double* P )
{
	double t, h;
	sere_status status = normalized( chain, temperature, humidity, &t, &h );
	if ( status != SERE_OK || P == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int32_t S = chain->state_count;
	for ( int32_t i = 0; i < S; ++i )
	{
		double p[SERE_MARKOV_MAX_OUTCOMES];
		int32_t to[SERE_MARKOV_MAX_OUTCOMES];
		int32_t n = row( chain, i, t, h, p, to );
		for ( int32_t j = 0; j < S; ++j )
		{
			P[i * S + j] = 0.0;
		}
		for ( int32_t k = 0; k < n; ++k )
		{
			P[i * S + to[k]] += p[k];
		}
	}
	return SERE_OK;
}

void sere_markov_propagate( const double* P, int32_t state_count, const double* pi, double* next )
{
	for ( int32_t j = 0; j < state_count; ++j )
	{
		double sum = 0.0;
		for ( int32_t i = 0; i < state_count; ++i )
		{
			sum += pi[i] * P[i * state_count + j];
		}
		next[j] = sum;
	}
}

sere_status sere_markov_day_prepare( const sere_markov_chain* chain, double temperature, double humidity,
									 sere_markov_day* day )
{
	double t, h;
	sere_status status = normalized( chain, temperature, humidity, &t, &h );
	if ( status != SERE_OK || day == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	day->state_count = chain->state_count;
	for ( int32_t s = 0; s < 256; ++s )
	{
		for ( int k = 0; k < SERE_MARKOV_MAX_OUTCOMES; ++k )
		{
			day->threshold[s][k] = NEVER;
			day->target[s][k] = s;
		}
	}
	for ( int32_t i = 0; i < chain->state_count; ++i )
	{
		double p[SERE_MARKOV_MAX_OUTCOMES];
		int32_t to[SERE_MARKOV_MAX_OUTCOMES];
		int32_t n = row( chain, i, t, h, p, to );
		double cumulative = 0.0;
		for ( int32_t k = 0; k < n; ++k )
		{
			day->target[i][k] = to[k];
			cumulative += p[k];
			/* The last outcome takes whatever rounding left, so the row covers every u. */
			double scaled = k == n - 1 ? UNIFORM_RANGE : nearbyint( cumulative * UNIFORM_RANGE );
			day->threshold[i][k] = scaled >= UNIFORM_RANGE ? NEVER : (uint32_t) scaled;
		}
		for ( int32_t k = n; k < SERE_MARKOV_MAX_OUTCOMES; ++k )
		{
			day->target[i][k] = to[n - 1];
		}
	}
	return SERE_OK;
}

/* One leaf: the outcome index is the number of thresholds at or below u (written out for the
 * SERE_MARKOV_MAX_OUTCOMES − 1 = 7 thresholds so the leaf loop vectorizes). */
_Static_assert( SERE_MARKOV_MAX_OUTCOMES == 8, "step_leaf compares 7 thresholds" );
static inline uint8_t step_leaf( const uint32_t* threshold, const int32_t* target, int32_t s, uint32_t u )
{
	const int32_t at = s * SERE_MARKOV_MAX_OUTCOMES;
	int32_t k = ( u >= threshold[at] ) + ( u >= threshold[at + 1] ) + ( u >= threshold[at + 2] ) +
				( u >= threshold[at + 3] ) + ( u >= threshold[at + 4] ) + ( u >= threshold[at + 5] ) +
				( u >= threshold[at + 6] );
	return (uint8_t) target[at + k];
}

sere_status sere_markov_advance( const sere_markov_day* day, uint8_t* states, int64_t leaf_count, uint64_t first_leaf,
								 uint64_t seed, int64_t day_index, int64_t* counts, int32_t threads )
{
	if ( day == NULL || day->state_count < 1 || day->state_count > SERE_MARKOV_MAX_STATES || leaf_count < 0 ||
		 ( leaf_count > 0 && states == NULL ) || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const uint64_t key = sere_random_key( seed, (uint64_t) day_index );
	const uint32_t* threshold = &day->threshold[0][0];
	const int32_t* target = &day->target[0][0];
	const int64_t blocks = ( leaf_count + BLOCK - 1 ) / BLOCK;
	int64_t histogram[256] = { 0 };
#pragma omp parallel num_threads( sere_team_for( threads ) )
	{
		int64_t local[4][256] = { { 0 } };
#pragma omp for schedule( static )
		for ( int64_t block = 0; block < blocks; ++block )
		{
			const int64_t first = block * BLOCK;
			const int64_t count = leaf_count - first < BLOCK ? leaf_count - first : BLOCK;
			uint8_t* s = states + first;
#pragma omp simd
			for ( int64_t l = 0; l < count; ++l )
			{
				uint32_t u = (uint32_t) ( sere_random_u64( key, first_leaf + (uint64_t) ( first + l ) ) >> 33 );
				s[l] = step_leaf( threshold, target, s[l], u );
			}
			/* Four interleaved histograms, so runs of equal states do not serialize on one
			 * counter. */
			int64_t l = 0;
			for ( ; l + 4 <= count; l += 4 )
			{
				++local[0][s[l]];
				++local[1][s[l + 1]];
				++local[2][s[l + 2]];
				++local[3][s[l + 3]];
			}
			for ( ; l < count; ++l )
			{
				++local[0][s[l]];
			}
		}
		/* Integer sums: the same totals in any order, so the thread count cannot change them. */
#pragma omp critical( sere_markov_histogram )
		for ( int b = 0; b < 256; ++b )
		{
			histogram[b] += ( local[0][b] + local[1][b] ) + ( local[2][b] + local[3][b] );
		}
	}
	int bad = 0;
	for ( int b = day->state_count; b < 256; ++b )
	{
		bad |= histogram[b] != 0;
	}
	if ( counts != NULL )
	{
		memcpy( counts, histogram, (size_t) day->state_count * sizeof( int64_t ) );
	}
	return bad ? SERE_ERR_ARGUMENT : SERE_OK;
}

sere_status sere_markov_count( const uint8_t* states, int64_t leaf_count, int32_t state_count, int64_t* counts,
							   int32_t threads )
{
	if ( leaf_count < 0 || ( leaf_count > 0 && states == NULL ) || counts == NULL || state_count < 1 ||
		 state_count > SERE_MARKOV_MAX_STATES || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int64_t histogram[256] = { 0 };
#pragma omp parallel num_threads( sere_team_for( threads ) )
	{
		int64_t local[256] = { 0 };
#pragma omp for schedule( static )
		for ( int64_t l = 0; l < leaf_count; ++l )
		{
			++local[states[l]];
		}
#pragma omp critical( sere_markov_histogram )
		for ( int b = 0; b < 256; ++b )
		{
			histogram[b] += local[b];
		}
	}
	memcpy( counts, histogram, (size_t) state_count * sizeof( int64_t ) );
	int bad = 0;
	for ( int b = state_count; b < 256; ++b )
	{
		bad |= histogram[b] != 0;
	}
	return bad ? SERE_ERR_ARGUMENT : SERE_OK;
}
