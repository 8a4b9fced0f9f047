#define _POSIX_C_SOURCE 200809L
#include "render/render.h"

#include "common/io.h"
#include "core/array.h"
#include "render/internal/draw.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Camera frame of a view: screen right, screen up and the direction toward the viewer, in
 * model coordinates. Azimuth turns the camera about +z, elevation tilts it up to look down. */
typedef struct frame
{
	double right[3], up[3], toward[3];
} frame;

static frame view_frame( const sere_render_view* view )
{
	const double degree = 3.14159265358979323846 / 180.0;
	double ca = cos( view->azimuth * degree ), sa = sin( view->azimuth * degree );
	double ce = cos( view->elevation * degree ), se = sin( view->elevation * degree );
	frame f = {
		.right = { ca, sa, 0.0 },
		.up = { -sa * se, ca * se, ce },
		.toward = { sa * ce, -ca * ce, se },
	};
	return f;
}

static double dot3( const double a[3], double x, double y, double z )
{
	return a[0] * x + a[1] * y + a[2] * z;
}

static double vertex_z( const sere_render_mesh* mesh, int32_t i )
{
	return mesh->z != NULL ? mesh->z[i] : 0.0;
}

/* Point i of the mesh's vertices followed by the extra points (3 doubles each). */
static void point_at( const sere_render_mesh* mesh, const double* extra, int32_t i, double p[3] )
{
	if ( i < mesh->vertex_count )
	{
		p[0] = mesh->x[i], p[1] = mesh->y[i], p[2] = vertex_z( mesh, i );
		return;
	}
	const double* e = extra + 3 * (size_t) ( i - mesh->vertex_count );
	p[0] = e[0], p[1] = e[1], p[2] = e[2];
}

static sere_status check_mesh( const sere_render_mesh* mesh, char* err, size_t err_size )
{
	if ( mesh == NULL || mesh->vertex_count < 0 || mesh->triangle_count < 0 ||
		 ( mesh->vertex_count > 0 && ( mesh->x == NULL || mesh->y == NULL ) ) ||
		 ( mesh->triangle_count > 0 && mesh->triangles == NULL ) )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: mesh arrays missing or negative counts" );
	}
	for ( int32_t i = 0; i < mesh->vertex_count; ++i )
	{
		if ( !isfinite( mesh->x[i] ) || !isfinite( mesh->y[i] ) || !isfinite( vertex_z( mesh, i ) ) )
		{
			return sere_fail( SERE_ERR_NONFINITE, err, err_size, "render: vertex %d has a non-finite coordinate",
							  (int) i );
		}
	}
	for ( int32_t k = 0; k < 3 * mesh->triangle_count; ++k )
	{
		if ( mesh->triangles[k] < 0 || mesh->triangles[k] >= mesh->vertex_count )
		{
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: triangle %d uses vertex %d of %d",
							  (int) ( k / 3 ), (int) mesh->triangles[k], (int) mesh->vertex_count );
		}
	}
	return SERE_OK;
}

static sere_status check_view( const sere_render_view* view, char* err, size_t err_size )
{
	if ( !isfinite( view->azimuth ) || !isfinite( view->elevation ) || !isfinite( view->center[0] ) ||
		 !isfinite( view->center[1] ) || !isfinite( view->center[2] ) || !isfinite( view->margin ) )
	{
		return sere_fail( SERE_ERR_NONFINITE, err, err_size, "render: view angles, center and margin must be finite" );
	}
	return SERE_OK;
}

/* The ground plane of a scene resolved against the mesh: its height and its quad. */
typedef struct ground_plane
{
	double z;
	double box[4];
} ground_plane;

