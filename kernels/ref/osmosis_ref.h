/* sere reference twin — Jeong Eq. 9 assembled literally (nonsymmetric) and solved densely. For
 * tests on small layers only. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* A x = rhs for the n × n row-major A, by Gaussian elimination with partial pivoting in place
 * (A and rhs are overwritten); SERE_ERR_GEOMETRY for a zero pivot (singular A). */
sere_status sere_dense_ref_solve( double* A, double* rhs, double* x, int32_t n );

/* (I − Δt L°) w' = w + water_rate Δt with L° of Jeong Eq. 8 (row weight 2/E_i), by Gaussian
 * elimination with partial pivoting; writes w' (not clamped) into w_out for the layer's
 * particles [first, first + count). */
sere_status sere_osmosis_ref_step( int32_t first, int32_t count, const int32_t* a, const int32_t* b,
								   int32_t spring_count, const float* x, const float* y, const float* z,
								   const float* tau, const double* M, const double* w, double dt, double lambda_min,
								   double lambda_max, double water_rate, double* w_out );

#ifdef __cplusplus
}
#endif
