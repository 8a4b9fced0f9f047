#include "mesh/bspline.h"

#include <math.h>
#include <stdlib.h>

/* 5-point Gauss–Legendre on [0, 1]: exact for polynomials of degree 9, and the speed |C'(t)| of
 * a cubic span is smooth, so one rule per sub-step gives the arc length to ~1e-12 relative. */
static const double gauss_node[5] = { 0.046910077030668, 0.230765344947158, 0.5, 0.769234655052842, 0.953089922969332 };
static const double gauss_weight[5] = { 0.118463442528095, 0.239314335249683, 0.284444444444444, 0.239314335249683,
										0.118463442528095 };

void sere_bspline_destroy( sere_bspline* spline )
{
	if ( spline == NULL )
	{
		return;
	}
	free( spline->cx );
	free( spline->cy );
	free( spline->cumulative );
	spline->cx = spline->cy = spline->cumulative = NULL;
	spline->count = 0;
	spline->length = 0.0;
}

/* Solves the cyclic system v_{i−1} + 4 v_i + v_{i+1} = 6 q_i (indices mod n) by Sherman–Morrison:
 * the cyclic matrix is A = T + u wᵀ with u = (γ, 0, ..., 0, 1)ᵀ, w = (1, 0, ..., 0, 1/γ)ᵀ and
 * γ = −4, where T is tridiagonal with off-diagonals 1 and diagonal 4 except 4 − γ = 8 in row 0
 * and 4 − 1/γ = 4.25 in row n − 1; two Thomas solves T y = 6q, T z = u give
 * v = y − (wᵀy / (1 + wᵀz)) z. */
static void solve_cyclic( const double* q, int32_t n, double* v, double* work )
{
	const double gamma = -4.0;
	double* c = work;		  /* Thomas forward sweep coefficients */
	double* y = work + n;	  /* T y = 6 q */
	double* z = work + 2 * n; /* T z = u */
	for ( int pass = 0; pass < 2; ++pass )
	{
		double* out = pass == 0 ? y : z;
		double beta = 4.0 - gamma;
		out[0] = ( pass == 0 ? 6.0 * q[0] : gamma ) / beta;
		c[0] = 1.0 / beta;
		for ( int32_t i = 1; i < n; ++i )
		{
			double diagonal = i == n - 1 ? 4.0 - 1.0 / gamma : 4.0;
			beta = diagonal - c[i - 1];
			double rhs = pass == 0 ? 6.0 * q[i] : ( i == n - 1 ? 1.0 : 0.0 );
			out[i] = ( rhs - out[i - 1] ) / beta;
			c[i] = 1.0 / beta;
		}
		for ( int32_t i = n - 2; i >= 0; --i )
		{
			out[i] -= c[i] * out[i + 1];
		}
	}
	double factor = ( y[0] + y[n - 1] / gamma ) / ( 1.0 + z[0] + z[n - 1] / gamma );
	for ( int32_t i = 0; i < n; ++i )
	{
		v[i] = y[i] - factor * z[i];
	}
}

/* Span i at local u ∈ [0, 1]: the uniform cubic B-spline basis on P_{i−1}, P_i, P_{i+1}, P_{i+2}. */
static void span_eval( const sere_bspline* s, int32_t i, double u, double* x, double* y, double* dx, double* dy )
{
	const int32_t n = s->count;
	const int32_t i0 = ( i + n - 1 ) % n, i1 = i, i2 = ( i + 1 ) % n, i3 = ( i + 2 ) % n;
	const double v = 1.0 - u, u2 = u * u, u3 = u2 * u;
	const double b0 = v * v * v / 6.0;
	const double b1 = ( 3.0 * u3 - 6.0 * u2 + 4.0 ) / 6.0;
	const double b2 = ( -3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0 ) / 6.0;
	const double b3 = u3 / 6.0;
	*x = b0 * s->cx[i0] + b1 * s->cx[i1] + b2 * s->cx[i2] + b3 * s->cx[i3];
	*y = b0 * s->cy[i0] + b1 * s->cy[i1] + b2 * s->cy[i2] + b3 * s->cy[i3];
	if ( dx != NULL && dy != NULL )
	{
		const double d0 = -0.5 * v * v;
		const double d1 = 1.5 * u2 - 2.0 * u;
		const double d2 = -1.5 * u2 + u + 0.5;
		const double d3 = 0.5 * u2;
		*dx = d0 * s->cx[i0] + d1 * s->cx[i1] + d2 * s->cx[i2] + d3 * s->cx[i3];
		*dy = d0 * s->cy[i0] + d1 * s->cy[i1] + d2 * s->cy[i2] + d3 * s->cy[i3];
	}
}

