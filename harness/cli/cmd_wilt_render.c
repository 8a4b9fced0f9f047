/* sere wilt — pictures through harness/render: the leaves as one mesh colored by each leaf's
 * wilting, the stem and petioles as segments, and a progress bar; no camera or painter here. */
#include "cli/cmd_wilt_shared.h"
#include "common/io.h"

#include <math.h>
#include <stdlib.h>

/* Pixels over the plant kept for the progress bar. */
#define BAR_ROOM 30

/* A leaf's colour for its wilting parameter t (0 fresh, 1 fully wilted; the leaves start from
 * the lowest to the highest, Lu Sec. 7): green turning yellow-brown. */
static void leaf_color( double t, float rgb[3] )
{
	double w = 0.85 * t;
	rgb[0] = (float) ( 0.20 + 0.42 * w );
	rgb[1] = (float) ( 0.52 - 0.04 * w );
	rgb[2] = (float) ( 0.16 + 0.02 * w );
}

sere_status wilt_picture_fit( wilt_picture* pic, double azimuth, double elevation, int width, int height,
							  const sere_plant* plant, char* err, size_t err_size )
{
	int32_t n = plant->vertex_count;
	pic->width = width;
	pic->height = height;
	pic->rgb = malloc( 3 * (size_t) n * sizeof( float ) );
	float* room = malloc( 6 * (size_t) n * sizeof( float ) );
	if ( pic->rgb == NULL || room == NULL )
	{
		free( room );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "sere wilt: out of memory for the pictures" );
	}
	/* Each leaf vertex at rest and mirrored below its leaf's base, a little deeper than the
	 * mirror image: the lowest a drooping leaf can reach. */
	float* x = room;
	float* y = room + 2 * n;
	float* z = room + 4 * n;
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double root = plant->joints.z[plant->joint_first[k]];
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			x[2 * i] = x[2 * i + 1] = plant->rx[i];
			y[2 * i] = y[2 * i + 1] = plant->ry[i];
			z[2 * i] = plant->rz[i];
			z[2 * i + 1] = (float) ( 2.0 * root - plant->rz[i] - 0.2 * fabs( plant->rz[i] - root ) );
		}
	}
	/* render's azimuth 0 looks along +y from the -y side; wilt's 0 looks from +x. */
	pic->view = ( sere_render_view ){ .azimuth = azimuth + 90.0, .elevation = elevation, .margin = 0.05 * width };
	sere_render_mesh points = { .x = x, .y = y, .z = z, .vertex_count = 2 * plant->vertex_first[plant->leaf_count] };
	sere_status result = sere_render_fit_view( &points, width, height - BAR_ROOM, &pic->view, err, err_size );
	free( room );
	return result;
}

void wilt_picture_free( wilt_picture* pic )
{
	free( pic->rgb );
	pic->rgb = NULL;
}

/* The stem from the lowest leaf base to the top, then the petioles from the stem to each leaf
 * base, under the leaves. */
static int draw_stem( cairo_t* cr, const wilt_picture* pic, const sere_plant* plant, const float* stem_top )
{
	double h = pic->height - BAR_ROOM;
	double stem[6] = { 0.0, 0.0, stem_top[3], 0.0, 0.0, stem_top[2] };
	sere_render_segments segments = {
		stem, 1, { 0.35f, 0.42f, 0.18f }, fmax( 2.0, 0.012 * pic->view.scale * ( stem_top[2] - stem_top[3] + 1.0 ) )
	};
	sere_render_segments_draw( cr, 0.0, BAR_ROOM, pic->width, h, &pic->view, &segments );
	double* petioles = malloc( 6 * (size_t) plant->leaf_count * sizeof( double ) );
	if ( petioles == NULL )
	{
		return -1;
	}
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		int32_t root = plant->joint_first[k];
		double* p = petioles + 6 * k;
		p[0] = p[1] = 0.0;
		p[2] = plant->joints.z[root] - 0.3 * stem_top[4];
		p[3] = plant->joints.x[root], p[4] = plant->joints.y[root], p[5] = plant->joints.z[root];
	}
	segments.xyz = petioles;
	segments.count = plant->leaf_count;
	segments.width = 2.0;
	sere_render_segments_draw( cr, 0.0, BAR_ROOM, pic->width, h, &pic->view, &segments );
	free( petioles );
	return 0;
}

/* The progress bar and one swatch per leaf (bottom leaf first) in its current colour; no text,
 * so no font machinery. */
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
		float rgb[3];
		leaf_color( plant->leaf_t[k], rgb );
		cairo_set_source_rgb( cr, rgb[0], rgb[1], rgb[2] );
		cairo_rectangle( cr, 12.0 + k * swatch, 20.0, 0.8 * swatch, 6.0 );
		cairo_fill( cr );
	}
}

sere_status wilt_picture_png( const char* path, wilt_picture* pic, const sere_plant* plant, const float* stem_top,
							  double progress, char* err, size_t err_size )
{
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		float rgb[3];
		leaf_color( plant->leaf_t[k], rgb );
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			pic->rgb[3 * i] = rgb[0], pic->rgb[3 * i + 1] = rgb[1], pic->rgb[3 * i + 2] = rgb[2];
		}
	}
	sere_render_canvas canvas;
	sere_status result = sere_render_canvas_create( &canvas, pic->width, pic->height, err, err_size );
	if ( result != SERE_OK )
	{
		return result;
	}
	cairo_t* cr = canvas.cr;
	cairo_pattern_t* sky = cairo_pattern_create_linear( 0, 0, 0, pic->height );
	cairo_pattern_add_color_stop_rgb( sky, 0.0, 0.86, 0.91, 0.97 );
	cairo_pattern_add_color_stop_rgb( sky, 1.0, 0.99, 0.99, 0.97 );
	cairo_set_source( cr, sky );
	cairo_paint( cr );
	cairo_pattern_destroy( sky );
	sere_render_mesh leaves = { .x = plant->x,
								.y = plant->y,
								.z = plant->z,
								.vertex_count = plant->vertex_count,
								.triangles = plant->tri,
								.triangle_count = plant->triangle_count,
								.rgb = pic->rgb };
	/* A leaf is a thin sheet: both faces lit alike, a third of the light ambient. */
	sere_render_style style = { .ambient = 0.3 };
	if ( draw_stem( cr, pic, plant, stem_top ) != 0 )
	{
		result = sere_fail( SERE_ERR_MEMORY, err, err_size, "sere wilt: out of memory for the picture" );
	}
	else
	{
		result = sere_render_mesh_draw( cr, 0.0, BAR_ROOM, pic->width, pic->height - BAR_ROOM, &leaves, &pic->view,
										&style, err, err_size );
	}
	if ( result == SERE_OK )
	{
		draw_progress( cr, plant, progress );
		result = sere_render_canvas_write_png( &canvas, path, err, err_size );
	}
	sere_render_canvas_destroy( &canvas );
	return result;
}
