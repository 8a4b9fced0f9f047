/* sere fuzz — harness/read/seasonleaf.c compiled as it is, with its two static readers (key points,
 * PGM masks) exported under fuzz_ names. The fuzz targets that link this file get the whole of
 * seasonleaf.c from here rather than from the library, so the readers stay unchanged. */
#include "../harness/read/seasonleaf.c"

#include "seasonleaf_shim.h"

sere_status fuzz_read_keys( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height, char* err,
							size_t err_size )
{
	return read_keys( path, xy, count, width, height, err, err_size );
}

sere_status fuzz_read_pgm( const char* path, float** gray, int32_t* width, int32_t* height, char* err, size_t err_size )
{
	return read_pgm( path, gray, width, height, err, err_size );
}
