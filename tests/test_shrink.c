/* Spring rest lengths from masses (Sec. 5.1, Jeong Eq. 11–12). */
#include "drying/layers.h"
#include "drying/shrink.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static sere_shrink_params shrink_params( double sigma_vein, double sigma_surf, double alpha )
{
	sere_shrink_params params = {
		.sigma_vein = sigma_vein, .sigma_surf = sigma_surf, .alpha = alpha, .m_min = 0.1, .min_length_ratio = 0.2
	};
	return params;
}

/* Distance in float ulps (same sign assumed: both are lengths). */
static int64_t ulps( float u, float v )
{
	int32_t a, b;
	memcpy( &a, &u, sizeof( a ) );
	memcpy( &b, &v, sizeof( b ) );
	return llabs( (long long) a - (long long) b );
}

Test( shrink, eq12_by_hand )
{
	/* Three springs, each between two particles of mass 0.6 and initial mass 1:
	 * v_rel = (0.6 + 0.6)/(1 + 1) = 0.6 (Jeong Eq. 11), so 1 − v_rel = 0.4. */
	int32_t a[3] = { 0, 2, 4 }, b[3] = { 1, 3, 5 };
	uint8_t kind[3] = { SERE_SPRING_T, SERE_SPRING_V, SERE_SPRING_L };
	float rest0[3] = { 2.0f, 2.0f, 2.0f }, rest[3];
	double m0[6] = { 1.0, 1.0, 1.0, 1.0, 1.0, 1.0 };
	double m[6] = { 0.6, 0.6, 0.6, 0.6, 0.6, 0.6 };
	/* α = 1: l = 2 (1 − 0.5 · 0.4) = 1.6. α = 2: l = 2 (1 − 0.5 · 0.16) = 1.84. α = 1.3:
	 * 0.4^1.3 = exp(1.3 ln 0.4) = exp(1.3 · −0.9162907318741551) = exp(−1.1911779514364016)
	 * = 0.3038631171729496, l = 2 (1 − 0.5 · 0.30386...) = 1.6961368828270504. The expected
	 * values are rounded to float once, as the kernel rounds its double result: tolerance one
	 * ulp for the double-precision power (see shrink.h). */
	const double alphas[3] = { 1.0, 2.0, 1.3 };
	const double expected[3] = { 1.6, 1.84, 1.6961368828270504 };
	for ( int k = 0; k < 3; ++k )
	{
		sere_shrink_params params = shrink_params( 0.5, 0.5, alphas[k] );
		memcpy( rest, rest0, sizeof( rest ) );
		cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &params, 0 ), SERE_OK );
		for ( int s = 0; s < 3; ++s )
		{
			cr_expect_leq( ulps( rest[s], (float) expected[k] ), 1, "alpha %g spring %d: %.9g vs %.9g", alphas[k], s,
						   rest[s], expected[k] );
		}
	}
}

Test( shrink, vein_springs_use_sigma_vein )
{
	int32_t a[4] = { 0, 0, 0, 0 }, b[4] = { 1, 1, 1, 1 };
	uint8_t kind[4] = { SERE_SPRING_T | SERE_SPRING_VEIN, SERE_SPRING_T, SERE_SPRING_V | SERE_SPRING_VEIN,
						SERE_SPRING_L };
	float rest0[4] = { 1.0f, 1.0f, 1.0f, 1.0f }, rest[4];
	double m0[2] = { 1.0, 1.0 }, m[2] = { 0.5, 0.5 };
	/* α = 1, 1 − v_rel = 0.5: σ_vein = 1 gives 0.5, σ_surf = 0.2 gives 0.9; one ulp for the
	 * double-precision power rounded to float. */
	sere_shrink_params params = shrink_params( 1.0, 0.2, 1.0 );
	params.min_length_ratio = 0.0;
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 4, m, m0, &params, 0 ), SERE_OK );
	const float expected[4] = { 0.5f, 0.9f, 0.5f, 0.9f };
	for ( int s = 0; s < 4; ++s )
	{
		cr_expect_leq( ulps( rest[s], expected[s] ), 1, "spring %d: %.9g", s, rest[s] );
	}
}

