/* Draws data/leaves/example_aux.png: the paper's auxiliary image (Fig. 3b) for a simple ovate
 * leaf - green blade, red veins, blue base dot - in the colors harness/leafimage.h expects.
 * Deterministic. Build and run from the repository root:
 *   cc data/tools/auximage.c $(pkg-config --cflags --libs cairo) -lm -o /tmp/auximage && /tmp/auximage
 */
#include <cairo.h>
#include <math.h>
#include <stdio.h>

/* Half width of the blade at height t in [0, 1] of its length (ovate, pointed tip). */
double sere_aux_half_width( double t )
{
	return 0.36 * sin( 3.14159265358979 * t ) * pow( t, 0.35 ) * pow( 1.0 - t, 0.25 ) * 1.25;
}

int main( void )
{
	const int width = 400, height = 600;
	const double length = 520.0, x0 = 200.0, y0 = 560.0; /* base at (x0, y0), tip up */
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, width, height );
	cairo_t* cr = cairo_create( surface );
	cairo_set_source_rgb( cr, 1, 1, 1 );
	cairo_paint( cr );
	cairo_move_to( cr, x0, y0 );
	for ( int i = 1; i <= 200; ++i )
	{
		double t = i / 200.0;
		cairo_line_to( cr, x0 + length * sere_aux_half_width( t ), y0 - length * t );
	}
	for ( int i = 199; i >= 1; --i )
	{
		double t = i / 200.0;
		cairo_line_to( cr, x0 - length * sere_aux_half_width( t ), y0 - length * t );
	}
	cairo_close_path( cr );
	cairo_set_source_rgb( cr, 0.3, 0.6, 0.2 );
	cairo_fill( cr );
	cairo_set_source_rgb( cr, 0.9, 0.05, 0.05 );
	cairo_set_line_width( cr, 4.0 );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	cairo_move_to( cr, x0, y0 - 6 );
	cairo_line_to( cr, x0, y0 - 0.92 * length );
	cairo_stroke( cr );
	for ( int k = 0; k < 5; ++k )
	{
		double t = 0.18 + 0.14 * k;
		for ( int side = -1; side <= 1; side += 2 )
		{
			double reach = 0.7 * length * sere_aux_half_width( t + 0.08 );
			cairo_move_to( cr, x0, y0 - length * t );
			cairo_line_to( cr, x0 + side * reach, y0 - length * ( t + 0.1 ) );
			cairo_stroke( cr );
		}
	}
	cairo_set_source_rgb( cr, 0.05, 0.1, 0.95 );
	cairo_arc( cr, x0, y0 - 2, 5, 0, 2 * 3.14159265358979 );
	cairo_fill( cr );
	cairo_status_t status = cairo_surface_write_to_png( surface, "data/leaves/example_aux.png" );
	cairo_destroy( cr );
	cairo_surface_destroy( surface );
	return status == CAIRO_STATUS_SUCCESS ? 0 : 1;
}
