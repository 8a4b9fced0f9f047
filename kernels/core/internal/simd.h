/* sere — private to the kernels (not installed, not part of the API): the SIMD lane layer.
 *
 * A kernel body is written once over sere_vf (SERE_LANES floats) and sere_vmask (one flag per
 * lane); the build picks the width: AVX-512 (16 lanes), AVX2 with FMA (8) or a portable 4 lanes
 * in plain C. Every operation is lane-wise IEEE single precision, so a body gives the same bits at
 * every width; only the reductions (max) cross lanes, and a maximum does not depend on the order
 * it is taken in. The compiler contracts nothing (-ffp-contract=off); a fused multiply-add is a
 * body's explicit choice, sere_vf_fma, which rounds once at every width (the FMA instruction, or
 * C's fmaf where the target has none).
 *
 * The record loads serve kernels that keep a particle as one 16-byte record (x, y, z, w): a lane
 * fetches its record with one 128-bit load and an in-register 4 × 4 transpose hands out the
 * components, instead of one gather per component. The groups of a fixed eight or four floats
 * (the BVH's nodes, a contact's record) are in simd_fixed.h. */
#pragma once

#include "core/internal/simd_fixed.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined( __AVX512F__ ) || defined( __AVX2__ )
#include <immintrin.h>
#endif

#if defined( __AVX512F__ )

#define SERE_LANES 16
typedef __m512 sere_vf;
typedef __mmask16 sere_vmask;

static inline sere_vf sere_vf_splat( float a )
{
	return _mm512_set1_ps( a );
}
static inline sere_vf sere_vf_add( sere_vf a, sere_vf b )
{
	return _mm512_add_ps( a, b );
}
static inline sere_vf sere_vf_sub( sere_vf a, sere_vf b )
{
	return _mm512_sub_ps( a, b );
}
static inline sere_vf sere_vf_mul( sere_vf a, sere_vf b )
{
	return _mm512_mul_ps( a, b );
}
static inline sere_vf sere_vf_div( sere_vf a, sere_vf b )
{
	return _mm512_div_ps( a, b );
}
/* a b + c, rounded once. */
static inline sere_vf sere_vf_fma( sere_vf a, sere_vf b, sere_vf c )
{
	return _mm512_fmadd_ps( a, b, c );
}
/* c − a b, rounded once. */
static inline sere_vf sere_vf_fnma( sere_vf a, sere_vf b, sere_vf c )
{
	return _mm512_fnmadd_ps( a, b, c );
}
static inline sere_vf sere_vf_sqrt( sere_vf a )
{
	return _mm512_sqrt_ps( a );
}
static inline sere_vf sere_vf_min( sere_vf a, sere_vf b )
{
	return _mm512_min_ps( a, b );
}
static inline sere_vf sere_vf_max( sere_vf a, sere_vf b )
{
	return _mm512_max_ps( a, b );
}
static inline sere_vf sere_vf_abs( sere_vf a )
{
	return _mm512_abs_ps( a );
}
/* a > b (ordered: false when either is NaN). */
static inline sere_vmask sere_vf_gt( sere_vf a, sere_vf b )
{
	return _mm512_cmp_ps_mask( a, b, _CMP_GT_OQ );
}
/* a ≠ b (unordered: true when either is NaN). */
static inline sere_vmask sere_vf_ne( sere_vf a, sere_vf b )
{
	return _mm512_cmp_ps_mask( a, b, _CMP_NEQ_UQ );
}
static inline sere_vmask sere_vmask_and( sere_vmask a, sere_vmask b )
{
	return (sere_vmask) ( a & b );
}
/* The first n lanes (0 ≤ n ≤ SERE_LANES). */
static inline sere_vmask sere_vmask_first( int32_t n )
{
	return (sere_vmask) ( ( 1u << n ) - 1u );
}
static inline int32_t sere_vmask_count( sere_vmask m )
{
	return __builtin_popcount( (unsigned) m );
}
/* a where m is set, 0 elsewhere. */
static inline sere_vf sere_vf_keep( sere_vmask m, sere_vf a )
{
	return _mm512_maskz_mov_ps( m, a );
}
/* The largest lane of a where m is set, −∞ when m is empty. */
static inline float sere_vf_max_where( sere_vmask m, sere_vf a )
{
	return _mm512_mask_reduce_max_ps( m, a );
}
/* p[0 .. n) in the first n lanes, fill in the others; reads nothing past p + n. */
static inline sere_vf sere_vf_load_first( const float* p, int32_t n, float fill )
{
	return _mm512_mask_loadu_ps( _mm512_set1_ps( fill ), sere_vmask_first( n ), p );
}
/* The first n lanes of a to p[0 .. n); writes nothing past p + n. */
static inline void sere_vf_store_first( float* p, int32_t n, sere_vf a )
{
	_mm512_mask_storeu_ps( p, sere_vmask_first( n ), a );
}
/* The in-register 4 × 4 transpose inside every 128-bit lane: lane j of r[k] holds the record of
 * 128-bit lane j / 4 … as the record loads place them; it is its own inverse. */