static ground_plane resolve_ground( const sere_render_mesh* mesh, const sere_render_scene* scene )
{
	ground_plane g = { scene->ground_z,
					   { scene->ground_box[0], scene->ground_box[1], scene->ground_box[2], scene->ground_box[3] } };
	double lo[3] = { 0.0, 0.0, 0.0 }, hi[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t i = 0; i < mesh->vertex_count; ++i )
	{
		double p[3] = { mesh->x[i], mesh->y[i], vertex_z( mesh, i ) };
		for ( int c = 0; c < 3; ++c )
		{
			lo[c] = ( i == 0 || p[c] < lo[c] ) ? p[c] : lo[c];
			hi[c] = ( i == 0 || p[c] > hi[c] ) ? p[c] : hi[c];
		}
	}
	if ( !isfinite( g.z ) )
	{
		g.z = lo[2];
	}
	int usable = isfinite( g.box[0] ) && isfinite( g.box[1] ) && isfinite( g.box[2] ) && isfinite( g.box[3] );
	if ( !usable || !( g.box[0] < g.box[2] ) || !( g.box[1] < g.box[3] ) )
	{
		double side = fmax( hi[0] - lo[0], hi[1] - lo[1] );
		double grow = side > 0.0 ? 0.2 * side : 0.5;
		g.box[0] = lo[0] - grow, g.box[1] = lo[1] - grow;
		g.box[2] = hi[0] + grow, g.box[3] = hi[1] + grow;
	}
	return g;
}

/* Fits the mesh's vertices and `extra` more points (3 doubles each); with on_screen the
 * center is the middle of their projection rather than of their box. */
static sere_status fit_points( const sere_render_mesh* mesh, const double* extra, int extra_count, int on_screen,
							   double w, double h, sere_render_view* view, char* err, size_t err_size )
{
	sere_status status = check_view( view, err, err_size );
	status = status == SERE_OK ? check_mesh( mesh, err, err_size ) : status;
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t total = mesh->vertex_count + extra_count;
	double lo[3] = { 0.0, 0.0, 0.0 }, hi[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t i = 0; i < total; ++i )
	{
		double p[3];
		point_at( mesh, extra, i, p );
		for ( int c = 0; c < 3; ++c )
		{
			lo[c] = ( i == 0 || p[c] < lo[c] ) ? p[c] : lo[c];
			hi[c] = ( i == 0 || p[c] > hi[c] ) ? p[c] : hi[c];
		}
	}
	for ( int c = 0; c < 3; ++c )
	{
		view->center[c] = 0.5 * ( lo[c] + hi[c] );
	}
	/* The tight projected half-extents about the box center, so the fitted mesh touches the
	 * margin on at least one side rather than the looser projected box. */
	frame f = view_frame( view );
	if ( on_screen )
	{
		/* Moved across the screen to the middle of the projected extents, so an oblique scene
		 * does not leave its region's top or bottom empty. */
		double lo_x = 0.0, hi_x = 0.0, lo_y = 0.0, hi_y = 0.0;
		for ( int32_t i = 0; i < total; ++i )
		{
			double p[3];
			point_at( mesh, extra, i, p );
			double x = p[0] - view->center[0], y = p[1] - view->center[1], z = p[2] - view->center[2];
			double sx = dot3( f.right, x, y, z ), sy = dot3( f.up, x, y, z );
			lo_x = fmin( lo_x, sx ), hi_x = fmax( hi_x, sx ), lo_y = fmin( lo_y, sy ), hi_y = fmax( hi_y, sy );
		}
		for ( int c = 0; c < 3; ++c )
		{
			view->center[c] += 0.5 * ( lo_x + hi_x ) * f.right[c] + 0.5 * ( lo_y + hi_y ) * f.up[c];
		}
	}
	double half_x = 0.0, half_y = 0.0;
	for ( int32_t i = 0; i < total; ++i )
	{
		double p[3];
		point_at( mesh, extra, i, p );
		double x = p[0] - view->center[0], y = p[1] - view->center[1], z = p[2] - view->center[2];
		half_x = fmax( half_x, fabs( dot3( f.right, x, y, z ) ) );
		half_y = fmax( half_y, fabs( dot3( f.up, x, y, z ) ) );
	}
	double room_x = fmax( 1.0, 0.5 * w - view->margin ), room_y = fmax( 1.0, 0.5 * h - view->margin );
	double scale = INFINITY;
	scale = half_x > 0.0 ? fmin( scale, room_x / half_x ) : scale;
	scale = half_y > 0.0 ? fmin( scale, room_y / half_y ) : scale;
	view->scale = isfinite( scale ) ? scale : 1.0;
	return SERE_OK;
}

