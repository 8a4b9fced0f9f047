/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "drying/shrink.h"

#include "core/internal/team.h"

#include "drying/layers.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ln 2 split so that n · LN2_HI is exact for |n| < 2^11 (Cody–Waite reduction). */
#define LN2_HI	6.93147180369123816490e-01
#define LN2_LO	1.90821492927058770002e-10
#define INV_LN2 1.44269504088896338700e+00
/* The bits of √2 rounded down: mantissas in [1, 2) compare like their bit patterns. */
#define SQRT2_BITS 0x3FF6A09E667F3BCCull
/* Adding and subtracting 1.5 · 2^52 rounds a double below 2^51 to the nearest integer. */
#define ROUND_MAGIC 6755399441055744.0

/* c[0] x^(count−1) + … + c[count−1] by Horner's rule, highest power first, each step one fused
 * multiply-add (C's fma: one rounding wherever it runs, so the bits do not depend on the target). */
static inline double horner( const double* c, int count, double x )
{
	double sum = c[0];
	for ( int k = 1; k < count; ++k )
	{
		sum = fma( sum, x, c[k] );
	}
	return sum;
}

/* x^alpha for x in [2^-53, 1] and alpha > 0 as exp(alpha ln x), built from operations gcc
 * turns into SIMD lanes (bit casts, integer/double conversions, polynomials; no libm call, no
 * branch). Relative error at most 2e-13 over that range for alpha ≤ 10 (shrink.h): the series
 * stop where the length, l⁰ (1 − σ x^α) rounded to float, can no longer tell. */
static inline double pow_unit( double x, double alpha )
{
	/* x = mantissa · 2^e with the mantissa in [√½, √2), so ln of it converges fast below. The
	 * split is done on the bits (halving = one less in the exponent field): a floating-point
	 * select here would be sunk into a branch, which -ftrapping-math forbids vectorizing. */
	uint64_t bits;
	memcpy( &bits, &x, sizeof( bits ) );
	uint64_t mantissa_bits = ( bits & 0x000FFFFFFFFFFFFFull ) | 0x3FF0000000000000ull;
	uint64_t high = mantissa_bits > SQRT2_BITS;
	mantissa_bits -= high << 52;
	/* The exponent e = (bits >> 52) − 1023 + high as a double, through the bits of 2^52 + that
	 * count (< 2^12) less 2^52, both exact: AVX2 has no int64 → double conversion, and one such
	 * conversion kept gcc from vectorizing the whole loop. */
	uint64_t count_bits = 0x4330000000000000ull | ( ( bits >> 52 ) + high );
	double count;
	memcpy( &count, &count_bits, sizeof( count ) );
	double de = ( count - 4503599627370496.0 ) - 1023.0;
	double mantissa;
	memcpy( &mantissa, &mantissa_bits, sizeof( mantissa ) );

	/* ln m = 2 atanh t with t = (m − 1)/(m + 1), |t| ≤ 0.1716: the odd series to t^15 leaves
	 * a truncation below 0.1716^17/17 ≈ 6e-15 relative, far under the float the length is
	 * stored in. */
	double t = ( mantissa - 1.0 ) / ( mantissa + 1.0 );
	double t2 = t * t;
	static const double atanh_series[] = { 1.0 / 15.0, 1.0 / 13.0, 1.0 / 11.0, 1.0 / 9.0,
										   1.0 / 7.0,  1.0 / 5.0,  1.0 / 3.0,  1.0 };
	double series = horner( atanh_series, 8, t2 );
	double ln_mantissa = 2.0 * t * series;
	double y = alpha * ( de * LN2_HI + ( de * LN2_LO + ln_mantissa ) );

	/* exp(y) = 2^n e^r with n the integer nearest y/ln 2 and |r| ≤ ln2/2. n is read from the
	 * bits of the rounded sum (its low 52 bits hold n + 2^51 while |n| < 2^51) and clamped as
	 * an integer, so lanes whose result is discarded (any x, NaN included) convert nothing out
	 * of range. Below 2^-1022 the result saturates at about 2^-1022, far below anything that
	 * moves l⁰ (1 − σ x^α) in float. */
	double shifted = y * INV_LN2 + ROUND_MAGIC;
	double n = shifted - ROUND_MAGIC;
	double r = ( y - n * LN2_HI ) - n * LN2_LO;
	/* Taylor to r^11: the remainder is below 0.347^12/12! ≈ 7e-15. */
	static const double exp_series[] = {
		1.0 / 39916800.0, 1.0 / 3628800.0, 1.0 / 362880.0, 1.0 / 40320.0, 1.0 / 5040.0, 1.0 / 720.0,
		1.0 / 120.0,	  1.0 / 24.0,	   1.0 / 6.0,	   0.5,			  1.0,			1.0
	};
	double p = horner( exp_series, 12, r );
	uint64_t shifted_bits;
	memcpy( &shifted_bits, &shifted, sizeof( shifted_bits ) );
	int64_t k = (int64_t) ( shifted_bits & 0x000FFFFFFFFFFFFFull ) - 0x0008000000000000ll;
	k = k < -1022 ? -1022 : k;
	k = k > 1023 ? 1023 : k;
	uint64_t scale_bits = (uint64_t) ( k + 1023 ) << 52;
	double scale;
	memcpy( &scale, &scale_bits, sizeof( scale ) );
	return p * scale;
}