Test( shrink, stop_rules )
{
	int32_t a[4] = { 0, 2, 4, 6 }, b[4] = { 1, 3, 5, 7 };
	uint8_t kind[4] = { SERE_SPRING_T, SERE_SPRING_T, SERE_SPRING_T, SERE_SPRING_T };
	float rest0[4] = { 1.0f, 1.0f, 1.0f, 1.0f }, rest[4] = { 0.9f, 0.9f, 0.9f, 0.9f };
	double m0[8] = { 1, 1, 1, 1, 1, 1, 1, 1 };
	/* σ = 1, α = 1, so l = v_rel l⁰. Spring 0: one end below m_min = 0.1 (v_rel = 0.5).
	 * Spring 1: v_rel = 0.5. Spring 2: v_rel = 0.2, below the ratio 0.3. Spring 3: v_rel = 0.35,
	 * just above it. Lengths computed in double and rounded once: one ulp. */
	double m[8] = { 0.05, 0.95, 0.5, 0.5, 0.2, 0.2, 0.35, 0.35 };
	sere_shrink_params params = shrink_params( 1.0, 1.0, 1.0 );
	params.min_length_ratio = 0.3;
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 4, m, m0, &params, 0 ), SERE_OK );
	cr_expect_eq( rest[0], 0.9f, "below m_min: keeps its current length" );
	cr_expect_leq( ulps( rest[1], 0.5f ), 1, "%.9g", rest[1] );
	cr_expect_eq( rest[2], 0.9f, "below the length ratio: keeps its current length" );
	cr_expect_leq( ulps( rest[3], 0.35f ), 1, "above the ratio: shrinks, %.9g", rest[3] );
}

Test( shrink, negative_sigma_expands_and_gained_water_restores )
{
	int32_t a[2] = { 0, 2 }, b[2] = { 1, 3 };
	uint8_t kind[2] = { SERE_SPRING_T | SERE_SPRING_VEIN, SERE_SPRING_V };
	float rest0[2] = { 1.0f, 1.0f }, rest[2] = { 1.0f, 1.0f };
	double m0[4] = { 1, 1, 1, 1 };
	double dry[4] = { 0.5, 0.5, 0.5, 0.5 };
	/* σ < 0 (Fig. 15a): l = l⁰ (1 + 0.4 · 0.5) = 1.2. */
	sere_shrink_params params = shrink_params( -0.4, 0.4, 1.0 );
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 2, dry, m0, &params, 0 ), SERE_OK );
	cr_expect_leq( ulps( rest[0], 1.2f ), 1, "%.9g", rest[0] );
	cr_expect_leq( ulps( rest[1], 0.8f ), 1, "%.9g", rest[1] );
	/* More water than the fresh leaf (v_rel = 1.5): the base clamps to 0, both back to l⁰. */
	double wet[4] = { 1.5, 1.5, 1.5, 1.5 };
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 2, wet, m0, &params, 0 ), SERE_OK );
	cr_expect_eq( rest[0], 1.0f );
	cr_expect_eq( rest[1], 1.0f );
}

Test( shrink, simd_lanes_match_the_libm_formula )
{
	/* 4099 springs (not a multiple of the vector width, so tails run too) over random masses;
	 * the kernel's vectorized power against the scalar formula with libm's pow, both in double
	 * and rounded to float once: equal or one ulp apart (the power's relative error is at most
	 * 2e-13, shrink.h, far under half a float ulp except next to a rounding tie). */
	enum
	{
		COUNT = 4099,
		PARTICLES = 1000
	};
	int32_t* a = malloc( sizeof( int32_t ) * COUNT );
	int32_t* b = malloc( sizeof( int32_t ) * COUNT );
	uint8_t* kind = malloc( COUNT );
	float* rest0 = malloc( sizeof( float ) * COUNT );
	float* rest = malloc( sizeof( float ) * COUNT );
	double* m = malloc( sizeof( double ) * PARTICLES );
	double* m0 = malloc( sizeof( double ) * PARTICLES );
	srand( 12345 );
	for ( int i = 0; i < PARTICLES; ++i )
	{
		m0[i] = 0.1 + 0.9 * rand() / (double) RAND_MAX;
		m[i] = m0[i] * ( 0.15 + 1.0 * rand() / (double) RAND_MAX ); /* some above m⁰: gained water */
	}
	for ( int s = 0; s < COUNT; ++s )
	{
		a[s] = rand() % PARTICLES;
		b[s] = ( a[s] + 1 + rand() % ( PARTICLES - 1 ) ) % PARTICLES;
		kind[s] = (uint8_t) ( ( s % 3 ) | ( s % 5 == 0 ? SERE_SPRING_VEIN : 0 ) );
		rest0[s] = 0.01f + (float) rand() / (float) RAND_MAX;
		rest[s] = rest0[s];
	}
	const double alphas[3] = { 1.3, 0.7, 3.0 };
	for ( int k = 0; k < 3; ++k )
	{
		sere_shrink_params params = shrink_params( 0.9, 0.4, alphas[k] );
		params.min_length_ratio = 0.0;
		params.m_min = 0.0;
		memcpy( rest, rest0, sizeof( float ) * COUNT );
		cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, COUNT, m, m0, &params, 0 ), SERE_OK );
		int64_t worst = 0;
		for ( int s = 0; s < COUNT; ++s )
		{
			double v_rel = ( m[a[s]] + m[b[s]] ) / ( m0[a[s]] + m0[b[s]] );
			double sigma = ( kind[s] & SERE_SPRING_VEIN ) ? params.sigma_vein : params.sigma_surf;
			double power = v_rel < 1.0 ? pow( 1.0 - v_rel, alphas[k] ) : 0.0;
			float expected = (float) ( (double) rest0[s] * ( 1.0 - sigma * power ) );
			int64_t d = ulps( rest[s], expected );
			worst = d > worst ? d : worst;
		}
		cr_expect_leq( worst, 1, "alpha %g: %lld ulps", alphas[k], (long long) worst );
	}
	free( a ), free( b ), free( kind ), free( rest0 ), free( rest ), free( m ), free( m0 );
}