static double speed( const sere_bspline* s, int32_t span, double u )
{
	double x, y, dx, dy;
	span_eval( s, span, u, &x, &y, &dx, &dy );
	return hypot( dx, dy );
}

/* Arc length of span `span` over local parameters [u0, u1]. */
static double arc( const sere_bspline* s, int32_t span, double u0, double u1 )
{
	double sum = 0.0;
	for ( int k = 0; k < 5; ++k )
	{
		sum += gauss_weight[k] * speed( s, span, u0 + ( u1 - u0 ) * gauss_node[k] );
	}
	return sum * ( u1 - u0 );
}

sere_status sere_bspline_fit( const double* x, const double* y, int32_t count, sere_bspline* spline )
{
	if ( spline == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*spline = ( sere_bspline ){ 0 };
	/* the arc-length table's indices, count · SERE_BSPLINE_STEPS, are int32_t */
	if ( x == NULL || y == NULL || count < 3 || count > INT32_MAX / SERE_BSPLINE_STEPS )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < count; ++i )
	{
		if ( !isfinite( x[i] ) || !isfinite( y[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	for ( int32_t i = 0; i < count; ++i )
	{
		int32_t j = ( i + 1 ) % count;
		if ( x[i] == x[j] && y[i] == y[j] )
		{
			return SERE_ERR_GEOMETRY;
		}
	}
	spline->cx = malloc( (size_t) count * sizeof( double ) );
	spline->cy = malloc( (size_t) count * sizeof( double ) );
	spline->cumulative = malloc( ( (size_t) count * SERE_BSPLINE_STEPS + 1 ) * sizeof( double ) );
	double* work = malloc( 3 * (size_t) count * sizeof( double ) );
	if ( spline->cx == NULL || spline->cy == NULL || spline->cumulative == NULL || work == NULL )
	{
		free( work );
		sere_bspline_destroy( spline );
		return SERE_ERR_MEMORY;
	}
	spline->count = count;
	solve_cyclic( x, count, spline->cx, work );
	solve_cyclic( y, count, spline->cy, work );
	free( work );

	double total = 0.0;
	for ( int32_t i = 0; i < count; ++i )
	{
		for ( int32_t k = 0; k < SERE_BSPLINE_STEPS; ++k )
		{
			spline->cumulative[i * SERE_BSPLINE_STEPS + k] = total;
			total += arc( spline, i, (double) k / SERE_BSPLINE_STEPS, (double) ( k + 1 ) / SERE_BSPLINE_STEPS );
		}
	}
	spline->cumulative[count * SERE_BSPLINE_STEPS] = total;
	spline->length = total;
	if ( !( total > 0.0 ) || !isfinite( total ) )
	{
		sere_bspline_destroy( spline );
		return SERE_ERR_GEOMETRY;
	}
	return SERE_OK;
}

void sere_bspline_eval( const sere_bspline* spline, double t, double* x, double* y, double* dx, double* dy )
{
	const double n = (double) spline->count;
	t = fmod( t, n );
	if ( t < 0.0 )
	{
		t += n;
	}
	int32_t span = (int32_t) floor( t );
	if ( span >= spline->count )
	{
		span = spline->count - 1;
	}
	span_eval( spline, span, t - span, x, y, dx, dy );
}

sere_status sere_bspline_sample( const sere_bspline* spline, int32_t count, double* x, double* y, double* t )
{
	if ( spline == NULL || spline->count < 3 || count < 3 || x == NULL || y == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t steps = spline->count * SERE_BSPLINE_STEPS;
	int32_t step = 0;
	for ( int32_t k = 0; k < count; ++k )
	{
		const double target = spline->length * (double) k / (double) count;
		while ( step + 1 < steps && spline->cumulative[step + 1] <= target )
		{
			++step;
		}
		/* Newton on the arc length inside the sub-step, from its linear estimate. */
		const int32_t span = step / SERE_BSPLINE_STEPS;
		const double u0 = (double) ( step % SERE_BSPLINE_STEPS ) / SERE_BSPLINE_STEPS;
		const double h = 1.0 / SERE_BSPLINE_STEPS;
		const double s0 = spline->cumulative[step], s1 = spline->cumulative[step + 1];
		double u = s1 > s0 ? u0 + h * ( target - s0 ) / ( s1 - s0 ) : u0;
		for ( int it = 0; it < 4; ++it )
		{
			double v = speed( spline, span, u );
			if ( !( v > 0.0 ) )
			{
				break;
			}
			u -= ( s0 + arc( spline, span, u0, u ) - target ) / v;
			u = u < u0 ? u0 : ( u > u0 + h ? u0 + h : u );
		}
		span_eval( spline, span, u, x + k, y + k, NULL, NULL );
		if ( t != NULL )
		{
			t[k] = span + u;
		}
	}
	return SERE_OK;
}
