/* sere — private to the kernels (not installed, not part of the API): the lane layer's fixed
 * widths, included by core/internal/simd.h (which picks the build's own width).
 *
 * Fixed groups of eight and of four floats, for data laid out that wide whatever the build's
 * width: the BVH's eight-lane nodes and eight-row tables, a contact's (x, y, z, w) record. They
 * are 256- and 128-bit registers when the build has AVX2 (also under AVX-512, where a 512-bit
 * register would stay half empty) and plain C arrays otherwise. Lane-wise IEEE as in simd.h; the
 * reductions take the pairwise tree the AVX instructions take (halves, then pairs, then the
 * last two), at every width, so even the order-dependent cases (±0, NaN) agree. */
#pragma once

#include <math.h>
#include <stdint.h>
#include <string.h>

/* x86 minss/maxss: the second operand unless the first comparison holds, so a NaN first operand
 * is dropped and a NaN second one returned. One instruction each, where fminf and fmaxf are
 * library calls (for their NaN rule); for values that are never NaN, their answer (but for the
 * sign of a zero). */
static inline float sere_min_x86( float a, float b )
{
	return a < b ? a : b;
}
static inline float sere_max_x86( float a, float b )
{
	return a > b ? a : b;
}

#if defined( __AVX2__ )

#include <immintrin.h>

typedef __m256 sere_v8;
typedef __m256 sere_m8; /* a lane is set when all its bits are */
typedef __m128 sere_v4;

static inline sere_v8 sere_v8_load( const float* p )
{
	return _mm256_loadu_ps( p );
}
static inline sere_v8 sere_v8_splat( float a )
{
	return _mm256_set1_ps( a );
}
static inline sere_v8 sere_v8_add( sere_v8 a, sere_v8 b )
{
	return _mm256_add_ps( a, b );
}
static inline sere_v8 sere_v8_sub( sere_v8 a, sere_v8 b )
{
	return _mm256_sub_ps( a, b );
}
static inline sere_v8 sere_v8_mul( sere_v8 a, sere_v8 b )
{
	return _mm256_mul_ps( a, b );
}
/* The compares are ordered: false when either side is NaN. */
static inline sere_m8 sere_v8_le( sere_v8 a, sere_v8 b )
{
	return _mm256_cmp_ps( a, b, _CMP_LE_OQ );
}
static inline sere_m8 sere_v8_ge( sere_v8 a, sere_v8 b )
{
	return _mm256_cmp_ps( a, b, _CMP_GE_OQ );
}
static inline sere_m8 sere_v8_lt( sere_v8 a, sere_v8 b )
{
	return _mm256_cmp_ps( a, b, _CMP_LT_OQ );
}
static inline sere_m8 sere_v8_gt( sere_v8 a, sere_v8 b )
{
	return _mm256_cmp_ps( a, b, _CMP_GT_OQ );
}
/* p[j] = s and p[j] > s, lane-wise over eight int32. */
static inline sere_m8 sere_i8_eq( const int32_t* p, int32_t s )
{
	return _mm256_castsi256_ps(
		_mm256_cmpeq_epi32( _mm256_loadu_si256( (const __m256i*) p ), _mm256_set1_epi32( s ) ) );
}
static inline sere_m8 sere_i8_gt( const int32_t* p, int32_t s )
{
	return _mm256_castsi256_ps(
		_mm256_cmpgt_epi32( _mm256_loadu_si256( (const __m256i*) p ), _mm256_set1_epi32( s ) ) );
}
static inline sere_m8 sere_m8_and( sere_m8 a, sere_m8 b )
{
	return _mm256_and_ps( a, b );
}
static inline sere_m8 sere_m8_or( sere_m8 a, sere_m8 b )
{
	return _mm256_or_ps( a, b );
}
/* a and not b. */
static inline sere_m8 sere_m8_and_not( sere_m8 a, sere_m8 b )
{
	return _mm256_andnot_ps( b, a );
}
static inline sere_m8 sere_m8_all( void )
{
	return _mm256_castsi256_ps( _mm256_set1_epi32( -1 ) );
}
/* Bit j set when lane j is. */
static inline uint32_t sere_m8_bits( sere_m8 m )
{
	return (uint32_t) _mm256_movemask_ps( m );
}
static inline float sere_v8_min_all( const float* p )
{
	__m256 a = _mm256_loadu_ps( p );
	__m128 m = _mm_min_ps( _mm256_castps256_ps128( a ), _mm256_extractf128_ps( a, 1 ) );
	m = _mm_min_ps( m, _mm_movehl_ps( m, m ) );
	m = _mm_min_ss( m, _mm_shuffle_ps( m, m, 1 ) );
	return _mm_cvtss_f32( m );
}
static inline float sere_v8_max_all( const float* p )
{
	__m256 a = _mm256_loadu_ps( p );
	__m128 m = _mm_max_ps( _mm256_castps256_ps128( a ), _mm256_extractf128_ps( a, 1 ) );
	m = _mm_max_ps( m, _mm_movehl_ps( m, m ) );
	m = _mm_max_ss( m, _mm_shuffle_ps( m, m, 1 ) );
	return _mm_cvtss_f32( m );
}
/* x[l], y[l], z[l] = the first three floats of record at[l] (records of four, any alignment):
 * one 16-byte load per record and a transpose in registers, where the hardware gathers
 * (vgatherdps, three per record) measured slower on the collision response. */
