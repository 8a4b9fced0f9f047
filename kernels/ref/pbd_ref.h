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

#ifdef __cplusplus
}
#endif