/* keep ? kept : updated on the bits, for the same reason as in pow_unit. */
static inline float select_float( int keep, float kept, float updated )
{
	uint32_t a, b;
	memcpy( &a, &kept, sizeof( a ) );
	memcpy( &b, &updated, sizeof( b ) );
	uint32_t mask = 0u - (uint32_t) keep;
	uint32_t bits = ( a & mask ) | ( b & ~mask );
	float result;
	memcpy( &result, &bits, sizeof( result ) );
	return result;
}

sere_status sere_shrink( const int32_t* a, const int32_t* b, const uint8_t* kind, const float* rest0, float* rest,
						 int32_t first, int32_t count, const double* m, const double* m0,
						 const sere_shrink_params* params, int32_t threads )
{
	if ( params == NULL || !( params->alpha > 0.0 && params->alpha <= DBL_MAX ) ||
		 !( params->sigma_vein >= -DBL_MAX && params->sigma_vein <= DBL_MAX ) ||
		 !( params->sigma_surf >= -DBL_MAX && params->sigma_surf <= DBL_MAX ) ||
		 !( params->min_length_ratio >= 0.0 && params->min_length_ratio <= 1.0 ) || params->m_min != params->m_min ||
		 first < 0 || count < 0 || (int64_t) first + count > INT32_MAX || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( count == 0 )
	{
		return SERE_OK;
	}
	if ( a == NULL || b == NULL || kind == NULL || rest0 == NULL || rest == NULL || m == NULL || m0 == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	const double alpha = params->alpha, m_min = params->m_min, ratio = params->min_length_ratio;
	const double sigma_vein = params->sigma_vein, sigma_surf = params->sigma_surf;
	const int32_t end = first + count;
	int bad = 0;
	/* One SIMD lane per spring: the masses are gathered (double), everything else is
	 * contiguous; no lane depends on another, so any split over threads gives the same bits.
	 * Every value is computed in every lane and then selected (&, | rather than &&, ||), so
	 * the loop has no branch for the vectorizer to refuse under -ftrapping-math. */
#pragma omp parallel for simd num_threads( sere_team_for( threads ) ) schedule( static ) reduction( | : bad )
	for ( int32_t s = first; s < end; ++s )
	{
		double ma = m[a[s]], mb = m[b[s]];
		double v_rel = ( ma + mb ) / ( m0[a[s]] + m0[b[s]] ); /* Jeong Eq. 11 */
		/* The base 1 − v_rel lies in [2^-53, 1] when v_rel is in [0, 1); gained water
		 * (v_rel ≥ 1), negative masses and NaN clamp it to 0 (see shrink.h). */
		double loss = 1.0 - v_rel;
		int shrinking = ( v_rel < 1.0 ) & ( v_rel >= 0.0 );
		double power = pow_unit( fabs( loss ), alpha );
		uint64_t power_bits;
		memcpy( &power_bits, &power, sizeof( power_bits ) );
		power_bits &= (uint64_t) 0 - (uint64_t) shrinking;
		memcpy( &power, &power_bits, sizeof( power ) );
		double sigma = ( kind[s] & SERE_SPRING_VEIN ) ? sigma_vein : sigma_surf;
		double l0 = (double) rest0[s];
		double length = l0 * ( 1.0 - sigma * power ); /* Jeong Eq. 12 */
		/* the length is stored as a float: one past FLT_MAX would be written as infinity */
		int finite = ( v_rel <= DBL_MAX ) & ( v_rel >= -DBL_MAX ) & ( length <= FLT_MAX ) & ( length >= -FLT_MAX );
		int stopped = ( ma < m_min ) | ( mb < m_min ) | ( length < ratio * l0 ) | !finite;
		bad |= !finite;
		rest[s] = select_float( stopped, rest[s], (float) length );
	}
	return bad ? SERE_ERR_NONFINITE : SERE_OK;
}