static inline void sere_vf_transpose4( const sere_vf r[4], sere_vf* c0, sere_vf* c1, sere_vf* c2, sere_vf* c3 )
{
	__m512 t0 = _mm512_unpacklo_ps( r[0], r[1] ), t1 = _mm512_unpackhi_ps( r[0], r[1] );
	__m512 t2 = _mm512_unpacklo_ps( r[2], r[3] ), t3 = _mm512_unpackhi_ps( r[2], r[3] );
	*c0 = _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) );
	*c1 = _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) );
	*c2 = _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) );
	*c3 = _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) );
}
/* Lane j of c0..c3 receives the four floats at base + offset[j] (16-byte aligned). Lane j's
 * record sits in 128-bit lane j / 4 of register j % 4; the transpose then gathers the
 * components. AVX-512 gathers cost three times as much for the PBD sweep on this machine. */
static inline void sere_vf_load_records_at( const float* base, const int32_t* offset, sere_vf* c0, sere_vf* c1,
											sere_vf* c2, sere_vf* c3 )
{
	__m512 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm512_castps128_ps512( _mm_load_ps( base + offset[k] ) );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( base + offset[k + 4] ), 1 );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( base + offset[k + 8] ), 2 );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( base + offset[k + 12] ), 3 );
	}
	sere_vf_transpose4( r, c0, c1, c2, c3 );
}
/* The inverse of sere_vf_load_records_at for every lane: 128-bit stores straight from the
 * transposed registers. */
