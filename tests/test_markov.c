/* The Markov chain of leaf states (seed 002, Sec. 5, Tang Eq. 5–6): rows are probability
 * distributions for every temperature and humidity, the corners give the user's constants, the
 * sampled population follows the exact distribution (chi-square), and the counter-based
 * generator makes the result independent of threads and of how the leaves are split. */
#include "season/markov.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* A six-state chain shaped like the seasons: green → yellow-green → yellow → red → brown →
 * fallen (absorbing), with a shortcut yellow → brown. Warm and wet keep leaves green; cold and
 * dry age them. */
#define STATES 6

static const double stay_corners[STATES * 4] = {
	/* wet-cold wet-warm dry-cold dry-warm */
	0.90, 0.99, 0.80, 0.95, /* green */
	0.85, 0.97, 0.70, 0.90, /* yellow-green */
	0.80, 0.95, 0.60, 0.85, /* yellow */
	0.75, 0.92, 0.55, 0.80, /* red */
	0.70, 0.90, 0.50, 0.75, /* brown */
	0.20, 0.30, 0.40, 0.50, /* fallen: no successors, so it keeps every leaf whatever this says */
};

static const sere_markov_transition seasonal_transitions[] = {
	{ 0, 1, { 0.6, 0.2, 0.9, 0.5 } }, { 1, 2, { 0.7, 0.3, 1.0, 0.6 } }, { 2, 3, { 0.5, 0.5, 0.4, 0.6 } },
	{ 2, 4, { 0.3, 0.1, 0.8, 0.2 } }, { 3, 4, { 0.8, 0.4, 1.0, 0.7 } }, { 4, 5, { 0.9, 0.5, 1.0, 0.8 } },
};

static sere_markov_chain seasonal_chain( void )
{
	sere_markov_chain c;
	c.state_count = STATES;
	c.stay = stay_corners;
	c.transition_count = (int32_t) ( sizeof( seasonal_transitions ) / sizeof( seasonal_transitions[0] ) );
	c.transitions = seasonal_transitions;
	c.cold = 0.0;
	c.warm = 25.0;
	c.dry = 30.0;
	c.wet = 90.0;
	return c;
}

Test( markov, rows_sum_to_one_for_any_weather )
{
	sere_markov_chain c = seasonal_chain();
	double P[STATES * STATES];
	/* Far beyond the corners too: they act like the nearest corner. */
	for ( double T = -40.0; T <= 60.0; T += 0.7 )
	{
		for ( double H = -20.0; H <= 130.0; H += 1.3 )
		{
			cr_assert_eq( sere_markov_matrix( &c, T, H, P ), SERE_OK );
			for ( int i = 0; i < STATES; ++i )
			{
				double sum = 0.0;
				for ( int j = 0; j < STATES; ++j )
				{
					cr_assert( P[i * STATES + j] >= 0.0 && P[i * STATES + j] <= 1.0 );
					sum += P[i * STATES + j];
				}
				/* A row is at most 8 products and a division in double: 1e-12 is far above the
				 * rounding (~1e-15) and far below any real error. */
				cr_assert( fabs( sum - 1.0 ) <= 1e-12, "row %d at T=%g H=%g sums to %.17g", i, T, H, sum );
			}
		}
	}
	/* Random chains with random corner values, including exact zeros and ones. */
	double stay[4 * 12];
	sere_markov_transition tr[24];
	for ( int trial = 0; trial < 200; ++trial )
	{
		uint64_t key = sere_random_key( 7, (uint64_t) trial );
		uint64_t counter = 0;
		sere_markov_chain r = { 0 };
		r.state_count = 2 + (int32_t) ( sere_random_u64( key, counter++ ) % 11 );
		for ( int k = 0; k < 4 * r.state_count; ++k )
		{
			uint64_t u = sere_random_u64( key, counter++ );
			stay[k] = u % 7 == 0 ? 0.0 : ( u % 7 == 1 ? 1.0 : (double) ( u >> 11 ) / 9007199254740992.0 );
		}
		int n = 0;
		for ( int i = 0; i < r.state_count; ++i )
		{
			for ( int j = 0; j < r.state_count && n < 24; ++j )
			{
				uint64_t u = sere_random_u64( key, counter++ );
				if ( i != j && u % 4 == 0 )
				{
					tr[n].from = i;
					tr[n].to = j;
					for ( int q = 0; q < 4; ++q )
					{
						uint64_t v = sere_random_u64( key, counter++ );
						tr[n].weight[q] = v % 5 == 0 ? 0.0 : (double) ( v >> 11 ) / 9007199254740992.0;
					}
					++n;
				}
			}
		}
		r.stay = stay;
		r.transitions = tr;
		r.transition_count = n;
		r.cold = -5.0;
		r.warm = 30.0;
		r.dry = 0.0;
		r.wet = 100.0;
		if ( sere_markov_validate( &r ) != SERE_OK )
		{
			continue; /* more than 7 successors drawn for one state */
		}
		double Q[12 * 12];
		for ( double T = -10.0; T <= 35.0; T += 4.5 )
		{
			for ( double H = -5.0; H <= 105.0; H += 11.0 )
			{
				cr_assert_eq( sere_markov_matrix( &r, T, H, Q ), SERE_OK );
				for ( int i = 0; i < r.state_count; ++i )
				{
					double sum = 0.0;
					for ( int j = 0; j < r.state_count; ++j )
					{
						cr_assert( Q[i * r.state_count + j] >= 0.0 );
						sum += Q[i * r.state_count + j];
					}
					cr_assert( fabs( sum - 1.0 ) <= 1e-12, "random chain %d row %d sums to %.17g", trial, i, sum );
				}
			}
		}
	}
}

