#define _POSIX_C_SOURCE 200809L
#include "render/leafpics.h"

#include "common/io.h"
#include "render/internal/draw.h"
#include "render/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A render error ("render: ...") restated as "<path>: frame N: ..."; returns its status. */
static sere_status fail_render( sere_status status, char* err, size_t err_size, const char* path, int frame )
{
	char inner[256] = { 0 };
	if ( err != NULL && err_size > 0 )
	{
		snprintf( inner, sizeof( inner ), "%s", err );
	}
	const char* reason = strncmp( inner, "render: ", 8 ) == 0 ? inner + 8 : inner;
	return sere_fail( status, err, err_size, "%s: frame %d: %s", path, frame, reason );
}

/* The xy footprint of a frame; -1 with a message when a coordinate is not finite. */
static sere_status footprint( const char* path, const sere_leafpics_frame* f, double lo[2], double hi[2], char* err,
							  size_t err_size )
{
	for ( int32_t i = 0; i < f->vertex_count; ++i )
	{
		double p[3] = { f->x[i], f->y[i], f->z != NULL ? f->z[i] : 0.0 };
		if ( !isfinite( p[0] ) || !isfinite( p[1] ) || !isfinite( p[2] ) )
		{
			return sere_fail( SERE_ERR_NONFINITE, err, err_size, "%s: frame %d: vertex %d has a non-finite coordinate",
							  path, f->frame, (int) i );
		}
		for ( int c = 0; c < 2; ++c )
		{
			lo[c] = ( i == 0 || p[c] < lo[c] ) ? p[c] : lo[c];
			hi[c] = ( i == 0 || p[c] > hi[c] ) ? p[c] : hi[c];
		}
	}
	return SERE_OK;
}

static sere_status check_input( const char* path, int frame_count, const sere_leafpics_frame* frames,
								const int32_t* tri, int32_t tri_count, char* err, size_t err_size )
{
	if ( path == NULL || path[0] == '\0' )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "leafpics: no output path" );
	}
	if ( frames == NULL || frame_count < 1 || frame_count > 16 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: %d frames, expected 1..16", path, frame_count );
	}
	if ( tri_count < 0 || ( tri_count > 0 && tri == NULL ) )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: triangle list missing or negative count %d", path,
						  (int) tri_count );
	}
	for ( int k = 0; k < frame_count; ++k )
	{
		const sere_leafpics_frame* f = frames + k;
		if ( f->vertex_count < 1 || f->x == NULL || f->y == NULL )
		{
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: frame %d has no vertices", path, f->frame );
		}
	}
	return SERE_OK;
}

/* The mesh of a frame colored by its water content into rgb (3 floats per vertex). */
static sere_render_mesh frame_mesh( const sere_leafpics_frame* f, const int32_t* tri, int32_t tri_count, float* rgb )
{
	sere_render_mesh mesh = {
		.x = f->x,
		.y = f->y,
		.z = f->z,
		.vertex_count = f->vertex_count,
		.triangles = tri,
		.triangle_count = tri_count,
	};
	if ( f->rwc != NULL )
	{
		sere_render_dry_colors( f->rwc, f->vertex_count, rgb );
		mesh.rgb = rgb;
	}
	else
	{
		sere_render_dry_color( f->relative_water, mesh.color );
	}
	return mesh;
}

static void caption_of( const sere_leafpics_frame* f, char* text, size_t size )
{
	snprintf( text, size, "frame %d, RWC %.2f", f->frame, f->relative_water );
}

/* A horizontal bar of the fresh-to-dry blend (dry on the left), tinted as the lower face when
 * lower is set; the blend is linear, so two color stops give it exactly. */
static void blend_bar( cairo_t* cr, double x, double y, double w, double h, int lower )
{
	float dry[3], fresh[3];
	sere_render_dry_color( 0.0, dry );
	sere_render_dry_color( 1.0, fresh );
	if ( lower )
	{
		sere_render_lower_tint( dry, dry );
		sere_render_lower_tint( fresh, fresh );
	}
	cairo_pattern_t* gradient = cairo_pattern_create_linear( x, 0.0, x + w, 0.0 );
	cairo_pattern_add_color_stop_rgb( gradient, 0.0, dry[0], dry[1], dry[2] );
	cairo_pattern_add_color_stop_rgb( gradient, 1.0, fresh[0], fresh[1], fresh[2] );
	sere_render_gradient_box( cr, gradient, x, y, w, h, 0.35 );
}

