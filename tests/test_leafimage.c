#include "leafimage.h"
#include "leafload.h"
#include "model.h"

#include <cairo.h>
#include <criterion/criterion.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

Test( leafimage, example_traces_like_its_pixels )
{
	const char* path = "data/leaves/example_aux.png";
	sere_leaf_file leaf;
	char err[1024];
	cr_assert_eq( sere_leaf_from_png( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
	/* Ground truth from the pixels themselves: the blade is every non-white pixel. */
	png_image png;
	memset( &png, 0, sizeof( png ) );
	png.version = PNG_IMAGE_VERSION;
	cr_assert( png_image_begin_read_from_file( &png, path ) );
	png.format = PNG_FORMAT_RGBA;
	uint8_t* rgba = malloc( PNG_IMAGE_SIZE( png ) );
	cr_assert( png_image_finish_read( &png, NULL, rgba, 0, NULL ) );
	int blade = 0, top = (int) png.height, bottom = 0;
	for ( uint32_t i = 0; i < png.width * png.height; ++i )
	{
		const uint8_t* p = rgba + 4 * i;
		if ( !( p[0] > 230 && p[1] > 230 && p[2] > 230 ) )
		{
			blade += 1;
			int y = (int) ( i / png.width );
			top = y < top ? y : top;
			bottom = y > bottom ? y : bottom;
		}
	}
	free( rgba );
	double scale = 1.0 / ( bottom - top + 1 );
	/* The outline runs along pixel edges, simplified by at most 0.4 px: its area matches the
	 * pixel count within 1% (the antialiased rim is partly counted either way). */
	double area = sere_shape_area( &leaf.shape );
	cr_expect_gt( area, 0.0, "counter-clockwise" );
	cr_expect_leq( fabs( area - blade * scale * scale ), 0.01 * blade * scale * scale, "area %g vs %g pixels", area,
				   blade * scale * scale );
	/* The drawing has a midvein and 10 secondary veins; the midvein reaches towards the tip. */
	cr_expect_eq( leaf.shape.vein_count, 11 );
	cr_expect_eq( leaf.veins[0].order, 1 );
	cr_expect_eq( leaf.veins[0].parent, -1 );
	const double* tip = leaf.vein_xy + 2 * ( leaf.veins[0].first + leaf.veins[0].count - 1 );
	cr_expect_gt( tip[1], 0.8, "midvein ends at %g", tip[1] );
	for ( int32_t v = 1; v < leaf.shape.vein_count; ++v )
	{
		cr_expect_eq( leaf.veins[v].parent, 0 );
		cr_expect_eq( leaf.veins[v].order, 2 );
	}
	cr_expect_eq( leaf.shape.base_x, 0.0 );
	cr_expect_eq( leaf.shape.base_y, 0.0 );
	/* And the traced leaf builds a model through the same path as a .leaf file. */
	sere_build_params params = sere_build_params_default();
	params.point_count = 800;
	params.boundary_count = sere_boundary_for_points( area, sere_shape_perimeter( &leaf.shape ), 800 );
	sere_model model;
	cr_expect_eq( sere_model_build( &leaf.shape, &params, &model, NULL ), SERE_OK );
	sere_model_destroy( &model );
	sere_leaf_file_free( &leaf );
}

/* Draws a test image: an ellipse blade, optional veins and base dot. */
static void draw( const char* path, int blade, int midvein, int stray, int base )
{
	cairo_surface_t* s = cairo_image_surface_create( CAIRO_FORMAT_RGB24, 200, 300 );
	cairo_t* cr = cairo_create( s );
	cairo_set_source_rgb( cr, 1, 1, 1 );
	cairo_paint( cr );
	if ( blade )
	{
		cairo_save( cr );
		cairo_translate( cr, 100, 150 );
		cairo_scale( cr, 60, 130 );
		cairo_arc( cr, 0, 0, 1, 0, 2 * 3.14159265358979 );
		cairo_restore( cr );
		cairo_set_source_rgb( cr, 0.3, 0.6, 0.2 );
		cairo_fill( cr );
	}
	cairo_set_source_rgb( cr, 0.9, 0.05, 0.05 );
	cairo_set_line_width( cr, 3 );
	if ( midvein )
	{
		cairo_move_to( cr, 100, 275 );
		cairo_line_to( cr, 100, 40 );
		cairo_stroke( cr );
	}
	if ( stray )
	{
		cairo_move_to( cr, 130, 150 );
		cairo_line_to( cr, 145, 120 );
		cairo_stroke( cr );
	}
	if ( base )
	{
		cairo_set_source_rgb( cr, 0.05, 0.1, 0.95 );
		cairo_arc( cr, 100, 279, 4, 0, 2 * 3.14159265358979 );
		cairo_fill( cr );
	}
	cairo_surface_write_to_png( s, path );
	cairo_destroy( cr );
	cairo_surface_destroy( s );
}

static void expect_bad( const char* path, const char* phrase )
{
	sere_leaf_file leaf;
	char err[1024];
	cr_expect_neq( sere_leaf_from_png( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s accepted", path );
	cr_expect_eq( strncmp( err, path, strlen( path ) ), 0, "%s", err );
	cr_expect_not_null( strstr( err, phrase ), "expected '%s' in: %s", phrase, err );
}

Test( leafimage, bad_images_give_clear_errors )
{
	draw( "/tmp/sere-img-ok.png", 1, 1, 0, 1 );
	sere_leaf_file leaf;
	char err[1024];
	cr_assert_eq( sere_leaf_from_png( "/tmp/sere-img-ok.png", &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
	sere_leaf_file_free( &leaf );
	draw( "/tmp/sere-img-white.png", 0, 0, 0, 0 );
	expect_bad( "/tmp/sere-img-white.png", "no leaf" );
	draw( "/tmp/sere-img-noveins.png", 1, 0, 0, 1 );
	expect_bad( "/tmp/sere-img-noveins.png", "no veins" );
	draw( "/tmp/sere-img-nobase.png", 1, 1, 0, 0 );
	expect_bad( "/tmp/sere-img-nobase.png", "no base" );
	draw( "/tmp/sere-img-stray.png", 1, 1, 1, 1 );
	expect_bad( "/tmp/sere-img-stray.png", "does not touch the vein network" );
	FILE* f = fopen( "/tmp/sere-img-text.png", "w" );
	fputs( "this is not a picture\n", f );
	fclose( f );
	expect_bad( "/tmp/sere-img-text.png", "not a readable PNG" );
	expect_bad( "/tmp/sere-img-missing.png", "not a readable PNG" );
	const char* names[] = { "ok", "white", "noveins", "nobase", "stray", "text" };
	for ( size_t k = 0; k < sizeof( names ) / sizeof( names[0] ); ++k )
	{
		char path[128];
		snprintf( path, sizeof( path ), "/tmp/sere-img-%s.png", names[k] );
		remove( path );
	}
	/* The image path is also what sere_leaf_load takes for a .png */
	sere_leaf any;
	cr_expect_eq( sere_leaf_load( "data/leaves/example_aux.png", &any, err, sizeof( err ) ), 0, "%s", err );
	sere_leaf_free( &any );
}
