/* sere — building the mass-spring model of a triangle mesh (massspring.h): the structural and
 * flexion springs, the particle bands and colors a sweep limits them in, and the particle →
 * spring incidence the force gather reads. */
#include "season/internal/massspring_shared.h"

#include "core/array.h"
#include "solve/color.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

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

static sere_status validate_input( const float* x, const float* y, const float* z, int32_t vertex_count,
								   const int32_t* tri, int32_t triangle_count )
{
	if ( x == NULL || y == NULL || z == NULL || tri == NULL || vertex_count < 3 || triangle_count < 1 ||
		 triangle_count > INT32_MAX / 3 ) /* three sides a triangle, counted in int32_t */
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
	return SERE_OK;
}

/* Tang Sec. 4.2, steps 1–3: every pair of adjacent particles joined once. The triangle sides,
 * keyed by their undirected edge (lo << 32 | hi) with the triangle as index and the opposite
 * vertex as value, sorted so each edge's one (boundary) or two (interior) sides stand together.
 * A manifold mesh has no edge in three triangles and no two triangles on the same three points. */
static sere_status sorted_sides( const int32_t* tri, int32_t triangle_count, sere_sort_item* sides, int32_t* edges,
								 int32_t* hinges )
{
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			uint32_t p = (uint32_t) tri[3 * t + ( k + 1 ) % 3], q = (uint32_t) tri[3 * t + ( k + 2 ) % 3];
			uint64_t key = p < q ? ( (uint64_t) p << 32 ) | q : ( (uint64_t) q << 32 ) | p;
			sides[3 * t + k] = ( sere_sort_item ){ key, t, tri[3 * t + k] };
		}
	}
	int32_t side_count = 3 * triangle_count;
	sere_sort_items( sides, side_count );
	*edges = 0;
	*hinges = 0;
	sere_status status = SERE_OK;
	for ( int32_t k = 0; k < side_count; )
	{
		int32_t run = 1;
		while ( k + run < side_count && sides[k + run].key == sides[k].key )
		{
			++run;
		}
		if ( run > 2 || ( run == 2 && sides[k].value == sides[k + 1].value ) )
		{
			status = SERE_ERR_GEOMETRY;
		}
		*edges += 1;
		*hinges += run == 2;
		k += run;
	}
	return status;
}

static bool alloc_springs( sere_massspring* ms, int32_t edges, int32_t hinges, int32_t vertex_count )
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
	return ms->a != NULL && ms->b != NULL && ms->rest0 != NULL && ms->fx != NULL && ms->fy != NULL && ms->fz != NULL &&
		   ms->incidence_offsets != NULL && ms->incidence != NULL && ms->incidence_sign != NULL && ms->xrec != NULL &&
		   ms->vrec != NULL;
}

/* One structural spring per edge (into sa, sb, srest, colored and ordered later) and one flexion
 * spring per interior edge, across the hinge between the two opposite vertices (into ms). */
static sere_status fill_springs( sere_massspring* ms, const sere_sort_item* sides, int32_t side_count, const float* x,
								 const float* y, const float* z, int32_t* sa, int32_t* sb, float* srest )
{
	sere_status status = SERE_OK;
	int32_t e = 0, h = ms->structural_count;
	for ( int32_t k = 0; k < side_count; )
	{
		int32_t run = k + 1 < side_count && sides[k + 1].key == sides[k].key ? 2 : 1;
		sa[e] = (int32_t) ( sides[k].key >> 32 );
		sb[e] = (int32_t) ( sides[k].key & 0xffffffffu );
		srest[e] = distance( x, y, z, sa[e], sb[e] );
		if ( !( srest[e] > 0.0f ) )
		{
			status = SERE_ERR_GEOMETRY;
		}
		++e;
		if ( run == 2 )
		{
			int32_t c = sides[k].value, d = sides[k + 1].value;
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
	return status;
}

/* Each vertex's springs (CSR), with the sign of the spring's force there: the force f of spring
 * s pulls a toward b, +f at a and −f at b. */
static sere_status build_incidence( sere_massspring* ms )
{
	int32_t total = ms->structural_count + ms->flexion_count;
	int32_t vertex_count = ms->vertex_count;
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
		return SERE_ERR_MEMORY;
	}
	memcpy( fill, offsets, (size_t) vertex_count * sizeof( int32_t ) );
	for ( int32_t s = 0; s < total; ++s )
	{
		ms->incidence[fill[ms->a[s]]] = s;
		ms->incidence_sign[fill[ms->a[s]]++] = 1.0f;
		ms->incidence[fill[ms->b[s]]] = s;
		ms->incidence_sign[fill[ms->b[s]]++] = -1.0f;
	}
	free( fill );
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
	sere_status status = validate_input( x, y, z, vertex_count, tri, triangle_count );
	if ( status != SERE_OK )
	{
		return status;
	}
	sere_sort_item* sides = malloc( 3 * (size_t) triangle_count * sizeof( sere_sort_item ) );
	if ( sides == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	int32_t edges, hinges;
	status = sorted_sides( tri, triangle_count, sides, &edges, &hinges );
	sere_massspring* ms = status == SERE_OK ? calloc( 1, sizeof( sere_massspring ) ) : NULL;
	int32_t* sa = NULL;
	int32_t* sb = NULL;
	float* srest = NULL;
	sere_coloring coloring = { 0 };
	if ( status == SERE_OK )
	{
		sa = malloc( (size_t) edges * sizeof( int32_t ) );
		sb = malloc( (size_t) edges * sizeof( int32_t ) );
		srest = malloc( (size_t) edges * sizeof( float ) );
		if ( ms == NULL || !alloc_springs( ms, edges, hinges, vertex_count ) || sa == NULL || sb == NULL ||
			 srest == NULL )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	if ( status == SERE_OK )
	{
		status = fill_springs( ms, sides, 3 * triangle_count, x, y, z, sa, sb, srest );
	}
	free( sides );
	if ( status == SERE_OK )
	{
		status = sere_coloring_create( sa, sb, edges, vertex_count, &coloring );
	}
	if ( status == SERE_OK )
	{
		status = sweep_order( ms, sa, sb, srest, edges, vertex_count, &coloring );
	}
	if ( status == SERE_OK )
	{
		status = build_incidence( ms );
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

sere_massspring_topology sere_massspring_get_topology( const sere_massspring* ms )
{
	sere_massspring_topology t = { 0 };
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
