#define _POSIX_C_SOURCE 200809L
#include "picture.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sere_picture_dry_color( double relative_water, double rgb[3] )
{
	const double fresh[3] = { 0.27, 0.56, 0.17 }, dry[3] = { 0.55, 0.36, 0.17 };
	double t = fmin( 1.0, fmax( 0.0, relative_water ) );
	for ( int k = 0; k < 3; ++k )
	{
		rgb[k] = dry[k] + t * ( fresh[k] - dry[k] );
	}
}

static int write_png( cairo_surface_t* surface, const char* path, char* err, size_t err_size )
{
	char tmp[4096];
	snprintf( tmp, sizeof( tmp ), "%s.tmp", path );
	cairo_status_t status = cairo_surface_write_to_png( surface, tmp );
	if ( status != CAIRO_STATUS_SUCCESS || rename( tmp, path ) != 0 )
	{
		remove( tmp );
		snprintf( err, err_size, "%s: cannot write PNG (%s)", path, cairo_status_to_string( status ) );
		return -1;
	}
	return 0;
}

/* View: rotate about z by the azimuth, then tilt by the elevation; screen x right, y up. */
typedef struct view
{
	double ca, sa, ce, se;
	double cx, cy, cz, scale;
} view;

static void project( const view* v, double x, double y, double z, double* sx, double* sy, double* depth )
{
	x -= v->cx, y -= v->cy, z -= v->cz;
	double rx = v->ca * x - v->sa * y;
	double ry = v->sa * x + v->ca * y;
	*sx = rx * v->scale;
	*sy = ( ry * v->se + z * v->ce ) * v->scale;
	*depth = ry * v->ce - z * v->se;
}

typedef struct order_item
{
	double depth;
	int32_t t;
} order_item;

static int compare_depth( const void* pa, const void* pb )
{
	const order_item* a = pa;
	const order_item* b = pb;
	if ( a->depth != b->depth )
	{
		return a->depth < b->depth ? 1 : -1; /* far first */
	}
	return ( a->t > b->t ) - ( a->t < b->t );
}

static void draw_mesh( cairo_t* cr, const view* v, const sere_panel* panel, double ox, double oy, order_item* order )
{
	const int32_t* tri = panel->tri;
	for ( int32_t t = 0; t < panel->triangle_count; ++t )
	{
		double sx, sy, d = 0.0, dd;
		for ( int k = 0; k < 3; ++k )
		{
			int32_t i = tri[3 * t + k];
			project( v, panel->x[i], panel->y[i], panel->z[i], &sx, &sy, &dd );
			d += dd;
		}
		order[t] = ( order_item ){ d, t };
	}
	qsort( order, (size_t) panel->triangle_count, sizeof( order_item ), compare_depth );
	const double light[3] = { -0.4, 0.5, 0.77 };
	for ( int32_t k = 0; k < panel->triangle_count; ++k )
	{
		const int32_t* c = tri + 3 * order[k].t;
		double ax = panel->x[c[1]] - panel->x[c[0]], ay = panel->y[c[1]] - panel->y[c[0]],
			   az = panel->z[c[1]] - panel->z[c[0]];
		double bx = panel->x[c[2]] - panel->x[c[0]], by = panel->y[c[2]] - panel->y[c[0]],
			   bz = panel->z[c[2]] - panel->z[c[0]];
		double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
		double length = sqrt( nx * nx + ny * ny + nz * nz );
		double lambert = length > 0.0 ? fabs( nx * light[0] + ny * light[1] + nz * light[2] ) / length : 0.0;
		double rwc = ( panel->rwc[c[0]] + panel->rwc[c[1]] + panel->rwc[c[2]] ) / 3.0;
		double rgb[3];
		sere_picture_dry_color( rwc, rgb );
		double shade = 0.35 + 0.65 * lambert;
		cairo_new_path( cr );
		for ( int q = 0; q < 3; ++q )
		{
			double sx, sy, d;
			project( v, panel->x[c[q]], panel->y[c[q]], panel->z[c[q]], &sx, &sy, &d );
			cairo_line_to( cr, ox + sx, oy - sy );
		}
		cairo_close_path( cr );
		cairo_set_source_rgb( cr, rgb[0] * shade, rgb[1] * shade, rgb[2] * shade );
		cairo_fill_preserve( cr );
		cairo_set_line_width( cr, 0.3 );
		cairo_stroke( cr );
	}
}

