#include "massspring.h"

#include "color.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined( __AVX512F__ ) || defined( __AVX__ )
#include <immintrin.h>
#endif

struct sere_massspring
{
	int32_t vertex_count;
	int32_t structural_count;
	int32_t flexion_count;
	int32_t* a; /* structural springs in sweep order (below), then flexion springs */
	int32_t* b;
	float* rest0;
	int32_t color_count;
	/* The sweep (Eq. 2) works on bands: the particles cut by breadth-first level into
	 * band_count ranges, so that a structural spring lies inside one band or joins two
	 * neighbouring ones. A sweep limits the springs inside the bands (bands in parallel: they
	 * share no particle, and each band's thread takes its colors in turn with no barrier), then
	 * the springs joining bands c and c + 1 for even c, then for odd c. The structural springs
	 * are stored in that order, item by item (bands, even cuts, odd cuts), each item by color:
	 * run k = item k / color_count, color k % color_count is [run_offsets[k], run_offsets[k+1]). */
	int32_t band_count;
	int32_t* run_offsets;
	/* Particle → springs incidence (CSR), each list in ascending spring order, with the sign
	 * the spring's force takes at that particle: the fixed gather order makes the sum the same
	 * for any thread count. */
	int32_t* incidence_offsets;
	int32_t* incidence;
	float* incidence_sign;
	/* Per-spring force of the current step. */
	float *fx, *fy, *fz;
	/* The step works on particle records, (x, y, z, 1/m) and (vx, vy, vz, 0): a SIMD lane
	 * fetches one spring end with a single 16-byte load instead of one gather per component. */
	float* xrec;
	float* vrec;
};

sere_ms_params sere_ms_params_default( void )
{
	sere_ms_params p;
	p.dt = 1e-3f;
	p.gravity[0] = 0.0f;
	p.gravity[1] = 0.0f;
	p.gravity[2] = -1.0f;
	p.stiffness = 40.0f;
	p.bend_stiffness = 4.0f;
	p.damping = 0.02f;
	p.drag = 0.01f;
	p.shrink = 0.0f;
	p.curl = 0.0f;
	p.strain_limit = 0.1f;
	p.strain_tolerance = 1e-3f;
	p.max_sweeps = 500;
	return p;
}

