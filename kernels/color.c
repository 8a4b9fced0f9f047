#include "color.h"

#include <stdlib.h>
#include <string.h>

void sere_coloring_destroy( sere_coloring* coloring )
{
	sere_free( coloring->order );
	sere_free( coloring->color );
	memset( coloring, 0, sizeof( *coloring ) );
}

sere_status sere_color_springs( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
								sere_coloring* coloring )
{
	memset( coloring, 0, sizeof( *coloring ) );
	if ( a == NULL || b == NULL || spring_count <= 0 || particle_count <= 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	uint64_t* used = calloc( (size_t) particle_count, sizeof( uint64_t ) ); /* colors at each particle */
	coloring->order = sere_alloc( sizeof( int32_t ) * (size_t) sere_pad( spring_count ) );
	coloring->color = sere_alloc( sizeof( int32_t ) * (size_t) sere_pad( spring_count ) );
	if ( used == NULL || coloring->order == NULL || coloring->color == NULL )
	{
		free( used );
		sere_coloring_destroy( coloring );
		return SERE_ERR_MEMORY;
	}
	int32_t size[SERE_MAX_COLORS] = { 0 };
	int32_t colors = 0;
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		if ( a[s] < 0 || a[s] >= particle_count || b[s] < 0 || b[s] >= particle_count || a[s] == b[s] )
		{
			free( used );
			sere_coloring_destroy( coloring );
			return SERE_ERR_ARGUMENT;
		}
		uint64_t taken = used[a[s]] | used[b[s]];
		int32_t best = -1;
		for ( int32_t c = 0; c < colors; ++c )
		{
			if ( !( taken >> c & 1u ) && ( best < 0 || size[c] < size[best] ) )
			{
				best = c;
			}
		}
		if ( best < 0 )
		{
			if ( colors == SERE_MAX_COLORS )
			{
				free( used );
				sere_coloring_destroy( coloring );
				return SERE_ERR_CAPACITY;
			}
			best = colors++;
		}
		coloring->color[s] = best;
		size[best] += 1;
		used[a[s]] |= 1ull << best;
		used[b[s]] |= 1ull << best;
	}
	free( used );
	coloring->color_count = colors;
	coloring->min_batch = spring_count;
	for ( int32_t c = 0; c < colors; ++c )
	{
		coloring->offsets[c + 1] = coloring->offsets[c] + size[c];
		coloring->min_batch = size[c] < coloring->min_batch ? size[c] : coloring->min_batch;
		coloring->max_batch = size[c] > coloring->max_batch ? size[c] : coloring->max_batch;
	}
	int32_t fill[SERE_MAX_COLORS];
	memcpy( fill, coloring->offsets, sizeof( fill ) );
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		coloring->order[fill[coloring->color[s]]++] = s;
	}
	return SERE_OK;
}