sere_status sere_render_fit_view( const sere_render_mesh* mesh, double w, double h, sere_render_view* view, char* err,
								  size_t err_size )
{
	return fit_points( mesh, NULL, 0, 0, w, h, view, err, err_size );
}

static void ground_corners( const ground_plane* g, double corners[12] )
{
	const int pick[4][2] = { { 0, 1 }, { 2, 1 }, { 2, 3 }, { 0, 3 } };
	for ( int k = 0; k < 4; ++k )
	{
		corners[3 * k + 0] = g->box[pick[k][0]];
		corners[3 * k + 1] = g->box[pick[k][1]];
		corners[3 * k + 2] = g->z;
	}
}

sere_status sere_render_fit_scene( const sere_render_mesh* mesh, const sere_render_scene* scene, double w, double h,
								   sere_render_view* view, char* err, size_t err_size )
{
	if ( scene == NULL || !scene->ground )
	{
		return fit_points( mesh, NULL, 0, 0, w, h, view, err, err_size );
	}
	sere_status status = check_mesh( mesh, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	ground_plane g = resolve_ground( mesh, scene );
	double corners[12];
	ground_corners( &g, corners );
	return fit_points( mesh, corners, 4, 1, w, h, view, err, err_size );
}

void sere_render_project( const sere_render_view* view, double x0, double y0, double w, double h, double x, double y,
						  double z, double* sx, double* sy )
{
	frame f = view_frame( view );
	x -= view->center[0], y -= view->center[1], z -= view->center[2];
	*sx = x0 + 0.5 * w + view->scale * dot3( f.right, x, y, z );
	*sy = y0 + 0.5 * h - view->scale * dot3( f.up, x, y, z );
}

static void vertex_color( const sere_render_mesh* mesh, int32_t i, double rgb[3] )
{
	for ( int c = 0; c < 3; ++c )
	{
		if ( mesh->rgb != NULL )
		{
			rgb[c] = mesh->rgb[3 * i + c];
		}
		else if ( mesh->rgb8 != NULL )
		{
			rgb[c] = mesh->rgb8[3 * i + c] / 255.0;
		}
		else
		{
			rgb[c] = mesh->color[c];
		}
	}
}

void sere_render_gradient_box( cairo_t* cr, cairo_pattern_t* gradient, double x, double y, double w, double h,
							   double grey )
{
	cairo_rectangle( cr, x, y, w, h );
	cairo_set_source( cr, gradient );
	cairo_fill_preserve( cr );
	cairo_pattern_destroy( gradient );
	cairo_set_source_rgb( cr, grey, grey, grey );
	cairo_set_line_width( cr, 1.0 );
	cairo_stroke( cr );
}

sere_status sere_render_cairo_failed( cairo_t* cr, char* err, size_t err_size )
{
	cairo_status_t status = cairo_status( cr );
	if ( status != CAIRO_STATUS_SUCCESS )
	{
		return sere_fail( status == CAIRO_STATUS_NO_MEMORY ? SERE_ERR_MEMORY : SERE_ERR_ARGUMENT, err, err_size,
						  "render: cairo: %s", cairo_status_to_string( status ) );
	}
	return SERE_OK;
}

void sere_render_lower_tint( const float rgb[3], float out[3] )
{
	const float pale[3] = { 0.88f, 0.88f, 0.82f };
	for ( int c = 0; c < 3; ++c )
	{
		out[c] = 0.5f * rgb[c] + 0.5f * pale[c];
	}
}

/* The ground quad and the mesh's vertical shadow on it, in screen space (screen holds the
 * mesh's own projection, 3 doubles per vertex; the shadow is projected here). */
static void draw_ground( cairo_t* cr, const sere_render_mesh* mesh, const sere_render_scene* scene,
						 const sere_render_view* view, const frame* f, double cx, double cy )
{
	ground_plane g = resolve_ground( mesh, scene );
	double corners[12];
	ground_corners( &g, corners );
	for ( int k = 0; k < 4; ++k )
	{
		double x = corners[3 * k] - view->center[0], y = corners[3 * k + 1] - view->center[1],
			   z = corners[3 * k + 2] - view->center[2];
		double sx = cx + view->scale * dot3( f->right, x, y, z ), sy = cy - view->scale * dot3( f->up, x, y, z );
		if ( k == 0 )
		{
			cairo_move_to( cr, sx, sy );
		}
		else
		{
			cairo_line_to( cr, sx, sy );
		}
	}
	cairo_close_path( cr );
	cairo_set_source_rgb( cr, 0.87, 0.87, 0.86 );
	cairo_fill_preserve( cr );
	cairo_set_source_rgb( cr, 0.62, 0.62, 0.61 );
	cairo_set_line_width( cr, 1.2 );
	cairo_stroke_preserve( cr );
	if ( scene->no_shadow )
	{
		cairo_new_path( cr );
		return;
	}
	cairo_save( cr );
	cairo_clip( cr );
	/* Every projected triangle turned the same way round on screen, so the nonzero winding
	 * rule fills their union once: where the leaf folds over itself the shadow is not darker,
	 * and there are no seams between neighbours. */
	for ( int32_t t = 0; t < mesh->triangle_count; ++t )
	{
		const int32_t* c = mesh->triangles + 3 * t;
		double p[3][2];
		for ( int q = 0; q < 3; ++q )
		{
			double x = mesh->x[c[q]] - view->center[0], y = mesh->y[c[q]] - view->center[1], z = g.z - view->center[2];
			p[q][0] = cx + view->scale * dot3( f->right, x, y, z );
			p[q][1] = cy - view->scale * dot3( f->up, x, y, z );
		}
		double area = ( p[1][0] - p[0][0] ) * ( p[2][1] - p[0][1] ) - ( p[1][1] - p[0][1] ) * ( p[2][0] - p[0][0] );
		if ( area == 0.0 )
		{
			continue;
		}
		int second = area > 0.0 ? 1 : 2, third = area > 0.0 ? 2 : 1;
		cairo_move_to( cr, p[0][0], p[0][1] );
		cairo_line_to( cr, p[second][0], p[second][1] );
		cairo_line_to( cr, p[third][0], p[third][1] );
		cairo_close_path( cr );
	}
	cairo_set_fill_rule( cr, CAIRO_FILL_RULE_WINDING );
	cairo_set_source_rgba( cr, 0.12, 0.12, 0.14, 0.45 );
	cairo_fill( cr );
	cairo_restore( cr );
}

sere_status sere_render_mesh_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_mesh* mesh,
								   sere_render_view* view, const sere_render_style* style, char* err, size_t err_size )
{
	return sere_render_mesh_draw_scene( cr, x0, y0, w, h, mesh, view, style, NULL, err, err_size );
}