sere_status sere_ms_mass_from_gray( const float* gray, int32_t n, float m_min, float m_max, float* mass )
{
	if ( n < 0 || ( n > 0 && ( gray == NULL || mass == NULL ) ) || !isfinite( m_min ) || !isfinite( m_max ) ||
		 !( m_min > 0.0f ) || !( m_min <= m_max ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( isnan( gray[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	const double scale = 1.0 / log( 256.0 );
	for ( int32_t i = 0; i < n; ++i )
	{
		double g = gray[i] < 0.0f ? 0.0 : ( gray[i] > 1.0f ? 1.0 : (double) gray[i] );
		double t = log1p( 255.0 * g ) * scale; /* Eq. 3 */
		mass[i] = (float) ( m_min + ( (double) m_max - m_min ) * t );
	}
	return SERE_OK;
}

void sere_massspring_destroy( sere_massspring* ms )
{
	if ( ms == NULL )
	{
		return;
	}
	sere_free( ms->a );
	sere_free( ms->b );
	sere_free( ms->rest0 );
	sere_free( ms->run_offsets );
	sere_free( ms->incidence_offsets );
	sere_free( ms->incidence );
	sere_free( ms->incidence_sign );
	sere_free( ms->fx );
	sere_free( ms->fy );
	sere_free( ms->fz );
	sere_free( ms->xrec );
	sere_free( ms->vrec );
	free( ms );
}

/* One triangle side: the undirected edge (lo, hi), the triangle it belongs to and the vertex
 * opposite it there. */
typedef struct side
{
	int32_t lo, hi, triangle, opposite;
} side;

static int compare_sides( const void* pa, const void* pb )
{
	const side* a = pa;
	const side* b = pb;
	if ( a->lo != b->lo )
	{
		return a->lo < b->lo ? -1 : 1;
	}
	if ( a->hi != b->hi )
	{
		return a->hi < b->hi ? -1 : 1;
	}
	return ( a->triangle > b->triangle ) - ( a->triangle < b->triangle );
}

static float distance( const float* x, const float* y, const float* z, int32_t i, int32_t j )
{
	float dx = x[j] - x[i], dy = y[j] - y[i], dz = z[j] - z[i];
	return sqrtf( ( dx * dx + dy * dy ) + dz * dz );
}

/* Bands hold at least this many particles, so that the springs joining two bands stay a
 * small share; at most MAX_BANDS of them. The count depends on the mesh only, never on the
 * thread count, so every thread count limits the springs in the same order. */
#define BAND_PARTICLES 512
#define MAX_BANDS	   16

/* Breadth-first levels over the structural springs (each connected piece continues the level
 * count of the previous one), then bands of whole levels holding about equal shares of the
 * particles. Fills band_of (per particle) and returns the band count. */
static int32_t cut_bands( const int32_t* sa, const int32_t* sb, int32_t edges, int32_t n, int32_t* band_of,
						  int32_t* scratch )
{
	int32_t* start = scratch;		   /* n + 1: adjacency offsets */
	int32_t* adjacent = start + n + 1; /* 2 edges */
	int32_t* level = adjacent + 2 * (size_t) edges;
	int32_t* queue = level + n;
	memset( start, 0, sizeof( int32_t ) * ( (size_t) n + 1 ) );
	for ( int32_t e = 0; e < edges; ++e )
	{
		++start[sa[e] + 1], ++start[sb[e] + 1];
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		start[i + 1] += start[i];
	}
	int32_t* fill = queue; /* the queue is not in use yet */
	memcpy( fill, start, sizeof( int32_t ) * (size_t) n );
	for ( int32_t e = 0; e < edges; ++e )
	{
		adjacent[fill[sa[e]]++] = sb[e];
		adjacent[fill[sb[e]]++] = sa[e];
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		level[i] = -1;
	}
	int32_t head = 0, tail = 0, top = 0;
	for ( int32_t root = 0; root < n; ++root )
	{
		if ( level[root] >= 0 )
		{
			continue;
		}
		level[root] = top;
		queue[tail++] = root;
		while ( head < tail )
		{
			int32_t i = queue[head++];
			top = level[i] > top ? level[i] : top;
			for ( int32_t k = start[i]; k < start[i + 1]; ++k )
			{
				if ( level[adjacent[k]] < 0 )
				{
					level[adjacent[k]] = level[i] + 1;
					queue[tail++] = adjacent[k];
				}
			}
		}
		top += 1;
	}
	/* particles per level, then bands of whole levels */
	int32_t* per_level = start; /* reuse: top ≤ n levels */
	memset( per_level, 0, sizeof( int32_t ) * ( (size_t) top + 1 ) );
	for ( int32_t i = 0; i < n; ++i )
	{
		++per_level[level[i]];
	}
	int32_t bands = n / BAND_PARTICLES;
	bands = bands < 1 ? 1 : bands > MAX_BANDS ? MAX_BANDS : bands;
	for ( ;; )
	{
		/* level l goes to the band its first particle's rank falls in */
		int32_t before = 0, used = 0, previous = -1;
		for ( int32_t l = 0; l < top; ++l )
		{
			int32_t band = (int32_t) ( (int64_t) before * bands / n );
			used += band != previous;
			previous = band;
			queue[l] = band;
			before += per_level[l];
		}
		if ( used == bands || bands == 1 )
		{
			break;
		}
		bands -= 1; /* a level wider than a band's share: fewer, wider bands */
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		band_of[i] = queue[level[i]];
	}
	return bands;
}

/* Stores the structural springs in sweep order (see the struct) and their runs. */
static sere_status sweep_order( sere_massspring* ms, const int32_t* sa, const int32_t* sb, const float* srest,
								int32_t edges, int32_t n, const sere_coloring* coloring )
{
	int32_t* band_of = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* scratch = malloc( sizeof( int32_t ) * ( 3 * (size_t) n + 1 + 2 * (size_t) edges ) );
	if ( band_of == NULL || scratch == NULL )
	{
		free( band_of ), free( scratch );
		return SERE_ERR_MEMORY;
	}
	const int32_t bands = cut_bands( sa, sb, edges, n, band_of, scratch );
	const int32_t colors = coloring->color_count, cuts = bands - 1, items = bands + cuts;
	/* item rank: bands 0..R−1, then even cuts, then odd cuts */
	int32_t rank_of_cut[MAX_BANDS];
	int32_t next = bands;
	for ( int32_t c = 0; c < cuts; c += 2 )
	{
		rank_of_cut[c] = next++;
	}
	for ( int32_t c = 1; c < cuts; c += 2 )
	{
		rank_of_cut[c] = next++;
	}
	ms->band_count = bands;
	ms->run_offsets = sere_alloc( sizeof( int32_t ) * ( (size_t) items * colors + 1 ) );
	if ( ms->run_offsets == NULL )
	{
		free( band_of ), free( scratch );
		return SERE_ERR_MEMORY;
	}
	/* counting sort by run (item rank, color), stable in the coloring's order */
	int32_t* offsets = ms->run_offsets;
	memset( offsets, 0, sizeof( int32_t ) * ( (size_t) items * colors + 1 ) );
	int32_t* run_of = scratch; /* per position in the coloring's order */
	for ( int32_t k = 0; k < edges; ++k )
	{
		int32_t s = coloring->order[k];
		int32_t ra = band_of[sa[s]], rb = band_of[sb[s]];
		int32_t item = ra == rb ? ra : rank_of_cut[ra < rb ? ra : rb];
		run_of[k] = item * colors + coloring->color[s];
		++offsets[run_of[k] + 1];
	}
	for ( int32_t r = 0; r < items * colors; ++r )
	{
		offsets[r + 1] += offsets[r];
	}
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) items * colors );
	if ( fill == NULL )
	{
		free( band_of ), free( scratch );
		return SERE_ERR_MEMORY;
	}
	memcpy( fill, offsets, sizeof( int32_t ) * (size_t) items * colors );
	for ( int32_t k = 0; k < edges; ++k )
	{
		int32_t s = coloring->order[k], at = fill[run_of[k]]++;
		ms->a[at] = sa[s];
		ms->b[at] = sb[s];
		ms->rest0[at] = srest[s];
	}
	ms->color_count = colors;
	free( band_of ), free( scratch ), free( fill );
	return SERE_OK;
}

sere_status sere_massspring_create( const float* x, const float* y, const float* z, int32_t vertex_count,
									const int32_t* tri, int32_t triangle_count, sere_massspring** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( x == NULL || y == NULL || z == NULL || tri == NULL || vertex_count < 3 || triangle_count < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		if ( !isfinite( x[i] ) || !isfinite( y[i] ) || !isfinite( z[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * t;
		for ( int k = 0; k < 3; ++k )
		{
			if ( v[k] < 0 || v[k] >= vertex_count )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
		if ( v[0] == v[1] || v[1] == v[2] || v[2] == v[0] )
		{
			return SERE_ERR_ARGUMENT;
		}
	}

	/* Sec. 4.2, steps 1–3: every pair of adjacent particles joined once. Sorting the triangle
	 * sides groups each edge's one (boundary) or two (interior) sides together. */
	side* sides = malloc( 3 * (size_t) triangle_count * sizeof( side ) );
	if ( sides == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			int32_t p = tri[3 * t + ( k + 1 ) % 3], q = tri[3 * t + ( k + 2 ) % 3];
			sides[3 * t + k] = ( side ){ p < q ? p : q, p < q ? q : p, t, tri[3 * t + k] };
		}
	}
	qsort( sides, 3 * (size_t) triangle_count, sizeof( side ), compare_sides );

	int32_t side_count = 3 * triangle_count;
	int32_t edges = 0, hinges = 0;
	sere_status status = SERE_OK;
	for ( int32_t k = 0; k < side_count; )
	{
		int32_t run = 1;
		while ( k + run < side_count && sides[k + run].lo == sides[k].lo && sides[k + run].hi == sides[k].hi )
		{
			++run;
		}
		if ( run > 2 || ( run == 2 && sides[k].opposite == sides[k + 1].opposite ) )
		{
			status = SERE_ERR_GEOMETRY;
		}
		edges += 1;
		hinges += run == 2;
		k += run;
	}

	sere_massspring* ms = status == SERE_OK ? calloc( 1, sizeof( sere_massspring ) ) : NULL;
	int32_t* sa = NULL;
	int32_t* sb = NULL;
	float* srest = NULL;
	sere_coloring coloring = { 0 };
	if ( status == SERE_OK && ms == NULL )
	{
		status = SERE_ERR_MEMORY;
	}
	if ( status == SERE_OK )
	{
		int32_t total = sere_pad( edges + hinges );
		ms->vertex_count = vertex_count;
		ms->structural_count = edges;
		ms->flexion_count = hinges;
		ms->a = sere_alloc( (size_t) total * sizeof( int32_t ) );
		ms->b = sere_alloc( (size_t) total * sizeof( int32_t ) );
		ms->rest0 = sere_alloc( (size_t) total * sizeof( float ) );
		ms->fx = sere_alloc( (size_t) total * sizeof( float ) );
		ms->fy = sere_alloc( (size_t) total * sizeof( float ) );
		ms->fz = sere_alloc( (size_t) total * sizeof( float ) );
		ms->incidence_offsets = sere_alloc( (size_t) sere_pad( vertex_count + 1 ) * sizeof( int32_t ) );
		ms->incidence = sere_alloc( 2 * (size_t) total * sizeof( int32_t ) );
		ms->incidence_sign = sere_alloc( 2 * (size_t) total * sizeof( float ) );
		ms->xrec = sere_alloc( 4 * (size_t) sere_pad( vertex_count ) * sizeof( float ) );
		ms->vrec = sere_alloc( 4 * (size_t) sere_pad( vertex_count ) * sizeof( float ) );
		sa = malloc( (size_t) edges * sizeof( int32_t ) );
		sb = malloc( (size_t) edges * sizeof( int32_t ) );
		srest = malloc( (size_t) edges * sizeof( float ) );
		if ( ms->a == NULL || ms->b == NULL || ms->rest0 == NULL || ms->fx == NULL || ms->fy == NULL ||
			 ms->fz == NULL || ms->incidence_offsets == NULL || ms->incidence == NULL || ms->incidence_sign == NULL ||
			 ms->xrec == NULL || ms->vrec == NULL || sa == NULL || sb == NULL || srest == NULL )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	if ( status == SERE_OK )
	{
		int32_t e = 0, h = edges;
		for ( int32_t k = 0; k < side_count; )
		{
			int32_t run =
				k + 1 < side_count && sides[k + 1].lo == sides[k].lo && sides[k + 1].hi == sides[k].hi ? 2 : 1;
			sa[e] = sides[k].lo;
			sb[e] = sides[k].hi;
			srest[e] = distance( x, y, z, sa[e], sb[e] );
			if ( !( srest[e] > 0.0f ) )
			{
				status = SERE_ERR_GEOMETRY;
			}
			++e;
			if ( run == 2 )
			{
				int32_t c = sides[k].opposite, d = sides[k + 1].opposite;
				ms->a[h] = c < d ? c : d;
				ms->b[h] = c < d ? d : c;
				ms->rest0[h] = distance( x, y, z, c, d );
				if ( !( ms->rest0[h] > 0.0f ) )
				{
					status = SERE_ERR_GEOMETRY;
				}
				++h;
			}
			k += run;
		}
	}
	free( sides );
	if ( status == SERE_OK )
	{
		status = sere_color_springs( sa, sb, edges, vertex_count, &coloring );
	}
	if ( status == SERE_OK )
	{
		status = sweep_order( ms, sa, sb, srest, edges, vertex_count, &coloring );
	}
	if ( status == SERE_OK )
	{

		int32_t total = edges + hinges;
		int32_t* offsets = ms->incidence_offsets;
		for ( int32_t s = 0; s < total; ++s )
		{
			++offsets[ms->a[s] + 1];
			++offsets[ms->b[s] + 1];
		}
		for ( int32_t i = 0; i < vertex_count; ++i )
		{
			offsets[i + 1] += offsets[i];
		}
		int32_t* fill = malloc( (size_t) vertex_count * sizeof( int32_t ) );
		if ( fill == NULL )
		{
			status = SERE_ERR_MEMORY;
		}
		else
		{
			memcpy( fill, offsets, (size_t) vertex_count * sizeof( int32_t ) );
			for ( int32_t s = 0; s < total; ++s )
			{
				/* The force f of spring s pulls a toward b: +f at a, −f at b. */
				ms->incidence[fill[ms->a[s]]] = s;
				ms->incidence_sign[fill[ms->a[s]]++] = 1.0f;
				ms->incidence[fill[ms->b[s]]] = s;
				ms->incidence_sign[fill[ms->b[s]]++] = -1.0f;
			}
			free( fill );
		}
	}
	sere_coloring_destroy( &coloring );
	free( sa );
	free( sb );
	free( srest );
	if ( status != SERE_OK )
	{
		sere_massspring_destroy( ms );
		return status;
	}
	*out = ms;
	return SERE_OK;
}

sere_ms_topology sere_massspring_topology( const sere_massspring* ms )
{
	sere_ms_topology t = { 0 };
	if ( ms != NULL )
	{
		t.vertex_count = ms->vertex_count;
		t.structural_count = ms->structural_count;
		t.flexion_count = ms->flexion_count;
		t.a = ms->a;
		t.b = ms->b;
		t.rest0 = ms->rest0;
		t.color_count = ms->color_count;
		t.band_count = ms->band_count;
		t.run_count = ( 2 * ms->band_count - 1 ) * ms->color_count;
		t.run_offsets = ms->run_offsets;
	}
	return t;
}

static int params_valid( const sere_ms_params* p )
{
	return isfinite( p->dt ) && p->dt > 0.0f && isfinite( p->gravity[0] ) && isfinite( p->gravity[1] ) &&
		   isfinite( p->gravity[2] ) && isfinite( p->stiffness ) && p->stiffness >= 0.0f &&
		   isfinite( p->bend_stiffness ) && p->bend_stiffness >= 0.0f && isfinite( p->damping ) && p->damping >= 0.0f &&
		   p->drag >= 0.0f && p->drag < 1.0f && p->shrink >= 0.0f && p->shrink < 1.0f && p->curl >= 0.0f &&
		   p->curl < 1.0f && p->strain_limit > 0.0f && p->strain_limit < 1.0f && p->strain_tolerance > 0.0f &&
		   p->strain_tolerance < p->strain_limit && p->max_sweeps >= 1;
}

/* The constants of one kind of spring in one step. */
typedef struct spring_law
{
	float keep; /* L = keep · L⁰ */
	float k;	/* stiffness */
	float c;	/* damping */
} spring_law;

#if defined( __AVX512F__ )
/* Lane j of c0..c3 receives the four floats of record at[j]. Lane j's record sits in 128-bit
 * lane j / 4 of register j % 4; a 4 × 4 transpose inside every 128-bit lane then gathers the
 * components. */
static inline void load16( const float* rec, const int32_t* at, __m512* c0, __m512* c1, __m512* c2, __m512* c3 )
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

/* The inverse of load16 for the first `lanes` lanes (the transpose is its own inverse). */
static inline void store16( float* rec, const int32_t* at, int32_t lanes, __m512 c0, __m512 c1, __m512 c2, __m512 c3 )
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
	for ( int32_t j = 0; j < lanes; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 16 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
}

/* The spring indices of a chunk of 16 from [s, s + left); lanes past the end repeat lane 0,
 * whose particles this chunk owns, so their loads never read a record another thread writes. */
static inline int32_t chunk_ends( const int32_t* sa, const int32_t* sb, int32_t s, int32_t left, int32_t* ia,
								  int32_t* ib )
{
	const int32_t lanes = left < 16 ? left : 16;
	for ( int32_t j = 0; j < 16; ++j )
	{
		ia[j] = sa[s + ( j < lanes ? j : 0 )];
		ib[j] = sb[s + ( j < lanes ? j : 0 )];
	}
	return lanes;
}

static inline __m512 norm3( __m512 x, __m512 y, __m512 z )
{
	return _mm512_sqrt_ps(
		_mm512_add_ps( _mm512_add_ps( _mm512_mul_ps( x, x ), _mm512_mul_ps( y, y ) ), _mm512_mul_ps( z, z ) ) );
}
#elif defined( __AVX__ )
/* The AVX (256-bit) build: the same operations as the AVX-512 one, eight springs to a step.
 * Without it a machine lacking AVX-512 ran the one-spring loops, slower than the reference. */

/* Lane j of c0..c3 receives the four floats of record at[j] (the 128-bit loads and in-lane
 * 4 × 4 transpose of load16). */
static inline void load8( const float* rec, const int32_t* at, __m256* c0, __m256* c1, __m256* c2, __m256* c3 )
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

/* The inverse of load8 for the first `lanes` lanes. */
static inline void store8( float* rec, const int32_t* at, int32_t lanes, __m256 c0, __m256 c1, __m256 c2, __m256 c3 )
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
	for ( int32_t j = 0; j < lanes; ++j )
	{
		_mm_store_ps( rec + 4 * at[j], _mm_load_ps( tmp + 8 * ( j % 4 ) + 4 * ( j / 4 ) ) );
	}
}

/* The spring indices of a chunk of 8 from [s, s + left); lanes past the end repeat lane 0 (see
 * chunk_ends). */
static inline int32_t chunk_ends8( const int32_t* sa, const int32_t* sb, int32_t s, int32_t left, int32_t* ia,
								   int32_t* ib )
{
	const int32_t lanes = left < 8 ? left : 8;
	for ( int32_t j = 0; j < 8; ++j )
	{
		ia[j] = sa[s + ( j < lanes ? j : 0 )];
		ib[j] = sb[s + ( j < lanes ? j : 0 )];
	}
	return lanes;
}

/* All ones in the first `lanes` lanes. */
static inline __m256i lane_mask8( int32_t lanes )
{
	return _mm256_cmpgt_epi32( _mm256_set1_epi32( lanes ), _mm256_setr_epi32( 0, 1, 2, 3, 4, 5, 6, 7 ) );
}

/* rest0[s ..] in the first `lanes` lanes, 1 in the others (as _mm512_mask_loadu_ps with 1). */
static inline __m256 load_rest8( const float* rest0, int32_t s, int32_t lanes )
{
	__m256i m = lane_mask8( lanes );
	return _mm256_blendv_ps( _mm256_set1_ps( 1.0f ), _mm256_maskload_ps( rest0 + s, m ), _mm256_castsi256_ps( m ) );
}

static inline __m256 norm3_8( __m256 x, __m256 y, __m256 z )
{
	return _mm256_sqrt_ps(
		_mm256_add_ps( _mm256_add_ps( _mm256_mul_ps( x, x ), _mm256_mul_ps( y, y ) ), _mm256_mul_ps( z, z ) ) );
}

/* Largest of the lanes of v whose sign bit is set in mask (−inf when none). */
static inline float masked_max8( __m256 v, __m256 mask )
{
	v = _mm256_blendv_ps( _mm256_set1_ps( -INFINITY ), v, mask );
	__m128 m = _mm_max_ps( _mm256_castps256_ps128( v ), _mm256_extractf128_ps( v, 1 ) );
	m = _mm_max_ps( m, _mm_movehl_ps( m, m ) );
	m = _mm_max_ss( m, _mm_shuffle_ps( m, m, 1 ) );
	return _mm_cvtss_f32( m );
}

static inline __m256 abs8( __m256 v )
{
	return _mm256_and_ps( v, _mm256_castsi256_ps( _mm256_set1_epi32( 0x7fffffff ) ) );
}
#endif

/* Packs the particles into records (x, y, z, 1/m) and (vx, vy, vz, 0). */
static void pack( sere_massspring* ms, const sere_ms_particles* p )
{
	float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
#pragma omp for schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		xr[4 * i] = p->x[i];
		xr[4 * i + 1] = p->y[i];
		xr[4 * i + 2] = p->z[i];
		xr[4 * i + 3] = p->inv_m[i];
		vr[4 * i] = p->vx[i];
		vr[4 * i + 1] = p->vy[i];
		vr[4 * i + 2] = p->vz[i];
		vr[4 * i + 3] = 0.0f;
	}
}

/* The per-spring forces of springs [first, first + count) (see the header for the law). */
static void spring_forces( sere_massspring* ms, int32_t first, int32_t count, spring_law law )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	const float* restrict vr = ms->vrec;
	float* restrict fx = ms->fx;
	float* restrict fy = ms->fy;
	float* restrict fz = ms->fz;
#if defined( __AVX512F__ )
	const int32_t chunks = ( count + 15 ) / 16;
	const __m512 keep = _mm512_set1_ps( law.keep ), k = _mm512_set1_ps( law.k ), c = _mm512_set1_ps( law.c );
	const __m512 one = _mm512_set1_ps( 1.0f ), zero = _mm512_setzero_ps();
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + 16 * chunk;
		int32_t ia[16], ib[16];
		const int32_t lanes = chunk_ends( sa, sb, s, count - 16 * chunk, ia, ib );
		const __mmask16 m = (__mmask16) ( ( 1u << lanes ) - 1u );
		__m512 ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		load16( xr, ia, &ax, &ay, &az, &aw );
		load16( xr, ib, &bx, &by, &bz, &bw );
		load16( vr, ia, &avx, &avy, &avz, &unused );
		load16( vr, ib, &bvx, &bvy, &bvz, &unused );
		__m512 dx = _mm512_sub_ps( bx, ax ), dy = _mm512_sub_ps( by, ay ), dz = _mm512_sub_ps( bz, az );
		__m512 len = norm3( dx, dy, dz );
		__m512 inv = _mm512_maskz_div_ps( _mm512_cmp_ps_mask( len, zero, _CMP_GT_OQ ), one, len );
		__m512 nx = _mm512_mul_ps( dx, inv ), ny = _mm512_mul_ps( dy, inv ), nz = _mm512_mul_ps( dz, inv );
		__m512 rest = _mm512_mul_ps( _mm512_mask_loadu_ps( one, m, rest0 + s ), keep );
		__m512 strain = _mm512_div_ps( _mm512_sub_ps( len, rest ), rest );
		__m512 rvx = _mm512_sub_ps( bvx, avx ), rvy = _mm512_sub_ps( bvy, avy ), rvz = _mm512_sub_ps( bvz, avz );
		__m512 along = _mm512_add_ps( _mm512_add_ps( _mm512_mul_ps( rvx, nx ), _mm512_mul_ps( rvy, ny ) ),
									  _mm512_mul_ps( rvz, nz ) );
		__m512 f = _mm512_add_ps( _mm512_mul_ps( k, strain ), _mm512_mul_ps( c, along ) );
		_mm512_mask_storeu_ps( fx + s, m, _mm512_mul_ps( f, nx ) );
		_mm512_mask_storeu_ps( fy + s, m, _mm512_mul_ps( f, ny ) );
		_mm512_mask_storeu_ps( fz + s, m, _mm512_mul_ps( f, nz ) );
	}
#elif defined( __AVX__ )
	const int32_t chunks = ( count + 7 ) / 8;
	const __m256 keep = _mm256_set1_ps( law.keep ), k = _mm256_set1_ps( law.k ), c = _mm256_set1_ps( law.c );
	const __m256 one = _mm256_set1_ps( 1.0f ), zero = _mm256_setzero_ps();
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + 8 * chunk;
		int32_t ia[8], ib[8];
		const int32_t lanes = chunk_ends8( sa, sb, s, count - 8 * chunk, ia, ib );
		const __m256i m = lane_mask8( lanes );
		__m256 ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		load8( xr, ia, &ax, &ay, &az, &aw );
		load8( xr, ib, &bx, &by, &bz, &bw );
		load8( vr, ia, &avx, &avy, &avz, &unused );
		load8( vr, ib, &bvx, &bvy, &bvz, &unused );
		__m256 dx = _mm256_sub_ps( bx, ax ), dy = _mm256_sub_ps( by, ay ), dz = _mm256_sub_ps( bz, az );
		__m256 len = norm3_8( dx, dy, dz );
		__m256 inv = _mm256_and_ps( _mm256_cmp_ps( len, zero, _CMP_GT_OQ ), _mm256_div_ps( one, len ) );
		__m256 nx = _mm256_mul_ps( dx, inv ), ny = _mm256_mul_ps( dy, inv ), nz = _mm256_mul_ps( dz, inv );
		__m256 rest = _mm256_mul_ps( load_rest8( rest0, s, lanes ), keep );
		__m256 strain = _mm256_div_ps( _mm256_sub_ps( len, rest ), rest );
		__m256 rvx = _mm256_sub_ps( bvx, avx ), rvy = _mm256_sub_ps( bvy, avy ), rvz = _mm256_sub_ps( bvz, avz );
		__m256 along = _mm256_add_ps( _mm256_add_ps( _mm256_mul_ps( rvx, nx ), _mm256_mul_ps( rvy, ny ) ),
									  _mm256_mul_ps( rvz, nz ) );
		__m256 f = _mm256_add_ps( _mm256_mul_ps( k, strain ), _mm256_mul_ps( c, along ) );
		_mm256_maskstore_ps( fx + s, m, _mm256_mul_ps( f, nx ) );
		_mm256_maskstore_ps( fy + s, m, _mm256_mul_ps( f, ny ) );
		_mm256_maskstore_ps( fz + s, m, _mm256_mul_ps( f, nz ) );
	}
#else
#pragma omp for schedule( static )
	for ( int32_t s = first; s < first + count; ++s )
	{
		const float* a = xr + 4 * sa[s];
		const float* b = xr + 4 * sb[s];
		const float* va = vr + 4 * sa[s];
		const float* vb = vr + 4 * sb[s];
		float dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
		float len = sqrtf( ( dx * dx + dy * dy ) + dz * dz );
		float inv = len > 0.0f ? 1.0f / len : 0.0f;
		float nx = dx * inv, ny = dy * inv, nz = dz * inv;
		float rest = rest0[s] * law.keep;
		float strain = ( len - rest ) / rest;
		float along = ( ( vb[0] - va[0] ) * nx + ( vb[1] - va[1] ) * ny ) + ( vb[2] - va[2] ) * nz;
		float f = law.k * strain + law.c * along;
		fx[s] = f * nx;
		fy[s] = f * ny;
		fz[s] = f * nz;
	}
#endif
}

/* Eq. 1: every particle gathers its springs' forces in a fixed order, then a = g + F/m,
 * v ← (1 − drag)(v + a Δt), in the velocity records. */
static void integrate_velocities( sere_massspring* ms, int32_t count, const sere_ms_params* params )
{
	const int32_t* restrict offsets = ms->incidence_offsets;
	const int32_t* restrict incidence = ms->incidence;
	const float* restrict sign = ms->incidence_sign;
	const float* restrict fx = ms->fx;
	const float* restrict fy = ms->fy;
	const float* restrict fz = ms->fz;
	const float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
	const float dt = params->dt, keep = 1.0f - params->drag;
	const float gx = params->gravity[0], gy = params->gravity[1], gz = params->gravity[2];
#pragma omp for schedule( static )
	for ( int32_t i = 0; i < count; ++i )
	{
		float sx = 0.0f, sy = 0.0f, sz = 0.0f;
		for ( int32_t e = offsets[i]; e < offsets[i + 1]; ++e )
		{
			const int32_t s = incidence[e];
			sx += sign[e] * fx[s];
			sy += sign[e] * fy[s];
			sz += sign[e] * fz[s];
		}
		const float w = xr[4 * i + 3];
		float* v = vr + 4 * i;
		if ( w > 0.0f )
		{
			v[0] = ( v[0] + dt * ( gx + w * sx ) ) * keep;
			v[1] = ( v[1] + dt * ( gy + w * sy ) ) * keep;
			v[2] = ( v[2] + dt * ( gz + w * sz ) ) * keep;
		}
		else
		{
			v[0] = 0.0f;
			v[1] = 0.0f;
			v[2] = 0.0f;
		}
	}
}

/* Eq. 2 on one run of structural springs [first, first + count), by the calling thread: no two
 * of them share a particle, so they are limited at the same time (16, or 8 with AVX, to a SIMD step). Each spring off
 * [lo_factor L, hi_factor L] gets its relative velocity changed along p = x_ab + v_ab Δt so that |p| lands on the
 * nearer bound. Raises *worst_io to the largest distance off the band (relative to L) this thread found before
 * correcting and adds the number of its springs that were off to *off_band. */
static void limit_run( sere_massspring* ms, int32_t first, int32_t count, float keep, float lo_factor, float hi_factor,
					   float dt, float* worst_io, int32_t* off_band )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
	float worst = *worst_io;
	int32_t n = 0;
#if defined( __AVX512F__ )
	const int32_t chunks = ( count + 15 ) / 16;
	const __m512 vkeep = _mm512_set1_ps( keep ), vlo = _mm512_set1_ps( lo_factor ), vhi = _mm512_set1_ps( hi_factor );
	const __m512 vdt = _mm512_set1_ps( dt ), one = _mm512_set1_ps( 1.0f ), zero = _mm512_setzero_ps();
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + 16 * chunk;
		int32_t ia[16], ib[16];
		const int32_t lanes = chunk_ends( sa, sb, s, count - 16 * chunk, ia, ib );
		const __mmask16 m = (__mmask16) ( ( 1u << lanes ) - 1u );
		__m512 ax, ay, az, wa, bx, by, bz, wb, avx, avy, avz, avw, bvx, bvy, bvz, bvw;
		load16( xr, ia, &ax, &ay, &az, &wa );
		load16( xr, ib, &bx, &by, &bz, &wb );
		load16( vr, ia, &avx, &avy, &avz, &avw );
		load16( vr, ib, &bvx, &bvy, &bvz, &bvw );
		__m512 px = _mm512_add_ps( _mm512_sub_ps( bx, ax ), _mm512_mul_ps( vdt, _mm512_sub_ps( bvx, avx ) ) );
		__m512 py = _mm512_add_ps( _mm512_sub_ps( by, ay ), _mm512_mul_ps( vdt, _mm512_sub_ps( bvy, avy ) ) );
		__m512 pz = _mm512_add_ps( _mm512_sub_ps( bz, az ), _mm512_mul_ps( vdt, _mm512_sub_ps( bvz, avz ) ) );
		__m512 len = norm3( px, py, pz );
		__m512 rest = _mm512_mul_ps( _mm512_mask_loadu_ps( one, m, rest0 + s ), vkeep );
		__m512 target = _mm512_min_ps( _mm512_max_ps( len, _mm512_mul_ps( rest, vlo ) ), _mm512_mul_ps( rest, vhi ) );
		__m512 off = _mm512_sub_ps( len, target );
		__mmask16 violated = _mm512_mask_cmp_ps_mask( m, off, zero, _CMP_NEQ_UQ );
		if ( violated == 0 )
		{
			continue;
		}
		n += __builtin_popcount( violated );
		worst = fmaxf( worst, _mm512_mask_reduce_max_ps( violated, _mm512_div_ps( _mm512_abs_ps( off ), rest ) ) );
		__m512 w = _mm512_add_ps( wa, wb );
		__mmask16 move =
			_mm512_mask_cmp_ps_mask( _mm512_mask_cmp_ps_mask( violated, w, zero, _CMP_GT_OQ ), len, zero, _CMP_GT_OQ );
		__m512 scale = _mm512_maskz_div_ps( move, off, _mm512_mul_ps( _mm512_mul_ps( len, vdt ), w ) );
		__m512 sa_ = _mm512_mul_ps( wa, scale ), sb_ = _mm512_mul_ps( wb, scale );
		store16( vr, ia, lanes, _mm512_add_ps( avx, _mm512_mul_ps( sa_, px ) ),
				 _mm512_add_ps( avy, _mm512_mul_ps( sa_, py ) ), _mm512_add_ps( avz, _mm512_mul_ps( sa_, pz ) ), avw );
		store16( vr, ib, lanes, _mm512_sub_ps( bvx, _mm512_mul_ps( sb_, px ) ),
				 _mm512_sub_ps( bvy, _mm512_mul_ps( sb_, py ) ), _mm512_sub_ps( bvz, _mm512_mul_ps( sb_, pz ) ), bvw );
	}
#elif defined( __AVX__ )
	const int32_t chunks = ( count + 7 ) / 8;
	const __m256 vkeep = _mm256_set1_ps( keep ), vlo = _mm256_set1_ps( lo_factor ), vhi = _mm256_set1_ps( hi_factor );
	const __m256 vdt = _mm256_set1_ps( dt ), zero = _mm256_setzero_ps();
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + 8 * chunk;
		int32_t ia[8], ib[8];
		const int32_t lanes = chunk_ends8( sa, sb, s, count - 8 * chunk, ia, ib );
		const __m256 m = _mm256_castsi256_ps( lane_mask8( lanes ) );
		__m256 ax, ay, az, wa, bx, by, bz, wb, avx, avy, avz, avw, bvx, bvy, bvz, bvw;
		load8( xr, ia, &ax, &ay, &az, &wa );
		load8( xr, ib, &bx, &by, &bz, &wb );
		load8( vr, ia, &avx, &avy, &avz, &avw );
		load8( vr, ib, &bvx, &bvy, &bvz, &bvw );
		__m256 px = _mm256_add_ps( _mm256_sub_ps( bx, ax ), _mm256_mul_ps( vdt, _mm256_sub_ps( bvx, avx ) ) );
		__m256 py = _mm256_add_ps( _mm256_sub_ps( by, ay ), _mm256_mul_ps( vdt, _mm256_sub_ps( bvy, avy ) ) );
		__m256 pz = _mm256_add_ps( _mm256_sub_ps( bz, az ), _mm256_mul_ps( vdt, _mm256_sub_ps( bvz, avz ) ) );
		__m256 len = norm3_8( px, py, pz );
		__m256 rest = _mm256_mul_ps( load_rest8( rest0, s, lanes ), vkeep );
		__m256 target = _mm256_min_ps( _mm256_max_ps( len, _mm256_mul_ps( rest, vlo ) ), _mm256_mul_ps( rest, vhi ) );
		__m256 off = _mm256_sub_ps( len, target );
		__m256 violated = _mm256_and_ps( m, _mm256_cmp_ps( off, zero, _CMP_NEQ_UQ ) );
		int violated_bits = _mm256_movemask_ps( violated );
		if ( violated_bits == 0 )
		{
			continue;
		}
		n += __builtin_popcount( (unsigned) violated_bits );
		worst = fmaxf( worst, masked_max8( _mm256_div_ps( abs8( off ), rest ), violated ) );
		__m256 w = _mm256_add_ps( wa, wb );
		__m256 move = _mm256_and_ps( _mm256_and_ps( violated, _mm256_cmp_ps( w, zero, _CMP_GT_OQ ) ),
									 _mm256_cmp_ps( len, zero, _CMP_GT_OQ ) );
		__m256 scale = _mm256_and_ps( move, _mm256_div_ps( off, _mm256_mul_ps( _mm256_mul_ps( len, vdt ), w ) ) );
		__m256 sa_ = _mm256_mul_ps( wa, scale ), sb_ = _mm256_mul_ps( wb, scale );
		store8( vr, ia, lanes, _mm256_add_ps( avx, _mm256_mul_ps( sa_, px ) ),
				_mm256_add_ps( avy, _mm256_mul_ps( sa_, py ) ), _mm256_add_ps( avz, _mm256_mul_ps( sa_, pz ) ), avw );
		store8( vr, ib, lanes, _mm256_sub_ps( bvx, _mm256_mul_ps( sb_, px ) ),
				_mm256_sub_ps( bvy, _mm256_mul_ps( sb_, py ) ), _mm256_sub_ps( bvz, _mm256_mul_ps( sb_, pz ) ), bvw );
	}