static inline void sere_vf_store_records_at( float* base, const int32_t* offset, sere_vf c0, sere_vf c1, sere_vf c2,
											 sere_vf c3 )
{
	const __m512 c[4] = { c0, c1, c2, c3 };
	__m512 r[4];
	sere_vf_transpose4( c, &r[0], &r[1], &r[2], &r[3] );
	for ( int k = 0; k < 4; ++k )
	{
		_mm_store_ps( base + offset[k], _mm512_castps512_ps128( r[k] ) );
		_mm_store_ps( base + offset[k + 4], _mm512_extractf32x4_ps( r[k], 1 ) );
		_mm_store_ps( base + offset[k + 8], _mm512_extractf32x4_ps( r[k], 2 ) );
		_mm_store_ps( base + offset[k + 12], _mm512_extractf32x4_ps( r[k], 3 ) );
	}
}
/* Lane j of c0..c3 receives the four floats of record at[j] (16-byte aligned records). */
static inline void sere_vf_load_records( const float* rec, const int32_t* at, sere_vf* c0, sere_vf* c1, sere_vf* c2,
										 sere_vf* c3 )
{
	__m512 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm512_castps128_ps512( _mm_load_ps( rec + 4 * at[k] ) );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( rec + 4 * at[k + 4] ), 1 );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( rec + 4 * at[k + 8] ), 2 );
		r[k] = _mm512_insertf32x4( r[k], _mm_load_ps( rec + 4 * at[k + 12] ), 3 );
	}
	sere_vf_transpose4( r, c0, c1, c2, c3 );
}
/* The inverse of sere_vf_load_records for the first n lanes (the transpose is its own inverse). */
static inline void sere_vf_store_records( float* rec, const int32_t* at, int32_t n, sere_vf c0, sere_vf c1, sere_vf c2,
										  sere_vf c3 )
{
	_Alignas( 64 ) float tmp[64];
	const __m512 c[4] = { c0, c1, c2, c3 };
	__m512 r[4];
	sere_vf_transpose4( c, &r[0], &r[1], &r[2], &r[3] );
	for ( int k = 0; k < 4; ++k )
	{
		_mm512_store_ps( tmp + 16 * k, r[k] );
	}
	for ( int32_t j = 0; j < n; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 16 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
}
/* Lane j of c0..c3 receives record j of the SERE_LANES consecutive records at rec (64-byte
 * aligned): four 512-bit loads and two rounds of two-source permutes, instead of sixteen 128-bit
 * loads with their inserts. */
static inline void sere_vf_load_block_records( const float* rec, sere_vf* c0, sere_vf* c1, sere_vf* c2, sere_vf* c3 )
{
	const __m512 r0 = _mm512_load_ps( rec ), r1 = _mm512_load_ps( rec + 16 );
	const __m512 r2 = _mm512_load_ps( rec + 32 ), r3 = _mm512_load_ps( rec + 48 );
	/* first round: [c0 of records 0–7 | c1 of records 0–7], and so on */
	const __m512i even = _mm512_setr_epi32( 0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29 );
	const __m512i odd = _mm512_setr_epi32( 2, 6, 10, 14, 18, 22, 26, 30, 3, 7, 11, 15, 19, 23, 27, 31 );
	const __m512 a = _mm512_permutex2var_ps( r0, even, r1 ), b = _mm512_permutex2var_ps( r0, odd, r1 );
	const __m512 c = _mm512_permutex2var_ps( r2, even, r3 ), d = _mm512_permutex2var_ps( r2, odd, r3 );
	const __m512i low = _mm512_setr_epi32( 0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23 );
	const __m512i high = _mm512_setr_epi32( 8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31 );
	*c0 = _mm512_permutex2var_ps( a, low, c ), *c1 = _mm512_permutex2var_ps( a, high, c );
	*c2 = _mm512_permutex2var_ps( b, low, d ), *c3 = _mm512_permutex2var_ps( b, high, d );
}
/* The inverse of sere_vf_load_block_records: the permutes back, then four 512-bit stores (a
 * transpose through a buffer re-read by 128-bit loads made the descent's block wait on the
 * buffer's stores). */
static inline void sere_vf_store_block_records( float* rec, sere_vf c0, sere_vf c1, sere_vf c2, sere_vf c3 )
{
	/* first round: [c0 c1 interleaved for records 0–7], [c2 c3 the same], then records 8–15 */
	const __m512i low = _mm512_setr_epi32( 0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23 );
	const __m512i high = _mm512_setr_epi32( 8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31 );
	const __m512 a = _mm512_permutex2var_ps( c0, low, c1 ), b = _mm512_permutex2var_ps( c2, low, c3 );
	const __m512 c = _mm512_permutex2var_ps( c0, high, c1 ), d = _mm512_permutex2var_ps( c2, high, c3 );
	const __m512i first = _mm512_setr_epi32( 0, 1, 16, 17, 2, 3, 18, 19, 4, 5, 20, 21, 6, 7, 22, 23 );
	const __m512i second = _mm512_setr_epi32( 8, 9, 24, 25, 10, 11, 26, 27, 12, 13, 28, 29, 14, 15, 30, 31 );
	_mm512_store_ps( rec, _mm512_permutex2var_ps( a, first, b ) );
	_mm512_store_ps( rec + 16, _mm512_permutex2var_ps( a, second, b ) );
	_mm512_store_ps( rec + 32, _mm512_permutex2var_ps( c, first, d ) );
	_mm512_store_ps( rec + 48, _mm512_permutex2var_ps( c, second, d ) );
}
static inline sere_vf sere_vf_load( const float* p )
{
	return _mm512_load_ps( p );
}
static inline void sere_vf_store( float* p, sere_vf a )
{
	_mm512_store_ps( p, a );
}
/* a = b (ordered: false when either is NaN). */
static inline sere_vmask sere_vf_eq( sere_vf a, sere_vf b )
{
	return _mm512_cmp_ps_mask( a, b, _CMP_EQ_OQ );
}
/* not a ≤ b (unordered: true when either is NaN). */
static inline sere_vmask sere_vf_not_le( sere_vf a, sere_vf b )
{
	return _mm512_cmp_ps_mask( a, b, _CMP_NLE_UQ );
}
static inline sere_vmask sere_vmask_none( void )
{
	return 0;
}
static inline sere_vmask sere_vmask_or( sere_vmask a, sere_vmask b )
{
	return (sere_vmask) ( a | b );
}
static inline int sere_vmask_any( sere_vmask m )
{
	return m != 0;
}
/* The first of the SERE_LANES indices at p that differs from j, or SERE_LANES when none does:
 * where a run of equal indices ends, in one compare instead of one branch an index. */
static inline int32_t sere_vi_first_ne( const int32_t* p, int32_t j )
{
	__mmask16 ne = _mm512_cmpneq_epi32_mask( _mm512_loadu_si512( p ), _mm512_set1_epi32( j ) );
	return ne != 0 ? __builtin_ctz( ne ) : SERE_LANES;
}
/* The largest lane of a. */
static inline float sere_vf_max_all( sere_vf a )
{
	return _mm512_reduce_max_ps( a );
}

#elif defined( __AVX2__ ) && defined( __FMA__ )

/* Every AVX2 processor has FMA; a build that enables one without the other takes the portable
 * width. */
#define SERE_LANES 8
typedef __m256 sere_vf;
/* A lane is set when all its bits are (the compare results AVX gives). */
typedef __m256 sere_vmask;

static inline sere_vf sere_vf_splat( float a )
{
	return _mm256_set1_ps( a );
}
static inline sere_vf sere_vf_add( sere_vf a, sere_vf b )
{
	return _mm256_add_ps( a, b );
}
static inline sere_vf sere_vf_sub( sere_vf a, sere_vf b )
{
	return _mm256_sub_ps( a, b );
}
static inline sere_vf sere_vf_mul( sere_vf a, sere_vf b )
{
	return _mm256_mul_ps( a, b );
}
static inline sere_vf sere_vf_div( sere_vf a, sere_vf b )
{
	return _mm256_div_ps( a, b );
}
/* a b + c, rounded once. */
static inline sere_vf sere_vf_fma( sere_vf a, sere_vf b, sere_vf c )
{
	return _mm256_fmadd_ps( a, b, c );
}
/* c − a b, rounded once. */
static inline sere_vf sere_vf_fnma( sere_vf a, sere_vf b, sere_vf c )
{
	return _mm256_fnmadd_ps( a, b, c );
}
static inline sere_vf sere_vf_sqrt( sere_vf a )
{
	return _mm256_sqrt_ps( a );
}
static inline sere_vf sere_vf_min( sere_vf a, sere_vf b )
{
	return _mm256_min_ps( a, b );
}
static inline sere_vf sere_vf_max( sere_vf a, sere_vf b )
{
	return _mm256_max_ps( a, b );
}
static inline sere_vf sere_vf_abs( sere_vf a )
{
	return _mm256_and_ps( a, _mm256_castsi256_ps( _mm256_set1_epi32( 0x7fffffff ) ) );
}
static inline sere_vmask sere_vf_gt( sere_vf a, sere_vf b )
{
	return _mm256_cmp_ps( a, b, _CMP_GT_OQ );
}
static inline sere_vmask sere_vf_ne( sere_vf a, sere_vf b )
{
	return _mm256_cmp_ps( a, b, _CMP_NEQ_UQ );
}
static inline sere_vmask sere_vmask_and( sere_vmask a, sere_vmask b )
{
	return _mm256_and_ps( a, b );
}
static inline sere_vmask sere_vmask_first( int32_t n )
{
	return _mm256_castsi256_ps(
		_mm256_cmpgt_epi32( _mm256_set1_epi32( n ), _mm256_setr_epi32( 0, 1, 2, 3, 4, 5, 6, 7 ) ) );
}
static inline int32_t sere_vmask_count( sere_vmask m )
{
	return __builtin_popcount( (unsigned) _mm256_movemask_ps( m ) );
}
static inline sere_vf sere_vf_keep( sere_vmask m, sere_vf a )
{
	return _mm256_and_ps( m, a );
}
static inline float sere_vf_max_all( sere_vf a )
{
	__m128 h = _mm_max_ps( _mm256_castps256_ps128( a ), _mm256_extractf128_ps( a, 1 ) );
	h = _mm_max_ps( h, _mm_movehl_ps( h, h ) );
	h = _mm_max_ss( h, _mm_shuffle_ps( h, h, 1 ) );
	return _mm_cvtss_f32( h );
}
static inline float sere_vf_max_where( sere_vmask m, sere_vf a )
{
	return sere_vf_max_all( _mm256_blendv_ps( _mm256_set1_ps( -INFINITY ), a, m ) );
}
static inline sere_vf sere_vf_load_first( const float* p, int32_t n, float fill )
{
	__m256 m = sere_vmask_first( n );
	return _mm256_blendv_ps( _mm256_set1_ps( fill ), _mm256_maskload_ps( p, _mm256_castps_si256( m ) ), m );
}
static inline void sere_vf_store_first( float* p, int32_t n, sere_vf a )
{
	_mm256_maskstore_ps( p, _mm256_castps_si256( sere_vmask_first( n ) ), a );
}
/* The in-lane 4 × 4 transpose, as the AVX-512 one; its own inverse. */
static inline void sere_vf_transpose4( const sere_vf r[4], sere_vf* c0, sere_vf* c1, sere_vf* c2, sere_vf* c3 )
{
	__m256 t0 = _mm256_unpacklo_ps( r[0], r[1] ), t1 = _mm256_unpackhi_ps( r[0], r[1] );
	__m256 t2 = _mm256_unpacklo_ps( r[2], r[3] ), t3 = _mm256_unpackhi_ps( r[2], r[3] );
	*c0 = _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) );
	*c1 = _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) );
	*c2 = _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) );
	*c3 = _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) );
}
/* As the AVX-512 versions: 128-bit record loads, then the in-lane 4 × 4 transpose. */
static inline void sere_vf_load_records_at( const float* base, const int32_t* offset, sere_vf* c0, sere_vf* c1,
											sere_vf* c2, sere_vf* c3 )
{
	__m256 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( base + offset[k] ) ),
									 _mm_load_ps( base + offset[k + 4] ), 1 );
	}
	sere_vf_transpose4( r, c0, c1, c2, c3 );
}
static inline void sere_vf_store_records_at( float* base, const int32_t* offset, sere_vf c0, sere_vf c1, sere_vf c2,
											 sere_vf c3 )
{
	const __m256 c[4] = { c0, c1, c2, c3 };
	__m256 r[4];
	sere_vf_transpose4( c, &r[0], &r[1], &r[2], &r[3] );
	for ( int k = 0; k < 4; ++k )
	{
		_mm_store_ps( base + offset[k], _mm256_castps256_ps128( r[k] ) );
		_mm_store_ps( base + offset[k + 4], _mm256_extractf128_ps( r[k], 1 ) );
	}
}
static inline void sere_vf_load_records( const float* rec, const int32_t* at, sere_vf* c0, sere_vf* c1, sere_vf* c2,
										 sere_vf* c3 )
{
	__m256 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( rec + 4 * at[k] ) ),
									 _mm_load_ps( rec + 4 * at[k + 4] ), 1 );
	}
	sere_vf_transpose4( r, c0, c1, c2, c3 );
}
static inline void sere_vf_store_records( float* rec, const int32_t* at, int32_t n, sere_vf c0, sere_vf c1, sere_vf c2,
										  sere_vf c3 )
{
	_Alignas( 32 ) float tmp[32];
	const __m256 c[4] = { c0, c1, c2, c3 };
	__m256 r[4];
	sere_vf_transpose4( c, &r[0], &r[1], &r[2], &r[3] );
	for ( int k = 0; k < 4; ++k )
	{
		_mm256_store_ps( tmp + 8 * k, r[k] );
	}
	for ( int32_t j = 0; j < n; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 8 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
}
/* Lane j of c0..c3 receives record j of the SERE_LANES consecutive records at rec: the record
 * loads at fixed offsets. */
static inline void sere_vf_load_block_records( const float* rec, sere_vf* c0, sere_vf* c1, sere_vf* c2, sere_vf* c3 )
{
	static const int32_t offset[SERE_LANES] = { 0, 4, 8, 12, 16, 20, 24, 28 };
	sere_vf_load_records_at( rec, offset, c0, c1, c2, c3 );
}
/* The inverse of sere_vf_load_block_records. */
static inline void sere_vf_store_block_records( float* rec, sere_vf c0, sere_vf c1, sere_vf c2, sere_vf c3 )
{
	static const int32_t offset[SERE_LANES] = { 0, 4, 8, 12, 16, 20, 24, 28 };
	sere_vf_store_records_at( rec, offset, c0, c1, c2, c3 );
}
static inline sere_vf sere_vf_load( const float* p )
{
	return _mm256_load_ps( p );
}
static inline void sere_vf_store( float* p, sere_vf a )
{
	_mm256_store_ps( p, a );
}
static inline sere_vmask sere_vf_eq( sere_vf a, sere_vf b )
{
	return _mm256_cmp_ps( a, b, _CMP_EQ_OQ );
}
static inline sere_vmask sere_vf_not_le( sere_vf a, sere_vf b )
{
	return _mm256_cmp_ps( a, b, _CMP_NLE_UQ );
}
static inline sere_vmask sere_vmask_none( void )
{
	return _mm256_setzero_ps();
}
static inline sere_vmask sere_vmask_or( sere_vmask a, sere_vmask b )
{
	return _mm256_or_ps( a, b );
}
static inline int sere_vmask_any( sere_vmask m )
{
	return _mm256_movemask_ps( m ) != 0;
}
static inline int32_t sere_vi_first_ne( const int32_t* p, int32_t j )
{
	__m256i eq = _mm256_cmpeq_epi32( _mm256_loadu_si256( (const __m256i*) p ), _mm256_set1_epi32( j ) );
	unsigned ne = ~(unsigned) _mm256_movemask_ps( _mm256_castsi256_ps( eq ) ) & 0xffu;
	return ne != 0 ? __builtin_ctz( ne ) : SERE_LANES;
}

#else

/* The portable width: four lanes in plain C, which compilers map onto whatever vectors the
 * target has (SSE, NEON) or run lane by lane, with the same bits either way. */
#define SERE_LANES 4
typedef struct
{
	float v[SERE_LANES];
} sere_vf;
typedef struct
{
	int32_t v[SERE_LANES];
} sere_vmask;

#define SERE_VF_LANEWISE( expr )                                                                                       \
	sere_vf r;                                                                                                         \
	for ( int j = 0; j < SERE_LANES; ++j )                                                                             \
	{                                                                                                                  \
		r.v[j] = ( expr );                                                                                             \
	}                                                                                                                  \
	return r

#define SERE_VMASK_LANEWISE( expr )                                                                                    \
	sere_vmask r;                                                                                                      \
	for ( int j = 0; j < SERE_LANES; ++j )                                                                             \
	{                                                                                                                  \
		r.v[j] = ( expr );                                                                                             \
	}                                                                                                                  \
	return r

static inline sere_vf sere_vf_splat( float a )
{
	SERE_VF_LANEWISE( a );
}
static inline sere_vf sere_vf_add( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] + b.v[j] );
}
static inline sere_vf sere_vf_sub( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] - b.v[j] );
}
static inline sere_vf sere_vf_mul( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] * b.v[j] );
}
static inline sere_vf sere_vf_div( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] / b.v[j] );
}
/* a b + c, rounded once (C's fmaf: the instruction where the target has one). */
static inline sere_vf sere_vf_fma( sere_vf a, sere_vf b, sere_vf c )
{
	SERE_VF_LANEWISE( fmaf( a.v[j], b.v[j], c.v[j] ) );
}
/* c − a b, rounded once. */
static inline sere_vf sere_vf_fnma( sere_vf a, sere_vf b, sere_vf c )
{
	SERE_VF_LANEWISE( fmaf( -a.v[j], b.v[j], c.v[j] ) );
}
static inline sere_vf sere_vf_sqrt( sere_vf a )
{
	SERE_VF_LANEWISE( sqrtf( a.v[j] ) );
}
/* min/max as the x86 instructions define them: the second operand when the first comparison
 * fails (a NaN, or two zeros). */
