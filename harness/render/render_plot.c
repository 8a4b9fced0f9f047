/* sere harness — the text, axes and plots of harness/render: labels, colorbars, line plots and
 * the plane triangulation picture (the shaded meshes and canvases are in render.c). */
#define _POSIX_C_SOURCE 200809L
#include "render/render.h"

#include "common/io.h"
#include "render/internal/draw.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SERE_RENDER_FONT "DejaVu Sans"

static void set_font( cairo_t* cr, double size, int bold )
{
	cairo_select_font_face( cr, SERE_RENDER_FONT, CAIRO_FONT_SLANT_NORMAL,
							bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL );
	cairo_set_font_size( cr, size );
}

static double text_width( cairo_t* cr, const char* text )
{
	cairo_text_extents_t extents;
	cairo_text_extents( cr, text, &extents );
	return extents.x_advance;
}

static void show_text( cairo_t* cr, double x, double y, int align, const char* text )
{
	double shift = align == 1 ? 0.5 * text_width( cr, text ) : ( align == 2 ? text_width( cr, text ) : 0.0 );
	cairo_move_to( cr, x - shift, y );
	cairo_show_text( cr, text );
}

void sere_render_text( cairo_t* cr, double x, double y, double size, int bold, int align, const char* text )
{
	if ( text == NULL || text[0] == '\0' )
	{
		return;
	}
	set_font( cr, size, bold );
	show_text( cr, x, y, align, text );
}

/* Axis ticks at the "nice" multiples 1, 2, 5 x 10^k of a step chosen for about `target`
 * intervals over [lo, hi]; with expand the range grows to whole steps. */
typedef struct ticks
{
	double lo, hi, step;
	long first, last; /* tick values are k * step for k in [first, last] */
	int decimals;
} ticks;

static ticks nice_ticks( double lo, double hi, int target, int expand )
{
	ticks t;
	double raw = ( hi - lo ) / target;
	double magnitude = pow( 10.0, floor( log10( raw ) ) );
	double fraction = raw / magnitude;
	double nice = fraction < 1.5 ? 1.0 : ( fraction < 3.0 ? 2.0 : ( fraction < 7.0 ? 5.0 : 10.0 ) );
	t.step = nice * magnitude;
	/* A step of 1e-9 of itself absorbs rounding in lo / step so a value that is a whole
	 * multiple is not pushed to the next one. */
	double slack = 1e-9;
	t.first = (long) ( expand ? floor( lo / t.step + slack ) : ceil( lo / t.step - slack ) );
	t.last = (long) ( expand ? ceil( hi / t.step - slack ) : floor( hi / t.step + slack ) );
	t.lo = expand ? t.first * t.step : lo;
	t.hi = expand ? t.last * t.step : hi;
	int d = (int) -floor( log10( t.step ) + slack );
	t.decimals = d > 0 ? d : 0;
	return t;
}

static void tick_label( const ticks* t, long k, char* text, size_t size )
{
	double value = k * t->step;
	double largest = fmax( fabs( t->first * t->step ), fabs( t->last * t->step ) );
	if ( k == 0 )
	{
		snprintf( text, size, "0" );
	}
	else if ( largest >= 1e6 || t->decimals > 5 )
	{
		snprintf( text, size, "%.3g", value );
	}
	else
	{
		snprintf( text, size, "%.*f", t->decimals, value );
	}
}

void sere_render_colorbar( cairo_t* cr, double x, double y, double w, double h, double lo, double hi,
						   const char* label )
{
	cairo_save( cr );
	cairo_pattern_t* gradient = cairo_pattern_create_linear( 0.0, y + h, 0.0, y );
	for ( int k = 0; k < 10; ++k )
	{
		float rgb[3];
		sere_render_colormap( k / 9.0, rgb );
		cairo_pattern_add_color_stop_rgb( gradient, k / 9.0, rgb[0], rgb[1], rgb[2] );
	}
	sere_render_gradient_box( cr, gradient, x, y, w, h, 0.3 );
	set_font( cr, 12, 0 );
	if ( hi > lo && isfinite( lo ) && isfinite( hi ) )
	{
		ticks t = nice_ticks( lo, hi, (int) fmax( 2.0, fmin( 8.0, h / 50.0 ) ), 0 );
		for ( long k = t.first; k <= t.last; ++k )
		{
			double ty = y + h - ( k * t.step - lo ) / ( hi - lo ) * h;
			char text[64];
			tick_label( &t, k, text, sizeof( text ) );
			cairo_move_to( cr, x + w, ty );
			cairo_line_to( cr, x + w + 4, ty );
			cairo_stroke( cr );
			show_text( cr, x + w + 7, ty + 4, 0, text );
		}
	}
	if ( label != NULL )
	{
		show_text( cr, x + 0.5 * w, y - 9, 1, label );
	}
	cairo_restore( cr );
}