#else
	for ( int32_t s = first; s < first + count; ++s )
	{
		const float* a = xr + 4 * sa[s];
		const float* b = xr + 4 * sb[s];
		float* va = vr + 4 * sa[s];
		float* vb = vr + 4 * sb[s];
		float px = ( b[0] - a[0] ) + dt * ( vb[0] - va[0] );
		float py = ( b[1] - a[1] ) + dt * ( vb[1] - va[1] );
		float pz = ( b[2] - a[2] ) + dt * ( vb[2] - va[2] );
		float len = sqrtf( ( px * px + py * py ) + pz * pz );
		float rest = rest0[s] * keep;
		float target = len < rest * lo_factor ? rest * lo_factor : ( len > rest * hi_factor ? rest * hi_factor : len );
		float off = len - target;
		if ( off == 0.0f )
		{
			continue;
		}
		n += 1;
		float rel = fabsf( off ) / rest;
		worst = rel > worst ? rel : worst;
		float w = a[3] + b[3];
		float scale = w > 0.0f && len > 0.0f ? off / ( ( len * dt ) * w ) : 0.0f;
		float sa_ = a[3] * scale, sb_ = b[3] * scale;
		va[0] = va[0] + sa_ * px;
		va[1] = va[1] + sa_ * py;
		va[2] = va[2] + sa_ * pz;
		vb[0] = vb[0] - sb_ * px;
		vb[1] = vb[1] - sb_ * py;
		vb[2] = vb[2] - sb_ * pz;
	}
