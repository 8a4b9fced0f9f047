/* sere — the one growable-array step, the one sort of (key, index) pairs and the checks of index
 * and coordinate arrays shared by every room. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* The capacity a growable array needs to hold need elements: capacity itself when it already
 * does, otherwise doubled (starting from first when the array is empty) until it does. -1 when
 * need is past INT32_MAX, so a caller's int32_t counts never wrap, and when an empty array must
 * grow from a first below 1. */
int32_t sere_array_capacity( int32_t capacity, int64_t need, int32_t first );

/* realloc for count elements of element bytes, the byte count checked for overflow. NULL on
 * failure, and then array is still the caller's, unchanged. */
void* sere_array_resize( void* array, int32_t count, size_t element );

/* Appends one element of element bytes, copied from item, to array, which holds *count elements
 * and has room for *capacity: a full array grows first, to sere_array_capacity( *capacity,
 * *count + 1, first ). Returns the array, moved or not, with *count and *capacity updated; NULL on
 * failure, and then array, *count and *capacity are unchanged and the array is still the
 * caller's. */
void* sere_array_append( void* array, int32_t* count, int32_t* capacity, int32_t first, const void* item,
						 size_t element );

/* Whether each of the count indices lies in [0, bound): the triangles or edges of a mesh name only
 * its vertices. */
bool sere_array_indices_valid( const int32_t* index, int64_t count, int32_t bound );

/* Whether points a and b are consecutive on an outline numbered 0 .. outline_count − 1 in order
 * (either way round, the closing edge outline_count − 1 to 0 included): the one boundary edge a
 * triangulation whose outline comes first may have. */
bool sere_outline_edge( int32_t a, int32_t b, int32_t outline_count );

/* Whether the first count entries of each of the array_count float arrays are finite, on
 * `threads` threads (base.h). */
bool sere_array_finite( const float* const* arrays, int32_t array_count, int32_t count, int32_t threads );

/* A sort key and the index of what it belongs to; value rides along unsorted. */
typedef struct sere_sort_item
{
	uint64_t key;
	int32_t index;
	int32_t value;
} sere_sort_item;

/* Sorts by key, equal keys by index: a total order, so the answer is the same on every C
 * library whatever its qsort does with ties. */
void sere_sort_items( sere_sort_item* items, int32_t count );

/* A key whose unsigned order is the order of the finite double d (-0 and +0 one key). */
uint64_t sere_sort_key_double( double d );

#ifdef __cplusplus
}
#endif
