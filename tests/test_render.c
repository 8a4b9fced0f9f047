#define _POSIX_C_SOURCE 200809L
#include "render.h"

#include <cairo.h>
#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A fresh directory per test, removed with its files afterwards. */
typedef struct scratch
{
	char dir[64];
} scratch;

static void scratch_make( scratch* s )
{
	snprintf( s->dir, sizeof( s->dir ), "/tmp/sere-render-XXXXXX" );
	cr_assert_not_null( mkdtemp( s->dir ) );
}

static void scratch_path( const scratch* s, const char* name, char* path, size_t size )
{
	snprintf( path, size, "%s/%s", s->dir, name );
}

/* Names in the directory that end in ".tmp": an atomic write must leave none. */
static int scratch_tmp_count( const scratch* s )
{
	DIR* dir = opendir( s->dir );
	cr_assert_not_null( dir );
	int count = 0;
	for ( struct dirent* entry = readdir( dir ); entry != NULL; entry = readdir( dir ) )
	{
		size_t length = strlen( entry->d_name );
		count += length >= 4 && strcmp( entry->d_name + length - 4, ".tmp" ) == 0;
	}
	closedir( dir );
	return count;
}

static void scratch_remove( scratch* s )
{
	DIR* dir = opendir( s->dir );
	cr_assert_not_null( dir );
	for ( struct dirent* entry = readdir( dir ); entry != NULL; entry = readdir( dir ) )
	{
		if ( strcmp( entry->d_name, "." ) != 0 && strcmp( entry->d_name, ".." ) != 0 )
		{
			char path[512];
			scratch_path( s, entry->d_name, path, sizeof( path ) );
			remove( path );
		}
	}
	closedir( dir );
	rmdir( s->dir );
}

/* Pixel (x, y) of a PNG read back from disk as 8-bit r, g, b. */
typedef struct picture
{
	cairo_surface_t* surface;
	int width, height;
} picture;

static picture picture_load( const char* path )
{
	picture p;
	p.surface = cairo_image_surface_create_from_png( path );
	cr_assert_eq( cairo_surface_status( p.surface ), CAIRO_STATUS_SUCCESS, "%s does not read back as a PNG", path );
	p.width = cairo_image_surface_get_width( p.surface );
	p.height = cairo_image_surface_get_height( p.surface );
	return p;
}

static void picture_rgb( const picture* p, int x, int y, int rgb[3] )
{
	const unsigned char* data = cairo_image_surface_get_data( p->surface );
	uint32_t pixel = *(const uint32_t*) ( data + (size_t) y * (size_t) cairo_image_surface_get_stride( p->surface ) +
										  4 * (size_t) x );
	rgb[0] = (int) ( ( pixel >> 16 ) & 255 );
	rgb[1] = (int) ( ( pixel >> 8 ) & 255 );
	rgb[2] = (int) ( pixel & 255 );
}

/* Two triangles covering the unit square in the plane z = height. */
static const float square_x[4] = { 0.0f, 1.0f, 1.0f, 0.0f };
static const float square_y[4] = { 0.0f, 0.0f, 1.0f, 1.0f };
static const int32_t square_triangles[6] = { 0, 1, 2, 0, 2, 3 };

static sere_render_mesh square_mesh( const float* z, float r, float g, float b )
{
	sere_render_mesh mesh = {
		.x = square_x,
		.y = square_y,
		.z = z,
		.vertex_count = 4,
		.triangles = square_triangles,
		.triangle_count = 2,
		.color = { r, g, b },
	};
	return mesh;
}

