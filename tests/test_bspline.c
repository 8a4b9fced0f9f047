/* The closed B-spline of seed 002 (Sec. 3, Fig. 1a): it runs through every key point, is C²
 * at every joint (the closing one included), a circle's key points give a curve of length 2πr,
 * the samples lie at equal arc length starting at key point 0, and bad key points are refused. */
#include "mesh/bspline.h"

#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>

#define BSPLINE_PI 3.14159265358979323846

/* Key points of an irregular closed outline: a five-lobed star, radii jittered per point and the
 * whole shifted far from the origin, so no symmetry hides an error and the solve runs on
 * coordinates of size ~100. */
#define LOBED_COUNT 23

static void lobed_keys( double* x, double* y )
{
	for ( int32_t i = 0; i < LOBED_COUNT; ++i )
	{
		double a = 2.0 * BSPLINE_PI * i / LOBED_COUNT;
		double r = 10.0 * ( 1.0 + 0.3 * cos( 5.0 * a ) + 0.05 * sin( 7.0 * i ) );
		x[i] = 100.0 + r * cos( a );
		y[i] = -50.0 + r * sin( a );
	}
}

static double max_abs( const double* x, const double* y, int32_t n )
{
	double m = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		m = fmax( m, fmax( fabs( x[i] ), fabs( y[i] ) ) );
	}
	return m;
}

/* The curve passes through Q_i at t = i. The control points solve a cyclic system whose matrix
 * (1 4 1)/6 has eigenvalues in [1/3, 1] (condition number 3), so the solve and the evaluation lose
 * a few ulps of the largest coordinate: 64 ε · max|Q| (~1e-12 here) is generous for rounding yet
 * a million times smaller than any real miss (an off-by-one span or a wrong basis moves the point
 * by a fraction of the key spacing, ~1). */
Test( bspline, interpolates_every_key_point )
{
	double x[LOBED_COUNT], y[LOBED_COUNT];
	lobed_keys( x, y );
	sere_bspline s;
	cr_assert_eq( sere_bspline_fit( x, y, LOBED_COUNT, &s ), SERE_OK );
	cr_assert_eq( s.count, LOBED_COUNT );
	const double tol = 64.0 * DBL_EPSILON * max_abs( x, y, LOBED_COUNT );
	double worst = 0.0;
	for ( int32_t i = 0; i < LOBED_COUNT; ++i )
	{
		double px, py;
		sere_bspline_eval( &s, (double) i, &px, &py, NULL, NULL );
		double e = hypot( px - x[i], py - y[i] );
		worst = fmax( worst, e );
		cr_expect_leq( e, tol, "key point %d missed by %g (tolerance %g)", i, e, tol );
		/* t is taken modulo count: one period on either side gives the same point */
		double qx, qy;
		sere_bspline_eval( &s, (double) ( i + LOBED_COUNT ), &qx, &qy, NULL, NULL );
		cr_expect_leq( hypot( qx - x[i], qy - y[i] ), tol, "t = %d + count", i );
		sere_bspline_eval( &s, (double) ( i - LOBED_COUNT ), &qx, &qy, NULL, NULL );
		cr_expect_leq( hypot( qx - x[i], qy - y[i] ), tol, "t = %d - count", i );
	}
	cr_log_info( "interpolation: worst miss %.3g (tolerance %.3g)", worst, tol );
	/* the smallest closed curve: three key points */
	double tx[3] = { 0.0, 1.0, 0.25 }, ty[3] = { 0.0, 0.0, 1.0 };
	sere_bspline t;
	cr_assert_eq( sere_bspline_fit( tx, ty, 3, &t ), SERE_OK );
	for ( int32_t i = 0; i < 3; ++i )
	{
		double px, py;
		sere_bspline_eval( &t, (double) i, &px, &py, NULL, NULL );
		cr_expect_leq( hypot( px - tx[i], py - ty[i] ), 64.0 * DBL_EPSILON, "triangle key point %d", i );
	}
	sere_bspline_destroy( &t );
	sere_bspline_destroy( &s );
}