/* Whether the segment (ax, ay)-(bx, by) meets the box [x0, x1] x [y0, y1] (Liang-Barsky). */
static int segment_meets_box( double ax, double ay, double bx, double by, double x0, double y0, double x1, double y1 )
{
	double dx = bx - ax, dy = by - ay;
	double p[4] = { -dx, dx, -dy, dy };
	double q[4] = { ax - x0, x1 - ax, ay - y0, y1 - ay };
	double t0 = 0.0, t1 = 1.0;
	for ( int k = 0; k < 4; ++k )
	{
		if ( p[k] == 0.0 )
		{
			if ( q[k] < 0.0 )
			{
				return 0;
			}
			continue;
		}
		double t = q[k] / p[k];
		if ( p[k] < 0.0 )
		{
			t0 = fmax( t0, t );
		}
		else
		{
			t1 = fmin( t1, t );
		}
		if ( t0 > t1 )
		{
			return 0;
		}
	}
	return 1;
}

static int finite_point( const sere_render_series* s, int32_t i )
{
	return isfinite( s->x[i] ) && isfinite( s->y[i] );
}

typedef struct plot_area
{
	double left, top, width, height;
	ticks x, y;
} plot_area;

static double plot_x( const plot_area* a, double x )
{
	return a->left + ( x - a->x.lo ) / ( a->x.hi - a->x.lo ) * a->width;
}

static double plot_y( const plot_area* a, double y )
{
	return a->top + a->height - ( y - a->y.lo ) / ( a->y.hi - a->y.lo ) * a->height;
}

static void draw_legend( cairo_t* cr, const plot_area* a, const sere_render_series* series, int series_count )
{
	const double row = 18.0, swatch = 24.0, inset = 8.0;
	double widest = 0.0;
	int named = 0;
	set_font( cr, 12, 0 );
	for ( int s = 0; s < series_count; ++s )
	{
		if ( series[s].name != NULL && series[s].name[0] != '\0' )
		{
			widest = fmax( widest, text_width( cr, series[s].name ) );
			named += 1;
		}
	}
	if ( named == 0 )
	{
		return;
	}
	double bw = 10.0 + swatch + 8.0 + widest + 10.0, bh = 8.0 + row * named;
	/* Top right, top left, bottom right, bottom left: the first that the fewest curve
	 * segments cross. */
	double corners[4][2] = {
		{ a->left + a->width - inset - bw, a->top + inset },
		{ a->left + inset, a->top + inset },
		{ a->left + a->width - inset - bw, a->top + a->height - inset - bh },
		{ a->left + inset, a->top + a->height - inset - bh },
	};
	int best = 0;
	long best_hits = -1;
	for ( int c = 0; c < 4; ++c )
	{
		long hits = 0;
		for ( int s = 0; s < series_count; ++s )
		{
			for ( int32_t i = 1; i < series[s].count; ++i )
			{
				if ( finite_point( series + s, i - 1 ) && finite_point( series + s, i ) &&
					 segment_meets_box( plot_x( a, series[s].x[i - 1] ), plot_y( a, series[s].y[i - 1] ),
										plot_x( a, series[s].x[i] ), plot_y( a, series[s].y[i] ), corners[c][0],
										corners[c][1], corners[c][0] + bw, corners[c][1] + bh ) )
				{
					hits += 1;
				}
			}
		}
		if ( best_hits < 0 || hits < best_hits )
		{
			best = c;
			best_hits = hits;
		}
	}
	double bx = corners[best][0], by = corners[best][1];
	cairo_rectangle( cr, floor( bx ) + 0.5, floor( by ) + 0.5, floor( bw ), floor( bh ) );
	cairo_set_source_rgba( cr, 1.0, 1.0, 1.0, 0.9 );
	cairo_fill_preserve( cr );
	cairo_set_source_rgb( cr, 0.75, 0.75, 0.75 );
	cairo_set_line_width( cr, 1.0 );
	cairo_stroke( cr );
	int line = 0;
	for ( int s = 0; s < series_count; ++s )
	{
		if ( series[s].name == NULL || series[s].name[0] == '\0' )
		{
			continue;
		}
		double ly = by + 4.0 + row * ( line + 0.5 );
		const double dash[2] = { 6.0, 4.0 };
		cairo_set_dash( cr, dash, series[s].dashed ? 2 : 0, 0.0 );
		cairo_set_source_rgb( cr, series[s].rgb[0], series[s].rgb[1], series[s].rgb[2] );
		cairo_set_line_width( cr, 2.0 );
		cairo_move_to( cr, bx + 10.0, ly );
		cairo_line_to( cr, bx + 10.0 + swatch, ly );
		cairo_stroke( cr );
		cairo_set_dash( cr, dash, 0, 0.0 );
		cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
		show_text( cr, bx + 10.0 + swatch + 8.0, ly + 4.0, 0, series[s].name );
		line += 1;
	}
}

