#include "leafload.h"

#include <stdio.h>
#include <string.h>

int sere_leaf_load( const char* path, sere_leaf* leaf, char* err, size_t err_size )
{
	return sere_leaf_read( path, &leaf->file, err, err_size ) == SERE_OK ? 0 : -1;
}

void sere_leaf_free( sere_leaf* leaf )
{
	sere_leaf_file_free( &leaf->file );
}
