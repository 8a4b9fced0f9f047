/* sere harness — A leaf, a silhouette or a gray image from a PNG: the stages in order (see leafimage.h). */
#include "read/leafimage_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The outline of the traced pixels with the base at (base_x, base_y). Full processing first; a
 * sub-pixel neck can make the simplified loop touch itself, then less processing is used (the
 * raw marching-squares loop is always simple). SERE_OK, or the status after its message. */
static sere_status outline_of( reader* r, const points* traced, double base_x, double base_y, outline* o )
{
	sere_status status = SERE_ERR_GEOMETRY;
	for ( int level = 0; level < 3 && status == SERE_ERR_GEOMETRY; ++level )
	{
		status = leafimage_make_outline( traced, level < 1, level < 2, base_x, base_y, o );
	}
	if ( status == SERE_OK )
	{
		return SERE_OK;
	}
	return status == SERE_ERR_MEMORY ? leafimage_fail( r, status, "out of memory for the outline" )
									 : leafimage_fail( r, status, "the traced outline is not a simple polygon" );
}

sere_status sere_leaf_from_png_mapped( const char* path, sere_leaf_file* leaf, sere_leaf_image_map* map, char* err,
									   size_t err_size )
{
	reader r = leafimage_reader_start( path, err, err_size );
	if ( path == NULL || leaf == NULL )
	{
		return leafimage_fail( &r, SERE_ERR_ARGUMENT, path == NULL ? "no file name" : "no leaf to fill" );
	}
	memset( leaf, 0, sizeof( *leaf ) );
	if ( map != NULL )
	{
		memset( map, 0, sizeof( *map ) );
	}
	points traced = { 0 };
	outline o = { 0 };
	veins_work v = { 0 };
	sere_status status =
		leafimage_trace_png( &r, &traced, "blade pixels (the blade is any color but white or transparent)" );
	if ( status != SERE_OK )
	{
		goto done;
	}
	int veins_found = 0;
	for ( int32_t i = 0; i < r.n && !veins_found; ++i )
	{
		veins_found = r.region[i] && r.kind[i] == KIND_VEIN;
	}
	if ( !veins_found )
	{
		status = leafimage_fail( &r, SERE_ERR_GEOMETRY,
								 "no veins: draw them as red strokes (R > 200, G < 80, B < 80) over the blade" );
		goto done;
	}
	/* the coverage (ink_max) is no longer needed: it becomes the base dot's mask */
	double dot_x = 0.0, dot_y = 0.0, dot_radius = 0.0;
	if ( leafimage_base_dot( &r, &dot_x, &dot_y, &dot_radius ) == 0 )
	{
		int elsewhere = 0;
		for ( int32_t i = 0; i < r.n && !elsewhere; ++i )
		{
			elsewhere = r.kind[i] == KIND_BASE;
		}
		status = leafimage_fail( &r, SERE_ERR_GEOMETRY, "no base: %s",
								 elsewhere
									 ? "the blue dot is off the leaf; draw it inside the blade, touching the margin"
									 : "draw a blue dot (B > 200, R < 80, G < 80) touching the margin at the petiole" );
		goto done;
	}
	status = outline_of( &r, &traced, dot_x, dot_y, &o );
	if ( status != SERE_OK )
	{
		goto done;
	}
	if ( o.dot_distance > dot_radius + 3.0 )
	{
		int32_t x = (int32_t) dot_x, y = (int32_t) dot_y;
		status = leafimage_fail(
			&r, SERE_ERR_GEOMETRY,
			"the blue base dot at pixel (%d, %d) is %.0f px inside the margin: draw it touching the margin", x, y,
			o.dot_distance );
		goto done;
	}
	status = leafimage_skeleton_veins( &r, &v, dot_x, dot_y, dot_radius, o.base_px, o.base_py );
	if ( status != SERE_OK )
	{
		goto done;
	}
	status = leafimage_place_veins( &r, &v, &o, leaf );
	if ( status != SERE_OK )
	{
		goto done;
	}
	leaf->outline_xy = o.xy;
	o.xy = NULL;
	leaf->shape.base_x = 0.0;
	leaf->shape.base_y = 0.0;
	leaf->shape.outline_count = o.count;
	leaf->shape.outline_xy = leaf->outline_xy;
	/* named like a .leaf file: the file name without its extension */
	const char* slash = strrchr( r.path, '/' );
	const char* file = slash != NULL ? slash + 1 : r.path;
	const char* dot = strrchr( file, '.' );
	int length = dot != NULL && dot > file ? (int) ( dot - file ) : (int) strlen( file );
	snprintf( leaf->name, sizeof( leaf->name ), "%.*s", length, file );
	sere_shape_check check;
	status = sere_shape_validate( &leaf->shape, &check );
	if ( status != SERE_OK )
	{
		status =
			leafimage_fail( &r, status, "the traced leaf is not usable: %s", sere_shape_problem_text( check.problem ) );
		goto done;
	}
	if ( map != NULL )
	{
		*map = ( sere_leaf_image_map ){ r.w, r.h, o.base_px, o.base_py, o.scale };
	}

done:
	if ( status != SERE_OK )
	{
		sere_leaf_file_destroy( leaf );
	}
	leafimage_veins_work_free( &v );
	free( o.xy );
	free( traced.xy );
	leafimage_reader_free( &r );
	return status;
}