/* The data's box, or the axes' fixed y range; a constant curve widened so it still gets an
 * axis. -1 with a message when no point is finite or the fixed range is empty. */
static sere_status plot_range( const sere_render_axes* axes, const sere_render_series* series, int series_count,
							   double lo[2], double hi[2], char* err, size_t err_size )
{
	lo[0] = lo[1] = INFINITY;
	hi[0] = hi[1] = -INFINITY;
	for ( int s = 0; s < series_count; ++s )
	{
		for ( int32_t i = 0; i < series[s].count; ++i )
		{
			if ( finite_point( series + s, i ) )
			{
				lo[0] = fmin( lo[0], series[s].x[i] ), hi[0] = fmax( hi[0], series[s].x[i] );
				lo[1] = fmin( lo[1], series[s].y[i] ), hi[1] = fmax( hi[1], series[s].y[i] );
			}
		}
	}
	if ( !( lo[0] <= hi[0] ) )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: plot '%s' has no finite point",
						  axes->title ? axes->title : "" );
	}
	if ( axes->fixed_y )
	{
		if ( !( axes->y_min < axes->y_max ) || !isfinite( axes->y_min ) || !isfinite( axes->y_max ) )
		{
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: plot y range [%g, %g] is empty", axes->y_min,
							  axes->y_max );
		}
		lo[1] = axes->y_min, hi[1] = axes->y_max;
	}
	for ( int c = 0; c < 2; ++c )
	{
		/* A constant curve still gets an axis: widen by a tenth of its size, or by 1 at 0. */
		if ( hi[c] == lo[c] )
		{
			double pad = lo[c] != 0.0 ? 0.1 * fabs( lo[c] ) : 1.0;
			lo[c] -= pad, hi[c] += pad;
		}
	}
	return SERE_OK;
}

/* The grid, the tick marks and their labels. */
static void draw_grid( cairo_t* cr, const plot_area* a )
{
	char text[64];
	/* Grid lines on pixel centers so 1-pixel lines stay crisp. */
	cairo_set_line_width( cr, 1.0 );
	cairo_set_source_rgb( cr, 0.9, 0.9, 0.9 );
	for ( long k = a->y.first; k <= a->y.last; ++k )
	{
		double py = floor( plot_y( a, k * a->y.step ) ) + 0.5;
		cairo_move_to( cr, a->left, py );
		cairo_line_to( cr, a->left + a->width, py );
	}
	for ( long k = a->x.first; k <= a->x.last; ++k )
	{
		double px = floor( plot_x( a, k * a->x.step ) ) + 0.5;
		cairo_move_to( cr, px, a->top );
		cairo_line_to( cr, px, a->top + a->height );
	}
	cairo_stroke( cr );

	cairo_set_source_rgb( cr, 0.25, 0.25, 0.25 );
	for ( long k = a->y.first; k <= a->y.last; ++k )
	{
		double py = floor( plot_y( a, k * a->y.step ) ) + 0.5;
		cairo_move_to( cr, a->left - 4.0, py );
		cairo_line_to( cr, a->left, py );
		cairo_stroke( cr );
		tick_label( &a->y, k, text, sizeof( text ) );
		show_text( cr, a->left - 7.0, py + 4.0, 2, text );
	}
	for ( long k = a->x.first; k <= a->x.last; ++k )
	{
		double px = floor( plot_x( a, k * a->x.step ) ) + 0.5;
		cairo_move_to( cr, px, a->top + a->height );
		cairo_line_to( cr, px, a->top + a->height + 4.0 );
		cairo_stroke( cr );
		tick_label( &a->x, k, text, sizeof( text ) );
		show_text( cr, px, a->top + a->height + 17.0, 1, text );
	}
}