static inline void sere_v8_gather_records( const float* rec, const int32_t at[8], float* x, float* y, float* z )
{
	__m256 r[4];
	for ( int k = 0; k < 4; ++k )
	{
		r[k] = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_loadu_ps( rec + 4 * (size_t) at[k] ) ),
									 _mm_loadu_ps( rec + 4 * (size_t) at[k + 4] ), 1 );
	}
	__m256 xy01 = _mm256_unpacklo_ps( r[0], r[1] ), zw01 = _mm256_unpackhi_ps( r[0], r[1] );
	__m256 xy23 = _mm256_unpacklo_ps( r[2], r[3] ), zw23 = _mm256_unpackhi_ps( r[2], r[3] );
	_mm256_storeu_ps( x, _mm256_shuffle_ps( xy01, xy23, _MM_SHUFFLE( 1, 0, 1, 0 ) ) );
	_mm256_storeu_ps( y, _mm256_shuffle_ps( xy01, xy23, _MM_SHUFFLE( 3, 2, 3, 2 ) ) );
	_mm256_storeu_ps( z, _mm256_shuffle_ps( zw01, zw23, _MM_SHUFFLE( 1, 0, 1, 0 ) ) );
}
/* out[4 l + r] = row r, lane l of the rows x, y, z, w: eight records of four, by the same
 * transposition, where a vectorized loop would extract and store every float on its own. */
