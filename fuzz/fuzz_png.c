/* sere fuzz — the image readers: the PNG leaf (harness/read/leafimage.c: sere_leaf_from_png_mapped,
 * sere_silhouette_from_png, sere_png_read_gray) and the PGM mask map (harness/read/seasonleaf.c,
 * read_pgm, through seasonleaf_shim.c).
 *
 * Every input is given to all four. A rejected input must come back with a message and nothing
 * to free; an accepted leaf must be a valid shape and its map must fit the image; a silhouette
 * or gray image must have the size it claims.
 *
 * A mutated PNG chunk would almost always fail its CRC, and libpng would stop there; so the CRC
 * of every complete chunk is recomputed before the readers see the input, letting the fuzzer
 * change the header, palette and transparency of an image and reach the pixel processing. */
#define _GNU_SOURCE
#include "fuzz.h"

#include "read/leafimage.h"
#include "seasonleaf_shim.h"

#include <math.h>
#include <string.h>
#include <zlib.h>

int LLVMFuzzerInitialize( int* argc, char*** argv )
{
	(void) argc, (void) argv;
	fuzz_quiet();
	return 0;
}

static uint32_t big_endian( const uint8_t* p )
{
	return (uint32_t) p[0] << 24 | (uint32_t) p[1] << 16 | (uint32_t) p[2] << 8 | p[3];
}

/* A copy of the input with the CRC of each complete chunk after the PNG signature made right. */
static uint8_t* fix_crcs( const uint8_t* data, size_t size )
{
	uint8_t* fixed = malloc( size > 0 ? size : 1 );
	if ( fixed == NULL )
	{
		abort();
	}
	memcpy( fixed, data, size );
	static const uint8_t signature[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' };
	if ( size < 8 || memcmp( data, signature, 8 ) != 0 )
	{
		return fixed;
	}
	for ( size_t at = 8; at + 12 <= size; )
	{
		uint32_t length = big_endian( fixed + at );
		if ( length > size - at - 12 )
		{
			break;
		}
		uint32_t crc = (uint32_t) crc32( 0L, fixed + at + 4, (uInt) length + 4 );
		uint8_t* out = fixed + at + 8 + length;
		out[0] = (uint8_t) ( crc >> 24 ), out[1] = (uint8_t) ( crc >> 16 ), out[2] = (uint8_t) ( crc >> 8 );
		out[3] = (uint8_t) crc;
		at += 12 + (size_t) length;
	}
	return fixed;
}

int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size )
{
	uint8_t* fixed = fix_crcs( data, size );
	const char* path = fuzz_file( fixed, size );
	free( fixed );
	char err[1024] = "";
	sere_leaf_file leaf;
	sere_leaf_image_map map;
	if ( sere_leaf_from_png_mapped( path, &leaf, &map, err, sizeof( err ) ) == SERE_OK )
	{
		sere_shape_check check;
		FUZZ_CHECK( sere_shape_validate( &leaf.shape, &check ) == SERE_OK );
		FUZZ_CHECK( map.width >= 1 && map.height >= 1 && map.pixels_per_unit > 0.0 );
		FUZZ_CHECK( map.base_px >= 0.0 && map.base_px <= map.width && map.base_py >= 0.0 && map.base_py <= map.height );
		sere_leaf_file_destroy( &leaf );
	}
	else
	{
		FUZZ_CHECK( err[0] != '\0' && leaf.outline_xy == NULL && leaf.vein_xy == NULL && leaf.veins == NULL );
	}

	double* xy = NULL;
	int32_t count = 0, width = 0, height = 0;
	err[0] = '\0';
	if ( sere_silhouette_from_png( path, &xy, &count, &width, &height, err, sizeof( err ) ) == SERE_OK )
	{
		FUZZ_CHECK( count >= 3 && width >= 1 && height >= 1 );
		for ( int32_t i = 0; i < count; ++i )
		{
			FUZZ_CHECK( isfinite( xy[2 * i] ) && isfinite( xy[2 * i + 1] ) );
		}
		free( xy );
	}
	else
	{
		FUZZ_CHECK( err[0] != '\0' );
	}

	float* gray = NULL;
	err[0] = '\0';
	if ( sere_png_read_gray( path, &gray, &width, &height, err, sizeof( err ) ) == SERE_OK )
	{
		FUZZ_CHECK( width >= 1 && height >= 1 );
		FUZZ_CHECK( gray[0] >= 0.0f && gray[0] <= 1.0f && gray[(size_t) width * height - 1] >= 0.0f &&
					gray[(size_t) width * height - 1] <= 1.0f );
		free( gray );
	}
	else
	{
		FUZZ_CHECK( err[0] != '\0' );
	}

	gray = NULL;
	err[0] = '\0';
	if ( fuzz_read_pgm( path, &gray, &width, &height, err, sizeof( err ) ) == SERE_OK )
	{
		FUZZ_CHECK( width >= 1 && height >= 1 );
		for ( size_t i = 0; i < (size_t) width * height; ++i )
		{
			FUZZ_CHECK( gray[i] >= 0.0f && gray[i] <= 1.0f );
		}
		free( gray );
	}
	else
	{
		FUZZ_CHECK( err[0] != '\0' );
	}
	return 0;
}
