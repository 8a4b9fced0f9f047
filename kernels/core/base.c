#include "core/base.h"

#include "core/internal/simd.h"

#include <stdlib.h>
#include <string.h>

/* The Makefile passes the VERSION file's contents; there is no second copy to fall out of step. */
#ifndef SERE_VERSION
#error "SERE_VERSION is not defined: build libsere with its Makefile (it passes -DSERE_VERSION from VERSION)"
#endif

const char* sere_version( void )
{
	return SERE_VERSION;
}

const char* sere_simd_path( void )
{
	/* the lane layer's own choice of width, so the name cannot drift from what the kernels run */
	return SERE_LANES == 16 ? "AVX-512" : SERE_LANES == 8 ? "AVX2" : "portable";
}

const char* sere_status_text( sere_status status )
{
	switch ( status )
	{
		case SERE_OK:
			return "ok";
		case SERE_ERR_ARGUMENT:
			return "invalid argument";
		case SERE_ERR_MEMORY:
			return "out of memory";
		case SERE_ERR_NONFINITE:
			return "NaN or infinity in the input";
		case SERE_ERR_GEOMETRY:
			return "degenerate or invalid geometry";
		case SERE_ERR_COUNTS:
			return "no triangulation gives these particle and spring counts";
		case SERE_ERR_NOT_SPD:
			return "matrix is not symmetric positive definite";
		case SERE_ERR_NO_CONVERGE:
			return "iteration cap reached before the tolerance";
		case SERE_ERR_CAPACITY:
			return "workspace too small for the input";
		case SERE_ERR_IO:
			return "file could not be read or written";
		case SERE_ERR_PARSE:
			return "text not in the expected format";
		case SERE_STATUS_COUNT:
			break;
	}
	return "unknown status";
}

void* sere_alloc( size_t bytes )
{
	if ( bytes == 0 || bytes > SIZE_MAX - ( SERE_ALIGN - 1 ) )
	{
		return NULL; /* past SIZE_MAX − 63 the round-up would wrap to a 0-byte block */
	}
	size_t rounded = ( bytes + SERE_ALIGN - 1 ) & ~(size_t) ( SERE_ALIGN - 1 );
	void* memory = aligned_alloc( SERE_ALIGN, rounded );
	if ( memory != NULL )
	{
		memset( memory, 0, rounded );
	}
	return memory;
}

void sere_free( void* memory )
{
	free( memory );
}

void sere_free_all( void* const* arrays, size_t count )
{
	for ( size_t k = 0; k < count; ++k )
	{
		sere_free( arrays[k] );
	}
}

bool sere_alloc_floats( float** const* arrays, int32_t array_count, size_t count )
{
	for ( int32_t k = 0; k < array_count; ++k )
	{
		*arrays[k] = count <= SIZE_MAX / sizeof( float ) ? sere_alloc( count * sizeof( float ) ) : NULL;
		if ( *arrays[k] == NULL )
		{
			return false;
		}
	}
	return true;
}