static inline sere_vf sere_vf_min( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] < b.v[j] ? a.v[j] : b.v[j] );
}
static inline sere_vf sere_vf_max( sere_vf a, sere_vf b )
{
	SERE_VF_LANEWISE( a.v[j] > b.v[j] ? a.v[j] : b.v[j] );
}
static inline sere_vf sere_vf_abs( sere_vf a )
{
	SERE_VF_LANEWISE( fabsf( a.v[j] ) );
}
static inline sere_vmask sere_vf_gt( sere_vf a, sere_vf b )
{
	SERE_VMASK_LANEWISE( a.v[j] > b.v[j] );
}
static inline sere_vmask sere_vf_ne( sere_vf a, sere_vf b )
{
	SERE_VMASK_LANEWISE( !( a.v[j] == b.v[j] ) );
}
static inline sere_vmask sere_vmask_and( sere_vmask a, sere_vmask b )
{
	SERE_VMASK_LANEWISE( a.v[j] && b.v[j] );
}
static inline sere_vmask sere_vmask_first( int32_t n )
{
	SERE_VMASK_LANEWISE( j < n );
}
static inline int32_t sere_vmask_count( sere_vmask m )
{
	int32_t n = 0;
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		n += m.v[j] != 0;
	}
	return n;
}
static inline sere_vf sere_vf_keep( sere_vmask m, sere_vf a )
{
	SERE_VF_LANEWISE( m.v[j] ? a.v[j] : 0.0f );
}
static inline float sere_vf_max_where( sere_vmask m, sere_vf a )
{
	float best = -INFINITY;
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		best = m.v[j] && a.v[j] > best ? a.v[j] : best;
	}
	return best;
}
static inline sere_vf sere_vf_load_first( const float* p, int32_t n, float fill )
{
	SERE_VF_LANEWISE( j < n ? p[j] : fill );
}
static inline void sere_vf_store_first( float* p, int32_t n, sere_vf a )
{
	for ( int j = 0; j < n; ++j )
	{
		p[j] = a.v[j];
	}
}
static inline void sere_vf_load_records( const float* rec, const int32_t* at, sere_vf* c0, sere_vf* c1, sere_vf* c2,
										 sere_vf* c3 )
{
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		const float* r = rec + 4 * at[j];
		c0->v[j] = r[0];
		c1->v[j] = r[1];
		c2->v[j] = r[2];
		c3->v[j] = r[3];
	}
}
static inline void sere_vf_store_records( float* rec, const int32_t* at, int32_t n, sere_vf c0, sere_vf c1, sere_vf c2,
										  sere_vf c3 )
{
	for ( int j = 0; j < n; ++j )
	{
		float* r = rec + 4 * at[j];
		r[0] = c0.v[j];
		r[1] = c1.v[j];
		r[2] = c2.v[j];
		r[3] = c3.v[j];
	}
}