#endif
	*worst_io = worst;
	*off_band += n;
}

/* This thread's share of the structural springs' extremes after the step, with p = x_ab + v_ab Δt
 * computed exactly as the position update will compute it: the largest excess of |p|/L beyond
 * [1 − τ, 1 + τ] (≤ 0 when all are inside) and the largest | |p|/L − 1 |. */
static void band_measure( const sere_massspring* ms, float keep, float tau, float dt, float* excess_out,
						  float* strain_out )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	const float* restrict vr = ms->vrec;
	float excess = -1.0f, strain = 0.0f;
#if defined( __AVX512F__ )
	const int32_t count = ms->structural_count;
	const int32_t chunks = ( count + 15 ) / 16;
	const __m512 vkeep = _mm512_set1_ps( keep ), vdt = _mm512_set1_ps( dt ), one = _mm512_set1_ps( 1.0f );
	const __m512 hi = _mm512_set1_ps( 1.0f + tau ), lo = _mm512_set1_ps( 1.0f - tau );
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = 16 * chunk;
		int32_t ia[16], ib[16];
		const int32_t lanes = chunk_ends( sa, sb, s, count - s, ia, ib );
		const __mmask16 m = (__mmask16) ( ( 1u << lanes ) - 1u );
		__m512 ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		load16( xr, ia, &ax, &ay, &az, &aw );
		load16( xr, ib, &bx, &by, &bz, &bw );
		load16( vr, ia, &avx, &avy, &avz, &unused );
		load16( vr, ib, &bvx, &bvy, &bvz, &unused );
		__m512 px = _mm512_sub_ps( _mm512_add_ps( bx, _mm512_mul_ps( bvx, vdt ) ),
								   _mm512_add_ps( ax, _mm512_mul_ps( avx, vdt ) ) );
		__m512 py = _mm512_sub_ps( _mm512_add_ps( by, _mm512_mul_ps( bvy, vdt ) ),
								   _mm512_add_ps( ay, _mm512_mul_ps( avy, vdt ) ) );
		__m512 pz = _mm512_sub_ps( _mm512_add_ps( bz, _mm512_mul_ps( bvz, vdt ) ),
								   _mm512_add_ps( az, _mm512_mul_ps( avz, vdt ) ) );
		__m512 ratio =
			_mm512_div_ps( norm3( px, py, pz ), _mm512_mul_ps( _mm512_mask_loadu_ps( one, m, rest0 + s ), vkeep ) );
		__m512 out = _mm512_max_ps( _mm512_sub_ps( ratio, hi ), _mm512_sub_ps( lo, ratio ) );
		excess = fmaxf( excess, _mm512_mask_reduce_max_ps( m, out ) );
		strain = fmaxf( strain, _mm512_mask_reduce_max_ps( m, _mm512_abs_ps( _mm512_sub_ps( ratio, one ) ) ) );
	}