/* Every line's end points must be mesh vertices. */
static sere_status check_lines( const sere_render_mesh* mesh, const sere_render_style* style, char* err,
								size_t err_size )
{
	for ( int32_t s = 0; s < style->line_set_count; ++s )
	{
		const sere_render_lines* lines = style->lines + s;
		for ( int32_t k = 0; k < 2 * lines->count; ++k )
		{
			if ( lines->pairs[k] < 0 || lines->pairs[k] >= mesh->vertex_count )
			{
				return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: line %d of set %d uses vertex %d of %d",
								  (int) ( k / 2 ), (int) s, (int) lines->pairs[k], (int) mesh->vertex_count );
			}
		}
	}
	return SERE_OK;
}

/* Screen x, y and depth of every vertex (3 doubles each, depth growing away from the eye), and
 * the triangles far to near (painter's algorithm) by the sum of their corners' depths. */
static void project_mesh( const sere_render_mesh* mesh, const sere_render_view* view, const frame* f, double cx,
						  double cy, double* screen, sere_sort_item* order )
{
	size_t n = (size_t) mesh->vertex_count, t_count = (size_t) mesh->triangle_count;
	for ( size_t i = 0; i < n; ++i )
	{
		double x = mesh->x[i] - view->center[0], y = mesh->y[i] - view->center[1],
			   z = vertex_z( mesh, (int32_t) i ) - view->center[2];
		screen[3 * i + 0] = cx + view->scale * dot3( f->right, x, y, z );
		screen[3 * i + 1] = cy - view->scale * dot3( f->up, x, y, z );
		screen[3 * i + 2] = -dot3( f->toward, x, y, z );
	}
	for ( size_t t = 0; t < t_count; ++t )
	{
		const int32_t* c = mesh->triangles + 3 * t;
		/* Far first: the complement turns the larger depth into the smaller key; equal depths
		 * by triangle index, so the picture is one answer. */
		double depth = screen[3 * c[0] + 2] + screen[3 * c[1] + 2] + screen[3 * c[2] + 2];
		order[t] = ( sere_sort_item ){ ~sere_sort_key_double( depth ), (int32_t) t, 0 };
	}
	sere_sort_items( order, (int32_t) t_count );
}