int sere_picture_sheet( const char* path, const char* title, const sere_panel* panels, int count, int columns,
						char* err, size_t err_size )
{
	if ( count <= 0 || columns <= 0 )
	{
		snprintf( err, err_size, "%s: nothing to draw", path );
		return -1;
	}
	const int cell = 320, header = 40, caption = 24;
	int rows = ( count + columns - 1 ) / columns;
	int width = columns * cell, height = header + rows * ( cell + caption );
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, width, height );
	cairo_t* cr = cairo_create( surface );
	cairo_set_source_rgb( cr, 1, 1, 1 );
	cairo_paint( cr );
	cairo_select_font_face( cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD );
	cairo_set_font_size( cr, 18 );
	cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
	cairo_move_to( cr, 12, 27 );
	cairo_show_text( cr, title );

	/* Scale and centre from the first panel, so the sequence shows the leaf shrinking. */
	view v = { cos( -0.6 ), sin( -0.6 ), cos( 0.9 ), sin( 0.9 ), 0, 0, 0, 1 };
	const sere_panel* first = panels;
	double lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	int32_t max_triangles = 0;
	for ( int k = 0; k < count; ++k )
	{
		max_triangles = panels[k].triangle_count > max_triangles ? panels[k].triangle_count : max_triangles;
	}
	for ( int32_t t = 0; t < 3 * first->triangle_count; ++t )
	{
		int32_t i = first->tri[t];
		lo[0] = fmin( lo[0], first->x[i] ), hi[0] = fmax( hi[0], first->x[i] );
		lo[1] = fmin( lo[1], first->y[i] ), hi[1] = fmax( hi[1], first->y[i] );
		lo[2] = fmin( lo[2], first->z[i] ), hi[2] = fmax( hi[2], first->z[i] );
	}
	v.cx = 0.5 * ( lo[0] + hi[0] ), v.cy = 0.5 * ( lo[1] + hi[1] ), v.cz = 0.5 * ( lo[2] + hi[2] );
	double extent = fmax( hi[0] - lo[0], fmax( hi[1] - lo[1], hi[2] - lo[2] ) );
	v.scale = 0.8 * cell / fmax( extent, 1e-9 );
	order_item* order = malloc( sizeof( order_item ) * (size_t) ( max_triangles > 0 ? max_triangles : 1 ) );
	if ( order == NULL )
	{
		cairo_destroy( cr );
		cairo_surface_destroy( surface );
		snprintf( err, err_size, "%s: out of memory", path );
		return -1;
	}
	cairo_select_font_face( cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL );
	cairo_set_font_size( cr, 14 );
	for ( int k = 0; k < count; ++k )
	{
		double ox = ( k % columns ) * cell + 0.5 * cell;
		double oy = header + ( k / columns ) * ( cell + caption ) + 0.5 * cell;
		/* Every panel at the first panel's scale but centred on its own leaf, so a leaf that
		 * drifts stays in its cell while its shrinking shows. */
		view centred = v;
		double c[3] = { 0.0, 0.0, 0.0 };
		for ( int32_t t = 0; t < 3 * panels[k].triangle_count; ++t )
		{
			int32_t i = panels[k].tri[t];
			c[0] += panels[k].x[i], c[1] += panels[k].y[i], c[2] += panels[k].z[i];
		}
		double inv = 1.0 / fmax( 1.0, 3.0 * panels[k].triangle_count );
		centred.cx = c[0] * inv, centred.cy = c[1] * inv, centred.cz = c[2] * inv;
		draw_mesh( cr, &centred, panels + k, ox, oy, order );
		cairo_text_extents_t extents;
		cairo_text_extents( cr, panels[k].caption, &extents );
		cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
		cairo_move_to( cr, ox - 0.5 * extents.width, oy + 0.5 * cell + 16 );
		cairo_show_text( cr, panels[k].caption );
	}
	free( order );
	cairo_destroy( cr );
	int result = write_png( surface, path, err, err_size );
	cairo_surface_destroy( surface );
	return result;
}

static double nice_step( double range )
{
	double raw = range / 5.0;
	double magnitude = pow( 10.0, floor( log10( raw ) ) );
	double fraction = raw / magnitude;
	return magnitude * ( fraction < 1.5 ? 1.0 : ( fraction < 3.5 ? 2.0 : ( fraction < 7.5 ? 5.0 : 10.0 ) ) );
}

