/* sere reference twin — serial Gauss–Seidel PBD over springs in their natural order on an
 * array-of-structs particle layout, written the straightforward way (the baseline). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_ref_particle
{
	float x, y, z;
	float inv_m;
} sere_ref_particle;

typedef struct sere_ref_spring
{
	int32_t a, b;
	float rest;
} sere_ref_spring;

/* Sweeps until max |C/l| < tolerance or max_iterations; returns the sweeps run. */
int32_t sere_pbd_ref_project( sere_ref_particle* particles, const sere_ref_spring* springs, int32_t spring_count,
							  float stiffness, float tolerance, int32_t max_iterations, float* max_strain );

/* ‖h‖₂, ‖M (x − x̃)‖₂ and ‖∇C(x)ᵀλ‖₂ of an XPBD step (Macklin et al. 2016 Eq. 8) into out[0..2],
 * over the particles with inv_m > 0: the constraints' forces summed spring by spring into a
 * per-particle array, in double. Returns the particles counted, −1 when that array cannot be
 * allocated. */
int32_t sere_pbd_ref_step_residual( const sere_ref_particle* particles, const sere_ref_particle* predicted,
									int32_t particle_count, const sere_ref_spring* springs, const float* lambda,
									int32_t spring_count, double out[3] );

#ifdef __cplusplus
}
#endif
