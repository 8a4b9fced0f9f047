/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "core/array.h"

#include "core/internal/team.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int32_t sere_array_capacity( int32_t capacity, int64_t need, int32_t first )
{
	if ( need > INT32_MAX )
	{
		return -1;
	}
	if ( need <= capacity )
	{
		return capacity;
	}
	if ( capacity <= 0 && first < 1 )
	{
		return -1; /* nothing to double from */
	}
	int64_t grown = capacity > 0 ? capacity : first;
	while ( grown < need )
	{
		grown *= 2;
	}
	return (int32_t) ( grown < INT32_MAX ? grown : INT32_MAX );
}

void* sere_array_resize( void* array, int32_t count, size_t element )
{
	if ( count < 0 || ( element > 0 && (size_t) count > SIZE_MAX / element ) )
	{
		return NULL;
	}
	return realloc( array, (size_t) count * element );
}

void* sere_array_append( void* array, int32_t* count, int32_t* capacity, int32_t first, const void* item,
						 size_t element )
{
	if ( *count == *capacity )
	{
		int32_t grown = sere_array_capacity( *capacity, (int64_t) *count + 1, first );
		void* resized = grown > 0 ? sere_array_resize( array, grown, element ) : NULL;
		if ( resized == NULL )
		{
			return NULL;
		}
		array = resized;
		*capacity = grown;
	}
	memcpy( (char*) array + (size_t) *count * element, item, element );
	*count += 1;
	return array;
}

bool sere_outline_edge( int32_t a, int32_t b, int32_t outline_count )
{
	const int32_t lo = a < b ? a : b, hi = a < b ? b : a;
	return lo >= 0 && hi < outline_count && ( hi == lo + 1 || ( lo == 0 && hi == outline_count - 1 ) );
}

bool sere_array_indices_valid( const int32_t* index, int64_t count, int32_t bound )
{
	for ( int64_t k = 0; k < count; ++k )
	{
		if ( index[k] < 0 || index[k] >= bound )
		{
			return false;
		}
	}
	return true;
}

bool sere_array_finite( const float* const* arrays, int32_t array_count, int32_t count, int32_t threads )
{
	int bad = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static ) reduction( | : bad )
	for ( int32_t i = 0; i < count; ++i )
	{
		for ( int32_t a = 0; a < array_count; ++a )
		{
			bad |= !isfinite( arrays[a][i] );
		}
	}
	return bad == 0;
}

static int compare_items( const void* pa, const void* pb )
{
	const sere_sort_item* a = pa;
	const sere_sort_item* b = pb;
	if ( a->key != b->key )
	{
		return a->key < b->key ? -1 : 1;
	}
	return ( a->index > b->index ) - ( a->index < b->index );
}

void sere_sort_items( sere_sort_item* items, int32_t count )
{
	if ( count > 1 )
	{
		qsort( items, (size_t) count, sizeof( sere_sort_item ), compare_items );
	}
}

uint64_t sere_sort_key_double( double d )
{
	/* Adding 0.0 turns -0 into +0, so the two zeros compare equal here as they do as doubles. */
	double positive_zero = d + 0.0;
	uint64_t bits;
	memcpy( &bits, &positive_zero, sizeof( bits ) );
	return ( bits >> 63 ) != 0 ? ~bits : bits | ( 1ull << 63 );
}
