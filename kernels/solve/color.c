#include "solve/color.h"

#include <stdlib.h>
#include <string.h>

/* Each rebalancing pass is one walk over the springs; a few passes settle the sizes. */
#define REBALANCE_PASSES 8

void sere_coloring_destroy( sere_coloring* coloring )
{
	sere_free( coloring->order );
	sere_free( coloring->color );
	memset( coloring, 0, sizeof( *coloring ) );
}

static sere_status fail( sere_coloring* coloring, uint64_t* used, sere_status status )
{
	free( used );
	sere_coloring_destroy( coloring );
	return status;
}

sere_status sere_coloring_create( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
								  sere_coloring* coloring )
{
	if ( coloring == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
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
		return fail( coloring, used, SERE_ERR_MEMORY );
	}
	int32_t size[SERE_MAX_COLORS] = { 0 };
	int32_t colors = 0;
	uint64_t open = 0; /* bit c set for every color opened so far */
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		if ( a[s] < 0 || a[s] >= particle_count || b[s] < 0 || b[s] >= particle_count || a[s] == b[s] )
		{
			return fail( coloring, used, SERE_ERR_ARGUMENT );
		}
		/* The least-used open color free at both ends; ascending bit order breaks ties toward
		 * the lowest color, which keeps the result independent of anything but the input. */
		uint64_t admissible = open & ~( used[a[s]] | used[b[s]] );
		int32_t best = -1;
		while ( admissible != 0 )
		{
			int32_t c = __builtin_ctzll( admissible );
			admissible &= admissible - 1;
			if ( best < 0 || size[c] < size[best] )
			{
				best = c;
			}
		}
		if ( best < 0 )
		{
			if ( colors == SERE_MAX_COLORS )
			{
				return fail( coloring, used, SERE_ERR_CAPACITY );
			}
			best = colors++;
			open |= 1ull << best;
		}
		coloring->color[s] = best;
		size[best] += 1;
		used[a[s]] |= 1ull << best;
		used[b[s]] |= 1ull << best;
	}
	/* Rebalance: a spring in a large color moves to a smaller one free at both its ends (the
	 * smallest such, lowest on a tie) when that narrows the gap; repeat while springs move. */
	for ( int pass = 0; pass < REBALANCE_PASSES; ++pass )
	{
		int32_t moved = 0;
		for ( int32_t s = 0; s < spring_count; ++s )
		{
			int32_t from = coloring->color[s];
			uint64_t admissible = open & ~( used[a[s]] | used[b[s]] );
			int32_t best = -1;
			while ( admissible != 0 )
			{
				int32_t c = __builtin_ctzll( admissible );
				admissible &= admissible - 1;
				if ( size[c] + 1 < size[from] && ( best < 0 || size[c] < size[best] ) )
				{
					best = c;
				}
			}
			if ( best >= 0 )
			{
				/* Color `from` is an independent set: s is its only spring at a[s] and b[s]. */
				used[a[s]] = ( used[a[s]] & ~( 1ull << from ) ) | 1ull << best;
				used[b[s]] = ( used[b[s]] & ~( 1ull << from ) ) | 1ull << best;
				size[from] -= 1, size[best] += 1;
				coloring->color[s] = best;
				moved += 1;
			}
		}
		if ( moved == 0 )
		{
			break;
		}
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
	/* A counting sort by color keeps ascending spring order within each color. */
	int32_t fill[SERE_MAX_COLORS];
	memcpy( fill, coloring->offsets, sizeof( fill ) );
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		coloring->order[fill[coloring->color[s]]++] = s;
	}
	return SERE_OK;
}

void sere_coloring_gather_i32( const sere_coloring* coloring, const int32_t* in, int32_t* out )
{
	const int32_t count = coloring->offsets[coloring->color_count];
	for ( int32_t k = 0; k < count; ++k )
	{
		out[k] = in[coloring->order[k]];
	}
}

void sere_coloring_gather_f32( const sere_coloring* coloring, const float* in, float* out )
{
	const int32_t count = coloring->offsets[coloring->color_count];
	for ( int32_t k = 0; k < count; ++k )
	{
		out[k] = in[coloring->order[k]];
	}
}

void sere_coloring_gather_u8( const sere_coloring* coloring, const uint8_t* in, uint8_t* out )
{
	const int32_t count = coloring->offsets[coloring->color_count];
	for ( int32_t k = 0; k < count; ++k )
	{
		out[k] = in[coloring->order[k]];
	}
}
