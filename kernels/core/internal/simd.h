/* sere — private to the kernels (not installed, not part of the API): the SIMD lane layer.
 *
 * A kernel body is written once over sere_vf (SERE_LANES floats) and sere_vmask (one flag per
 * lane); the build picks the width: AVX-512 (16 lanes), AVX2 (8) or a portable 4 lanes in plain
 * C. Every operation is lane-wise IEEE single precision (no FMA: -ffp-contract=off, and none is
 * called here), so a body gives the same bits at every width; only the reductions (max) cross
 * lanes, and a maximum does not depend on the order it is taken in.
 *
 * The record loads serve kernels that keep a particle as one 16-byte record (x, y, z, w): a lane
 * fetches its record with one 128-bit load and an in-register 4 × 4 transpose hands out the
 * components, instead of one gather per component. */
#pragma once

#include <math.h>
#include <stdint.h>

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
/* Lane j of c0..c3 receives the four floats of record at[j] (16-byte aligned records). Lane j's
 * record sits in 128-bit lane j / 4 of register j % 4; a 4 × 4 transpose inside every 128-bit
 * lane then gathers the components. */
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
	__m512 t0 = _mm512_unpacklo_ps( r[0], r[1] ), t1 = _mm512_unpackhi_ps( r[0], r[1] );
	__m512 t2 = _mm512_unpacklo_ps( r[2], r[3] ), t3 = _mm512_unpackhi_ps( r[2], r[3] );
	*c0 = _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) );
	*c1 = _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) );
	*c2 = _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) );
	*c3 = _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) );
}
/* The inverse of sere_vf_load_records for the first n lanes (the transpose is its own inverse). */
static inline void sere_vf_store_records( float* rec, const int32_t* at, int32_t n, sere_vf c0, sere_vf c1, sere_vf c2,
										  sere_vf c3 )
{
	_Alignas( 64 ) float tmp[64];
	__m512 t0 = _mm512_unpacklo_ps( c0, c1 ), t1 = _mm512_unpackhi_ps( c0, c1 );
	__m512 t2 = _mm512_unpacklo_ps( c2, c3 ), t3 = _mm512_unpackhi_ps( c2, c3 );
	_mm512_store_ps( tmp, _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) ) );
	_mm512_store_ps( tmp + 16,
					 _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t0 ), _mm512_castps_pd( t2 ) ) ) );
	_mm512_store_ps( tmp + 32,
					 _mm512_castpd_ps( _mm512_unpacklo_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) ) );
	_mm512_store_ps( tmp + 48,
					 _mm512_castpd_ps( _mm512_unpackhi_pd( _mm512_castps_pd( t1 ), _mm512_castps_pd( t3 ) ) ) );
	for ( int32_t j = 0; j < n; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 16 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
}

#elif defined( __AVX2__ )

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
static inline float sere_vf_max_where( sere_vmask m, sere_vf a )
{
	a = _mm256_blendv_ps( _mm256_set1_ps( -INFINITY ), a, m );
	__m128 h = _mm_max_ps( _mm256_castps256_ps128( a ), _mm256_extractf128_ps( a, 1 ) );
	h = _mm_max_ps( h, _mm_movehl_ps( h, h ) );
	h = _mm_max_ss( h, _mm_shuffle_ps( h, h, 1 ) );
	return _mm_cvtss_f32( h );
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
/* As the AVX-512 version: 128-bit record loads, then the in-lane 4 × 4 transpose. */
static inline void sere_vf_load_records( const float* rec, const int32_t* at, sere_vf* c0, sere_vf* c1, sere_vf* c2,
										 sere_vf* c3 )
{
	__m256 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( rec + 4 * at[k] ) ),
									 _mm_load_ps( rec + 4 * at[k + 4] ), 1 );
	}
	__m256 t0 = _mm256_unpacklo_ps( r[0], r[1] ), t1 = _mm256_unpackhi_ps( r[0], r[1] );
	__m256 t2 = _mm256_unpacklo_ps( r[2], r[3] ), t3 = _mm256_unpackhi_ps( r[2], r[3] );
	*c0 = _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) );
	*c1 = _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) );
	*c2 = _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) );
	*c3 = _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) );
}
static inline void sere_vf_store_records( float* rec, const int32_t* at, int32_t n, sere_vf c0, sere_vf c1, sere_vf c2,
										  sere_vf c3 )
{
	_Alignas( 32 ) float tmp[32];
	__m256 t0 = _mm256_unpacklo_ps( c0, c1 ), t1 = _mm256_unpackhi_ps( c0, c1 );
	__m256 t2 = _mm256_unpacklo_ps( c2, c3 ), t3 = _mm256_unpackhi_ps( c2, c3 );
	_mm256_store_ps( tmp, _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) ) );
	_mm256_store_ps( tmp + 8,
					 _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t0 ), _mm256_castps_pd( t2 ) ) ) );
	_mm256_store_ps( tmp + 16,
					 _mm256_castpd_ps( _mm256_unpacklo_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) ) );
	_mm256_store_ps( tmp + 24,
					 _mm256_castpd_ps( _mm256_unpackhi_pd( _mm256_castps_pd( t1 ), _mm256_castps_pd( t3 ) ) ) );
	for ( int32_t j = 0; j < n; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 8 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
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

#undef SERE_VF_LANEWISE
#undef SERE_VMASK_LANEWISE

#endif

/* |(x, y, z)|, summed as (x² + y²) + z² at every width. */
static inline sere_vf sere_vf_norm3( sere_vf x, sere_vf y, sere_vf z )
{
	return sere_vf_sqrt( sere_vf_add( sere_vf_add( sere_vf_mul( x, x ), sere_vf_mul( y, y ) ), sere_vf_mul( z, z ) ) );
}