/* Inside a span the curve is a cubic in t, so its derivative D(t) is a quadratic and D' is linear.
 * Values of D at three points on one side of a joint therefore give that side's limits D(j±) and
 * D'(j±) exactly (quadratic extrapolation), up to rounding, without ever evaluating across the
 * joint. Nodes at 0.2, 0.4, 0.6 of a span keep rounding amplification small (weights ≤ 6/0.2).
 * A curve that were only C¹ (Catmull–Rom, say) has D' jumps of the size of the key spacing; C²
 * makes both jumps vanish to 1e-10 · scale, scale being the largest |D|, |D'| seen (~10 here).
 *
 * The derivative eval returns must also be the derivative of the positions: a central difference
 * at step 1e-4 inside a span is off by |x'''| δ²/6 ≈ 1e-8 · scale, plus rounding 1e-16·100/1e-4;
 * tolerance 1e-6 · scale. */
static void one_side( const sere_bspline* s, double joint, double dir, double* d, double* dd )
{
	const double delta = 0.2;
	double px[3], py[3];
	for ( int k = 0; k < 3; ++k )
	{
		double x, y;
		sere_bspline_eval( s, joint + dir * delta * ( k + 1 ), &x, &y, px + k, py + k );
	}
	/* Newton form in σ = (t − joint)/(dir·δ) through σ = 1, 2, 3, evaluated at σ = 0 */
	double f[2][3] = { { px[0], px[1], px[2] }, { py[0], py[1], py[2] } };
	for ( int c = 0; c < 2; ++c )
	{
		double d1 = f[c][1] - f[c][0], d2 = f[c][2] - 2.0 * f[c][1] + f[c][0];
		d[c] = f[c][0] - d1 + d2;
		dd[c] = ( d1 - 1.5 * d2 ) / ( dir * delta );
	}
}

Test( bspline, c2_at_every_joint_including_the_closing_one )
{
	double x[LOBED_COUNT], y[LOBED_COUNT];
	lobed_keys( x, y );
	sere_bspline s;
	cr_assert_eq( sere_bspline_fit( x, y, LOBED_COUNT, &s ), SERE_OK );
	double scale = 0.0, jump1 = 0.0, jump2 = 0.0;
	double left1[LOBED_COUNT + 1][2], right1[LOBED_COUNT + 1][2], left2[LOBED_COUNT + 1][2], right2[LOBED_COUNT + 1][2];
	for ( int32_t j = 0; j <= LOBED_COUNT; ++j )
	{
		/* joint j from span j − 1 (left) and span j (right); j = count is the closing joint,
		 * approached from the last span on the left and the first span (t > 0) on the right */
		one_side( &s, (double) j, -1.0, left1[j], left2[j] );
		one_side( &s, (double) j, +1.0, right1[j], right2[j] );
		double px, py, dx, dy;
		sere_bspline_eval( &s, (double) j, &px, &py, &dx, &dy );
		for ( int c = 0; c < 2; ++c )
		{
			scale = fmax( scale, fmax( fabs( left1[j][c] ), fabs( left2[j][c] ) ) );
		}
		/* eval at the joint itself agrees with the right-hand limit */
		cr_expect_leq( hypot( dx - right1[j][0], dy - right1[j][1] ), 1e-10 * ( 1.0 + hypot( dx, dy ) ), "joint %d",
					   j );
	}
	for ( int32_t j = 0; j <= LOBED_COUNT; ++j )
	{
		double e1 = hypot( left1[j][0] - right1[j][0], left1[j][1] - right1[j][1] );
		double e2 = hypot( left2[j][0] - right2[j][0], left2[j][1] - right2[j][1] );
		jump1 = fmax( jump1, e1 );
		jump2 = fmax( jump2, e2 );
		cr_expect_leq( e1, 1e-10 * scale, "joint %d: first derivative jumps by %g", j, e1 );
		cr_expect_leq( e2, 1e-10 * scale, "joint %d: second derivative jumps by %g", j, e2 );
	}
	/* the second derivative is not trivially zero: the test would miss nothing otherwise */
	cr_expect_gt( hypot( left2[3][0], left2[3][1] ), 1.0 );
	cr_log_info( "C2: largest jumps %.3g (D) and %.3g (D'), scale %.3g", jump1, jump2, scale );

	/* eval's derivative is d/dt of eval's point */
	double worst = 0.0;
	for ( int32_t k = 0; k < 4 * LOBED_COUNT; ++k )
	{
		double t = 0.25 * k + 0.125, h = 1e-4, xa, ya, xb, yb, px, py, dx, dy;
		sere_bspline_eval( &s, t - h, &xa, &ya, NULL, NULL );
		sere_bspline_eval( &s, t + h, &xb, &yb, NULL, NULL );
		sere_bspline_eval( &s, t, &px, &py, &dx, &dy );
		double e = hypot( ( xb - xa ) / ( 2.0 * h ) - dx, ( yb - ya ) / ( 2.0 * h ) - dy );
		worst = fmax( worst, e );
		cr_expect_leq( e, 1e-6 * scale, "t = %g: derivative off by %g", t, e );
	}
	cr_log_info( "derivative vs central difference: worst %.3g", worst );
	sere_bspline_destroy( &s );
}

