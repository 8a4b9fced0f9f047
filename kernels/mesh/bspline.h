/* sere — a closed B-spline through a leaf's key points, sampled at even arc length (seed 002,
 * Sec. 3, Fig. 1a: "the smooth B-spline curve running through these points is automatically
 * generated to approximate the leaf edges ... sampled to get the key points which are to be used
 * in Delaunay triangulation").
 *
 * The curve is the uniform cubic B-spline whose control points P solve
 *     (P_{i−1} + 4 P_i + P_{i+1}) / 6 = Q_i   (indices mod n)
 * for the n key points Q, so it passes through Q_i at parameter t = i and is C² everywhere,
 * the closing joint included. Span i, t ∈ [i, i + 1), runs from Q_i to Q_{i+1}. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_bspline
{
	int32_t count; /* n: key points = control points = spans */
	double* cx;	   /* control points */
	double* cy;
	double* cumulative; /* arc length from t = 0 to the start of each of SERE_BSPLINE_STEPS sub-steps per span */
	double length;		/* arc length of the whole closed curve */
} sere_bspline;

/* Sub-steps per span of the arc-length table. */
#define SERE_BSPLINE_STEPS 16

/* Fits the curve through count ≥ 3 key points (x, y), at most INT32_MAX / SERE_BSPLINE_STEPS
 * (SERE_ERR_ARGUMENT otherwise, as for NULL arrays). SERE_ERR_NONFINITE for NaN or infinite
 * input, SERE_ERR_GEOMETRY for two consecutive equal key points (the first and last count as
 * consecutive). The caller frees with sere_bspline_destroy (also safe after a failed fit). */
sere_status sere_bspline_fit( const double* x, const double* y, int32_t count, sere_bspline* spline );
void sere_bspline_destroy( sere_bspline* spline );

/* The point at parameter t (taken modulo count) and, when dx/dy are not NULL, the derivative
 * d(x, y)/dt there. */
void sere_bspline_eval( const sere_bspline* spline, double t, double* x, double* y, double* dx, double* dy );

/* count ≥ 3 points at equal arc-length spacing length/count, the first at t = 0 (key point 0),
 * in the direction of increasing t. t (may be NULL) receives each sample's parameter. */
sere_status sere_bspline_sample( const sere_bspline* spline, int32_t count, double* x, double* y, double* t );

#ifdef __cplusplus
}
#endif