Test( render, red_square_png_reads_back_red_on_white )
{
	scratch s;
	scratch_make( &s );
	char path[512], err[256] = { 0 };
	scratch_path( &s, "square.png", path, sizeof( path ) );
	sere_render_canvas canvas;
	cr_assert_eq( sere_render_canvas_create( &canvas, 64, 48, err, sizeof( err ) ), 0, "%s", err );
	sere_render_mesh mesh = square_mesh( NULL, 1.0f, 0.0f, 0.0f );
	sere_render_view view = { .azimuth = 0.0, .elevation = 90.0, .margin = 8.0 };
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 64, 48, &mesh, &view, NULL, err, sizeof( err ) ), 0, "%s",
				  err );
	/* The fit must fill the limiting (vertical) extent up to the margin: 48 - 2 * 8 pixels
	 * for one model unit, exact up to double rounding. */
	cr_assert_float_eq( view.scale, 32.0, 1e-12 );
	cr_assert_eq( sere_render_canvas_write_png( &canvas, path, err, sizeof( err ) ), 0, "%s", err );
	sere_render_canvas_destroy( &canvas );
	cr_assert_eq( scratch_tmp_count( &s ), 0, "a .tmp file remains after a successful write" );

	picture p = picture_load( path );
	cr_assert_eq( p.width, 64 );
	cr_assert_eq( p.height, 48 );
	int center[3], corner[3];
	picture_rgb( &p, 32, 24, center );
	picture_rgb( &p, 1, 1, corner );
	/* Shading only scales the red: it must stay bright and the other channels near zero. */
	cr_assert_gt( center[0], 150, "center red %d too dark", center[0] );
	cr_assert_lt( center[1], 20 );
	cr_assert_lt( center[2], 20 );
	cr_assert_eq( corner[0], 255 );
	cr_assert_eq( corner[1], 255 );
	cr_assert_eq( corner[2], 255 );
	/* Just outside the fitted square (margin 8, square spans x in [16, 48]) is background. */
	int outside[3];
	picture_rgb( &p, 12, 24, outside );
	cr_assert_eq( outside[0] + outside[1] + outside[2], 3 * 255 );
	cairo_surface_destroy( p.surface );
	scratch_remove( &s );
}

Test( render, nearer_square_hides_farther_whatever_the_order )
{
	/* Two stacked squares seen from above: the upper (z = 1, nearer) one is listed first, so
	 * only sorting by depth draws it last. */
	const float x[8] = { 0, 1, 1, 0, 0, 1, 1, 0 }, y[8] = { 0, 0, 1, 1, 0, 0, 1, 1 };
	const float z[8] = { 1, 1, 1, 1, 0, 0, 0, 0 };
	const int32_t triangles[12] = { 0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7 };
	const float rgb[24] = { 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0 };
	sere_render_mesh mesh = {
		.x = x, .y = y, .z = z, .vertex_count = 8, .triangles = triangles, .triangle_count = 4, .rgb = rgb
	};
	char err[256];
	sere_render_canvas canvas;
	cr_assert_eq( sere_render_canvas_create( &canvas, 40, 40, err, sizeof( err ) ), 0, "%s", err );
	sere_render_view view = { .azimuth = 0.0, .elevation = 90.0, .margin = 4.0 };
	sere_render_style unlit = { .unlit = 1 };
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 40, 40, &mesh, &view, &unlit, err, sizeof( err ) ), 0, "%s",
				  err );
	cairo_surface_flush( canvas.surface );
	picture p = { canvas.surface, 40, 40 };
	int center[3];
	picture_rgb( &p, 20, 13, center );
	/* Unlit, so the pixel is the nearer square's pure blue. */
	cr_assert_eq( center[0], 0 );
	cr_assert_eq( center[2], 255 );
	sere_render_canvas_destroy( &canvas );
}

Test( render, equal_depths_draw_in_index_order )
{
	/* The same square twice in one plane, red (vertices 0-3) and green (4-7): every depth
	 * ties, so the square whose triangles come later must end on top. That index tie-break
	 * is what makes a picture independent of the sort's whims. */
	const float x[8] = { 0, 1, 1, 0, 0, 1, 1, 0 }, y[8] = { 0, 0, 1, 1, 0, 0, 1, 1 };
	const float rgb[24] = { 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0 };
	const int32_t red_first[12] = { 0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7 };
	const int32_t green_first[12] = { 4, 5, 6, 4, 6, 7, 0, 1, 2, 0, 2, 3 };
	char err[256];
	for ( int pass = 0; pass < 2; ++pass )
	{
		sere_render_mesh mesh = { .x = x,
								  .y = y,
								  .vertex_count = 8,
								  .triangles = pass == 0 ? red_first : green_first,
								  .triangle_count = 4,
								  .rgb = rgb };
		sere_render_canvas canvas;
		cr_assert_eq( sere_render_canvas_create( &canvas, 30, 30, err, sizeof( err ) ), 0, "%s", err );
		sere_render_view view = { .azimuth = 0.0, .elevation = 90.0, .margin = 3.0 };
		sere_render_style unlit = { .unlit = 1 };
		cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 30, 30, &mesh, &view, &unlit, err, sizeof( err ) ), 0 );
		cairo_surface_flush( canvas.surface );
		picture p = { canvas.surface, 30, 30 };
		int pixel[3];
		picture_rgb( &p, 8, 12, pixel );
		int top = pass == 0 ? 1 : 0; /* green on top in pass 0, red in pass 1 */
		cr_assert_eq( pixel[top], 255, "pass %d: pixel (%d, %d, %d)", pass, pixel[0], pixel[1], pixel[2] );
		cr_assert_eq( pixel[1 - top], 0, "pass %d: pixel (%d, %d, %d)", pass, pixel[0], pixel[1], pixel[2] );
		sere_render_canvas_destroy( &canvas );
	}
}