/* Arc length of the curve over [t0, t1] by a fine polyline through eval (independent of the
 * kernel's quadrature table): the polyline falls short by ≈ κ²Δs²/24 relative, ~1e-11 here. */
static double polyline_length( const sere_bspline* s, double t0, double t1, int32_t pieces )
{
	double sum = 0.0, px, py;
	sere_bspline_eval( s, t0, &px, &py, NULL, NULL );
	for ( int32_t k = 1; k <= pieces; ++k )
	{
		double qx, qy;
		sere_bspline_eval( s, t0 + ( t1 - t0 ) * k / pieces, &qx, &qy, NULL, NULL );
		sum += hypot( qx - px, qy - py );
		px = qx, py = qy;
	}
	return sum;
}

/* n key points on a circle of radius r. The periodic cubic interpolant's derivative error is at
 * most h³‖f⁗‖/24 (Hall & Meyer 1976) for h = 1 in t, with f⁗ = r(2π/n)⁴ and |f'| = 2πr/n, so the
 * length, ∫|s'| dt over n spans, is within 2πr · (2π/n)³/24 of 2πr: 2.5e-3 relative for n = 16,
 * 3.2e-4 for n = 32. The error is in fact O(h⁴) (the circle's symmetry makes every span alike),
 * so doubling n must shrink it by ~16: checked as a factor > 8. The table's quadrature itself is
 * checked against a 2¹⁸-piece polyline through eval to 1e-9 relative. */
Test( bspline, circle_length_is_two_pi_r )
{
	const double r = 3.0, cx = 7.0, cy = -2.0;
	double error[2];
	for ( int pass = 0; pass < 2; ++pass )
	{
		const int32_t n = pass == 0 ? 16 : 32;
		double x[32], y[32];
		for ( int32_t i = 0; i < n; ++i )
		{
			x[i] = cx + r * cos( 2.0 * BSPLINE_PI * i / n );
			y[i] = cy + r * sin( 2.0 * BSPLINE_PI * i / n );
		}
		sere_bspline s;
		cr_assert_eq( sere_bspline_fit( x, y, n, &s ), SERE_OK );
		const double exact = 2.0 * BSPLINE_PI * r, bound = pow( 2.0 * BSPLINE_PI / n, 3.0 ) / 24.0;
		error[pass] = fabs( s.length - exact ) / exact;
		cr_expect_leq( error[pass], bound, "n = %d: length %.12g vs 2πr %.12g (relative %.3g, bound %.3g)", n, s.length,
					   exact, error[pass], bound );
		double reference = polyline_length( &s, 0.0, (double) n, 1 << 18 );
		cr_expect_leq( fabs( s.length - reference ), 1e-9 * reference, "n = %d: table %.15g, polyline %.15g", n,
					   s.length, reference );
		/* the table's last entry is the length, its first 0, and it increases */
		cr_expect_eq( s.cumulative[0], 0.0 );
		cr_expect_eq( s.cumulative[n * SERE_BSPLINE_STEPS], s.length );
		for ( int32_t k = 0; k < n * SERE_BSPLINE_STEPS; ++k )
		{
			cr_expect_gt( s.cumulative[k + 1], s.cumulative[k], "n = %d: table step %d", n, k );
		}
		cr_log_info( "circle n = %d: length %.12g, 2πr %.12g, relative %.3g (bound %.3g), polyline %.12g", n, s.length,
					 exact, error[pass], bound, reference );
		sere_bspline_destroy( &s );
	}
	cr_expect_gt( error[0], 8.0 * error[1], "O(h⁴) convergence: %.3g then %.3g", error[0], error[1] );
}