/* The legend line: both faces' color ramps and the shadow, from x at baseline y. */
static void legend( cairo_t* cr, double x, double y )
{
	const double bar = 120.0;
	cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
	sere_render_text( cr, x, y, 12, 0, 0, "upper face: dry" );
	blend_bar( cr, x + 96.0, y - 11.0, bar, 13.0, 0 );
	cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
	sere_render_text( cr, x + 102.0 + bar, y, 12, 0, 0, "fresh" );
	x += 102.0 + bar + 56.0;
	sere_render_text( cr, x, y, 12, 0, 0, "lower face: dry" );
	blend_bar( cr, x + 94.0, y - 11.0, bar, 13.0, 1 );
	cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
	sere_render_text( cr, x + 100.0 + bar, y, 12, 0, 0, "fresh" );
	x += 100.0 + bar + 56.0;
	cairo_rectangle( cr, x, y - 11.0, 26.0, 13.0 );
	cairo_set_source_rgb( cr, 0.87, 0.87, 0.86 );
	cairo_fill( cr );
	cairo_rectangle( cr, x + 8.0, y - 11.0, 18.0, 13.0 );
	cairo_set_source_rgba( cr, 0.12, 0.12, 0.14, 0.45 );
	cairo_fill( cr );
	cairo_rectangle( cr, x, y - 11.0, 26.0, 13.0 );
	cairo_set_source_rgb( cr, 0.62, 0.62, 0.61 );
	cairo_stroke( cr );
	cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
	sere_render_text( cr, x + 32.0, y, 12, 0, 0, "ground, shadow from above" );
}

/* The rows' names, turned to read upwards, left of the rows that start at y0. */
static void row_names( cairo_t* cr, double left, double y0, double ph, double pad )
{
	const char* names[2] = { "oblique view", "top view" };
	for ( int r = 0; r < 2; ++r )
	{
		double y = y0 + r * ( ph + pad );
		cairo_save( cr );
		cairo_translate( cr, left - 12.0, y + 0.5 * ph );
		cairo_rotate( cr, -0.5 * 3.14159265358979323846 );
		cairo_set_source_rgb( cr, 0.25, 0.25, 0.25 );
		sere_render_text( cr, 0.0, 0.0, 13, 1, 1, names[r] );
		cairo_restore( cr );
	}
}

