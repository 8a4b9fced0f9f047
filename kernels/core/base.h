/* sere — status codes, aligned allocation and padding shared by every kernel. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* Every array the kernels touch starts on a cache line and its length is padded to a
 * multiple of 16 elements, so 512-bit loops over float or int32 need no scalar tail. */
#define SERE_ALIGN 64
#define SERE_PAD   16

/* How many threads a kernel runs is said where it is called, never through OpenMP's global state
 * alone. A kernel called on an object (sere_pbd, sere_collide, sere_bvh, sere_cg_workspace,
 * sere_sgs, sere_osmosis, sere_crossings, sere_massspring, sere_leaf_sim, ...) runs with the count
 * set on that object by its sere_<object>_set_threads; a kernel called on plain arrays takes it
 * as its `threads` argument. 0, every object's initial count, stands for the caller's OpenMP
 * count at the call (omp_get_max_threads(): OMP_NUM_THREADS or omp_set_num_threads); 1 to
 * SERE_MAX_THREADS, that many. A region may run fewer while other processes keep cores busy,
 * and the descent (sere_vbd) runs its steps, and a leaf (sere_leaf_sim) its osmosis and
 * shrinkage, with one thread while their team has been measured slower than one thread
 * (core/internal/team.h; SERE_ADAPTIVE_THREADS=0 in the environment turns both off). Every
 * result is the same bits for every count. */

/* The most threads a kernel runs: a count above it (OpenMP's, or one set on an object, which
 * refuses more) runs this many. The one limit every kernel and command shares; per-thread slots
 * in a workspace are sized by it at most. */
#define SERE_MAX_THREADS 256

typedef enum sere_status
{
	SERE_OK = 0,
	SERE_ERR_ARGUMENT,	  /* a null pointer, a negative size, a parameter out of its range */
	SERE_ERR_MEMORY,	  /* an allocation failed */
	SERE_ERR_NONFINITE,	  /* NaN or infinity in the input */
	SERE_ERR_GEOMETRY,	  /* degenerate or invalid geometry: zero-length springs, crossing segments */
	SERE_ERR_COUNTS,	  /* particle/spring counts no triangulation can produce */
	SERE_ERR_NOT_SPD,	  /* the matrix is not symmetric positive definite (CG met pᵀAp ≤ 0) */
	SERE_ERR_NO_CONVERGE, /* an iteration cap was reached before the tolerance */
	SERE_ERR_CAPACITY,	  /* a workspace is too small for the input */
	SERE_ERR_IO,		  /* a file could not be opened, read, written or renamed (the harness's files) */
	SERE_ERR_PARSE,		  /* a file or option's text is not in its format (the harness's readers) */
	SERE_STATUS_COUNT
} sere_status;

/* The library's version, "MAJOR.MINOR.PATCH" (the VERSION file it was built from); a program
 * linked against the shared library gets the version of the libsere.so it runs with. */
const char* sere_version( void );

/* The lane width the kernels were compiled for, as core/internal/simd.h picks it: "AVX-512"
 * (__AVX512F__, 16 lanes), "AVX2" (__AVX2__ with __FMA__, 8 lanes) or "portable" (C, 4 lanes;
 * also a build with AVX, or AVX2 without FMA). Set by the compiler flags (ARCH=), not by the
 * machine the library runs on. */
const char* sere_simd_path( void );

/* A short English sentence for a status, never NULL. */
const char* sere_status_text( sere_status status );

/* Zeroed, SERE_ALIGN-aligned memory; NULL on failure or when bytes is 0. */
void* sere_alloc( size_t bytes );
void sere_free( void* memory );

/* sere_alloc of count floats into each *arrays[k], k < array_count, in order: the float columns
 * of a structure of arrays. false when one fails; the arrays allocated before it are the
 * caller's to free either way. */
bool sere_alloc_floats( float** const* arrays, int32_t array_count, size_t count );

/* sere_free of each of the count arrays: the release of a structure of arrays. */
void sere_free_all( void* const* arrays, size_t count );

/* n rounded up to a multiple of SERE_PAD. */
static inline int32_t sere_pad( int32_t n )
{
	return ( n + SERE_PAD - 1 ) & ~( SERE_PAD - 1 );
}

/* Whether a kernel accepts `threads` as a thread count (0 to SERE_MAX_THREADS): the check every
 * sere_<object>_set_threads and every `threads` argument makes (SERE_ERR_ARGUMENT otherwise). */
static inline int sere_threads_valid( int32_t threads )
{
	return threads >= 0 && threads <= SERE_MAX_THREADS;
}

/* *count = threads when a kernel accepts it (SERE_OK), else SERE_ERR_ARGUMENT and *count kept:
 * the body of every sere_<object>_set_threads. */
static inline sere_status sere_threads_store( int32_t* count, int32_t threads )
{
	if ( !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	*count = threads;
	return SERE_OK;
}

/* splitmix64: small, fast and fully determined by its state, so that sampling and scene
 * drawing give the same numbers on every machine and for every thread count. */
static inline uint64_t sere_splitmix64( uint64_t* state )
{
	uint64_t z = ( *state += 0x9e3779b97f4a7c15ull );
	z = ( z ^ ( z >> 30 ) ) * 0xbf58476d1ce4e5b9ull;
	z = ( z ^ ( z >> 27 ) ) * 0x94d049bb133111ebull;
	return z ^ ( z >> 31 );
}

/* A double in [0, 1) from the top 53 bits of sere_splitmix64. */
static inline double sere_splitmix_unit( uint64_t* state )
{
	return (double) ( sere_splitmix64( state ) >> 11 ) * ( 1.0 / 9007199254740992.0 );
}

#ifdef __cplusplus
}
#endif