static inline void sere_v8_scatter_records( const float* x, const float* y, const float* z, const float* w, float* out )
{
	__m256 rx = _mm256_loadu_ps( x ), ry = _mm256_loadu_ps( y ), rz = _mm256_loadu_ps( z ), rw = _mm256_loadu_ps( w );
	__m256 xy_lo = _mm256_unpacklo_ps( rx, ry ), xy_hi = _mm256_unpackhi_ps( rx, ry );
	__m256 zw_lo = _mm256_unpacklo_ps( rz, rw ), zw_hi = _mm256_unpackhi_ps( rz, rw );
	/* records 0, 4 | 1, 5 | 2, 6 | 3, 7 */
	__m256 r04 = _mm256_shuffle_ps( xy_lo, zw_lo, _MM_SHUFFLE( 1, 0, 1, 0 ) );
	__m256 r15 = _mm256_shuffle_ps( xy_lo, zw_lo, _MM_SHUFFLE( 3, 2, 3, 2 ) );
	__m256 r26 = _mm256_shuffle_ps( xy_hi, zw_hi, _MM_SHUFFLE( 1, 0, 1, 0 ) );
	__m256 r37 = _mm256_shuffle_ps( xy_hi, zw_hi, _MM_SHUFFLE( 3, 2, 3, 2 ) );
	_mm256_storeu_ps( out, _mm256_permute2f128_ps( r04, r15, 0x20 ) );
	_mm256_storeu_ps( out + 8, _mm256_permute2f128_ps( r26, r37, 0x20 ) );
	_mm256_storeu_ps( out + 16, _mm256_permute2f128_ps( r04, r15, 0x31 ) );
	_mm256_storeu_ps( out + 24, _mm256_permute2f128_ps( r26, r37, 0x31 ) );
}
/* Two groups of four side by side, and back. */
static inline sere_v8 sere_v8_pair( sere_v4 low, sere_v4 high )
{
	return _mm256_set_m128( high, low );
}
static inline sere_v4 sere_v8_low( sere_v8 a )
{
	return _mm256_castps256_ps128( a );
}
static inline sere_v4 sere_v8_high( sere_v8 a )
{
	return _mm256_extractf128_ps( a, 1 );
}
static inline sere_v8 sere_v8_zero( void )
{
	return _mm256_setzero_ps();
}

static inline sere_v4 sere_v4_load( const float* p )
{
	return _mm_loadu_ps( p );
}
static inline void sere_v4_store( float* p, sere_v4 a )
{
	_mm_storeu_ps( p, a );
}
static inline sere_v4 sere_v4_zero( void )
{
	return _mm_setzero_ps();
}
static inline sere_v4 sere_v4_add( sere_v4 a, sere_v4 b )
{
	return _mm_add_ps( a, b );
}
static inline sere_v4 sere_v4_mul( sere_v4 a, sere_v4 b )
{
	return _mm_mul_ps( a, b );
}
/* (a, a, a, w). */
static inline sere_v4 sere_v4_xyz( float a, float w )
{
	return _mm_set_ps( w, a, a, a );
}
/* Lane 3, the w of a record. */
static inline float sere_v4_w( sere_v4 a )
{
	return _mm_cvtss_f32( _mm_shuffle_ps( a, a, _MM_SHUFFLE( 3, 3, 3, 3 ) ) );
}

#else

typedef struct
{
	float v[8];
} sere_v8;
typedef struct
{
	int32_t v[8];
} sere_m8;
typedef struct
{
	float v[4];
} sere_v4;

#define SERE_LANEWISE( type, n, expr )                                                                                 \
	type r;                                                                                                            \
	for ( int j = 0; j < ( n ); ++j )                                                                                  \
	{                                                                                                                  \
		r.v[j] = ( expr );                                                                                             \
	}                                                                                                                  \
	return r