sere_status sere_leafpics_sheet( const char* path, const char* title, int frame_count,
								 const sere_leafpics_frame* frames, const int32_t* tri, int32_t tri_count,
								 float ground_z, char* err, size_t err_size )
{
	sere_status status = check_input( path, frame_count, frames, tri, tri_count, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	/* One ground tile size for every frame: the largest footprint, grown on every side. */
	double lo[16][2], hi[16][2], width = 0.0, height = 0.0;
	int32_t most = 0;
	for ( int k = 0; k < frame_count; ++k )
	{
		status = footprint( path, frames + k, lo[k], hi[k], err, err_size );
		if ( status != SERE_OK )
		{
			return status;
		}
		width = fmax( width, hi[k][0] - lo[k][0] );
		height = fmax( height, hi[k][1] - lo[k][1] );
		most = frames[k].vertex_count > most ? frames[k].vertex_count : most;
	}
	double side = fmax( width, height );
	double half_w = 0.5 * width + ( side > 0.0 ? 0.2 * side : 0.5 );
	double half_h = 0.5 * height + ( side > 0.0 ? 0.2 * side : 0.5 );
	sere_render_scene scenes[16];
	for ( int k = 0; k < frame_count; ++k )
	{
		double cx = 0.5 * ( lo[k][0] + hi[k][0] ), cy = 0.5 * ( lo[k][1] + hi[k][1] );
		scenes[k] = ( sere_render_scene ){
			.lower_tint = 1,
			.ground = 1,
			.ground_z = isfinite( ground_z ) ? ground_z : -INFINITY,
			.ground_box = { cx - half_w, cy - half_h, cx + half_w, cy + half_h },
		};
	}

	const int pw = SERE_LEAFPICS_PANEL_WIDTH, ph = SERE_LEAFPICS_PANEL_HEIGHT, pad = 12, left = 34, header = 26,
			  legend_height = 40;
	int has_title = title != NULL && title[0] != '\0';
	int top = has_title ? 44 : pad;
	int canvas_w = left + frame_count * ( pw + pad );
	int canvas_h = top + header + 2 * ph + 2 * pad + legend_height;
	canvas_w = canvas_w < 760 ? 760 : canvas_w;
	float* rgb = malloc( sizeof( float ) * 3 * (size_t) most );
	if ( rgb == NULL )
	{
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory for %d vertices", path, (int) most );
	}

	/* Each row's views: fitted frame by frame (centre on that frame's scene), then all drawn
	 * at the smallest of the fitted scales. */
	const double angles[2][2] = { { SERE_LEAFPICS_AZIMUTH, SERE_LEAFPICS_ELEVATION }, { 0.0, 90.0 } };
	sere_render_view views[2][16];
	for ( int r = 0; r < 2; ++r )
	{
		double scale = INFINITY;
		for ( int k = 0; k < frame_count; ++k )
		{
			views[r][k] = ( sere_render_view ){ .azimuth = angles[r][0], .elevation = angles[r][1], .margin = 10.0 };
			sere_render_mesh mesh = frame_mesh( frames + k, tri, tri_count, rgb );
			status = sere_render_fit_scene( &mesh, scenes + k, pw, ph, &views[r][k], err, err_size );
			if ( status != SERE_OK )
			{
				free( rgb );
				return fail_render( status, err, err_size, path, frames[k].frame );
			}
			scale = fmin( scale, views[r][k].scale );
		}
		for ( int k = 0; k < frame_count; ++k )
		{
			views[r][k].scale = scale;
		}
	}

	sere_render_canvas canvas;
	status = sere_render_canvas_create( &canvas, canvas_w, canvas_h, err, err_size );
	if ( status != SERE_OK )
	{
		free( rgb );
		return fail_render( status, err, err_size, path, frames[0].frame );
	}
	cairo_t* cr = canvas.cr;
	cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
	sere_render_text( cr, 0.5 * canvas_w, 29, 18, 1, 1, title );
	row_names( cr, left, top + header, ph, pad );
	for ( int k = 0; k < frame_count; ++k )
	{
		double x = left + k * ( pw + pad );
		char caption[96];
		caption_of( frames + k, caption, sizeof( caption ) );
		cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
		sere_render_text( cr, x + 0.5 * pw, top + header - 8.0, 14, 1, 1, caption );
		sere_render_mesh mesh = frame_mesh( frames + k, tri, tri_count, rgb );
		for ( int r = 0; r < 2; ++r )
		{
			status = sere_render_mesh_draw_scene( cr, x, top + header + r * ( ph + pad ), pw, ph, &mesh, &views[r][k],
												  NULL, scenes + k, err, err_size );
			if ( status != SERE_OK )
			{
				free( rgb );
				sere_render_canvas_destroy( &canvas );
				return fail_render( status, err, err_size, path, frames[k].frame );
			}
		}
	}
	free( rgb );
	legend( cr, left, top + header + 2 * ph + 2 * pad + 16.0 );
	sere_status result = sere_render_canvas_write_png( &canvas, path, err, err_size );
	sere_render_canvas_destroy( &canvas );
	return result;
}

sere_status sere_leafpics_view( const char* path, const char* title, const sere_leafpics_frame* frame,
								const int32_t* tri, int32_t tri_count, float ground_z, int size, char* err,
								size_t err_size )
{
	sere_status status = check_input( path, 1, frame, tri, tri_count, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	double lo[2], hi[2];
	status = footprint( path, frame, lo, hi, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	size = size > 0 ? size : 900;
	if ( size < 64 || size > 8192 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: picture size %d outside 64..8192", path, size );
	}
	float* rgb = malloc( sizeof( float ) * 3 * (size_t) frame->vertex_count );
	if ( rgb == NULL )
	{
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory for %d vertices", path,
						  (int) frame->vertex_count );
	}
	sere_render_scene scene = {
		.lower_tint = 1,
		.ground = 1,
		.ground_z = isfinite( ground_z ) ? ground_z : -INFINITY,
		.ground_box = { 0.0, 0.0, 0.0, 0.0 }, /* the footprint grown */
	};
	sere_render_mesh mesh = frame_mesh( frame, tri, tri_count, rgb );
	sere_render_view view = { .azimuth = SERE_LEAFPICS_AZIMUTH,
							  .elevation = SERE_LEAFPICS_ELEVATION,
							  .margin = 0.03 * size };
	int has_title = title != NULL && title[0] != '\0';
	double top = has_title ? 0.06 * size : 0.0, bottom = 0.05 * size;
	sere_render_canvas canvas;
	status = sere_render_canvas_create( &canvas, size, size, err, err_size );
	if ( status != SERE_OK )
	{
		free( rgb );
		return fail_render( status, err, err_size, path, frame->frame );
	}
	status = sere_render_mesh_draw_scene( canvas.cr, 0.0, top, size, size - top - bottom, &mesh, &view, NULL, &scene,
										  err, err_size );
	free( rgb );
	if ( status != SERE_OK )
	{
		sere_render_canvas_destroy( &canvas );
		return fail_render( status, err, err_size, path, frame->frame );
	}
	char caption[96];
	caption_of( frame, caption, sizeof( caption ) );
	cairo_set_source_rgb( canvas.cr, 0.1, 0.1, 0.1 );
	sere_render_text( canvas.cr, 0.5 * size, 0.042 * size, 0.026 * size, 1, 1, title );
	cairo_set_source_rgb( canvas.cr, 0.2, 0.2, 0.2 );
	sere_render_text( canvas.cr, 0.5 * size, size - 0.018 * size, 0.02 * size, 0, 1, caption );
	status = sere_render_canvas_write_png( &canvas, path, err, err_size );
	sere_render_canvas_destroy( &canvas );
	return status;
}