/* Samples: the first is key point 0 at t = 0; the parameters increase through one period; each
 * sample is the curve at its t (to rounding: t = span + u is rounded once more); the arc length
 * between consecutive samples (fine polyline through eval) is length/count to 1e-7 relative (the
 * Newton step solves to ~1e-12, the 4096-piece polyline itself is good to ~1e-9); and the chord
 * between them falls short of the arc only by the curvature sag, at most Δs · (κ_max Δs)²/24,
 * with κ_max measured here from eval's derivative (central differences). count = 400 on this
 * outline (length ≈ 90, κ_max ≈ 1.6) makes that ~0.5 %; the tolerance is 1.5 × the bound. A
 * sampler spacing by parameter instead of arc length is off by tens of percent. */
Test( bspline, samples_at_equal_arc_length )
{
	double x[LOBED_COUNT], y[LOBED_COUNT];
	lobed_keys( x, y );
	sere_bspline s;
	cr_assert_eq( sere_bspline_fit( x, y, LOBED_COUNT, &s ), SERE_OK );
	const int32_t count = 400;
	double* sx = malloc( sizeof( double ) * count );
	double* sy = malloc( sizeof( double ) * count );
	double* st = malloc( sizeof( double ) * count );
	cr_assert( sx && sy && st );
	cr_assert_eq( sere_bspline_sample( &s, count, sx, sy, st ), SERE_OK );
	const double step = s.length / count, scale = max_abs( x, y, LOBED_COUNT );
	cr_expect_eq( st[0], 0.0 );
	cr_expect_leq( hypot( sx[0] - x[0], sy[0] - y[0] ), 64.0 * DBL_EPSILON * scale, "first sample (%.17g, %.17g)",
				   sx[0], sy[0] );
	double kappa = 0.0;
	for ( int32_t k = 0; k < 64 * LOBED_COUNT; ++k )
	{
		double t = ( k + 0.5 ) / 64.0, h = 1e-5, px, py, ax, ay, bx, by, dx, dy;
		sere_bspline_eval( &s, t - h, &px, &py, &ax, &ay );
		sere_bspline_eval( &s, t + h, &px, &py, &bx, &by );
		sere_bspline_eval( &s, t, &px, &py, &dx, &dy );
		double ddx = ( bx - ax ) / ( 2.0 * h ), ddy = ( by - ay ) / ( 2.0 * h );
		kappa = fmax( kappa, fabs( dx * ddy - dy * ddx ) / pow( hypot( dx, dy ), 3.0 ) );
	}
	const double sag = 1.5 * ( kappa * step ) * ( kappa * step ) / 24.0;
	double chord_min = INFINITY, chord_max = 0.0, arc_worst = 0.0;
	for ( int32_t k = 0; k < count; ++k )
	{
		int32_t j = ( k + 1 ) % count;
		double t1 = j == 0 ? (double) LOBED_COUNT : st[j];
		cr_assert_lt( st[k], t1, "parameters increase at sample %d", k );
		double px, py;
		sere_bspline_eval( &s, st[k], &px, &py, NULL, NULL );
		cr_expect_leq( hypot( px - sx[k], py - sy[k] ), 64.0 * DBL_EPSILON * scale, "sample %d is the curve at its t",
					   k );
		double arc = polyline_length( &s, st[k], t1, 4096 );
		arc_worst = fmax( arc_worst, fabs( arc - step ) / step );
		cr_expect_leq( fabs( arc - step ), 1e-7 * step, "sample %d: arc %.12g vs %.12g", k, arc, step );
		double chord = hypot( sx[j] - sx[k], sy[j] - sy[k] );
		chord_min = fmin( chord_min, chord );
		chord_max = fmax( chord_max, chord );
		cr_expect_leq( chord, step * ( 1.0 + 1e-9 ), "sample %d: chord %.12g longer than the arc", k, chord );
		cr_expect_geq( chord, ( 1.0 - sag ) * step, "sample %d: chord %.12g vs %.12g", k, chord, step );
	}
	cr_log_info( "samples: length %.6g, length/count %.6g, chords in [%.6g, %.6g] (%.3g %% below at worst, allowed "
				 "%.3g %%, kappa_max %.3g), arc off by %.3g relative",
				 s.length, step, chord_min, chord_max, 100.0 * ( 1.0 - chord_min / step ), 100.0 * sag, kappa,
				 arc_worst );
	/* t may be NULL */
	double sx2[7], sy2[7];
	cr_expect_eq( sere_bspline_sample( &s, 7, sx2, sy2, NULL ), SERE_OK );
	free( sx ), free( sy ), free( st );
	sere_bspline_destroy( &s );
}