Test( shrink, only_the_given_range_and_same_bits_on_any_thread_count )
{
	enum
	{
		COUNT = 1000
	};
	int32_t a[COUNT], b[COUNT];
	uint8_t kind[COUNT];
	float rest0[COUNT], one[COUNT], two[COUNT];
	double m[COUNT + 1], m0[COUNT + 1];
	for ( int i = 0; i <= COUNT; ++i )
	{
		m0[i] = 1.0, m[i] = 0.3 + 0.6 * i / (double) COUNT;
	}
	for ( int s = 0; s < COUNT; ++s )
	{
		a[s] = s, b[s] = s + 1, kind[s] = (uint8_t) ( s % 2 ? SERE_SPRING_VEIN : 0 ), rest0[s] = 1.0f;
		one[s] = two[s] = 1.0f;
	}
	sere_shrink_params params = shrink_params( 0.5, 1.5, 1.3 );
	params.min_length_ratio = 0.0;
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_shrink( a, b, kind, rest0, one, 100, 800, m, m0, &params, 0 ), SERE_OK );
	omp_set_num_threads( 2 );
	cr_assert_eq( sere_shrink( a, b, kind, rest0, two, 100, 800, m, m0, &params, 0 ), SERE_OK );
	cr_expect_eq( memcmp( one, two, sizeof( one ) ), 0 );
	cr_expect( one[99] == 1.0f && one[900] == 1.0f && one[100] < 1.0f && one[899] < 1.0f );
}

Test( shrink, bad_input )
{
	int32_t a[3] = { 0, 2, 4 }, b[3] = { 1, 3, 5 };
	uint8_t kind[3] = { 0, 0, 0 };
	float rest0[3] = { 1.0f, 1.0f, 1.0f }, rest[3] = { 0.9f, 0.9f, 0.9f };
	double m0[6] = { 1, 1, 0, 0, 1, 1 };
	double m[6] = { 0.5, NAN, 0.5, 0.5, 0.5, 0.5 };
	sere_shrink_params params = shrink_params( 1.0, 1.0, 1.0 );
	/* NaN mass and a zero m⁰ sum: those springs keep their length, the third one shrinks. */
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &params, 0 ), SERE_ERR_NONFINITE );
	cr_expect( rest[0] == 0.9f && rest[1] == 0.9f && ulps( rest[2], 0.5f ) <= 1, "%g %g %g", rest[0], rest[1],
			   rest[2] );
	sere_shrink_params bad = params;
	bad.alpha = 0.0;
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &bad, 0 ), SERE_ERR_ARGUMENT );
	bad = params, bad.sigma_surf = NAN;
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &bad, 0 ), SERE_ERR_ARGUMENT );
	bad = params, bad.min_length_ratio = 1.5;
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &bad, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, -1, m, m0, &params, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, NULL, 0 ), SERE_ERR_ARGUMENT );
	/* a σ that takes the length past FLT_MAX: not finite once stored, so kept (it was stored as
	 * infinity with SERE_OK) */
	float kept[3] = { 0.9f, 0.9f, 0.9f };
	double fine[6] = { 0.5, 0.5, 0.5, 0.5, 0.5, 0.5 }, fresh[6] = { 1, 1, 1, 1, 1, 1 };
	bad = params, bad.sigma_surf = -1e39;
	cr_expect_eq( sere_shrink( a, b, kind, rest0, kept, 0, 3, fine, fresh, &bad, 0 ), SERE_ERR_NONFINITE );
	cr_expect( kept[0] == 0.9f && kept[1] == 0.9f && kept[2] == 0.9f, "%g %g %g", kept[0], kept[1], kept[2] );
	/* first + count past INT32_MAX once wrapped to an empty range and returned SERE_OK */
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, INT32_MAX - 1, 3, m, m0, &params, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_shrink( a, b, kind, rest0, rest, 0, 0, m, m0, &params, 0 ), SERE_OK );
}
