#include "read/leafload.h"

#include "read/leafimage.h"

#include <stdio.h>
#include <string.h>

sere_status sere_leaf_source_load( const char* path, sere_leaf_source* leaf, char* err, size_t err_size )
{
	size_t length = strlen( path );
	int png = length > 4 && ( strcmp( path + length - 4, ".png" ) == 0 || strcmp( path + length - 4, ".PNG" ) == 0 );
	return png ? sere_leaf_from_png( path, &leaf->file, err, err_size )
			   : sere_leaf_file_read( path, &leaf->file, err, err_size );
}

void sere_leaf_source_destroy( sere_leaf_source* leaf )
{
	sere_leaf_file_destroy( &leaf->file );
}