Test( bspline, bad_input_is_refused )
{
	double x[5] = { 0.0, 1.0, 1.0, 0.0, 0.5 }, y[5] = { 0.0, 0.0, 1.0, 1.0, 0.5 };
	sere_bspline s;
	cr_expect_eq( sere_bspline_fit( x, y, 2, &s ), SERE_ERR_ARGUMENT, "two key points" );
	cr_expect_eq( s.cx, NULL );
	sere_bspline_destroy( &s ); /* safe after a failed fit */
	cr_expect_eq( sere_bspline_fit( x, y, 0, &s ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_fit( x, y, -4, &s ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_fit( NULL, y, 4, &s ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_fit( x, NULL, 4, &s ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_fit( x, y, 4, NULL ), SERE_ERR_ARGUMENT );
	/* the arc-length table's index count · SERE_BSPLINE_STEPS would pass INT32_MAX (refused
	 * before a key point is read) */
	cr_expect_eq( sere_bspline_fit( x, y, INT32_MAX / SERE_BSPLINE_STEPS + 1, &s ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_fit( x, y, 4, &s ), SERE_OK, "the square itself is fine" );
	sere_bspline_destroy( &s );
	cr_expect_eq( s.cx, NULL );
	sere_bspline_destroy( &s ); /* twice is safe */

	x[2] = NAN;
	cr_expect_eq( sere_bspline_fit( x, y, 4, &s ), SERE_ERR_NONFINITE, "NaN x" );
	x[2] = 1.0, y[3] = INFINITY;
	cr_expect_eq( sere_bspline_fit( x, y, 4, &s ), SERE_ERR_NONFINITE, "infinite y" );
	y[3] = 1.0;

	double rx[4] = { 0.0, 1.0, 1.0, 0.0 }, ry[4] = { 0.0, 0.0, 0.0, 1.0 };
	cr_expect_eq( sere_bspline_fit( rx, ry, 4, &s ), SERE_ERR_GEOMETRY, "points 1 and 2 equal" );
	double lx[4] = { 0.0, 1.0, 1.0, 0.0 }, ly[4] = { 0.0, 0.0, 1.0, 0.0 };
	cr_expect_eq( sere_bspline_fit( lx, ly, 4, &s ), SERE_ERR_GEOMETRY, "last point equals the first" );
	cr_expect_eq( s.cx, NULL );
	/* equal but not consecutive points are allowed (a figure eight through its crossing) */
	double ex[4] = { 0.0, 1.0, 0.0, -1.0 }, ey[4] = { 0.0, 1.0, 0.0, 1.0 };
	cr_expect_eq( sere_bspline_fit( ex, ey, 4, &s ), SERE_OK );
	sere_bspline_destroy( &s );

	/* sampling: fewer than three samples, a failed spline, NULL outputs */
	cr_assert_eq( sere_bspline_fit( x, y, 5, &s ), SERE_OK );
	double sx[8], sy[8];
	cr_expect_eq( sere_bspline_sample( &s, 2, sx, sy, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_sample( &s, 3, NULL, sy, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_sample( &s, 3, sx, NULL, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_sample( NULL, 3, sx, sy, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_bspline_sample( &s, 8, sx, sy, NULL ), SERE_OK );
	sere_bspline_destroy( &s );
	cr_expect_eq( sere_bspline_sample( &s, 8, sx, sy, NULL ), SERE_ERR_ARGUMENT, "a destroyed spline" );
}