/* The light sits in camera space (upper left, in front of the screen) so every view of every
 * frame is lit alike; taken to model space once. */
static void model_light( const frame* f, double light[3] )
{
	double light_camera[3] = { -0.35, 0.45, 0.82 };
	double length = sqrt( dot3( light_camera, light_camera[0], light_camera[1], light_camera[2] ) );
	for ( int c = 0; c < 3; ++c )
	{
		light[c] =
			( light_camera[0] * f->right[c] + light_camera[1] * f->up[c] + light_camera[2] * f->toward[c] ) / length;
	}
}

/* One triangle: flat Lambert shading (two-sided), the lower face tinted when the scene asks,
 * filled and outlined. */
static void draw_triangle( cairo_t* cr, const sere_render_mesh* mesh, const int32_t* c, const double* screen,
						   const double light[3], const frame* f, const sere_render_style* style,
						   const sere_render_scene* scene )
{
	double ambient = style->ambient > 0.0 ? fmin( style->ambient, 1.0 ) : 0.45;
	double ax = mesh->x[c[1]] - mesh->x[c[0]], ay = mesh->y[c[1]] - mesh->y[c[0]],
		   az = vertex_z( mesh, c[1] ) - vertex_z( mesh, c[0] );
	double bx = mesh->x[c[2]] - mesh->x[c[0]], by = mesh->y[c[2]] - mesh->y[c[0]],
		   bz = vertex_z( mesh, c[2] ) - vertex_z( mesh, c[0] );
	double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
	double shade = 1.0;
	if ( !style->unlit )
	{
		double norm = sqrt( nx * nx + ny * ny + nz * nz );
		/* Two-sided: a leaf is a thin sheet lit from whichever side faces the light. */
		double lambert = norm > 0.0 ? fabs( dot3( light, nx, ny, nz ) ) / norm : 0.0;
		shade = ambient + ( 1.0 - ambient ) * lambert;
	}
	/* The lower face shows when the normal points away from the camera. */
	int lower = scene->lower_tint && dot3( f->toward, nx, ny, nz ) < 0.0;
	double rgb[3] = { 0.0, 0.0, 0.0 }, corner[3];
	for ( int q = 0; q < 3; ++q )
	{
		vertex_color( mesh, c[q], corner );
		if ( lower )
		{
			float given[3] = { (float) corner[0], (float) corner[1], (float) corner[2] }, tinted[3];
			sere_render_lower_tint( given, tinted );
			corner[0] = tinted[0], corner[1] = tinted[1], corner[2] = tinted[2];
		}
		for ( int j = 0; j < 3; ++j )
		{
			rgb[j] += corner[j] * shade / 3.0;
		}
	}
	cairo_move_to( cr, screen[3 * c[0]], screen[3 * c[0] + 1] );
	cairo_line_to( cr, screen[3 * c[1]], screen[3 * c[1] + 1] );
	cairo_line_to( cr, screen[3 * c[2]], screen[3 * c[2] + 1] );
	cairo_close_path( cr );
	cairo_set_source_rgb( cr, rgb[0], rgb[1], rgb[2] );
	cairo_fill_preserve( cr );
	/* Neighbouring antialiased triangles each cover a shared edge pixel only partly, which
	 * lets the background show through as faint seams; a hairline in the fill color (or
	 * the darker edge) closes them. */
	if ( style->edges )
	{
		cairo_set_source_rgb( cr, 0.6 * rgb[0], 0.6 * rgb[1], 0.6 * rgb[2] );
		cairo_set_line_width( cr, 0.6 );
	}
	else
	{
		cairo_set_line_width( cr, 0.5 );
	}
	cairo_stroke( cr );
}