Test( render, identical_calls_give_identical_pixels )
{
	float x[25], y[25], z[25], rgb[75];
	int32_t triangles[96];
	for ( int j = 0, v = 0; j < 5; ++j )
	{
		for ( int i = 0; i < 5; ++i, ++v )
		{
			x[v] = (float) i, y[v] = (float) j, z[v] = (float) ( 0.4 * sin( i * 1.3 + j * 0.7 ) );
			sere_render_dry_color( v / 24.0, rgb + 3 * v );
		}
	}
	for ( int j = 0, t = 0; j < 4; ++j )
	{
		for ( int i = 0; i < 4; ++i, t += 6 )
		{
			int32_t a = j * 5 + i;
			int32_t quad[6] = { a, a + 1, a + 6, a, a + 6, a + 5 };
			memcpy( triangles + t, quad, sizeof( quad ) );
		}
	}
	sere_render_mesh mesh = {
		.x = x, .y = y, .z = z, .vertex_count = 25, .triangles = triangles, .triangle_count = 32, .rgb = rgb
	};
	unsigned char* first = NULL;
	char err[256];
	for ( int pass = 0; pass < 2; ++pass )
	{
		sere_render_canvas canvas;
		cr_assert_eq( sere_render_canvas_create( &canvas, 80, 60, err, sizeof( err ) ), 0, "%s", err );
		sere_render_view view = { .azimuth = -30.0, .elevation = 35.0, .margin = 4.0 };
		sere_render_style edges = { .edges = 1 };
		cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 80, 60, &mesh, &view, &edges, err, sizeof( err ) ), 0 );
		cairo_surface_flush( canvas.surface );
		size_t bytes = (size_t) cairo_image_surface_get_stride( canvas.surface ) * 60;
		if ( pass == 0 )
		{
			first = malloc( bytes );
			memcpy( first, cairo_image_surface_get_data( canvas.surface ), bytes );
		}
		else
		{
			cr_assert_eq( memcmp( first, cairo_image_surface_get_data( canvas.surface ), bytes ), 0 );
		}
		sere_render_canvas_destroy( &canvas );
	}
	free( first );
}

Test( render, fit_keeps_every_vertex_inside_the_margin )
{
	float x[6] = { -2, 3, 0.5f, 1, -1, 2 }, y[6] = { 0, 1, 4, -3, 2, 2 }, z[6] = { 0, 1, -1, 2, 0.5f, -2 };
	sere_render_mesh mesh = { .x = x, .y = y, .z = z, .vertex_count = 6 };
	sere_render_view view = { .azimuth = 25.0, .elevation = 40.0, .margin = 10.0 };
	char err[256];
	cr_assert_eq( sere_render_fit_view( &mesh, 200, 100, &view, err, sizeof( err ) ), 0, "%s", err );
	double worst = 1e300;
	for ( int i = 0; i < 6; ++i )
	{
		double sx, sy;
		sere_render_project( &view, 0, 0, 200, 100, x[i], y[i], z[i], &sx, &sy );
		/* 1e-9 pixel: the fit is exact up to double rounding. */
		cr_assert_geq( sx, 10.0 - 1e-9 );
		cr_assert_leq( sx, 190.0 + 1e-9 );
		cr_assert_geq( sy, 10.0 - 1e-9 );
		cr_assert_leq( sy, 90.0 + 1e-9 );
		worst = fmin( worst, fmin( fmin( sx - 10.0, 190.0 - sx ), fmin( sy - 10.0, 90.0 - sy ) ) );
	}
	/* and the fit is tight: some vertex touches the margin. */
	cr_assert_float_eq( worst, 0.0, 1e-9 );
}

