/* The growable-array step and the aligned allocation every kernel uses (kernels/core/array.c,
 * base.c): growth by doubling, and the sizes no array can have refused instead of wrapped. */
#include "core/array.h"
#include "core/base.h"

#include <criterion/criterion.h>
#include <stdint.h>
#include <stdlib.h>

Test( array, capacity_doubles_from_first_and_refuses_what_cannot_grow )
{
	cr_expect_eq( sere_array_capacity( 0, 1, 16 ), 16 );
	cr_expect_eq( sere_array_capacity( 16, 16, 16 ), 16, "already holds it" );
	cr_expect_eq( sere_array_capacity( 16, 17, 16 ), 32 );
	cr_expect_eq( sere_array_capacity( 16, 100, 16 ), 128 );
	cr_expect_eq( sere_array_capacity( 1 << 30, ( 1LL << 30 ) + 1, 16 ), INT32_MAX, "the last doubling is capped" );
	cr_expect_eq( sere_array_capacity( 16, (int64_t) INT32_MAX + 1, 16 ), -1 );
	/* an empty array with nothing to double from once looped for ever */
	cr_expect_eq( sere_array_capacity( 0, 1, 0 ), -1 );
	cr_expect_eq( sere_array_capacity( 0, 1, -4 ), -1 );
	cr_expect_eq( sere_array_capacity( 8, 9, 0 ), 16, "a non-empty array doubles itself" );
}

Test( array, append_grows_and_a_refused_growth_leaves_the_array )
{
	int32_t count = 0, capacity = 0;
	int32_t* items = NULL;
	for ( int32_t k = 0; k < 100; ++k )
	{
		int32_t* grown = sere_array_append( items, &count, &capacity, 4, &k, sizeof( k ) );
		cr_assert_not_null( grown );
		items = grown;
	}
	cr_expect_eq( count, 100 );
	cr_expect_eq( capacity, 128 );
	for ( int32_t k = 0; k < 100; ++k )
	{
		cr_expect_eq( items[k], k );
	}
	free( items );
	count = 0, capacity = 0;
	int32_t one = 1;
	cr_expect_null( sere_array_append( NULL, &count, &capacity, 0, &one, sizeof( one ) ) );
	cr_expect_eq( count, 0 );
	cr_expect_eq( capacity, 0 );
}

Test( alloc, sizes_past_the_round_up_are_refused )
{
	void* block = sere_alloc( 100 );
	cr_assert_not_null( block );
	cr_expect_eq( (uintptr_t) block % SERE_ALIGN, 0u );
	sere_free( block );
	cr_expect_null( sere_alloc( 0 ) );
	/* a negative int32_t count of floats cast to size_t: the round-up to 64 bytes once wrapped
	 * to a 0-byte block that sere_alloc returned as if it held them */
	cr_expect_null( sere_alloc( sizeof( float ) * (size_t) (int32_t) -1 ) );
	cr_expect_null( sere_alloc( SIZE_MAX ) );
	float* column = NULL;
	float** columns[1] = { &column };
	cr_expect( !sere_alloc_floats( columns, 1, SIZE_MAX / 2 ) );
	cr_expect_null( column );
}

Test( array, outline_edges_join_consecutive_outline_points )
{
	cr_expect( sere_outline_edge( 2, 3, 5 ) );
	cr_expect( sere_outline_edge( 3, 2, 5 ), "either way round" );
	cr_expect( sere_outline_edge( 4, 0, 5 ), "the closing edge" );
	cr_expect( !sere_outline_edge( 1, 3, 5 ), "a chord" );
	cr_expect( !sere_outline_edge( 4, 5, 5 ), "a point past the outline" );
	cr_expect( !sere_outline_edge( -1, 0, 5 ) );
}