/* The line sets over the mesh, without occlusion. */
static void draw_lines( cairo_t* cr, const sere_render_style* style, const double* screen )
{
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	for ( int32_t s = 0; s < style->line_set_count; ++s )
	{
		const sere_render_lines* lines = style->lines + s;
		for ( int32_t k = 0; k < lines->count; ++k )
		{
			int32_t a = lines->pairs[2 * k], b = lines->pairs[2 * k + 1];
			cairo_move_to( cr, screen[3 * a], screen[3 * a + 1] );
			cairo_line_to( cr, screen[3 * b], screen[3 * b + 1] );
		}
		cairo_set_source_rgb( cr, lines->rgb[0], lines->rgb[1], lines->rgb[2] );
		cairo_set_line_width( cr, lines->width > 0.0 ? lines->width : 1.0 );
		cairo_stroke( cr );
	}
}

sere_status sere_render_mesh_draw_scene( cairo_t* cr, double x0, double y0, double w, double h,
										 const sere_render_mesh* mesh, sere_render_view* view,
										 const sere_render_style* style, const sere_render_scene* scene, char* err,
										 size_t err_size )
{
	const sere_render_style plain = { 0 };
	const sere_render_scene bare = { 0 };
	style = style != NULL ? style : &plain;
	scene = scene != NULL ? scene : &bare;
	sere_status status = check_view( view, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( view->scale <= 0.0 || !isfinite( view->scale ) )
	{
		status = sere_render_fit_scene( mesh, scene, w, h, view, err, err_size );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	else
	{
		status = check_mesh( mesh, err, err_size );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	status = check_lines( mesh, style, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	size_t n = (size_t) mesh->vertex_count, t_count = (size_t) mesh->triangle_count;
	double* screen = malloc( sizeof( double ) * 3 * ( n > 0 ? n : 1 ) );
	sere_sort_item* order = malloc( sizeof( sere_sort_item ) * ( t_count > 0 ? t_count : 1 ) );
	if ( screen == NULL || order == NULL )
	{
		free( screen );
		free( order );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "render: out of memory for %d triangles",
						  (int) mesh->triangle_count );
	}
	frame f = view_frame( view );
	double cx = x0 + 0.5 * w, cy = y0 + 0.5 * h;
	project_mesh( mesh, view, &f, cx, cy, screen, order );
	double light[3];
	model_light( &f, light );

	cairo_save( cr );
	cairo_rectangle( cr, x0, y0, w, h );
	cairo_clip( cr );
	cairo_set_antialias( cr, CAIRO_ANTIALIAS_DEFAULT );
	cairo_set_line_join( cr, CAIRO_LINE_JOIN_ROUND );
	if ( scene->ground )
	{
		draw_ground( cr, mesh, scene, view, &f, cx, cy );
	}
	for ( size_t k = 0; k < t_count; ++k )
	{
		draw_triangle( cr, mesh, mesh->triangles + 3 * order[k].index, screen, light, &f, style, scene );
	}
	draw_lines( cr, style, screen );
	cairo_restore( cr );
	free( screen );
	free( order );
	return sere_render_cairo_failed( cr, err, err_size );
}

void sere_render_segments_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_view* view,
								const sere_render_segments* segments )
{
	cairo_save( cr );
	cairo_rectangle( cr, x0, y0, w, h );
	cairo_clip( cr );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	for ( int32_t k = 0; k < segments->count; ++k )
	{
		const double* p = segments->xyz + 6 * k;
		double sx, sy;
		sere_render_project( view, x0, y0, w, h, p[0], p[1], p[2], &sx, &sy );
		cairo_move_to( cr, sx, sy );
		sere_render_project( view, x0, y0, w, h, p[3], p[4], p[5], &sx, &sy );
		cairo_line_to( cr, sx, sy );
	}
	cairo_set_source_rgb( cr, segments->rgb[0], segments->rgb[1], segments->rgb[2] );
	cairo_set_line_width( cr, segments->width > 0.0 ? segments->width : 1.0 );
	cairo_stroke( cr );
	cairo_restore( cr );
}

void sere_render_dry_color( double relative_water, float rgb[3] )
{
	const double fresh[3] = { 0.30, 0.55, 0.18 }, dry[3] = { 0.55, 0.38, 0.20 };
	/* fmax( 0, NaN ) is 0: an undefined water content shows as dry rather than as garbage. */
	double t = fmin( 1.0, fmax( 0.0, relative_water ) );
	for ( int c = 0; c < 3; ++c )
	{
		rgb[c] = (float) ( dry[c] + t * ( fresh[c] - dry[c] ) );
	}
}

void sere_render_dry_colors( const float* relative_water, int32_t n, float* rgb )
{
	for ( int32_t i = 0; i < n; ++i )
	{
		sere_render_dry_color( relative_water[i], rgb + 3 * i );
	}
}

/* Viridis sampled at ten evenly spaced points (8-bit sRGB); linear interpolation between the
 * samples stays within about 1% of the full table, which no picture shows. */
static const uint8_t colormap_table[10][3] = {
	{ 68, 1, 84 },	  { 72, 40, 120 },	{ 62, 73, 137 },  { 49, 104, 142 }, { 38, 130, 142 },
	{ 31, 158, 137 }, { 53, 183, 121 }, { 110, 206, 88 }, { 181, 222, 43 }, { 253, 231, 37 },
};

void sere_render_colormap( double t, float rgb[3] )
{
	t = isnan( t ) ? 0.0 : fmin( 1.0, fmax( 0.0, t ) );
	double position = t * 9.0;
	int k = (int) position;
	k = k > 8 ? 8 : k;
	double u = position - k;
	for ( int c = 0; c < 3; ++c )
	{
		double a = colormap_table[k][c], b = colormap_table[k + 1][c];
		rgb[c] = (float) ( ( a + u * ( b - a ) ) / 255.0 );
	}
}

void sere_render_colormap_values( const float* values, int32_t n, double lo, double hi, float* rgb )
{
	double span = hi - lo;
	for ( int32_t i = 0; i < n; ++i )
	{
		sere_render_colormap( span > 0.0 ? ( values[i] - lo ) / span : 0.5, rgb + 3 * i );
	}
}

void sere_render_palette( int index, float rgb[3] )
{
	/* Okabe & Ito's colorblind-safe set, the most distinct first. */
	static const uint8_t palette[8][3] = {
		{ 0, 114, 178 },   { 213, 94, 0 },	 { 0, 158, 115 }, { 230, 159, 0 },
		{ 204, 121, 167 }, { 86, 180, 233 }, { 0, 0, 0 },	  { 240, 228, 66 },
	};
	int k = ( ( index % 8 ) + 8 ) % 8;
	for ( int c = 0; c < 3; ++c )
	{
		rgb[c] = palette[k][c] / 255.0f;
	}
}

sere_status sere_render_canvas_create( sere_render_canvas* canvas, int width, int height, char* err, size_t err_size )
{
	canvas->surface = NULL;
	canvas->cr = NULL;
	canvas->width = width;
	canvas->height = height;
	if ( width <= 0 || height <= 0 || width > 32767 || height > 32767 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "render: canvas size %dx%d outside 1..32767", width,
						  height );
	}
	canvas->surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, width, height );
	canvas->cr = cairo_create( canvas->surface );
	sere_status status = sere_render_cairo_failed( canvas->cr, err, err_size );
	if ( status != SERE_OK )
	{
		sere_render_canvas_destroy( canvas );
		return status;
	}
	cairo_set_source_rgb( canvas->cr, 1.0, 1.0, 1.0 );
	cairo_paint( canvas->cr );
	return SERE_OK;
}