Test( render, dry_color_endpoints_midpoint_and_clamping )
{
	float rgb[3];
	/* The blend runs in double and rounds once to float: 1e-6 covers that rounding. */
	const float tolerance = 1e-6f;
	sere_render_dry_color( 1.0, rgb );
	cr_assert_float_eq( rgb[0], 0.30f, tolerance );
	cr_assert_float_eq( rgb[1], 0.55f, tolerance );
	cr_assert_float_eq( rgb[2], 0.18f, tolerance );
	sere_render_dry_color( 0.0, rgb );
	cr_assert_float_eq( rgb[0], 0.55f, tolerance );
	cr_assert_float_eq( rgb[1], 0.38f, tolerance );
	cr_assert_float_eq( rgb[2], 0.20f, tolerance );
	sere_render_dry_color( 0.5, rgb );
	cr_assert_float_eq( rgb[0], 0.425f, tolerance );
	cr_assert_float_eq( rgb[1], 0.465f, tolerance );
	cr_assert_float_eq( rgb[2], 0.19f, tolerance );
	sere_render_dry_color( 1.7, rgb );
	cr_assert_float_eq( rgb[1], 0.55f, tolerance );
	sere_render_dry_color( -3.0, rgb );
	cr_assert_float_eq( rgb[1], 0.38f, tolerance );
	sere_render_dry_color( NAN, rgb );
	cr_assert_float_eq( rgb[1], 0.38f, tolerance, "NaN water must show as dry" );
	float water[2] = { 0.25f, 0.75f }, many[6];
	sere_render_dry_colors( water, 2, many );
	cr_assert_float_eq( many[0], 0.4875f, tolerance );
	cr_assert_float_eq( many[3], 0.3625f, tolerance );
}

Test( render, colormap_ends_and_monotone_lightness )
{
	float rgb[3];
	/* 8-bit table entries divided by 255, rounded once to float. */
	sere_render_colormap( 0.0, rgb );
	cr_assert_float_eq( rgb[0], 68.0f / 255.0f, 1e-6f );
	cr_assert_float_eq( rgb[2], 84.0f / 255.0f, 1e-6f );
	sere_render_colormap( 1.0, rgb );
	cr_assert_float_eq( rgb[0], 253.0f / 255.0f, 1e-6f );
	cr_assert_float_eq( rgb[1], 231.0f / 255.0f, 1e-6f );
	/* A perceptual map must get lighter all the way, or a field shows false bands. */
	double previous = -1.0;
	for ( int k = 0; k <= 100; ++k )
	{
		sere_render_colormap( k / 100.0, rgb );
		double luma = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
		cr_assert_gt( luma, previous, "lightness drops at t = %g", k / 100.0 );
		previous = luma;
	}
	float values[3] = { 10.0f, 15.0f, 20.0f }, mapped[9], middle[3];
	sere_render_colormap_values( values, 3, 10.0, 20.0, mapped );
	sere_render_colormap( 0.5, middle );
	cr_assert_float_eq( mapped[3], middle[0], 1e-6f );
	cr_assert_float_eq( mapped[4], middle[1], 1e-6f );
}