static inline sere_v8 sere_v8_load( const float* p )
{
	SERE_LANEWISE( sere_v8, 8, p[j] );
}
static inline sere_v8 sere_v8_splat( float a )
{
	SERE_LANEWISE( sere_v8, 8, a );
}
static inline sere_v8 sere_v8_add( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_v8, 8, a.v[j] + b.v[j] );
}
static inline sere_v8 sere_v8_sub( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_v8, 8, a.v[j] - b.v[j] );
}
static inline sere_v8 sere_v8_mul( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_v8, 8, a.v[j] * b.v[j] );
}
static inline sere_m8 sere_v8_le( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] <= b.v[j] );
}
static inline sere_m8 sere_v8_ge( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] >= b.v[j] );
}
static inline sere_m8 sere_v8_lt( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] < b.v[j] );
}
static inline sere_m8 sere_v8_gt( sere_v8 a, sere_v8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] > b.v[j] );
}
static inline sere_m8 sere_i8_eq( const int32_t* p, int32_t s )
{
	SERE_LANEWISE( sere_m8, 8, p[j] == s );
}
static inline sere_m8 sere_i8_gt( const int32_t* p, int32_t s )
{
	SERE_LANEWISE( sere_m8, 8, p[j] > s );
}
static inline sere_m8 sere_m8_and( sere_m8 a, sere_m8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] && b.v[j] );
}
static inline sere_m8 sere_m8_or( sere_m8 a, sere_m8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] || b.v[j] );
}
static inline sere_m8 sere_m8_and_not( sere_m8 a, sere_m8 b )
{
	SERE_LANEWISE( sere_m8, 8, a.v[j] && !b.v[j] );
}
static inline sere_m8 sere_m8_all( void )
{
	SERE_LANEWISE( sere_m8, 8, 1 );
}
static inline uint32_t sere_m8_bits( sere_m8 m )
{
	uint32_t bits = 0;
	for ( int j = 0; j < 8; ++j )
	{
		bits |= (uint32_t) ( m.v[j] != 0 ) << j;
	}
	return bits;
}
static inline float sere_v8_min_all( const float* p )
{
	float m[4];
	for ( int j = 0; j < 4; ++j )
	{
		m[j] = sere_min_x86( p[j], p[j + 4] );
	}
	return sere_min_x86( sere_min_x86( m[0], m[2] ), sere_min_x86( m[1], m[3] ) );
}
static inline float sere_v8_max_all( const float* p )
{
	float m[4];
	for ( int j = 0; j < 4; ++j )
	{
		m[j] = sere_max_x86( p[j], p[j + 4] );
	}
	return sere_max_x86( sere_max_x86( m[0], m[2] ), sere_max_x86( m[1], m[3] ) );
}
static inline void sere_v8_gather_records( const float* rec, const int32_t at[8], float* x, float* y, float* z )
{
	for ( int l = 0; l < 8; ++l )
	{
		const float* r = rec + 4 * (size_t) at[l];
		x[l] = r[0], y[l] = r[1], z[l] = r[2];
	}
}
static inline void sere_v8_scatter_records( const float* x, const float* y, const float* z, const float* w, float* out )
{
	for ( int l = 0; l < 8; ++l )
	{
		out[4 * l] = x[l], out[4 * l + 1] = y[l], out[4 * l + 2] = z[l], out[4 * l + 3] = w[l];
	}
}
static inline sere_v8 sere_v8_pair( sere_v4 low, sere_v4 high )
{
	SERE_LANEWISE( sere_v8, 8, j < 4 ? low.v[j] : high.v[j - 4] );
}
static inline sere_v4 sere_v8_low( sere_v8 a )
{
	SERE_LANEWISE( sere_v4, 4, a.v[j] );
}
static inline sere_v4 sere_v8_high( sere_v8 a )
{
	SERE_LANEWISE( sere_v4, 4, a.v[j + 4] );
}
static inline sere_v8 sere_v8_zero( void )
{
	SERE_LANEWISE( sere_v8, 8, 0.0f );
}

static inline sere_v4 sere_v4_load( const float* p )
{
	SERE_LANEWISE( sere_v4, 4, p[j] );
}
static inline void sere_v4_store( float* p, sere_v4 a )
{
	memcpy( p, a.v, sizeof( a.v ) );
}
static inline sere_v4 sere_v4_zero( void )
{
	SERE_LANEWISE( sere_v4, 4, 0.0f );
}
static inline sere_v4 sere_v4_add( sere_v4 a, sere_v4 b )
{
	SERE_LANEWISE( sere_v4, 4, a.v[j] + b.v[j] );
}
static inline sere_v4 sere_v4_mul( sere_v4 a, sere_v4 b )
{
	SERE_LANEWISE( sere_v4, 4, a.v[j] * b.v[j] );
}
static inline sere_v4 sere_v4_xyz( float a, float w )
{
	SERE_LANEWISE( sere_v4, 4, j < 3 ? a : w );
}
static inline float sere_v4_w( sere_v4 a )
{
	return a.v[3];
}

#undef SERE_LANEWISE

#endif
