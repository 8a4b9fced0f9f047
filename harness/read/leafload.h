/* sere harness — one entry point for leaves: a .leaf file or an auxiliary PNG (Fig. 3a-b). */
#pragma once

#include "read/leaffile.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_leaf_source
{
	sere_leaf_file file;
} sere_leaf_source;

/* Reads PATH by its extension (.png: an auxiliary image, see leafimage.h; anything else: a
 * .leaf file); SERE_OK, else the reader's status with one line in err. */
sere_status sere_leaf_source_load( const char* path, sere_leaf_source* leaf, char* err, size_t err_size );
void sere_leaf_source_destroy( sere_leaf_source* leaf );

#ifdef __cplusplus
}
#endif