Test( render, plot_has_requested_size_and_ink )
{
	scratch s;
	scratch_make( &s );
	char path[512], err[256] = { 0 };
	scratch_path( &s, "plot.png", path, sizeof( path ) );
	double x[50], a[50], b[50];
	for ( int i = 0; i < 50; ++i )
	{
		x[i] = i * 20.0;
		a[i] = exp( -i / 20.0 );
		b[i] = i == 25 ? NAN : 0.5 + 0.01 * i;
	}
	sere_render_series series[2] = {
		{ .name = "relative water", .x = x, .y = a, .count = 50 },
		{ .name = "area", .x = x, .y = b, .count = 50, .dashed = 1 },
	};
	sere_render_palette( 0, series[0].rgb );
	sere_render_palette( 1, series[1].rgb );
	sere_render_axes axes = { .title = "drying", .x_label = "frame", .y_label = "fraction" };
	cr_assert_eq( sere_render_plot( path, 320, 200, &axes, series, 2, err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( scratch_tmp_count( &s ), 0 );
	picture p = picture_load( path );
	cr_assert_eq( p.width, 320 );
	cr_assert_eq( p.height, 200 );
	int ink = 0, blue = 0;
	for ( int yy = 0; yy < p.height; ++yy )
	{
		for ( int xx = 0; xx < p.width; ++xx )
		{
			int rgb[3];
			picture_rgb( &p, xx, yy, rgb );
			ink += rgb[0] + rgb[1] + rgb[2] < 3 * 255;
			/* The first curve's blue (0, 114, 178) with some antialiasing slack. */
			blue += rgb[2] > 140 && rgb[0] < 60 && rgb[1] < 150;
		}
	}
	cr_assert_gt( ink, 1000, "only %d non-white pixels", ink );
	cr_assert_gt( blue, 100, "the blue curve is missing (%d pixels)", blue );
	cairo_surface_destroy( p.surface );

	sere_render_series empty = { .name = "nothing", .x = x, .y = a, .count = 0 };
	scratch_path( &s, "empty.png", path, sizeof( path ) );
	cr_assert_eq( sere_render_plot( path, 320, 200, &axes, &empty, 1, err, sizeof( err ) ), -1 );
	cr_assert_neq( err[0], '\0' );
	cr_assert_eq( access( path, F_OK ), -1, "a failed plot must not leave a file" );
	scratch_remove( &s );
}

Test( render, unwritable_path_fails_with_a_message )
{
	char err[256] = { 0 };
	double x[2] = { 0, 1 }, y[2] = { 0, 1 };
	sere_render_series series = { .name = "line", .x = x, .y = y, .count = 2 };
	const char* path = "/nonexistent-sere-dir/plot.png";
	cr_assert_eq( sere_render_plot( path, 200, 150, NULL, &series, 1, err, sizeof( err ) ), -1 );
	cr_assert_not_null( strstr( err, path ), "message '%s' does not name the file", err );
	cr_assert_eq( access( "/nonexistent-sere-dir/plot.png.tmp", F_OK ), -1 );
}

Test( render, bad_meshes_are_refused )
{
	char err[256] = { 0 };
	sere_render_canvas canvas;
	cr_assert_eq( sere_render_canvas_create( &canvas, 20, 20, err, sizeof( err ) ), 0 );
	const int32_t wrong[3] = { 0, 1, 4 };
	sere_render_mesh mesh = square_mesh( NULL, 1, 1, 1 );
	mesh.triangles = wrong;
	mesh.triangle_count = 1;
	sere_render_view view = { .elevation = 90.0 };
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, NULL, err, sizeof( err ) ), -1 );
	cr_assert_not_null( strstr( err, "vertex 4" ), "%s", err );
	const float z[4] = { 0, NAN, 0, 0 };
	mesh = square_mesh( z, 1, 1, 1 );
	err[0] = '\0';
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, NULL, err, sizeof( err ) ), -1 );
	cr_assert_not_null( strstr( err, "non-finite" ), "%s", err );
	const int32_t far[2] = { 0, 9 };
	sere_render_lines lines = { .pairs = far, .count = 1, .width = 1.0 };
	sere_render_style style = { .lines = &lines, .line_set_count = 1 };
	mesh = square_mesh( NULL, 1, 1, 1 );
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, &style, err, sizeof( err ) ), -1 );
	sere_render_view lost = { .azimuth = NAN, .elevation = 90.0 };
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &lost, NULL, err, sizeof( err ) ), -1 );
	cr_assert_eq( cairo_status( canvas.cr ), CAIRO_STATUS_SUCCESS, "a refused draw must leave the context usable" );
	sere_render_canvas_destroy( &canvas );
	sere_render_canvas empty;
	cr_assert_eq( sere_render_canvas_create( &empty, 0, 10, err, sizeof( err ) ), -1 );
	cr_assert_null( empty.cr );
}