static cairo_status_t write_to_file( void* closure, const unsigned char* data, unsigned int length )
{
	return fwrite( data, 1, length, closure ) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

sere_status sere_render_canvas_write_png( const sere_render_canvas* canvas, const char* path, char* err,
										  size_t err_size )
{
	if ( canvas->cr == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: no canvas to write", path );
	}
	sere_status failed = sere_render_cairo_failed( canvas->cr, err, err_size );
	if ( failed != SERE_OK )
	{
		return failed;
	}
	cairo_surface_flush( canvas->surface );
	sere_atomic_file file;
	if ( sere_atomic_open( &file, path ) == NULL )
	{
		return sere_fail( SERE_ERR_IO, err, err_size, "%s: cannot write PNG: %s", path, strerror( errno ) );
	}
	cairo_status_t status = cairo_surface_write_to_png_stream( canvas->surface, write_to_file, file.f );
	if ( status != CAIRO_STATUS_SUCCESS )
	{
		int saved = errno;
		sere_atomic_abort( &file );
		return sere_fail( SERE_ERR_IO, err, err_size, "%s: cannot write PNG: %s (%s)", path,
						  cairo_status_to_string( status ), strerror( saved ) );
	}
	if ( sere_atomic_commit( &file ) != 0 )
	{
		return sere_fail( SERE_ERR_IO, err, err_size, "%s: cannot write PNG: %s", path, strerror( errno ) );
	}
	return SERE_OK;
}

void sere_render_canvas_destroy( sere_render_canvas* canvas )
{
	if ( canvas->cr != NULL )
	{
		cairo_destroy( canvas->cr );
	}
	if ( canvas->surface != NULL )
	{
		cairo_surface_destroy( canvas->surface );
	}
	canvas->cr = NULL;
	canvas->surface = NULL;
}

sere_status sere_render_contact_sheet( const char* path, const sere_render_sheet* sheet, char* err, size_t err_size )
{
	if ( sheet->count <= 0 || sheet->columns <= 0 || sheet->draw == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size,
						  "%s: a contact sheet needs panels, columns and a draw function", path );
	}
	const int pad = 12, caption_height = 26;
	int pw = sheet->panel_width > 0 ? sheet->panel_width : 320;
	int ph = sheet->panel_height > 0 ? sheet->panel_height : pw;
	int columns = sheet->columns < sheet->count ? sheet->columns : sheet->count;
	int rows = ( sheet->count + columns - 1 ) / columns;
	int title_height = sheet->title != NULL && sheet->title[0] != '\0' ? 44 : pad;
	int64_t width = (int64_t) columns * ( pw + pad ) + pad;
	int64_t height = title_height + (int64_t) rows * ( ph + caption_height + pad );
	sere_render_canvas canvas;
	if ( width > 32767 || height > 32767 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: a sheet of %d panels of %dx%d exceeds 32767 pixels",
						  path, sheet->count, pw, ph );
	}
	sere_status status = sere_render_canvas_create( &canvas, (int) width, (int) height, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	cairo_t* cr = canvas.cr;
	cairo_set_source_rgb( cr, 0.1, 0.1, 0.1 );
	sere_render_text( cr, 0.5 * width, 29, 18, 1, 1, sheet->title );
	for ( int k = 0; k < sheet->count; ++k )
	{
		double x = pad + ( k % columns ) * ( pw + pad );
		double y = title_height + ( k / columns ) * ( ph + caption_height + pad );
		char caption[256] = { 0 };
		cairo_save( cr );
		status = sheet->draw( sheet->user, k, cr, x, y, pw, ph, caption, sizeof( caption ), err, err_size );
		cairo_restore( cr );
		if ( status != SERE_OK )
		{
			sere_render_canvas_destroy( &canvas );
			return status;
		}
		cairo_set_source_rgb( cr, 0.15, 0.15, 0.15 );
		sere_render_text( cr, x + 0.5 * pw, y + ph + 18, 13, 0, 1, caption );
	}
	status = sere_render_canvas_write_png( &canvas, path, err, err_size );
	sere_render_canvas_destroy( &canvas );
	return status;
}
