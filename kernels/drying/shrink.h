/* sere — spring rest lengths from particle masses (Sec. 5.1, Jeong Eq. 11–12). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_shrink_params
{
	double sigma_vein, sigma_surf; /* σ of Jeong Eq. 12 for vein and other springs (negative expands, Fig. 15a) */
	double alpha;				   /* exponent of Jeong Eq. 12 (≈ 1.3, Sec. 5.1), > 0 */
	double m_min;				   /* a spring stops when a particle's mass is below it */
	double min_length_ratio;	   /* ... or when l would fall below this fraction of l⁰, in [0, 1] */
} sere_shrink_params;

/* For springs [first, first + count): v_rel = (m_a + m_b)/(m⁰_a + m⁰_b) (Jeong Eq. 11) and
 * l = l⁰ (1 − σ (1 − v_rel)^α) (Jeong Eq. 12), σ chosen by the SERE_SPRING_VEIN bit of kind.
 *
 * Stop rule (Sec. 5.1): a spring whose particle mass is below m_min, or whose new length is
 * below min_length_ratio · l⁰, keeps its current rest length.
 *
 * Water gained past the fresh state (v_rel > 1) makes the base 1 − v_rel negative, where a
 * real power is undefined. It is taken as 0, so l returns to l⁰ and goes no further: m⁰ is the
 * fresh, fully turgid leaf whose cell walls bound its size, and the odd extension
 * −σ |1 − v_rel|^α would make a spring fed by a water supply (Fig. 9) grow without bound
 * (σ_surf = 10 for grass, Table 2).
 *
 * The power is evaluated in double by an exp/log pair written for SIMD lanes (libm's pow does
 * not vectorize without -ffast-math) with series cut where the float length can no longer
 * tell: its relative error against libm's pow is at most 2e-14 for α ≤ 1, 6e-14 for α = 3 and
 * 2e-13 for α = 10 (x over [2^-53, 1]), far under the float rounding of l, so l equals the float
 * rounding of the libm formula or is one ulp off.
 * SERE_ERR_NONFINITE when v_rel or a length is not finite (NaN or infinite masses, a zero
 * m⁰ sum); those springs keep their rest length and the others are updated. On `threads` threads
 * (core/base.h; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). SERE_ERR_ARGUMENT also for a NULL
 * array or params, a negative first or count, first + count past INT32_MAX, or a parameter out
 * of its range (sere_shrink_params). */
sere_status sere_shrink( const int32_t* a, const int32_t* b, const uint8_t* kind, const float* rest0, float* rest,
						 int32_t first, int32_t count, const double* m, const double* m0,
						 const sere_shrink_params* params, int32_t threads );

#ifdef __cplusplus
}
#endif