Test( markov, corners_are_the_users_constants )
{
	sere_markov_chain c = seasonal_chain();
	double P[STATES * STATES];
	/* Wet and cold: T at the cold corner, H at the wet corner (Tang Eq. 5–6). */
	cr_assert_eq( sere_markov_matrix( &c, 0.0, 90.0, P ), SERE_OK );
	cr_assert_float_eq( P[0 * STATES + 0], 0.90, 1e-15 );
	cr_assert_float_eq( P[0 * STATES + 1], 0.10, 1e-15 );
	/* State 2 has two successors with constants 0.5 and 0.3 at wet-cold: (1 − 0.8) split 5:3. */
	cr_assert_float_eq( P[2 * STATES + 2], 0.80, 1e-15 );
	cr_assert_float_eq( P[2 * STATES + 3], 0.20 * 0.5 / 0.8, 1e-15 );
	cr_assert_float_eq( P[2 * STATES + 4], 0.20 * 0.3 / 0.8, 1e-15 );
	/* Dry and warm. */
	cr_assert_eq( sere_markov_matrix( &c, 25.0, 30.0, P ), SERE_OK );
	cr_assert_float_eq( P[2 * STATES + 3], 0.15 * 0.6 / 0.8, 1e-15 );
	cr_assert_float_eq( P[2 * STATES + 4], 0.15 * 0.2 / 0.8, 1e-15 );
	/* The centre of the rectangle is the mean of the four corners (bilinear). */
	cr_assert_eq( sere_markov_matrix( &c, 12.5, 60.0, P ), SERE_OK );
	cr_assert_float_eq( P[0], ( 0.90 + 0.99 + 0.80 + 0.95 ) / 4.0, 1e-15 );
	const double corner[4] = { 1.0, 2.0, 3.0, 4.0 };
	cr_assert_float_eq( sere_markov_bilinear( corner, 0.25, 0.5 ),
						0.5 * ( 0.75 * 3 + 0.25 * 4 ) + 0.5 * ( 0.75 * 1 + 0.25 * 2 ), 1e-15 );
	/* The state without successors keeps every leaf, whatever its stay constants. */
	cr_assert_eq( P[5 * STATES + 5], 1.0 );
}

