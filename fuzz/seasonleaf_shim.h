/* sere fuzz — the two static readers of harness/read/seasonleaf.c, reachable from a fuzz target. */
#pragma once

#include "core/base.h"

#include <stddef.h>

/* read_keys: the key points file (data/seasons/maple.keys). */
sere_status fuzz_read_keys( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height, char* err,
							size_t err_size );

/* read_pgm: a binary PGM mask map (data/masks/maple.pgm). */
sere_status fuzz_read_pgm( const char* path, float** gray, int32_t* width, int32_t* height, char* err,
						   size_t err_size );