/* Every series as a polyline clipped to the plot area, broken at non-finite points. */
static void draw_series( cairo_t* cr, const plot_area* a, const sere_render_series* series, int series_count )
{
	cairo_save( cr );
	cairo_rectangle( cr, a->left, a->top, a->width, a->height );
	cairo_clip( cr );
	cairo_set_line_join( cr, CAIRO_LINE_JOIN_ROUND );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	cairo_set_line_width( cr, 2.0 );
	for ( int s = 0; s < series_count; ++s )
	{
		const double dash[2] = { 6.0, 4.0 };
		cairo_set_dash( cr, dash, series[s].dashed ? 2 : 0, 0.0 );
		cairo_set_source_rgb( cr, series[s].rgb[0], series[s].rgb[1], series[s].rgb[2] );
		int pen_down = 0;
		for ( int32_t i = 0; i < series[s].count; ++i )
		{
			if ( !finite_point( series + s, i ) )
			{
				pen_down = 0;
				continue;
			}
			double px = plot_x( a, series[s].x[i] ), py = plot_y( a, series[s].y[i] );
			if ( pen_down )
			{
				cairo_line_to( cr, px, py );
			}
			else
			{
				cairo_move_to( cr, px, py );
				/* A lone point still shows as a dot (round cap on a zero-length segment). */
				cairo_line_to( cr, px, py );
			}
			pen_down = 1;
		}
		cairo_stroke( cr );
	}
	cairo_restore( cr );
}

sere_status sere_render_plot_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_axes* axes,
								   const sere_render_series* series, int series_count, char* err, size_t err_size )
{
	const sere_render_axes none = { 0 };
	axes = axes != NULL ? axes : &none;
	double lo[2], hi[2];
	sere_status status = plot_range( axes, series, series_count, lo, hi, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}

	plot_area a;
	a.x = nice_ticks( lo[0], hi[0], (int) fmax( 3.0, fmin( 10.0, w / 110.0 ) ), 1 );
	a.y = nice_ticks( lo[1], hi[1], (int) fmax( 3.0, fmin( 10.0, h / 70.0 ) ), !axes->fixed_y );
	cairo_save( cr );
	cairo_rectangle( cr, x0, y0, w, h );
	cairo_clip( cr );
	cairo_set_source_rgb( cr, 1.0, 1.0, 1.0 );
	cairo_paint( cr );
	int has_title = axes->title != NULL && axes->title[0] != '\0';
	int has_x_label = axes->x_label != NULL && axes->x_label[0] != '\0';
	int has_y_label = axes->y_label != NULL && axes->y_label[0] != '\0';
	set_font( cr, 12, 0 );
	double label_width = 0.0;
	char text[64];
	for ( long k = a.y.first; k <= a.y.last; ++k )
	{
		tick_label( &a.y, k, text, sizeof( text ) );
		label_width = fmax( label_width, text_width( cr, text ) );
	}
	tick_label( &a.x, a.x.last, text, sizeof( text ) );
	double last_x_half = 0.5 * text_width( cr, text );
	a.left = x0 + 12.0 + ( has_y_label ? 22.0 : 0.0 ) + label_width + 8.0;
	a.top = y0 + ( has_title ? 38.0 : 14.0 );
	double right = x0 + w - fmax( 16.0, last_x_half + 6.0 );
	double bottom = y0 + h - 10.0 - ( has_x_label ? 22.0 : 0.0 ) - 18.0;
	a.width = right - a.left, a.height = bottom - a.top;
	if ( a.width < 20.0 || a.height < 20.0 )
	{
		cairo_restore( cr );
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: plot region %gx%g too small", w, h );
	}

	draw_grid( cr, &a );
	draw_series( cr, &a, series, series_count );

	cairo_set_source_rgb( cr, 0.25, 0.25, 0.25 );
	cairo_set_line_width( cr, 1.0 );
	cairo_rectangle( cr, floor( a.left ) + 0.5, floor( a.top ) + 0.5, floor( a.width ), floor( a.height ) );
	cairo_stroke( cr );
	draw_legend( cr, &a, series, series_count );

	cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
	if ( has_title )
	{
		sere_render_text( cr, a.left + 0.5 * a.width, y0 + 24.0, 15, 1, 1, axes->title );
	}
	if ( has_x_label )
	{
		sere_render_text( cr, a.left + 0.5 * a.width, y0 + h - 12.0, 13, 0, 1, axes->x_label );
	}
	if ( has_y_label )
	{
		cairo_save( cr );
		cairo_translate( cr, x0 + 12.0 + 13.0, a.top + 0.5 * a.height );
		cairo_rotate( cr, -0.5 * 3.14159265358979323846 );
		sere_render_text( cr, 0.0, 0.0, 13, 0, 1, axes->y_label );
		cairo_restore( cr );
	}
	cairo_restore( cr );
	return sere_render_cairo_failed( cr, err, err_size );
}

