/* sere — private to massspring.c and massspring_build.c, not installed and not part of the API:
 * the mass-spring model's springs in sweep order, their incidence and the step's records. */
#pragma once

#include "season/massspring.h"

struct sere_massspring
{
	int32_t threads; /* sere_massspring_set_threads */
	int32_t vertex_count;
	int32_t structural_count;
	int32_t flexion_count;
	int32_t* a; /* structural springs in sweep order (below), then flexion springs */
	int32_t* b;
	float* rest0;
	int32_t color_count;
	/* The sweep (Tang Eq. 2) works on bands: the particles cut by breadth-first level into
	 * band_count ranges, so that a structural spring lies inside one band or joins two
	 * neighbouring ones. A sweep limits the springs inside the bands (bands in parallel: they
	 * share no particle, and each band's thread takes its colors in turn with no barrier), then
	 * the springs joining bands c and c + 1 for even c, then for odd c. The structural springs
	 * are stored in that order, item by item (bands, even cuts, odd cuts), each item by color:
	 * run k = item k / color_count, color k % color_count is [run_offsets[k], run_offsets[k+1]). */
	int32_t band_count;
	int32_t* run_offsets;
	/* Particle → springs incidence (CSR), each list in ascending spring order, with the sign
	 * the spring's force takes at that particle: the fixed gather order makes the sum the same
	 * for any thread count. */
	int32_t* incidence_offsets;
	int32_t* incidence;
	float* incidence_sign;
	/* Per-spring force of the current step. */
	float *fx, *fy, *fz;
	/* The step works on particle records, (x, y, z, 1/m) and (vx, vy, vz, 0): a SIMD lane
	 * fetches one spring end with a single 16-byte load instead of one gather per component. */
	float* xrec;
	float* vrec;
	/* Where sere_massspring_touch leaves its sums, so that the compiler keeps their loads. */
	float touch_sink;
};