#elif defined( __AVX__ )
	const int32_t count = ms->structural_count;
	const int32_t chunks = ( count + 7 ) / 8;
	const __m256 vkeep = _mm256_set1_ps( keep ), vdt = _mm256_set1_ps( dt ), one = _mm256_set1_ps( 1.0f );
	const __m256 hi = _mm256_set1_ps( 1.0f + tau ), lo = _mm256_set1_ps( 1.0f - tau );
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = 8 * chunk;
		int32_t ia[8], ib[8];
		const int32_t lanes = chunk_ends8( sa, sb, s, count - s, ia, ib );
		const __m256 m = _mm256_castsi256_ps( lane_mask8( lanes ) );
		__m256 ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		load8( xr, ia, &ax, &ay, &az, &aw );
		load8( xr, ib, &bx, &by, &bz, &bw );
		load8( vr, ia, &avx, &avy, &avz, &unused );
		load8( vr, ib, &bvx, &bvy, &bvz, &unused );
		__m256 px = _mm256_sub_ps( _mm256_add_ps( bx, _mm256_mul_ps( bvx, vdt ) ),
								   _mm256_add_ps( ax, _mm256_mul_ps( avx, vdt ) ) );
		__m256 py = _mm256_sub_ps( _mm256_add_ps( by, _mm256_mul_ps( bvy, vdt ) ),
								   _mm256_add_ps( ay, _mm256_mul_ps( avy, vdt ) ) );
		__m256 pz = _mm256_sub_ps( _mm256_add_ps( bz, _mm256_mul_ps( bvz, vdt ) ),
								   _mm256_add_ps( az, _mm256_mul_ps( avz, vdt ) ) );
		__m256 ratio = _mm256_div_ps( norm3_8( px, py, pz ), _mm256_mul_ps( load_rest8( rest0, s, lanes ), vkeep ) );
		__m256 out = _mm256_max_ps( _mm256_sub_ps( ratio, hi ), _mm256_sub_ps( lo, ratio ) );
		excess = fmaxf( excess, masked_max8( out, m ) );
		strain = fmaxf( strain, masked_max8( abs8( _mm256_sub_ps( ratio, one ) ), m ) );
	}
