#define _POSIX_C_SOURCE 200809L
#include "render/leafpics.h"
#include "render/render.h"

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
	/* fresh, dry, halfway; past either end clamps to that end, and NaN water shows as dry */
	const struct
	{
		double water;
		float rgb[3];
	} cases[] = {
		{ 1.0, { 0.30f, 0.55f, 0.18f } }, { 0.0, { 0.55f, 0.38f, 0.20f } },	 { 0.5, { 0.425f, 0.465f, 0.19f } },
		{ 1.7, { 0.30f, 0.55f, 0.18f } }, { -3.0, { 0.55f, 0.38f, 0.20f } }, { NAN, { 0.55f, 0.38f, 0.20f } },
	};
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		sere_render_dry_color( cases[k].water, rgb );
		for ( int c = 0; c < 3; ++c )
		{
			cr_assert_float_eq( rgb[c], cases[k].rgb[c], tolerance, "water %g, channel %d", cases[k].water, c );
		}
	}
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
	cr_assert_eq( sere_render_plot( path, 320, 200, &axes, &empty, 1, err, sizeof( err ) ), SERE_ERR_ARGUMENT );
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
	cr_assert_eq( sere_render_plot( path, 200, 150, NULL, &series, 1, err, sizeof( err ) ), SERE_ERR_IO );
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
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, NULL, err, sizeof( err ) ),
				  SERE_ERR_ARGUMENT );
	cr_assert_not_null( strstr( err, "vertex 4" ), "%s", err );
	const float z[4] = { 0, NAN, 0, 0 };
	mesh = square_mesh( z, 1, 1, 1 );
	err[0] = '\0';
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, NULL, err, sizeof( err ) ),
				  SERE_ERR_NONFINITE );
	cr_assert_not_null( strstr( err, "non-finite" ), "%s", err );
	const int32_t far[2] = { 0, 9 };
	sere_render_lines lines = { .pairs = far, .count = 1, .width = 1.0 };
	sere_render_style style = { .lines = &lines, .line_set_count = 1 };
	mesh = square_mesh( NULL, 1, 1, 1 );
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &view, &style, err, sizeof( err ) ),
				  SERE_ERR_ARGUMENT );
	sere_render_view lost = { .azimuth = NAN, .elevation = 90.0 };
	cr_assert_eq( sere_render_mesh_draw( canvas.cr, 0, 0, 20, 20, &mesh, &lost, NULL, err, sizeof( err ) ),
				  SERE_ERR_NONFINITE );
	cr_assert_eq( cairo_status( canvas.cr ), CAIRO_STATUS_SUCCESS, "a refused draw must leave the context usable" );
	sere_render_canvas_destroy( &canvas );
	sere_render_canvas empty;
	cr_assert_eq( sere_render_canvas_create( &empty, 0, 10, err, sizeof( err ) ), SERE_ERR_ARGUMENT );
	cr_assert_null( empty.cr );
}

typedef struct sheet_log
{
	int calls;
	int order_ok;
	int fail_at;
} sheet_log;