static inline void sere_vf_load_records_at( const float* base, const int32_t* offset, sere_vf* c0, sere_vf* c1,
											sere_vf* c2, sere_vf* c3 )
{
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		const float* r = base + offset[j];
		c0->v[j] = r[0];
		c1->v[j] = r[1];
		c2->v[j] = r[2];
		c3->v[j] = r[3];
	}
}
static inline void sere_vf_store_records_at( float* base, const int32_t* offset, sere_vf c0, sere_vf c1, sere_vf c2,
											 sere_vf c3 )
{
	for ( int j = 0; j < SERE_LANES; ++j )
	{
		float* r = base + offset[j];
		r[0] = c0.v[j];
		r[1] = c1.v[j];
		r[2] = c2.v[j];
		r[3] = c3.v[j];
	}
}
/* Lane j of c0..c3 receives record j of the SERE_LANES consecutive records at rec. */
static inline void sere_vf_load_block_records( const float* rec, sere_vf* c0, sere_vf* c1, sere_vf* c2, sere_vf* c3 )
{
	static const int32_t offset[SERE_LANES] = { 0, 4, 8, 12 };
	sere_vf_load_records_at( rec, offset, c0, c1, c2, c3 );
}
/* The inverse of sere_vf_load_block_records. */
static inline void sere_vf_store_block_records( float* rec, sere_vf c0, sere_vf c1, sere_vf c2, sere_vf c3 )
{
	static const int32_t offset[SERE_LANES] = { 0, 4, 8, 12 };
	sere_vf_store_records_at( rec, offset, c0, c1, c2, c3 );
}
static inline sere_vf sere_vf_load( const float* p )
{
	SERE_VF_LANEWISE( p[j] );
}
static inline void sere_vf_store( float* p, sere_vf a )
{
	memcpy( p, a.v, sizeof( a.v ) );
}
static inline sere_vmask sere_vf_eq( sere_vf a, sere_vf b )
{
	SERE_VMASK_LANEWISE( a.v[j] == b.v[j] );
}
static inline sere_vmask sere_vf_not_le( sere_vf a, sere_vf b )
{
	SERE_VMASK_LANEWISE( !( a.v[j] <= b.v[j] ) );
}
static inline sere_vmask sere_vmask_none( void )
{
	SERE_VMASK_LANEWISE( 0 );
}
static inline sere_vmask sere_vmask_or( sere_vmask a, sere_vmask b )
{
	SERE_VMASK_LANEWISE( a.v[j] || b.v[j] );
}
static inline int sere_vmask_any( sere_vmask m )
{
	return sere_vmask_count( m ) != 0;
}
static inline int32_t sere_vi_first_ne( const int32_t* p, int32_t j )
{
	for ( int32_t k = 0; k < SERE_LANES; ++k )
	{
		if ( p[k] != j )
		{
			return k;
		}
	}
	return SERE_LANES;
}
static inline float sere_vf_max_all( sere_vf a )
{
	float best = a.v[0];
	for ( int j = 1; j < SERE_LANES; ++j )
	{
		best = a.v[j] > best ? a.v[j] : best;
	}
	return best;
}

#undef SERE_VF_LANEWISE
#undef SERE_VMASK_LANEWISE

#endif

/* |(x, y, z)|, summed as (x² + y²) + z² at every width. */
static inline sere_vf sere_vf_norm3( sere_vf x, sere_vf y, sere_vf z )
{
	return sere_vf_sqrt( sere_vf_add( sere_vf_add( sere_vf_mul( x, x ), sere_vf_mul( y, y ) ), sere_vf_mul( z, z ) ) );
}
