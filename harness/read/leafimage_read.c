/* sere harness — Reading: any PNG as 8-bit RGBA or gray, and the reader the stages share. */
#include "read/leafimage_shared.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One line "PATH: problem" into the caller's buffer. */
sere_status leafimage_fail( reader* r, sere_status status, const char* format, ... )
{
	char what[512];
	va_list args;
	va_start( args, format );
	vsnprintf( what, sizeof( what ), format, args );
	va_end( args );
	if ( r->err != NULL && r->err_size > 0 )
	{
		snprintf( r->err, r->err_size, "%s: %s", r->path, what );
	}
	return status;
}

static void png_on_error( png_structp png, png_const_charp message )
{
	png_failure* failure = png_get_error_ptr( png );
	snprintf( failure->message, sizeof( failure->message ), "%s", message );
	longjmp( failure->jump, 1 );
}

static void png_on_warning( png_structp png, png_const_charp message )
{
	(void) png;
	(void) message;
}

static void png_close( reader* r )
{
	png_destroy_read_struct( &r->png, &r->info, NULL );
	fclose( r->file );
	r->file = NULL;
	free( r->rows );
	r->rows = NULL;
}

/* Any PNG (palette, gray, 1-16 bits, with or without alpha or tRNS, interlaced) as 8-bit RGBA. */
sere_status leafimage_load_png( reader* r )
{
	r->file = fopen( r->path, "rb" );
	if ( r->file == NULL )
	{
		return leafimage_fail( r, SERE_ERR_ARGUMENT, "cannot open: %s", strerror( errno ) );
	}
	png_byte signature[8];
	if ( fread( signature, 1, sizeof( signature ), r->file ) != sizeof( signature ) ||
		 png_sig_cmp( signature, 0, sizeof( signature ) ) != 0 )
	{
		fclose( r->file );
		r->file = NULL;
		return leafimage_fail( r, SERE_ERR_ARGUMENT, "not a PNG file" );
	}
	r->png = png_create_read_struct( PNG_LIBPNG_VER_STRING, &r->failure, png_on_error, png_on_warning );
	r->info = r->png != NULL ? png_create_info_struct( r->png ) : NULL;
	if ( r->info == NULL )
	{
		png_close( r );
		return leafimage_fail( r, SERE_ERR_MEMORY, "out of memory" );
	}
	if ( setjmp( r->failure.jump ) )
	{
		png_close( r );
		free( r->rgba );
		r->rgba = NULL;
		return leafimage_fail( r, SERE_ERR_ARGUMENT, "corrupt PNG: %s", r->failure.message );
	}
	png_init_io( r->png, r->file );
	png_set_sig_bytes( r->png, sizeof( signature ) );
	png_read_info( r->png, r->info );
	png_uint_32 width = png_get_image_width( r->png, r->info ), height = png_get_image_height( r->png, r->info );
	if ( width > MAX_SIDE || height > MAX_SIDE )
	{
		png_close( r );
		return leafimage_fail( r, SERE_ERR_ARGUMENT, "image too large: %lu x %lu pixels (at most %d x %d)",
							   (unsigned long) width, (unsigned long) height, MAX_SIDE, MAX_SIDE );
	}
	int color = png_get_color_type( r->png, r->info );
	png_set_expand( r->png ); /* palette -> RGB, gray below 8 bits -> 8 bits, tRNS -> alpha */
	png_set_strip_16( r->png );
	if ( color == PNG_COLOR_TYPE_GRAY || color == PNG_COLOR_TYPE_GRAY_ALPHA )
	{
		png_set_gray_to_rgb( r->png );
	}
	if ( ( color & PNG_COLOR_MASK_ALPHA ) == 0 && !png_get_valid( r->png, r->info, PNG_INFO_tRNS ) )
	{
		png_set_add_alpha( r->png, 0xff, PNG_FILLER_AFTER );
	}
	png_set_interlace_handling( r->png );
	png_read_update_info( r->png, r->info );
	if ( png_get_rowbytes( r->png, r->info ) != 4 * (size_t) width )
	{
		png_close( r );
		return leafimage_fail( r, SERE_ERR_ARGUMENT, "unsupported PNG layout" );
	}
	r->rgba = malloc( 4 * (size_t) width * height );
	r->rows = malloc( sizeof( png_bytep ) * height );
	if ( r->rgba == NULL || r->rows == NULL )
	{
		png_close( r );
		free( r->rgba );
		r->rgba = NULL;
		return leafimage_fail( r, SERE_ERR_MEMORY, "out of memory for a %lu x %lu image", (unsigned long) width,
							   (unsigned long) height );
	}
	for ( png_uint_32 y = 0; y < height; ++y )
	{
		r->rows[y] = r->rgba + 4 * (size_t) width * y;
	}
	png_read_image( r->png, r->rows );
	png_read_end( r->png, NULL );
	png_close( r );
	r->w = (int) width;
	r->h = (int) height;
	r->n = (int32_t) width * (int32_t) height;
	return SERE_OK;
}

/* The color convention of leafimage.h, and each pixel's ink: max(255 - R, 255 - G, 255 - B)
 * scaled by alpha, which is linear in the coverage of an antialiased rim over white or over
 * transparency, so ink / ink_max estimates how much of a pixel the blade covers. */
reader leafimage_reader_start( const char* path, char* err, size_t err_size )
{
	if ( err != NULL && err_size > 0 )
	{
		err[0] = '\0';
	}
	reader r = { 0 };
	r.path = path != NULL ? path : "(null)";
	r.err = err;
	r.err_size = err_size;
	return r;
}

void leafimage_reader_free( reader* r )
{
	free( r->kind ), free( r->ink ), free( r->ink_max ), free( r->region ), free( r->queue ), free( r->rgba );
}

/* Loads the PNG, classifies its pixels, finds the silhouette and traces its outline into
 * traced; no_leaf names what was missing when the silhouette is too small. The caller frees
 * traced.xy and the reader's buffers whatever the status. */
sere_status sere_png_read_gray( const char* path, float** gray, int32_t* width, int32_t* height, char* err,
								size_t err_size )
{
	reader r = leafimage_reader_start( path, err, err_size );
	if ( path == NULL || gray == NULL || width == NULL || height == NULL )
	{
		return leafimage_fail( &r, SERE_ERR_ARGUMENT, "no file name or no place for the image" );
	}
	*gray = NULL;
	sere_status status = leafimage_load_png( &r );
	if ( status != SERE_OK )
	{
		return status;
	}
	float* g = malloc( sizeof( float ) * (size_t) r.n );
	if ( g == NULL )
	{
		free( r.rgba );
		return leafimage_fail( &r, SERE_ERR_MEMORY, "out of memory for a %d x %d image", r.w, r.h );
	}
	for ( int32_t i = 0; i < r.n; ++i )
	{
		const uint8_t* p = r.rgba + 4 * (size_t) i;
		g[i] = (float) ( ( 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] ) * p[3] / ( 255.0 * 255.0 ) );
	}
	free( r.rgba );
	*gray = g;
	*width = r.w;
	*height = r.h;
	return SERE_OK;
}