static sere_status sheet_panel( void* user, int index, cairo_t* cr, double x, double y, double w, double h,
								char* caption, size_t caption_size, char* err, size_t err_size )
{
	sheet_log* log = user;
	log->order_ok &= index == log->calls;
	log->calls += 1;
	if ( index == log->fail_at )
	{
		snprintf( err, err_size, "panel %d failed", index );
		return SERE_ERR_ARGUMENT;
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
	cr_assert_eq( sere_render_contact_sheet( path, &sheet, err, sizeof( err ) ), SERE_ERR_ARGUMENT );
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
	cr_assert_eq( sere_render_plane_png( path, 300, 240, &plane, err, sizeof( err ) ), SERE_ERR_NONFINITE );
	scratch_remove( &s );
}

/* --- 3D scenes: ground, shadow, the two faces, and the drying-leaf sheets ------------------- */

/* The pixel of a canvas, read in place. */
static void canvas_rgb( const sere_render_canvas* canvas, double x, double y, int rgb[3] )
{
	cairo_surface_flush( canvas->surface );
	picture p = { canvas->surface, canvas->width, canvas->height };
	picture_rgb( &p, (int) floor( x ), (int) floor( y ), rgb );
}

static int brightness( const int rgb[3] )
{
	return rgb[0] + rgb[1] + rgb[2];
}

static int saturation( const int rgb[3] )
{
	int hi = rgb[0] > rgb[1] ? rgb[0] : rgb[1], lo = rgb[0] < rgb[1] ? rgb[0] : rgb[1];
	hi = rgb[2] > hi ? rgb[2] : hi, lo = rgb[2] < lo ? rgb[2] : lo;
	return hi - lo;
}

Test( render, scene_null_draws_the_same_pixels_as_mesh_draw )
{
	char err[256] = { 0 };
	const float z[4] = { 0.0f, 0.1f, 0.5f, 0.2f };
	sere_render_mesh mesh = square_mesh( z, 0.30f, 0.55f, 0.18f );
	sere_render_canvas a, b;
	cr_assert_eq( sere_render_canvas_create( &a, 70, 50, err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( sere_render_canvas_create( &b, 70, 50, err, sizeof( err ) ), 0, "%s", err );
	sere_render_view va = { .azimuth = -35.0, .elevation = 30.0, .margin = 4.0 }, vb = va;
	cr_assert_eq( sere_render_mesh_draw( a.cr, 0, 0, 70, 50, &mesh, &va, NULL, err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( sere_render_mesh_draw_scene( b.cr, 0, 0, 70, 50, &mesh, &vb, NULL, NULL, err, sizeof( err ) ), 0,
				  "%s", err );
	cr_assert_eq( va.scale, vb.scale );
	cairo_surface_flush( a.surface );
	cairo_surface_flush( b.surface );
	size_t bytes = (size_t) cairo_image_surface_get_stride( a.surface ) * 50;
	cr_assert_eq( memcmp( cairo_image_surface_get_data( a.surface ), cairo_image_surface_get_data( b.surface ), bytes ),
				  0, "a NULL scene changed the picture" );
	sere_render_canvas_destroy( &a );
	sere_render_canvas_destroy( &b );
}

/* A unit square floating at height `lift` (twice, stacked, with `stack`) over a ground at
 * z = 0 that spans [-2, 3]^2, seen from the -y side 45 degrees up: the square sits high on
 * the screen and its vertical shadow low, apart. */
static void shadow_scene( sere_render_canvas* canvas, sere_render_view* view, int stack )
{
	static const float x[8] = { 0, 1, 1, 0, 0, 1, 1, 0 }, y[8] = { 0, 0, 1, 1, 0, 0, 1, 1 };
	static const float z[8] = { 1, 1, 1, 1, 1.3f, 1.3f, 1.3f, 1.3f };
	static const int32_t tri[12] = { 0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6 }; /* the second one upside down */
	sere_render_mesh mesh = { .x = x,
							  .y = y,
							  .z = z,
							  .vertex_count = 8,
							  .triangles = tri,
							  .triangle_count = stack ? 4 : 2,
							  .color = { 0.30f, 0.55f, 0.18f } };
	sere_render_scene scene = { .lower_tint = 1, .ground = 1, .ground_z = 0.0, .ground_box = { -2, -2, 3, 3 } };
	char err[256] = { 0 };
	cr_assert_eq( sere_render_canvas_create( canvas, 200, 200, err, sizeof( err ) ), 0, "%s", err );
	*view = ( sere_render_view ){ .azimuth = 0.0, .elevation = 45.0, .margin = 4.0 };
	cr_assert_eq(
		sere_render_mesh_draw_scene( canvas->cr, 0, 0, 200, 200, &mesh, view, NULL, &scene, err, sizeof( err ) ), 0,
		"%s", err );
}

Test( render, ground_is_darker_in_the_shadow_than_far_from_the_leaf )
{
	sere_render_canvas canvas;
	sere_render_view view;
	shadow_scene( &canvas, &view, 0 );
	double sx, sy, fx, fy, lx, ly, ox, oy;
	sere_render_project( &view, 0, 0, 200, 200, 0.5, 0.5, 0.0, &sx, &sy );	/* under the leaf */
	sere_render_project( &view, 0, 0, 200, 200, 2.5, -1.5, 0.0, &fx, &fy ); /* far on the ground */
	sere_render_project( &view, 0, 0, 200, 200, 0.5, 0.5, 1.0, &lx, &ly );	/* the leaf itself */
	ox = oy = 1.0;															/* the region's margin, off the ground */
	int shadow[3], far[3], leaf[3], off[3];
	canvas_rgb( &canvas, sx, sy, shadow );
	canvas_rgb( &canvas, fx, fy, far );
	canvas_rgb( &canvas, lx, ly, leaf );
	canvas_rgb( &canvas, ox, oy, off );
	/* The ground is a light gray, neither white nor dark. */
	cr_assert( brightness( far ) > 3 * 180 && brightness( far ) < 3 * 245, "ground (%d, %d, %d)", far[0], far[1],
			   far[2] );
	cr_assert_eq( brightness( off ), 3 * 255, "background (%d, %d, %d) is not white", off[0], off[1], off[2] );
	cr_assert_lt( brightness( shadow ) + 3 * 60, brightness( far ), "shadow (%d, %d, %d) vs ground (%d, %d, %d)",
				  shadow[0], shadow[1], shadow[2], far[0], far[1], far[2] );
	/* The shadow is a gray, the leaf drawn over the ground is green. */
	cr_assert_lt( saturation( shadow ), 12 );
	cr_assert_gt( leaf[1], leaf[0] + 20, "leaf (%d, %d, %d) is not green", leaf[0], leaf[1], leaf[2] );
	sere_render_canvas_destroy( &canvas );

	/* A second layer over the first, turned the other way round: the shadow is one union, no
	 * darker where the two overlap (and no hole where their windings would cancel). */
	shadow_scene( &canvas, &view, 1 );
	int doubled[3];
	canvas_rgb( &canvas, sx, sy, doubled );
	for ( int c = 0; c < 3; ++c )
	{
		cr_assert_leq( abs( doubled[c] - shadow[c] ), 1, "channel %d: %d with two layers, %d with one", c, doubled[c],
					   shadow[c] );
	}
	sere_render_canvas_destroy( &canvas );
}

/* A pixel inside the unit square drawn unlit in color rgb, seen straight down
 * (elevation 90) or straight up (-90), its triangles counter-clockwise seen from +z or not. */
static void face_pixel( int flipped, double elevation, const sere_render_scene* scene, int rgb[3] )
{
	static const int32_t up[6] = { 0, 1, 2, 0, 2, 3 }, down[6] = { 0, 2, 1, 0, 3, 2 };
	sere_render_mesh mesh = square_mesh( NULL, 0.30f, 0.55f, 0.18f );
	mesh.triangles = flipped ? down : up;
	sere_render_canvas canvas;
	char err[256] = { 0 };
	cr_assert_eq( sere_render_canvas_create( &canvas, 40, 40, err, sizeof( err ) ), 0, "%s", err );
	sere_render_view view = { .azimuth = 0.0, .elevation = elevation, .margin = 4.0 };
	sere_render_style unlit = { .unlit = 1 };
	cr_assert_eq(
		sere_render_mesh_draw_scene( canvas.cr, 0, 0, 40, 40, &mesh, &view, &unlit, scene, err, sizeof( err ) ), 0,
		"%s", err );
	canvas_rgb( &canvas, 12, 20, rgb ); /* inside, away from either diagonal */
	sere_render_canvas_destroy( &canvas );
}

Test( render, lower_face_is_paler_than_upper_face )
{
	const sere_render_scene two_faces = { .lower_tint = 1 };
	const float green[3] = { 0.30f, 0.55f, 0.18f };
	float pale[3];
	sere_render_lower_tint( green, pale );
	int upper[3], flipped[3], below[3], flipped_below[3], plain[3];
	face_pixel( 0, 90.0, &two_faces, upper );
	face_pixel( 1, 90.0, &two_faces, flipped );
	face_pixel( 0, -90.0, &two_faces, below );
	face_pixel( 1, -90.0, &two_faces, flipped_below );
	face_pixel( 1, 90.0, NULL, plain );
	for ( int c = 0; c < 3; ++c )
	{
		/* Upper face: the colors as given; lower face (a flipped mesh from above, or the
		 * mesh seen from below): the documented tint. */
		cr_assert_leq( abs( upper[c] - (int) lroundf( 255.0f * green[c] ) ), 1, "upper channel %d: %d", c, upper[c] );
		cr_assert_leq( abs( flipped[c] - (int) lroundf( 255.0f * pale[c] ) ), 1, "flipped channel %d: %d", c,
					   flipped[c] );
		cr_assert_eq( below[c], flipped[c], "seen from below, channel %d: %d vs %d", c, below[c], flipped[c] );
		cr_assert_eq( flipped_below[c], upper[c], "flipped, from below, channel %d", c );
		/* Without a scene, both faces keep the colors (the old pictures). */
		cr_assert_eq( plain[c], upper[c] );
	}
	cr_assert_gt( brightness( flipped ), brightness( upper ) + 3 * 40, "lower face not lighter" );
	cr_assert_lt( 10 * saturation( flipped ), 7 * saturation( upper ), "lower face not greyer (%d vs %d)",
				  saturation( flipped ), saturation( upper ) );
}

/* A leaf-like disk of `rings` x `spokes` (plus the centre) whose rim is bent up by curl,
 * triangles counter-clockwise seen from +z; water drops towards the rim as the leaf dries. */
#define DISK_RINGS	   6
#define DISK_SPOKES	   24
#define DISK_VERTICES  ( 1 + DISK_RINGS * DISK_SPOKES )
#define DISK_TRIANGLES ( DISK_SPOKES * ( 2 * DISK_RINGS - 1 ) )

typedef struct disk
{
	float x[DISK_VERTICES], y[DISK_VERTICES], z[DISK_VERTICES], rwc[DISK_VERTICES];
} disk;

static int32_t disk_triangles[3 * DISK_TRIANGLES];

static void disk_make( disk* d, double curl, double shrink, double water )
{
	d->x[0] = d->y[0] = d->z[0] = 0.0f;
	d->rwc[0] = (float) water;
	for ( int r = 1; r <= DISK_RINGS; ++r )
	{
		for ( int a = 0; a < DISK_SPOKES; ++a )
		{
			int i = 1 + ( r - 1 ) * DISK_SPOKES + a;
			double t = 2.0 * 3.14159265358979323846 * a / DISK_SPOKES, u = (double) r / DISK_RINGS;
			d->x[i] = (float) ( shrink * u * cos( t ) );
			d->y[i] = (float) ( shrink * 1.4 * u * sin( t ) );
			d->z[i] = (float) ( curl * u * u );
			d->rwc[i] = (float) fmax( 0.0, water - ( 1.0 - water ) * 0.5 * u );
		}
	}
	int k = 0;
	for ( int a = 0; a < DISK_SPOKES; ++a )
	{
		disk_triangles[k++] = 0, disk_triangles[k++] = 1 + a, disk_triangles[k++] = 1 + ( a + 1 ) % DISK_SPOKES;
	}
	for ( int r = 1; r < DISK_RINGS; ++r )
	{
		for ( int a = 0; a < DISK_SPOKES; ++a )
		{
			int32_t i0 = 1 + ( r - 1 ) * DISK_SPOKES + a, i1 = 1 + ( r - 1 ) * DISK_SPOKES + ( a + 1 ) % DISK_SPOKES;
			disk_triangles[k++] = i0, disk_triangles[k++] = i0 + DISK_SPOKES, disk_triangles[k++] = i1 + DISK_SPOKES;
			disk_triangles[k++] = i0, disk_triangles[k++] = i1 + DISK_SPOKES, disk_triangles[k++] = i1;
		}
	}
}

static void disk_frames( disk d[3], sere_leafpics_frame frames[3] )
{
	disk_make( d + 0, 0.0, 1.0, 1.0 );
	disk_make( d + 1, 0.5, 0.9, 0.6 );
	disk_make( d + 2, 1.2, 0.8, 0.15 );
	const int number[3] = { 0, 400, 1600 };
	for ( int k = 0; k < 3; ++k )
	{
		frames[k] = ( sere_leafpics_frame ){ d[k].x, d[k].y, d[k].z, d[k].rwc, DISK_VERTICES, number[k], d[k].rwc[0] };
	}
}

static long file_bytes( const char* path, unsigned char** data )
{
	FILE* f = fopen( path, "rb" );
	cr_assert_not_null( f, "%s", path );
	fseek( f, 0, SEEK_END );
	long size = ftell( f );
	fseek( f, 0, SEEK_SET );
	*data = malloc( (size_t) size );
	cr_assert_eq( fread( *data, 1, (size_t) size, f ), (size_t) size );
	fclose( f );
	return size;
}

Test( render, leafpics_sheet_is_a_png_of_the_documented_size_and_deterministic )
{
	scratch s;
	scratch_make( &s );
	char path[512], again[512], err[256] = { 0 };
	scratch_path( &s, "leaf.png", path, sizeof( path ) );
	scratch_path( &s, "again.png", again, sizeof( again ) );
	disk d[3];
	sere_leafpics_frame frames[3];
	disk_frames( d, frames );
	cr_assert_eq(
		sere_leafpics_sheet( path, "drying", 3, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, err, sizeof( err ) ),
		0, "%s", err );
	cr_assert_eq( sere_leafpics_sheet( again, "drying", 3, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, err,
									   sizeof( err ) ),
				  0, "%s", err );
	cr_assert_eq( scratch_tmp_count( &s ), 0 );
	picture p = picture_load( path );
	cr_assert_eq( p.width, 34 + 3 * ( SERE_LEAFPICS_PANEL_WIDTH + 12 ) );
	cr_assert_eq( p.height, 694 );
	/* Leaf colors in both rows of every column: the fresh column green, the dry one brown. */
	int green[3] = { 0, 0, 0 }, brown[3] = { 0, 0, 0 };
	for ( int k = 0; k < 3; ++k )
	{
		for ( int row = 0; row < 2; ++row )
		{
			int x0 = 34 + k * ( SERE_LEAFPICS_PANEL_WIDTH + 12 ),
				y0 = 44 + 26 + row * ( SERE_LEAFPICS_PANEL_HEIGHT + 12 );
			for ( int y = y0; y < y0 + SERE_LEAFPICS_PANEL_HEIGHT; y += 2 )
			{
				for ( int x = x0; x < x0 + SERE_LEAFPICS_PANEL_WIDTH; x += 2 )
				{
					int rgb[3];
					picture_rgb( &p, x, y, rgb );
					green[k] += row == 0 && rgb[1] > rgb[0] + 25 && rgb[1] > rgb[2] + 25;
					brown[k] += row == 1 && rgb[0] > rgb[1] + 15 && rgb[1] > rgb[2] + 15;
				}
			}
		}
	}
	cr_assert_gt( green[0], 500, "fresh leaf not green (%d)", green[0] );
	cr_assert_gt( brown[2], 300, "dry leaf not brown (%d)", brown[2] );
	cr_assert_lt( brown[0], 20 );
	cairo_surface_destroy( p.surface );
	unsigned char *a, *b;
	long na = file_bytes( path, &a ), nb = file_bytes( again, &b );
	cr_assert( na == nb && memcmp( a, b, (size_t) na ) == 0, "the same input gave different PNG bytes" );
	free( a );
	free( b );

	scratch_path( &s, "view.png", path, sizeof( path ) );
	cr_assert_eq(
		sere_leafpics_view( path, NULL, frames + 2, disk_triangles, DISK_TRIANGLES, 0.0f, 300, err, sizeof( err ) ), 0,
		"%s", err );
	p = picture_load( path );
	cr_assert_eq( p.width, 300 );
	cr_assert_eq( p.height, 300 );
	cairo_surface_destroy( p.surface );
	scratch_remove( &s );
}

Test( render, leafpics_errors_name_the_file )
{
	char err[256] = { 0 };
	disk d[3];
	sere_leafpics_frame frames[3];
	disk_frames( d, frames );
	const char* bad = "/nonexistent-sere-dir/leaf.png";
	cr_assert_eq(
		sere_leafpics_sheet( bad, NULL, 3, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, err, sizeof( err ) ),
		SERE_ERR_IO );
	cr_assert_not_null( strstr( err, bad ), "%s", err );
	cr_assert_null( strchr( err, '\n' ) );
	err[0] = '\0';
	cr_assert_eq(
		sere_leafpics_view( bad, NULL, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, 0, err, sizeof( err ) ),
		SERE_ERR_IO );
	cr_assert_not_null( strstr( err, bad ), "%s", err );

	scratch s;
	scratch_make( &s );
	char path[512];
	scratch_path( &s, "broken.png", path, sizeof( path ) );
	int32_t wrong[3] = { 0, 1, DISK_VERTICES };
	err[0] = '\0';
	cr_assert_eq( sere_leafpics_sheet( path, NULL, 3, frames, wrong, 1, -INFINITY, err, sizeof( err ) ),
				  SERE_ERR_ARGUMENT );
	cr_assert_eq( strncmp( err, path, strlen( path ) ), 0, "%s", err );
	cr_assert_eq( access( path, F_OK ), -1 );
	d[1].z[5] = NAN;
	cr_assert_eq(
		sere_leafpics_sheet( path, NULL, 3, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, err, sizeof( err ) ),
		SERE_ERR_NONFINITE );
	cr_assert_not_null( strstr( err, "frame 400" ), "%s", err );
	cr_assert_eq(
		sere_leafpics_sheet( path, NULL, 0, frames, disk_triangles, DISK_TRIANGLES, -INFINITY, err, sizeof( err ) ),
		SERE_ERR_ARGUMENT );
	cr_assert_eq( scratch_tmp_count( &s ), 0 );
	scratch_remove( &s );
}

/* `sere wilt` draws with this renderer: its picture of a rest plant is not blank but shows
 * leaf-green pixels (green well over red and blue, unlike the pale sky) and the stem. */
Test( render, wilt_picture_shows_the_leaves )
{
	const char* bin = getenv( "SERE_BIN" );
	if ( bin == NULL || bin[0] == '\0' )
	{
		cr_skip_test( "SERE_BIN is not set (make test sets it to the built sere)" );
	}
	scratch s;
	scratch_make( &s );
	char line[1024], path[512];
	snprintf( line, sizeof( line ),
			  "'%s' wilt --leaves 2 --frames 1 --format png --size 160x120 --out '%s' >/dev/null 2>&1", bin, s.dir );
	cr_assert_eq( system( line ), 0, "failed: %s", line );
	scratch_path( &s, "frame_0000.png", path, sizeof( path ) );
	picture p = picture_load( path );
	cr_assert_eq( p.width, 160 );
	cr_assert_eq( p.height, 120 );
	int leaf = 0;
	for ( int y = 0; y < p.height; ++y )
	{
		for ( int x = 0; x < p.width; ++x )
		{
			int rgb[3];
			picture_rgb( &p, x, y, rgb );
			leaf += rgb[1] > rgb[0] + 20 && rgb[1] > rgb[2] + 20;
		}
	}
	cairo_surface_destroy( p.surface );
	cr_expect_gt( leaf, p.width * p.height / 50, "only %d leaf pixels of %d", leaf, p.width * p.height );
	cr_expect_eq( scratch_tmp_count( &s ), 0 );
	scratch_remove( &s );
}