sere_status sere_leaf_from_png( const char* path, sere_leaf_file* leaf, char* err, size_t err_size )
{
	return sere_leaf_from_png_mapped( path, leaf, NULL, err, err_size );
}

/* Without a blue dot the base is where a leaf drawn petiole down has its petiole: the outline
 * point nearest the middle of the bottom of the silhouette's bounding box. */
static void bottom_middle( const points* traced, double* x, double* y )
{
	double x_min = INFINITY, x_max = -INFINITY, y_max = -INFINITY;
	for ( int32_t i = 0; i < traced->count; ++i )
	{
		x_min = fmin( x_min, traced->xy[2 * i] );
		x_max = fmax( x_max, traced->xy[2 * i] );
		y_max = fmax( y_max, traced->xy[2 * i + 1] );
	}
	*x = 0.5 * ( x_min + x_max );
	*y = y_max;
}

sere_status sere_silhouette_from_png( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height,
									  char* err, size_t err_size )
{
	reader r = leafimage_reader_start( path, err, err_size );
	if ( path == NULL || xy == NULL || count == NULL || width == NULL || height == NULL )
	{
		return leafimage_fail( &r, SERE_ERR_ARGUMENT, "no file name or no place for the outline" );
	}
	*xy = NULL;
	*count = 0;
	points traced = { 0 };
	outline o = { 0 };
	sere_status status =
		leafimage_trace_png( &r, &traced, "non-background pixels (background is white or transparent)" );
	if ( status != SERE_OK )
	{
		goto done;
	}
	double base_x = 0.0, base_y = 0.0, radius = 0.0;
	if ( leafimage_base_dot( &r, &base_x, &base_y, &radius ) == 0 )
	{
		bottom_middle( &traced, &base_x, &base_y );
	}
	status = outline_of( &r, &traced, base_x, base_y, &o );
	if ( status != SERE_OK )
	{
		goto done;
	}
	/* back from leaf units to pixels (make_outline's mapping inverted) */
	for ( int32_t i = 0; i < o.count; ++i )
	{
		double x = o.xy[2 * i], y = o.xy[2 * i + 1];
		o.xy[2 * i] = o.base_px + x * o.scale;
		o.xy[2 * i + 1] = o.base_py - y * o.scale;
	}
	*xy = o.xy;
	*count = o.count;
	*width = r.w;
	*height = r.h;
	o.xy = NULL;

done:
	free( o.xy );
	free( traced.xy );
	leafimage_reader_free( &r );
	return status;
}
