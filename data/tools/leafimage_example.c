/* Draws data/leaves/example_aux.png, the paper's auxiliary image (Sec. 3.1, Fig. 3b) for a simple
 * ovate leaf in the colors harness/read/leafimage.h reads: a green blade on white, red veins (a
 * midvein, three pairs of secondaries, one tertiary) and a blue base dot touching the margin.
 *
 * The blade's right half is the curve x(s) = c L (s - s^3), y(s) = L s^2 for s in [0, 1] (x from
 * the axis, y up from the base): a rounded base, the widest point at a third of the length and a
 * tip of half-angle atan(c). Its area is (8/15) c L^2 exactly; tests/test_leafimage.c checks the
 * traced outline against that and against the curve's length, so the two files share these
 * numbers. Deterministic; build and run from the repository root:
 *   cc data/tools/leafimage_example.c $(pkg-config --cflags --libs cairo) -lm -o /tmp/leafimage-example
 *   /tmp/leafimage-example
 */
#include <cairo.h>
#include <math.h>
#include <stdio.h>

enum
{
	WIDTH = 400,
	HEIGHT = 600,
	SAMPLES = 1024, /* polygon edges per half of the blade: far below a pixel from the curve */
};

static const double L = 520.0;		/* leaf length in pixels */
static const double C = 0.78;		/* blade shape: tip half-angle atan(C) */
static const double BASE_X = 200.0; /* the base (petiole) in pixels, y down */
static const double BASE_Y = 570.0;
static const double DOT_RADIUS = 4.0;	/* blue base dot, inside the blade, touching the margin */
static const double MIDVEIN_END = 0.92; /* fraction of the length */
static const double SECONDARY_T[3] = { 0.16, 0.36, 0.56 };

/* The blade's half-width in pixels at height t (fraction of the length), from s = sqrt(t). */
static double half_width( double t )
{
	double s = sqrt( t );
	return C * L * ( s - s * s * s );
}

static void bezier( const double* p, double u, double* x, double* y )
{
	double a = ( 1 - u ) * ( 1 - u ) * ( 1 - u ), b = 3 * ( 1 - u ) * ( 1 - u ) * u, c = 3 * ( 1 - u ) * u * u,
		   d = u * u * u;
	*x = a * p[0] + b * p[2] + c * p[4] + d * p[6];
	*y = a * p[1] + b * p[3] + c * p[5] + d * p[7];
}

/* Secondary vein k on side -1 (left) or +1 (right) as a cubic Bezier: it leaves the midvein at
 * about 45 degrees and bends towards the tip, ending at 80% of the half-width. */
static void secondary( int k, int side, double* p )
{
	double t = SECONDARY_T[k], te = t + 0.17, reach = 0.8 * half_width( te );
	p[0] = BASE_X, p[1] = BASE_Y - L * t;
	p[2] = BASE_X + side * 0.3 * reach, p[3] = p[1] - 0.3 * reach;
	p[4] = BASE_X + side * 0.75 * reach, p[5] = BASE_Y - L * te + 0.12 * reach;
	p[6] = BASE_X + side * reach, p[7] = BASE_Y - L * te;
}

int main( void )
{
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, WIDTH, HEIGHT );
	cairo_t* cr = cairo_create( surface );
	cairo_set_source_rgb( cr, 1, 1, 1 );
	cairo_paint( cr );

	cairo_move_to( cr, BASE_X, BASE_Y );
	for ( int i = 1; i <= SAMPLES; ++i )
	{
		double s = (double) i / SAMPLES;
		cairo_line_to( cr, BASE_X + C * L * ( s - s * s * s ), BASE_Y - L * s * s );
	}
	for ( int i = SAMPLES - 1; i >= 1; --i )
	{
		double s = (double) i / SAMPLES;
		cairo_line_to( cr, BASE_X - C * L * ( s - s * s * s ), BASE_Y - L * s * s );
	}
	cairo_close_path( cr );
	cairo_set_source_rgb( cr, 0.3, 0.6, 0.2 );
	cairo_fill( cr );

	cairo_set_source_rgb( cr, 0.9, 0.05, 0.05 );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	cairo_set_line_width( cr, 4.0 );
	/* from the dot's centre, so the round cap stays under the dot instead of poking out */
	cairo_move_to( cr, BASE_X, BASE_Y - DOT_RADIUS );
	cairo_line_to( cr, BASE_X, BASE_Y - MIDVEIN_END * L );
	cairo_stroke( cr );
	cairo_set_line_width( cr, 3.0 );
	double p[8];
	for ( int k = 0; k < 3; ++k )
	{
		for ( int side = -1; side <= 1; side += 2 )
		{
			secondary( k, side, p );
			cairo_move_to( cr, p[0], p[1] );
			cairo_curve_to( cr, p[2], p[3], p[4], p[5], p[6], p[7] );
			cairo_stroke( cr );
		}
	}
	/* One tertiary vein, leaving the lowest left secondary outwards and down. */
	double qx, qy;
	secondary( 0, -1, p );
	bezier( p, 0.45, &qx, &qy );
	cairo_move_to( cr, qx, qy );
	cairo_line_to( cr, qx - 35.0, qy + 25.0 );
	cairo_stroke( cr );

	cairo_set_source_rgb( cr, 0.05, 0.1, 0.95 );
	cairo_arc( cr, BASE_X, BASE_Y - DOT_RADIUS, DOT_RADIUS, 0, 2.0 * 3.14159265358979323846 );
	cairo_fill( cr );

	cairo_status_t status = cairo_surface_write_to_png( surface, "data/leaves/example_aux.png" );
	cairo_destroy( cr );
	cairo_surface_destroy( surface );
	if ( status != CAIRO_STATUS_SUCCESS )
	{
		fprintf( stderr, "data/leaves/example_aux.png: %s\n", cairo_status_to_string( status ) );
		return 1;
	}
	return 0;
}
