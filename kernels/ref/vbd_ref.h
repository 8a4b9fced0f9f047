/* sere reference twin — the implicit step of solve/vbd.h written the straightforward way: the
 * step's energy E(x) = ½ Σ m_i |x_i − x̃_i|² + Σ_j k_j (|x_a − x_b| − l_j)²/2, its gradient, and a
 * minimizer that sweeps the particles one by one in index order (no colors, no SIMD), each moved
 * by a Newton step on its own 3 × 3 block, in double. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_vbd_ref_problem
{
	int32_t particle_count, spring_count;
	const float *tx, *ty, *tz; /* the prediction x̃ */
	const float* inv_m;		   /* 0: held where it is */
	const int32_t *a, *b;
	const float* rest;
	const double* stiffness; /* k_j = 1/α̃_j */
} sere_vbd_ref_problem;

/* The largest |∂E/∂x_i| over the particles with inv_m > 0, at x (3 doubles a particle). −1 when
 * the adjacency cannot be allocated. */
double sere_vbd_ref_gradient( const sere_vbd_ref_problem* problem, const double* x );

/* Descends from x (3 doubles a particle) until the largest |∂E/∂x_i| is below tolerance; returns
 * the sweeps run, −1 at max_sweeps or when the adjacency cannot be allocated. A spring's block is
 * k [n nᵀ + max(0, 1 − l/|d|)(I − n nᵀ)], the bending part left out under compression so that the
 * particle's block stays positive definite. */
int32_t sere_vbd_ref_descend( const sere_vbd_ref_problem* problem, double* x, double tolerance, int32_t max_sweeps );

#ifdef __cplusplus
}
#endif
