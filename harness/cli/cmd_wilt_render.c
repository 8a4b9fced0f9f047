/* sere wilt — pictures: a shaded orthographic view of the plant drawn back to front. */
#include "cli/cmd_wilt_shared.h"
#include "common/io.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------- */
/* Pictures: a shaded orthographic view drawn back to front. */

static double dot3( const double* a, const double* b )
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Fits the view to the rest plant and to its mirror image below each leaf's base, the room that
 * drooping leaves reach. */
void wilt_camera_fit( camera* c, double azimuth, double elevation, int width, int height, const sere_plant* plant )
{
	double ca = cos( azimuth ), sa = sin( azimuth ), ce = cos( elevation ), se = sin( elevation );
	double toward[3] = { ce * ca, ce * sa, se };
	double right[3] = { -sa, ca, 0.0 };
	double up[3] = { -se * ca, -se * sa, ce };
	memcpy( c->toward, toward, sizeof( toward ) );
	memcpy( c->right, right, sizeof( right ) );
	memcpy( c->up, up, sizeof( up ) );
	double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double root = plant->joints.z[plant->joint_first[k]];
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			for ( int mirror = 0; mirror < 2; ++mirror )
			{
				double z = mirror ? 2.0 * root - plant->rz[i] - 0.2 * fabs( plant->rz[i] - root ) : plant->rz[i];
				double p[3] = { plant->rx[i], plant->ry[i], z };
				double u = dot3( p, right ), v = dot3( p, up );
				umin = fmin( umin, u );
				umax = fmax( umax, u );
				vmin = fmin( vmin, v );
				vmax = fmax( vmax, v );
			}
		}
	}
	double span = fmax( ( umax - umin ) / width, ( vmax - vmin ) / ( height - 40 ) );
	c->scale = 1.0 / ( 1.1 * fmax( span, 1e-9 ) );
	c->u0 = 0.5 * ( umin + umax ) - 0.5 * width / c->scale;
	c->v0 = 0.5 * ( vmin + vmax ) + 0.5 * ( height - 30 ) / c->scale;
	c->width = width;
	c->height = height;
}

static void camera_project( const camera* c, const double p[3], double* sx, double* sy )
{
	*sx = ( dot3( p, c->right ) - c->u0 ) * c->scale;
	*sy = 30.0 + ( c->v0 - dot3( p, c->up ) ) * c->scale;
}

static int depth_order( const void* a, const void* b )
{
	const depth_item* p = a;
	const depth_item* q = b;
	if ( p->depth != q->depth )
	{
		return p->depth < q->depth ? -1 : 1;
	}
	return ( p->triangle > q->triangle ) - ( p->triangle < q->triangle );
}

static cairo_status_t write_stream( void* closure, const unsigned char* data, unsigned int length )
{
	return fwrite( data, 1, length, (FILE*) closure ) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

/* The plant as it stands: stem and petioles, then leaves back to front, Lambert-shaded on both
 * sides, green turning yellow-brown with each leaf's wilting parameter. A bar at the top left
 * shows how far the run has gone, with one swatch per leaf (bottom leaf first) in its colour; no
 * text, so no font machinery. */
/* Stem from the lowest leaf base to the top, petioles from the stem to each leaf base. */
static void draw_stem( cairo_t* cr, const camera* c, const sere_plant* plant, const float* stem_top )
{
	cairo_set_source_rgb( cr, 0.35, 0.42, 0.18 );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	double bottom[3] = { 0.0, 0.0, stem_top[3] }, top[3] = { 0.0, 0.0, stem_top[2] };
	double sx, sy;
	cairo_set_line_width( cr, fmax( 2.0, 0.012 * c->scale * ( stem_top[2] - stem_top[3] + 1.0 ) ) );
	camera_project( c, bottom, &sx, &sy );
	cairo_move_to( cr, sx, sy );
	camera_project( c, top, &sx, &sy );
	cairo_line_to( cr, sx, sy );
	cairo_stroke( cr );
	cairo_set_line_width( cr, 2.0 );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		int32_t root = plant->joint_first[k];
		double base[3] = { plant->joints.x[root], plant->joints.y[root], plant->joints.z[root] };
		double node[3] = { 0.0, 0.0, base[2] - 0.3 * stem_top[4] };
		camera_project( c, node, &sx, &sy );
		cairo_move_to( cr, sx, sy );
		camera_project( c, base, &sx, &sy );
		cairo_line_to( cr, sx, sy );
		cairo_stroke( cr );
	}
}

/* The triangles far to near (painter's order) by the depth of their corners' sum. */
static void sort_by_depth( const camera* c, const sere_plant* plant, depth_item* order )
{
	for ( int32_t t = 0; t < plant->triangle_count; ++t )
	{
		const int32_t* v = plant->tri + 3 * t;
		double d = 0.0;
		for ( int k = 0; k < 3; ++k )
		{
			double p[3] = { plant->x[v[k]], plant->y[v[k]], plant->z[v[k]] };
			d += dot3( p, c->toward );
		}
		order[t].depth = (float) d;
		order[t].triangle = t;
	}
	qsort( order, (size_t) plant->triangle_count, sizeof( depth_item ), depth_order );
}

