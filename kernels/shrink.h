/* sere — spring rest lengths from particle masses (Sec. 5.1, Eq. 11–12). */
#pragma once

#include "base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_shrink_params
{
	double sigma_vein, sigma_surf; /* σ of Eq. 12 for vein and other springs (negative expands, Fig. 15a) */
	double alpha;				   /* exponent of Eq. 12 (≈ 1.3, Sec. 5.1) */
	double m_min;				   /* a spring stops when a particle's mass is below it */
	double min_length_ratio;	   /* ... or when l would fall below this fraction of l⁰ */
} sere_shrink_params;

/* For springs [first, first + count): v_rel = (m_a + m_b)/(m⁰_a + m⁰_b) (Eq. 11) and
 * l = l⁰ (1 − σ (1 − v_rel)^α) (Eq. 12), σ chosen by the SERE_SPRING_VEIN bit of kind. A
 * spring whose particle mass is below m_min, or whose new length is below
 * min_length_ratio · l⁰, keeps its current rest length (Sec. 5.1 stop rule). When water is
 * gained (v_rel > 1) the base 1 − v_rel is negative; it is taken as 0, so supplied water
 * restores at most the rest length. */
sere_status sere_shrink( const int32_t* a, const int32_t* b, const uint8_t* kind, const float* rest0, float* rest,
						 int32_t first, int32_t count, const double* m, const double* m0,
						 const sere_shrink_params* params );

#ifdef __cplusplus
}
#endif