Test( markov, bad_chains_and_weather )
{
	double stay[4 * STATES];
	memcpy( stay, stay_corners, sizeof( stay ) );
	sere_markov_transition tr[8];
	memcpy( tr, seasonal_transitions, sizeof( seasonal_transitions ) );
	sere_markov_chain c = seasonal_chain();
	c.stay = stay;
	c.transitions = tr;
	double P[STATES * STATES];
	cr_assert_eq( sere_markov_validate( &c ), SERE_OK );

	stay[3] = 1.5;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	stay[3] = NAN;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_markov_matrix( &c, 10.0, 50.0, P ), SERE_ERR_NONFINITE );
	stay[3] = 0.95;

	tr[0].to = 0; /* to itself */
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	tr[0].to = STATES; /* out of range */
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	tr[0].to = 1;
	tr[1].weight[2] = -0.1;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	tr[1].weight[2] = 1.0;

	c.transition_count = 7;
	tr[6] = tr[0]; /* the same transition twice */
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	c.transition_count = 6;

	c.warm = c.cold;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	c.warm = 25.0;
	c.wet = INFINITY;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_NONFINITE );
	c.wet = 90.0;
	c.state_count = SERE_MARKOV_MAX_STATES + 1;
	cr_expect_eq( sere_markov_validate( &c ), SERE_ERR_ARGUMENT );
	c.state_count = STATES;

	cr_expect_eq( sere_markov_matrix( &c, NAN, 50.0, P ), SERE_ERR_NONFINITE );
	sere_markov_day day;
	cr_expect_eq( sere_markov_day_prepare( &c, 10.0, NAN, &day ), SERE_ERR_NONFINITE );

	/* Eight successors of one state: one more than SERE_MARKOV_MAX_OUTCOMES − 1. */
	double stay9[4 * 9] = { 0 };
	sere_markov_transition fan[8];
	for ( int k = 0; k < 8; ++k )
	{
		fan[k] = ( sere_markov_transition ){ 0, k + 1, { 0.5, 0.5, 0.5, 0.5 } };
	}
	sere_markov_chain wide = { 9, stay9, 8, fan, 0.0, 1.0, 0.0, 1.0 };
	cr_expect_eq( sere_markov_validate( &wide ), SERE_ERR_ARGUMENT );
	wide.transition_count = 7;
	cr_expect_eq( sere_markov_validate( &wide ), SERE_OK );
}

Test( markov, day_tables_cover_every_draw )
{
	sere_markov_chain c = seasonal_chain();
	sere_markov_day day;
	cr_assert_eq( sere_markov_day_prepare( &c, 8.0, 55.0, &day ), SERE_OK );
	for ( int s = 0; s < 256; ++s )
	{
		for ( int k = 1; k < SERE_MARKOV_MAX_OUTCOMES; ++k )
		{
			cr_assert( day.threshold[s][k] >= day.threshold[s][k - 1] );
		}
		/* 2³¹ is never reached by a 31-bit draw: the last slot always closes the row. */
		cr_assert_eq( day.threshold[s][SERE_MARKOV_MAX_OUTCOMES - 1], 0x80000000u );
	}
	double P[STATES * STATES];
	cr_assert_eq( sere_markov_matrix( &c, 8.0, 55.0, P ), SERE_OK );
	/* The stay slot's width is P_ii rounded to a multiple of 2⁻³¹. */
	for ( int s = 0; s < STATES - 1; ++s )
	{
		cr_assert( fabs( day.threshold[s][0] / 2147483648.0 - P[s * STATES + s] ) <= 0.5 / 2147483648.0 );
	}
}

/* Upper 0.1% points of the chi-square distribution for 1..10 degrees of freedom. */
static const double chi2_999[11] = {
	0.0, 10.828, 13.816, 16.266, 18.467, 20.515, 22.458, 24.322, 26.124, 27.877, 29.588
};

/* Chi-square statistic of counts against n·pi over the cells with pi > 0; *df = cells − 1. */
static double chi_square( const int64_t* counts, const double* pi, int cells, int64_t n, int* df )
{
	double chi = 0.0;
	int used = 0;
	for ( int s = 0; s < cells; ++s )
	{
		if ( pi[s] > 0.0 )
		{
			double expected = (double) n * pi[s];
			double d = (double) counts[s] - expected;
			chi += d * d / expected;
			++used;
		}
		else
		{
			cr_assert_eq( counts[s], 0, "state %d is unreachable but holds %ld leaves", s, (long) counts[s] );
		}
	}
	*df = used - 1;
	return chi;
}

/* 10⁶ leaves, all green on day 0, through k = 24 days of a cooling, drying autumn; the counts
 * after the last day against the chain's exact distribution. */