/* One triangle filled in its leaf's colour (greener to browner with the leaf's wilting), shaded
 * two-sided by the light direction. */
static void draw_triangle( cairo_t* cr, const camera* c, const sere_plant* plant, int32_t t, int32_t leaf,
						   const double light[3] )
{
	const int32_t* v = plant->tri + 3 * t;
	double p[3][3];
	for ( int k = 0; k < 3; ++k )
	{
		p[k][0] = plant->x[v[k]];
		p[k][1] = plant->y[v[k]];
		p[k][2] = plant->z[v[k]];
	}
	double e1[3] = { p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2] };
	double e2[3] = { p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	double nl = sqrt( dot3( n, n ) );
	double shade = nl > 0.0 ? 0.3 + 0.7 * fabs( dot3( n, light ) ) / nl : 0.3;
	double w = 0.85 * plant->leaf_t[leaf];
	double rgb[3] = { ( 0.20 + 0.42 * w ) * shade, ( 0.52 - 0.04 * w ) * shade, ( 0.16 + 0.02 * w ) * shade };
	cairo_set_source_rgb( cr, rgb[0], rgb[1], rgb[2] );
	for ( int k = 0; k < 3; ++k )
	{
		double sx, sy;
		camera_project( c, p[k], &sx, &sy );
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
	/* The thin stroke in the fill colour hides the antialiasing seams between triangles. */
	cairo_fill_preserve( cr );
	cairo_stroke( cr );
}

/* The leaves, far to near, lit from above the camera and a little to its left. */
static void draw_leaves( cairo_t* cr, const camera* c, const sere_plant* plant, depth_item* order )
{
	double light[3];
	for ( int a = 0; a < 3; ++a )
	{
		light[a] = c->toward[a] + 0.8 * c->up[a] - 0.3 * c->right[a];
	}
	double ll = sqrt( dot3( light, light ) );
	for ( int a = 0; a < 3; ++a )
	{
		light[a] /= ll;
	}
	sort_by_depth( c, plant, order );
	cairo_set_line_width( cr, 0.6 );
	cairo_set_line_join( cr, CAIRO_LINE_JOIN_ROUND );
	int32_t leaf = 0;
	for ( int32_t o = 0; o < plant->triangle_count; ++o )
	{
		int32_t t = order[o].triangle;
		while ( leaf > 0 && t < plant->triangle_first[leaf] )
		{
			--leaf;
		}
		while ( t >= plant->triangle_first[leaf + 1] )
		{
			++leaf;
		}
		draw_triangle( cr, c, plant, t, leaf, light );
	}
}

/* The progress bar and one swatch per leaf in its current colour. */
static void draw_progress( cairo_t* cr, const sere_plant* plant, double progress )
{
	cairo_set_source_rgb( cr, 0.75, 0.78, 0.8 );
	cairo_rectangle( cr, 12.0, 10.0, 160.0, 6.0 );
	cairo_fill( cr );
	cairo_set_source_rgb( cr, 0.3, 0.32, 0.35 );
	cairo_rectangle( cr, 12.0, 10.0, 160.0 * progress, 6.0 );
	cairo_fill( cr );
	double swatch = fmin( 10.0, 160.0 / plant->leaf_count );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double w = 0.85 * plant->leaf_t[k];
		cairo_set_source_rgb( cr, 0.20 + 0.42 * w, 0.52 - 0.04 * w, 0.16 + 0.02 * w );
		cairo_rectangle( cr, 12.0 + k * swatch, 20.0, 0.8 * swatch, 6.0 );
		cairo_fill( cr );
	}
}

int wilt_render_png( const char* path, const camera* c, const sere_plant* plant, const float* stem_top,
					 depth_item* order, double progress )
{
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, c->width, c->height );
	cairo_t* cr = cairo_create( surface );
	cairo_pattern_t* sky = cairo_pattern_create_linear( 0, 0, 0, c->height );
	cairo_pattern_add_color_stop_rgb( sky, 0.0, 0.86, 0.91, 0.97 );
	cairo_pattern_add_color_stop_rgb( sky, 1.0, 0.99, 0.99, 0.97 );
	cairo_set_source( cr, sky );
	cairo_paint( cr );
	cairo_pattern_destroy( sky );
	draw_stem( cr, c, plant, stem_top );
	draw_leaves( cr, c, plant, order );
	draw_progress( cr, plant, progress );
	cairo_surface_flush( surface );

	sere_atomic_file file;
	FILE* out = sere_atomic_open( &file, path );
	int result = -1;
	if ( out != NULL )
	{
		if ( cairo_surface_write_to_png_stream( surface, write_stream, out ) == CAIRO_STATUS_SUCCESS )
		{
			result = sere_atomic_commit( &file );
		}
		else
		{
			sere_atomic_abort( &file );
		}
	}
	cairo_destroy( cr );
	cairo_surface_destroy( surface );
	return result;
}
