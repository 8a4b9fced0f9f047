/* sere harness — the .leaf text format (see README, "Leaf files"). */
#pragma once

#include "shape.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* A leaf read from a file: owns its arrays; shape views them. */
typedef struct sere_leaf_file
{
	char name[128];
	double* outline_xy;
	double* vein_xy;
	sere_vein* veins;
	sere_leaf_shape shape;
	int32_t* outline_line; /* source line of each outline point, for error messages */
	int32_t* vein_line;	   /* source line of each vein point */
} sere_leaf_file;

/* Reads and validates a .leaf file. On failure returns the error and writes one line
 * "PATH:LINE: problem" (or "PATH: problem") into err; nothing needs freeing then. */
sere_status sere_leaf_read( const char* path, sere_leaf_file* leaf, char* err, size_t err_size );
void sere_leaf_file_free( sere_leaf_file* leaf );

/* Writes a shape as a .leaf file (to a temporary name, then renamed); 0 on success. */
int sere_leaf_write( const char* path, const sere_leaf_shape* shape, const char* name );

#ifdef __cplusplus
}
#endif