Test( markov, population_matches_the_exact_distribution, .timeout = 60 )
{
	const int64_t n = 1000000;
	const int days = 24;
	sere_markov_chain c = seasonal_chain();
	uint8_t* states = malloc( (size_t) n );
	cr_assert_not_null( states );
	const uint64_t seeds[3] = { 1, 2013, 0xC0FFEEull };
	for ( int trial = 0; trial < 3; ++trial )
	{
		memset( states, 0, (size_t) n );
		double pi[STATES] = { 1.0, 0, 0, 0, 0, 0 }, previous[STATES];
		int64_t counts[STATES];
		for ( int d = 0; d < days; ++d )
		{
			double T = 22.0 - 1.0 * d, H = 80.0 - 2.0 * d;
			double P[STATES * STATES], next[STATES];
			sere_markov_day day;
			cr_assert_eq( sere_markov_matrix( &c, T, H, P ), SERE_OK );
			cr_assert_eq( sere_markov_day_prepare( &c, T, H, &day ), SERE_OK );
			sere_markov_propagate( P, STATES, pi, next );
			memcpy( previous, pi, sizeof( pi ) );
			memcpy( pi, next, sizeof( pi ) );
			cr_assert_eq( sere_markov_advance( &day, states, n, 0, seeds[trial], d, counts, 0 ), SERE_OK );
		}
		int df;
		double chi = chi_square( counts, pi, STATES, n, &df );
		cr_assert_eq( df, 5 );
		/* Deterministic for the seed; a correct sampler exceeds the 0.1% point with probability
		 * 0.001 per seed, a wrong one (next test line) by orders of magnitude. */
		cr_expect( chi < chi2_999[df], "seed %lu: chi-square %.2f with %d degrees of freedom >= %.3f",
				   (unsigned long) seeds[trial], chi, df, chi2_999[df] );
		/* The same counts against the distribution one day earlier must fail clearly, so the
		 * test can tell a right sampler from a slightly wrong one. */
		int df_wrong;
		double chi_wrong = chi_square( counts, previous, STATES, n, &df_wrong );
		cr_expect( chi_wrong > 10.0 * chi2_999[df_wrong], "one day off only gives chi-square %.1f", chi_wrong );
	}
	free( states );
}

Test( markov, identical_for_any_thread_count_and_split )
{
	const int64_t n = 200003; /* not a multiple of the block size */
	sere_markov_chain c = seasonal_chain();
	uint8_t* one = calloc( (size_t) n, 1 );
	uint8_t* two = calloc( (size_t) n, 1 );
	uint8_t* split = calloc( (size_t) n, 1 );
	cr_assert( one != NULL && two != NULL && split != NULL );
	int64_t counts_one[STATES], counts_two[STATES], a[STATES], b[STATES];
	for ( int d = 0; d < 15; ++d )
	{
		sere_markov_day day;
		cr_assert_eq( sere_markov_day_prepare( &c, 20.0 - d, 70.0 - 3.0 * d, &day ), SERE_OK );
		omp_set_num_threads( 1 );
		cr_assert_eq( sere_markov_advance( &day, one, n, 0, 99, d, counts_one, 0 ), SERE_OK );
		omp_set_num_threads( 2 );
		cr_assert_eq( sere_markov_advance( &day, two, n, 0, 99, d, counts_two, 0 ), SERE_OK );
		/* The same population in two uneven pieces. */
		cr_assert_eq( sere_markov_advance( &day, split, 70001, 0, 99, d, a, 0 ), SERE_OK );
		cr_assert_eq( sere_markov_advance( &day, split + 70001, n - 70001, 70001, 99, d, b, 0 ), SERE_OK );
		for ( int s = 0; s < STATES; ++s )
		{
			cr_assert_eq( counts_one[s], counts_two[s] );
			cr_assert_eq( counts_one[s], a[s] + b[s] );
		}
	}
	cr_assert_eq( memcmp( one, two, (size_t) n ), 0 );
	cr_assert_eq( memcmp( one, split, (size_t) n ), 0 );
	int64_t counted[STATES];
	cr_assert_eq( sere_markov_count( one, n, STATES, counted, 0 ), SERE_OK );
	cr_assert_eq( memcmp( counted, counts_one, sizeof( counted ) ), 0 );
	/* Leaves really moved: the chain is not stuck in state 0. */
	cr_assert( counts_one[0] < n / 2 );
	omp_set_num_threads( 1 );
	free( one );
	free( two );
	free( split );
}

Test( markov, bad_leaf_states_are_reported_and_kept )
{
	sere_markov_chain c = seasonal_chain();
	sere_markov_day day;
	cr_assert_eq( sere_markov_day_prepare( &c, 5.0, 40.0, &day ), SERE_OK );
	uint8_t states[1000] = { 0 };
	states[17] = STATES;
	states[500] = 200;
	int64_t counts[STATES];
	cr_expect_eq( sere_markov_advance( &day, states, 1000, 0, 3, 0, counts, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( states[17], STATES );
	cr_expect_eq( states[500], 200 );
	cr_expect_eq( sere_markov_count( states, 1000, STATES, counts, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_markov_advance( &day, states, -1, 0, 3, 0, counts, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_markov_advance( NULL, states, 10, 0, 3, 0, counts, 0 ), SERE_ERR_ARGUMENT );
}