typedef struct sheet_log
{
	int calls;
	int order_ok;
	int fail_at;
} sheet_log;

static int sheet_panel( void* user, int index, cairo_t* cr, double x, double y, double w, double h, char* caption,
						size_t caption_size, char* err, size_t err_size )
{
	sheet_log* log = user;
	log->order_ok &= index == log->calls;
	log->calls += 1;
	if ( index == log->fail_at )
	{
		snprintf( err, err_size, "panel %d failed", index );
		return -1;
	}
	sere_render_mesh mesh = square_mesh( NULL, 0.30f, 0.55f, 0.18f );
	sere_render_view view = { .azimuth = 0.0, .elevation = 90.0, .margin = 6.0 };
	snprintf( caption, caption_size, "frame %d, RWC %.2f", 10 * index, 1.0 - 0.1 * index );
	return sere_render_mesh_draw( cr, x, y, w, h, &mesh, &view, NULL, err, err_size );
}

Test( render, contact_sheet_draws_every_panel_in_order )
{
	scratch s;
	scratch_make( &s );
	char path[512], err[256] = { 0 };
	scratch_path( &s, "sheet.png", path, sizeof( path ) );
	sheet_log log = { 0, 1, -1 };
	sere_render_sheet sheet = { .title = "drying",
								.columns = 2,
								.count = 3,
								.panel_width = 60,
								.panel_height = 50,
								.draw = sheet_panel,
								.user = &log };
	cr_assert_eq( sere_render_contact_sheet( path, &sheet, err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( log.calls, 3 );
	cr_assert( log.order_ok );
	cr_assert_eq( scratch_tmp_count( &s ), 0 );
	picture p = picture_load( path );
	/* Two columns and two rows of panels, plus captions and a title. */
	cr_assert_geq( p.width, 2 * 60 );
	cr_assert_geq( p.height, 2 * 50 + 40 );
	cairo_surface_destroy( p.surface );

	scratch_path( &s, "broken.png", path, sizeof( path ) );
	log = ( sheet_log ){ 0, 1, 1 };
	cr_assert_eq( sere_render_contact_sheet( path, &sheet, err, sizeof( err ) ), -1 );
	cr_assert_str_eq( err, "panel 1 failed" );
	cr_assert_eq( access( path, F_OK ), -1 );
	cr_assert_eq( scratch_tmp_count( &s ), 0 );
	scratch_remove( &s );
}

Test( render, plane_picture_shows_veins_in_red )
{
	scratch s;
	scratch_make( &s );
	char path[512], err[256] = { 0 };
	scratch_path( &s, "plane.png", path, sizeof( path ) );
	const float tau[4] = { 1.0f, 0.6f, 0.2f, 0.0f };
	const int32_t vein[2] = { 0, 2 }, outline[8] = { 0, 1, 1, 2, 2, 3, 3, 0 };
	sere_render_plane plane = { .title = "plane",
								.x = square_x,
								.y = square_y,
								.vertex_count = 4,
								.triangles = square_triangles,
								.triangle_count = 2,
								.scalar = tau,
								.scalar_name = "tau",
								.vein_pairs = vein,
								.vein_count = 1,
								.outline_pairs = outline,
								.outline_count = 4 };
	cr_assert_eq( sere_render_plane_png( path, 300, 240, &plane, err, sizeof( err ) ), 0, "%s", err );
	picture p = picture_load( path );
	int red = 0;
	for ( int yy = 0; yy < p.height; ++yy )
	{
		for ( int xx = 0; xx < p.width; ++xx )
		{
			int rgb[3];
			picture_rgb( &p, xx, yy, rgb );
			/* Vein red is (217, 31, 26); no colormap entry comes near it. */
			red += rgb[0] > 180 && rgb[1] < 70 && rgb[2] < 70;
		}
	}
	cr_assert_gt( red, 50, "the vein diagonal is missing (%d red pixels)", red );
	cairo_surface_destroy( p.surface );
	const float bad[4] = { 0.0f, INFINITY, 0.0f, 0.0f };
	plane.scalar = bad;
	cr_assert_eq( sere_render_plane_png( path, 300, 240, &plane, err, sizeof( err ) ), -1 );
	scratch_remove( &s );
}