sere_status sere_render_plot( const char* path, int width, int height, const sere_render_axes* axes,
							  const sere_render_series* series, int series_count, char* err, size_t err_size )
{
	sere_render_canvas canvas;
	sere_status status = sere_render_canvas_create( &canvas, width, height, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	sere_status result =
		sere_render_plot_draw( canvas.cr, 0.0, 0.0, width, height, axes, series, series_count, err, err_size );
	if ( result == 0 )
	{
		result = sere_render_canvas_write_png( &canvas, path, err, err_size );
	}
	sere_render_canvas_destroy( &canvas );
	return result;
}

sere_status sere_render_plane_png( const char* path, int width, int height, const sere_render_plane* plane, char* err,
								   size_t err_size )
{
	double lo = INFINITY, hi = -INFINITY;
	if ( plane->scalar != NULL )
	{
		for ( int32_t i = 0; i < plane->vertex_count; ++i )
		{
			if ( !isfinite( plane->scalar[i] ) )
			{
				return sere_fail( SERE_ERR_NONFINITE, err, err_size, "%s: scalar at vertex %d is not finite", path,
								  (int) i );
			}
			lo = fmin( lo, plane->scalar[i] ), hi = fmax( hi, plane->scalar[i] );
		}
	}
	sere_render_canvas canvas;
	sere_status status = sere_render_canvas_create( &canvas, width, height, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	float* rgb = NULL;
	sere_render_mesh mesh = {
		.x = plane->x,
		.y = plane->y,
		.vertex_count = plane->vertex_count,
		.triangles = plane->triangles,
		.triangle_count = plane->triangle_count,
		.color = { 0.80f, 0.89f, 0.72f },
	};
	if ( plane->scalar != NULL && plane->vertex_count > 0 )
	{
		rgb = malloc( sizeof( float ) * 3 * (size_t) plane->vertex_count );
		if ( rgb == NULL )
		{
			sere_render_canvas_destroy( &canvas );
			return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory", path );
		}
		sere_render_colormap_values( plane->scalar, plane->vertex_count, lo, hi, rgb );
		mesh.rgb = rgb;
	}
	sere_render_lines lines[2] = {
		{ plane->outline_pairs, plane->outline_pairs != NULL ? plane->outline_count : 0, { 0.15f, 0.15f, 0.15f }, 1.8 },
		{ plane->vein_pairs, plane->vein_pairs != NULL ? plane->vein_count : 0, { 0.85f, 0.12f, 0.10f }, 1.6 },
	};
	sere_render_style style = { .edges = 1, .unlit = 1, .lines = lines, .line_set_count = 2 };
	int has_title = plane->title != NULL && plane->title[0] != '\0';
	double top = has_title ? 40.0 : 8.0, bar = rgb != NULL ? 96.0 : 0.0;
	sere_render_view view = { .azimuth = 0.0, .elevation = 90.0, .margin = 14.0 };
	cairo_t* cr = canvas.cr;
	sere_status result = sere_render_mesh_draw( cr, 8.0, top, width - 16.0 - bar, height - top - 8.0, &mesh, &view,
												&style, err, err_size );
	if ( result == 0 )
	{
		cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
		sere_render_text( cr, 0.5 * width, 27.0, 17, 1, 1, plane->title );
		if ( rgb != NULL )
		{
			double bar_height = fmin( 320.0, height - top - 60.0 );
			sere_render_colorbar( cr, width - bar + 4.0, top + 0.5 * ( height - top - bar_height ), 18.0, bar_height,
								  lo, hi, plane->scalar_name );
		}
		result = sere_render_canvas_write_png( &canvas, path, err, err_size );
	}
	free( rgb );
	sere_render_canvas_destroy( &canvas );
	return result;
}