int sere_picture_plot( const char* path, const char* title, const char* x_label, const char* y_label,
					   const sere_series* series, int count, char* err, size_t err_size )
{
	const int width = 800, height = 480, left = 70, right = 20, top = 50, bottom = 55;
	double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
	for ( int s = 0; s < count; ++s )
	{
		for ( int32_t i = 0; i < series[s].count; ++i )
		{
			x0 = fmin( x0, series[s].x[i] ), x1 = fmax( x1, series[s].x[i] );
			y0 = fmin( y0, series[s].y[i] ), y1 = fmax( y1, series[s].y[i] );
		}
	}
	if ( !isfinite( x0 ) || !isfinite( y0 ) )
	{
		snprintf( err, err_size, "%s: no data to plot", path );
		return -1;
	}
	y0 = fmin( y0, 0.0 );
	if ( x1 <= x0 )
	{
		x1 = x0 + 1.0;
	}
	if ( y1 <= y0 )
	{
		y1 = y0 + 1.0;
	}
	double ystep = nice_step( y1 - y0 ), xstep = nice_step( x1 - x0 );
	y1 = ceil( y1 / ystep ) * ystep;
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, width, height );
	cairo_t* cr = cairo_create( surface );
	cairo_set_source_rgb( cr, 1, 1, 1 );
	cairo_paint( cr );
	double pw = width - left - right, ph = height - top - bottom;
#define PX( x ) ( left + ( (x) -x0 ) / ( x1 - x0 ) * pw )
#define PY( y ) ( top + ph - ( (y) -y0 ) / ( y1 - y0 ) * ph )
	cairo_select_font_face( cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL );
	cairo_set_font_size( cr, 12 );
	char label[64];
	for ( double y = ceil( y0 / ystep ) * ystep; y <= y1 + 1e-9 * ystep; y += ystep )
	{
		cairo_set_source_rgb( cr, 0.88, 0.88, 0.88 );
		cairo_move_to( cr, left, PY( y ) );
		cairo_line_to( cr, left + pw, PY( y ) );
		cairo_stroke( cr );
		snprintf( label, sizeof( label ), "%g", fabs( y ) < 1e-12 ? 0.0 : y );
		cairo_set_source_rgb( cr, 0.2, 0.2, 0.2 );
		cairo_move_to( cr, 8, PY( y ) + 4 );
		cairo_show_text( cr, label );
	}
	for ( double x = ceil( x0 / xstep ) * xstep; x <= x1 + 1e-9 * xstep; x += xstep )
	{
		cairo_set_source_rgb( cr, 0.88, 0.88, 0.88 );
		cairo_move_to( cr, PX( x ), top );
		cairo_line_to( cr, PX( x ), top + ph );
		cairo_stroke( cr );
		snprintf( label, sizeof( label ), "%g", x );
		cairo_set_source_rgb( cr, 0.2, 0.2, 0.2 );
		cairo_move_to( cr, PX( x ) - 8, top + ph + 18 );
		cairo_show_text( cr, label );
	}
	cairo_set_source_rgb( cr, 0.2, 0.2, 0.2 );
	cairo_rectangle( cr, left, top, pw, ph );
	cairo_stroke( cr );
	cairo_move_to( cr, left + 0.5 * pw - 40, height - 12 );
	cairo_show_text( cr, x_label );
	cairo_move_to( cr, left, top - 8 );
	cairo_show_text( cr, y_label );
	cairo_set_font_size( cr, 16 );
	cairo_move_to( cr, left, 24 );
	cairo_show_text( cr, title );
	cairo_set_font_size( cr, 12 );
	for ( int s = 0; s < count; ++s )
	{
		cairo_set_source_rgb( cr, series[s].r, series[s].g, series[s].b );
		cairo_set_line_width( cr, 2.0 );
		cairo_new_path( cr );
		for ( int32_t i = 0; i < series[s].count; ++i )
		{
			cairo_line_to( cr, PX( series[s].x[i] ), PY( series[s].y[i] ) );
		}
		cairo_stroke( cr );
		double lx = left + pw - 200, ly = top + 18 + 18 * s;
		cairo_move_to( cr, lx, ly - 4 );
		cairo_line_to( cr, lx + 24, ly - 4 );
		cairo_stroke( cr );
		cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
		cairo_move_to( cr, lx + 30, ly );
		cairo_show_text( cr, series[s].name );
	}
#undef PX
#undef PY
	cairo_destroy( cr );
	int result = write_png( surface, path, err, err_size );
	cairo_surface_destroy( surface );
	return result;
}