#else
#pragma omp for schedule( static )
	for ( int32_t s = 0; s < ms->structural_count; ++s )
	{
		const float* a = xr + 4 * sa[s];
		const float* b = xr + 4 * sb[s];
		const float* va = vr + 4 * sa[s];
		const float* vb = vr + 4 * sb[s];
		float px = ( b[0] + vb[0] * dt ) - ( a[0] + va[0] * dt );
		float py = ( b[1] + vb[1] * dt ) - ( a[1] + va[1] * dt );
		float pz = ( b[2] + vb[2] * dt ) - ( a[2] + va[2] * dt );
		float ratio = sqrtf( ( px * px + py * py ) + pz * pz ) / ( rest0[s] * keep );
		float out = ratio - ( 1.0f + tau ) > ( 1.0f - tau ) - ratio ? ratio - ( 1.0f + tau ) : ( 1.0f - tau ) - ratio;
		excess = out > excess ? out : excess;
		float dev = fabsf( ratio - 1.0f );
		strain = dev > strain ? dev : strain;
	}
#endif
	*excess_out = excess;
	*strain_out = strain;
}

sere_status sere_massspring_step( sere_massspring* ms, sere_ms_particles* p, const sere_ms_params* params,
								  sere_ms_report* report )
{
	if ( ms == NULL || p == NULL || params == NULL || p->count != ms->vertex_count || p->x == NULL || p->y == NULL ||
		 p->z == NULL || p->vx == NULL || p->vy == NULL || p->vz == NULL || p->inv_m == NULL ||
		 !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0, negative = 0;
#pragma omp parallel for schedule( static ) reduction( | : bad, negative )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		bad |= !isfinite( p->x[i] ) | !isfinite( p->y[i] ) | !isfinite( p->z[i] ) | !isfinite( p->vx[i] ) |
			   !isfinite( p->vy[i] ) | !isfinite( p->vz[i] ) | !isfinite( p->inv_m[i] );
		negative |= p->inv_m[i] < 0.0f;
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( negative )
	{
		return SERE_ERR_ARGUMENT;
	}

	const float keep = 1.0f - params->shrink;
	const spring_law structural = { keep, params->stiffness, params->damping };
	const spring_law flexion = { 1.0f - params->curl, params->bend_stiffness, params->damping };
	const float dt = params->dt, tau = params->strain_limit, tolerance = params->strain_tolerance;
	/* The sweeps aim at the band narrowed by the tolerance on both sides, so that once no
	 * spring is off that inner band by more than the tolerance, all are inside the true band. */
	const float inner_lo = 1.0f - tau + tolerance, inner_hi = 1.0f + tau - tolerance;
	float sweep_worst = 0.0f, excess = 0.0f, final_strain = 0.0f;
	int32_t sweeps = 0, limited = 0, sweep_limited = 0;
	int converged = 0;

#pragma omp parallel
	{
		pack( ms, p );
		spring_forces( ms, 0, ms->structural_count, structural );
		spring_forces( ms, ms->structural_count, ms->flexion_count, flexion );
		integrate_velocities( ms, p->count, params );

		for ( int32_t sweep = 0; sweep < params->max_sweeps; ++sweep )
		{
#pragma omp single
			{
				sweep_worst = 0.0f;
				sweep_limited = 0;
				excess = -1.0f;
				final_strain = 0.0f;
			}
			float mine = 0.0f;
			int32_t mine_limited = 0;
			/* The bands, then the even cuts, then the odd ones (items [0, R), [R, R + E),
			 * [R + E, 2R − 1)): within a phase the items share no particle. */
			const int32_t bands = ms->band_count, colors = ms->color_count, even = bands / 2;
			const int32_t phase_start[4] = { 0, bands, bands + even, 2 * bands - 1 };
			for ( int phase = 0; phase < 3; ++phase )
			{
#pragma omp for schedule( static )
				for ( int32_t item = phase_start[phase]; item < phase_start[phase + 1]; ++item )
				{
					for ( int32_t c = 0; c < colors; ++c )
					{
						const int32_t* run = ms->run_offsets + item * colors + c;
						limit_run( ms, run[0], run[1] - run[0], keep, inner_lo, inner_hi, dt, &mine, &mine_limited );
					}
				}
			}
			/* A maximum and an integer sum: the same in any order of the threads. */
#pragma omp critical( sere_massspring_worst )
			{
				sweep_worst = fmaxf( sweep_worst, mine );
				sweep_limited += mine_limited;
			}
#pragma omp barrier
			/* Every thread reads the same values, so every thread takes the same branches. A
			 * sweep's corrections can nudge springs it limited earlier, so a quiet sweep is
			 * confirmed by measuring the true band before stopping. */
			int done = sweep_worst <= tolerance;
			if ( done )
			{
				float own_excess, own_strain;
				band_measure( ms, keep, tau, dt, &own_excess, &own_strain );
#pragma omp critical( sere_massspring_worst )
				{
					excess = fmaxf( excess, own_excess );
					final_strain = fmaxf( final_strain, own_strain );
				}
#pragma omp barrier
				done = excess <= 0.0f;
			}
#pragma omp single
			{
				sweeps = sweep + 1;
				if ( sweep == 0 )
				{
					limited = sweep_limited;
				}
				converged = done;
			}
			if ( done )
			{
				break;
			}
		}
		if ( !converged )
		{
			float own_excess, own_strain;
			band_measure( ms, keep, tau, dt, &own_excess, &own_strain );
#pragma omp critical( sere_massspring_worst )
			final_strain = fmaxf( final_strain, own_strain );
		}

		const float* restrict vr = ms->vrec;
#pragma omp for schedule( static )
		for ( int32_t i = 0; i < p->count; ++i )
		{
			p->vx[i] = vr[4 * i];
			p->vy[i] = vr[4 * i + 1];
			p->vz[i] = vr[4 * i + 2];
			p->x[i] = p->x[i] + vr[4 * i] * dt;
			p->y[i] = p->y[i] + vr[4 * i + 1] * dt;
			p->z[i] = p->z[i] + vr[4 * i + 2] * dt;
		}
	}

	if ( report != NULL )
	{
		report->sweeps = sweeps;
		report->limited = limited;
		report->max_strain = final_strain;
		report->hit_cap = !converged;
	}
	return converged ? SERE_OK : SERE_ERR_NO_CONVERGE;
}
