/* sere harness — the .leaf text format (data/leaves/FORMAT.md describes it). */
#pragma once

#include "mesh/shape.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* The largest outline or vein point count a file may declare: far above any leaf worth
 * simulating, low enough that a corrupt count cannot ask for gigabytes. */
#define SERE_LEAF_MAX_POINTS 1000000

/* A leaf read from a file. It owns its arrays (malloc'd; the PNG reader fills the same struct)
 * and shape views them. outline_line and vein_line give the source line of every point, for
 * error messages; they are NULL for a leaf that did not come from a .leaf file. */
typedef struct sere_leaf_file
{
	char name[128];
	double* outline_xy;
	double* vein_xy;
	sere_vein* veins;
	sere_leaf_shape shape;
	int32_t* outline_line;
	int32_t* vein_line;
} sere_leaf_file;

/* Reads and validates a .leaf file. On failure returns the error, writes one line
 * "PATH:LINE: problem" (or "PATH: problem" when no line is at fault, e.g. the file cannot be
 * opened) into err, and leaves nothing to free. The name defaults to the file name without
 * its extension. */
sere_status sere_leaf_file_read( const char* path, sere_leaf_file* leaf, char* err, size_t err_size );
void sere_leaf_file_destroy( sere_leaf_file* leaf );

/* Writes a shape as a .leaf file that sere_leaf_file_read returns bit for bit (every coordinate in
 * the fewest digits that read back to the same double), to a temporary name and then renamed.
 * Refuses, with one line in err, a shape sere_shape_validate rejects and a name the reader
 * would not return unchanged (more than 127 characters, '#', control characters, leading or
 * trailing blanks); name may be NULL or empty for no name line. */
sere_status sere_leaf_file_write( const char* path, const sere_leaf_shape* shape, const char* name, char* err,
								  size_t err_size );

#ifdef __cplusplus
}
#endif
