/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "mesh/measure.h"

#include "core/internal/team.h"
#include "mesh/internal/measure_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Edge–triangle crossings: the exact segment–triangle test and the grid that finds the pairs
 * worth testing. */

bool sere_segment_crosses_triangle( const double p_in[3], const double q_in[3], const double a[3], const double b[3],
									const double c[3] )
{
	/* The edge volumes round differently from either end, so take the ends in a fixed
	 * (lexicographic) order: then the answer does not depend on how the caller orders them. */
	bool swap = p_in[0] != q_in[0] ? p_in[0] > q_in[0] : ( p_in[1] != q_in[1] ? p_in[1] > q_in[1] : p_in[2] > q_in[2] );
	const double* p = swap ? q_in : p_in;
	const double* q = swap ? p_in : q_in;
	/* Boxes first: every true crossing has overlapping boxes, and requiring it here makes the
	 * answers on near-degenerate input (where the volumes below are rounding noise) the same
	 * for the brute force and for the grid, which never looks at pairs with disjoint boxes. */
	for ( int k = 0; k < 3; ++k )
	{
		double lo = p[k] < q[k] ? p[k] : q[k], hi = p[k] < q[k] ? q[k] : p[k];
		double tlo = a[k] < b[k] ? a[k] : b[k], thi = a[k] < b[k] ? b[k] : a[k];
		tlo = c[k] < tlo ? c[k] : tlo, thi = c[k] > thi ? c[k] : thi;
		if ( tlo > hi || thi < lo )
		{
			return false;
		}
	}
	double ab[3], ac[3], n[3], ap[3], aq[3];
	sub3( b, a, ab );
	sub3( c, a, ac );
	cross3( ab, ac, n );
	sub3( p, a, ap );
	sub3( q, a, aq );
	double side_p = dot3( n, ap ), side_q = dot3( n, aq );
	if ( !( ( side_p > 0.0 && side_q < 0.0 ) || ( side_p < 0.0 && side_q > 0.0 ) ) )
	{
		return false;
	}
	/* The edge volumes are antisymmetric in the edge's ends (the cross product negates exactly),
	 * so the two triangles of a shared edge see the same volume with opposite signs there. */
	double d[3], corner[3][3];
	sub3( q, p, d );
	sub3( a, p, corner[0] );
	sub3( b, p, corner[1] );
	sub3( c, p, corner[2] );
	double volume[3];
	for ( int k = 0; k < 3; ++k )
	{
		double w[3];
		cross3( corner[k], corner[k == 2 ? 0 : k + 1], w );
		volume[k] = dot3( d, w );
	}
	return ( volume[0] > 0.0 && volume[1] > 0.0 && volume[2] > 0.0 ) ||
		   ( volume[0] < 0.0 && volume[1] < 0.0 && volume[2] < 0.0 );
}

bool sere_edge_crosses_triangle( const double p[3], const double q[3], int32_t ea, int32_t eb, const int32_t v[3],
								 const float* x, const float* y, const float* z )
{
	if ( v[0] == ea || v[1] == ea || v[2] == ea || v[0] == eb || v[1] == eb || v[2] == eb )
	{
		return false;
	}
	double a[3] = { x[v[0]], y[v[0]], z[v[0]] };
	double b[3] = { x[v[1]], y[v[1]], z[v[1]] };
	double c[3] = { x[v[2]], y[v[2]], z[v[2]] };
	return sere_segment_crosses_triangle( p, q, a, b, c );
}

typedef struct crossing_box
{
	float lo[3], hi[3];
} crossing_box;

/* A cell's entries come in 8 groups by which axes of the cell hold the low corner of the
 * triangle's box: bit 2 for x, 1 for y, 0 for z set when the box starts in this cell's slab
 * along that axis. z last: a flat leaf is one slab thick, so its groups an edge reads are
 * consecutive more often. */
enum
{
	kGroups = 8
};

struct sere_crossings
{
	int32_t threads; /* sere_crossings_set_threads */
	int32_t triangle_count;
	int32_t vertex_count;
	int32_t edge_count;
	int32_t* tri;
	int32_t *edge_a, *edge_b;
	crossing_box* box; /* per triangle, at the current positions */
	/* The grid: the triangles of group g overlapping cell c are entry[cell_start[kGroups c + g] ..
	 * cell_start[kGroups c + g + 1] − 1] */
	int32_t cell_capacity;
	int32_t entry_capacity;
	int32_t* cell_start;
	/* Each entry is a triangle as listed in one cell, with everything the edge loop reads
	 * before the predicate, in columns (so a run of entries is tested in vectors): its box
	 * (lo x, y, z, then hi x, y, z) and its corners. */
	float* entry_box[6];
	int32_t* entry_v[3];
};

/* A uniform grid over the bounds of the triangles; cell coordinates clamp to the grid, so the
 * map from a coordinate to its cell is monotone, which the one-cell-per-pair rule relies on. */
typedef struct crossing_grid
{
	double lo[3];
	double inv_h;
	int32_t n[3];
} crossing_grid;

static inline int32_t grid_cell( const crossing_grid* g, int axis, float x )
{
	double c = floor( ( (double) x - g->lo[axis] ) * g->inv_h );
	if ( !( c > 0.0 ) )
	{
		return 0;
	}
	return c >= (double) ( g->n[axis] - 1 ) ? g->n[axis] - 1 : (int32_t) c;
}

static int compare_u64( const void* a, const void* b )
{
	uint64_t u = *(const uint64_t*) a, v = *(const uint64_t*) b;
	return ( u > v ) - ( u < v );
}

/* The unique undirected edges of the triangles, sorted by (smaller end, larger end), without
 * edges whose two ends are one index. Returns the count, or −1 when allocation fails; *a, *b are
 * then NULL. Shared with the reference twin's contract (it extracts the same set). */
static int32_t unique_edges( const int32_t* tri, int32_t triangle_count, int32_t** a, int32_t** b )
{
	*a = NULL, *b = NULL;
	size_t capacity = 3 * (size_t) triangle_count;
	uint64_t* key = malloc( sizeof( uint64_t ) * ( capacity > 0 ? capacity : 1 ) );
	if ( key == NULL )
	{
		return -1;
	}
	size_t count = 0;
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			uint32_t i = (uint32_t) tri[3 * (size_t) t + k], j = (uint32_t) tri[3 * (size_t) t + ( k + 1 ) % 3];
			if ( i != j )
			{
				key[count++] = i < j ? ( (uint64_t) i << 32 ) | j : ( (uint64_t) j << 32 ) | i;
			}
		}
	}
	qsort( key, count, sizeof( uint64_t ), compare_u64 );
	size_t unique = 0;
	for ( size_t k = 0; k < count; ++k )
	{
		if ( unique == 0 || key[k] != key[unique - 1] )
		{
			key[unique++] = key[k];
		}
	}
	*a = sere_alloc( sizeof( int32_t ) * (size_t) sere_pad( (int32_t) unique + 1 ) );
	*b = sere_alloc( sizeof( int32_t ) * (size_t) sere_pad( (int32_t) unique + 1 ) );
	if ( *a == NULL || *b == NULL )
	{
		sere_free( *a );
		sere_free( *b );
		*a = NULL, *b = NULL;
		free( key );
		return -1;
	}
	for ( size_t k = 0; k < unique; ++k )
	{
		( *a )[k] = (int32_t) ( key[k] >> 32 );
		( *b )[k] = (int32_t) ( key[k] & 0xffffffffu );
	}
	free( key );
	return (int32_t) unique;
}

void sere_crossings_destroy( sere_crossings* c )
{
	if ( c == NULL )
	{
		return;
	}
	sere_free( c->tri );
	sere_free( c->edge_a );
	sere_free( c->edge_b );
	sere_free( c->box );
	sere_free( c->cell_start );
	for ( int k = 0; k < 6; ++k )
	{
		sere_free( c->entry_box[k] );
	}
	for ( int k = 0; k < 3; ++k )
	{
		sere_free( c->entry_v[k] );
	}
	free( c );
}

sere_status sere_crossings_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count,
								   sere_crossings** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	/* 3 T triangle indices and 8 T + 64 grid entries, and a block's step (16) past the last
	 * (crossings_run), must fit in int32 */
	if ( tri == NULL || triangle_count <= 0 || vertex_count <= 0 || triangle_count > ( INT32_MAX - 128 ) / 8 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( size_t k = 0; k < 3 * (size_t) triangle_count; ++k )
	{
		if ( tri[k] < 0 || tri[k] >= vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	sere_crossings* c = calloc( 1, sizeof( sere_crossings ) );
	if ( c == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	c->triangle_count = triangle_count;
	c->vertex_count = vertex_count;
	/* A sheet of T triangles of the mean size fills about T / 2 cells of that size, and a
	 * triangle's box overlaps up to 2 × 2 × 2 of them; four times those leave room for a
	 * crumpled sheet before the count has to coarsen the grid. */
	c->cell_capacity = 4 * triangle_count + 64;
	c->entry_capacity = 8 * triangle_count + 64;
	size_t tri_bytes = sizeof( int32_t ) * 3 * (size_t) triangle_count;
	c->tri = sere_alloc( tri_bytes );
	c->box = sere_alloc( sizeof( crossing_box ) * (size_t) triangle_count );
	c->cell_start = sere_alloc( sizeof( int32_t ) * ( kGroups * (size_t) c->cell_capacity + 1 ) );
	int failed = c->tri == NULL || c->box == NULL || c->cell_start == NULL;
	for ( int k = 0; k < 6; ++k )
	{
		c->entry_box[k] = sere_alloc( sizeof( float ) * (size_t) c->entry_capacity );
		failed |= c->entry_box[k] == NULL;
	}
	for ( int k = 0; k < 3; ++k )
	{
		c->entry_v[k] = sere_alloc( sizeof( int32_t ) * (size_t) c->entry_capacity );
		failed |= c->entry_v[k] == NULL;
	}
	if ( failed )
	{
		sere_crossings_destroy( c );
		return SERE_ERR_MEMORY;
	}
	memcpy( c->tri, tri, tri_bytes );
	c->edge_count = unique_edges( tri, triangle_count, &c->edge_a, &c->edge_b );
	if ( c->edge_count < 0 )
	{
		sere_crossings_destroy( c );
		return SERE_ERR_MEMORY;
	}
	*out = c;
	return SERE_OK;
}

/* Boxes of the triangles and the grid for them; false when a used position is not finite. */
static bool crossings_boxes( sere_crossings* c, const float* x, const float* y, const float* z, crossing_grid* g )
{
	int32_t tc = c->triangle_count;
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	double side_sum = 0.0;
	/* Sequential: a few operations per triangle, and the grid (not that it could change the
	 * count) is then the same for any thread count. */
	for ( int32_t t = 0; t < tc; ++t )
	{
		const int32_t* v = c->tri + 3 * (size_t) t;
		float p[3][3] = { { x[v[0]], y[v[0]], z[v[0]] }, { x[v[1]], y[v[1]], z[v[1]] }, { x[v[2]], y[v[2]], z[v[2]] } };
		float blo[3], bhi[3];
		float longest = 0.0f;
		for ( int a = 0; a < 3; ++a )
		{
			if ( !isfinite( p[0][a] ) || !isfinite( p[1][a] ) || !isfinite( p[2][a] ) )
			{
				return false;
			}
			/* finite from here on: plain comparisons give fminf's and fmaxf's answers
			 * without their NaN handling's library calls */
			blo[a] = p[0][a] < p[1][a] ? p[0][a] : p[1][a];
			blo[a] = p[2][a] < blo[a] ? p[2][a] : blo[a];
			bhi[a] = p[0][a] < p[1][a] ? p[1][a] : p[0][a];
			bhi[a] = p[2][a] > bhi[a] ? p[2][a] : bhi[a];
			lo[a] = blo[a] < lo[a] ? blo[a] : lo[a];
			hi[a] = bhi[a] > hi[a] ? bhi[a] : hi[a];
			longest = bhi[a] - blo[a] > longest ? bhi[a] - blo[a] : longest;
		}
		c->box[t] = ( crossing_box ){ { blo[0], blo[1], blo[2] }, { bhi[0], bhi[1], bhi[2] } };
		side_sum += longest;
	}
	double extent[3], largest = 0.0;
	for ( int a = 0; a < 3; ++a )
	{
		g->lo[a] = lo[a];
		extent[a] = (double) hi[a] - lo[a];
		largest = fmax( largest, extent[a] );
	}
	/* Cells the size of the mean triangle's longest box side, so a typical box overlaps a few
	 * cells and a cell holds a few triangles. */
	double h = side_sum / tc;
	if ( !( h > 0.0 ) )
	{
		h = largest > 0.0 ? largest : 1.0;
	}
	for ( ;; )
	{
		double cells = 1.0;
		for ( int a = 0; a < 3; ++a )
		{
			double n = floor( extent[a] / h ) + 1.0;
			cells *= n;
			g->n[a] = n < (double) c->cell_capacity ? (int32_t) n : c->cell_capacity;
		}
		g->inv_h = 1.0 / h;
		if ( cells > (double) c->cell_capacity )
		{
			/* too many cells for the buffer: grow the cell by the missing volume factor */
			h *= 1.01 * cbrt( cells / (double) c->cell_capacity );
			continue;
		}
		int64_t entries = 0;
		for ( int32_t t = 0; t < tc && entries <= c->entry_capacity; ++t )
		{
			const crossing_box* b = c->box + t;
			int64_t covered = 1;
			for ( int a = 0; a < 3; ++a )
			{
				covered *= grid_cell( g, a, b->hi[a] ) - grid_cell( g, a, b->lo[a] ) + 1;
			}
			entries += covered;
		}
		if ( entries > c->entry_capacity )
		{
			/* a few huge triangles (slivers flung far out) cover too many cells: coarsen; at
			 * one cell for everything there are exactly T entries, which always fit */
			h *= 1.5;
			continue;
		}
		return true;
	}
}

/* Counting sort of (cell and group, triangle) entries: cell_start[s] first counts the entries
 * of slots up to s, then each entry is placed by decrementing it, which leaves the start of
 * every slot. */
static void crossings_fill( sere_crossings* c, const crossing_grid* g )
{
	size_t slots = kGroups * (size_t) g->n[0] * (size_t) g->n[1] * (size_t) g->n[2];
	memset( c->cell_start, 0, sizeof( int32_t ) * ( slots + 1 ) );
	for ( int pass = 0; pass < 2; ++pass )
	{
		for ( int32_t t = 0; t < c->triangle_count; ++t )
		{
			const crossing_box* b = c->box + t;
			int32_t x0 = grid_cell( g, 0, b->lo[0] ), x1 = grid_cell( g, 0, b->hi[0] );
			int32_t y0 = grid_cell( g, 1, b->lo[1] ), y1 = grid_cell( g, 1, b->hi[1] );
			int32_t z0 = grid_cell( g, 2, b->lo[2] ), z1 = grid_cell( g, 2, b->hi[2] );
			const int32_t* v = c->tri + 3 * (size_t) t;
			for ( int32_t k = z0; k <= z1; ++k )
			{
				for ( int32_t j = y0; j <= y1; ++j )
				{
					for ( int32_t i = x0; i <= x1; ++i )
					{
						size_t cell = ( (size_t) k * g->n[1] + j ) * g->n[0] + i;
						size_t slot = kGroups * cell + 4 * ( i == x0 ) + 2 * ( j == y0 ) + ( k == z0 );
						if ( pass == 0 )
						{
							c->cell_start[slot] += 1;
							continue;
						}
						int32_t e = --c->cell_start[slot];
						for ( int a = 0; a < 3; ++a )
						{
							c->entry_box[a][e] = b->lo[a];
							c->entry_box[3 + a][e] = b->hi[a];
							c->entry_v[a][e] = v[a];
						}
					}
				}
			}
		}
		if ( pass == 0 )
		{
			for ( size_t slot = 1; slot <= slots; ++slot )
			{
				c->cell_start[slot] += c->cell_start[slot - 1];
			}
		}
	}
}

/* An edge as the grid loop tests it: its box, its ends in double for the predicate, their indices. */
typedef struct crossing_edge
{
	float lo[3], hi[3];
	double p[3], q[3];
	int32_t a, b;
} crossing_edge;

/* Entries first to last − 1 against the edge: the crossings among those whose box meets the
 * edge's and that share no corner with it. The filter runs in vectors over the columns, a block
 * at a time; the few entries it keeps (an edge's neighbours share its corners) go to the
 * predicate. */
static int64_t crossings_run( const sere_crossings* w, int32_t first, int32_t last, const crossing_edge* edge,
							  const float* x, const float* y, const float* z )
{
	enum
	{
		kBlock = 16
	};
	const float *lx = w->entry_box[0], *ly = w->entry_box[1], *lz = w->entry_box[2];
	const float *hx = w->entry_box[3], *hy = w->entry_box[4], *hz = w->entry_box[5];
	const int32_t *v0 = w->entry_v[0], *v1 = w->entry_v[1], *v2 = w->entry_v[2];
	const float elx = edge->lo[0], ely = edge->lo[1], elz = edge->lo[2];
	const float ehx = edge->hi[0], ehy = edge->hi[1], ehz = edge->hi[2];
	const int32_t a = edge->a, b = edge->b;
	int64_t found = 0;
	for ( int32_t s = first; s < last; s += kBlock )
	{
		int32_t m = last - s < kBlock ? last - s : kBlock;
		uint8_t keep[kBlock];
#pragma omp simd
		for ( int32_t k = 0; k < m; ++k )
		{
			int32_t i = s + k;
			int apart = ( lx[i] > ehx ) | ( hx[i] < elx ) | ( ly[i] > ehy ) | ( hy[i] < ely ) | ( lz[i] > ehz ) |
						( hz[i] < elz );
			int touching =
				( v0[i] == a ) | ( v1[i] == a ) | ( v2[i] == a ) | ( v0[i] == b ) | ( v1[i] == b ) | ( v2[i] == b );
			keep[k] = ( uint8_t ) !( apart | touching );
		}
		for ( int32_t k = 0; k < m; ++k )
		{
			if ( keep[k] )
			{
				const int32_t v[3] = { v0[s + k], v1[s + k], v2[s + k] };
				found += sere_edge_crosses_triangle( edge->p, edge->q, a, b, v, x, y, z );
			}
		}
	}
	return found;
}

sere_status sere_crossings_count( sere_crossings* c, const float* x, const float* y, const float* z, int64_t* count )
{
	if ( count != NULL )
	{
		*count = 0;
	}
	if ( c == NULL || x == NULL || y == NULL || z == NULL || count == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	crossing_grid grid;
	if ( !crossings_boxes( c, x, y, z, &grid ) )
	{
		return SERE_ERR_NONFINITE;
	}
	crossings_fill( c, &grid );
	const crossing_grid* g = &grid;
	const sere_crossings* w = c;
	int64_t total = 0;
#pragma omp parallel for num_threads( sere_team_for( w->threads ) ) schedule( dynamic, 256 ) reduction( + : total )
	for ( int32_t e = 0; e < w->edge_count; ++e )
	{
		int32_t ea = w->edge_a[e], eb = w->edge_b[e];
		/* every end is a triangle's corner, all finite (crossings_boxes): plain comparisons
		 * give fminf's and fmaxf's answers without their NaN handling's library calls */
		crossing_edge edge = {
			{ x[ea] < x[eb] ? x[ea] : x[eb], y[ea] < y[eb] ? y[ea] : y[eb], z[ea] < z[eb] ? z[ea] : z[eb] },
			{ x[ea] < x[eb] ? x[eb] : x[ea], y[ea] < y[eb] ? y[eb] : y[ea], z[ea] < z[eb] ? z[eb] : z[ea] },
			{ x[ea], y[ea], z[ea] },
			{ x[eb], y[eb], z[eb] },
			ea,
			eb,
		};
		int32_t x0 = grid_cell( g, 0, edge.lo[0] ), x1 = grid_cell( g, 0, edge.hi[0] );
		int32_t y0 = grid_cell( g, 1, edge.lo[1] ), y1 = grid_cell( g, 1, edge.hi[1] );
		int32_t z0 = grid_cell( g, 2, edge.lo[2] ), z1 = grid_cell( g, 2, edge.hi[2] );
		int64_t found = 0;
		for ( int32_t k = z0; k <= z1; ++k )
		{
			for ( int32_t j = y0; j <= y1; ++j )
			{
				for ( int32_t i = x0; i <= x1; ++i )
				{
					/* The pair is tested only in the cell holding the low corner of the
					 * overlap of the two boxes: that corner lies in both boxes, so exactly one
					 * cell both visit contains it; grid_cell is monotone, so its cell is the
					 * larger of the two low cells on each axis. Both boxes reach this cell, so
					 * on an axis where the edge's box starts before it, the triangle's must
					 * start in it: only the groups with those bits set are read, those next to
					 * one another as one run. */
					int need = 4 * ( i != x0 ) + 2 * ( j != y0 ) + ( k != z0 );
					const int32_t* start = w->cell_start + kGroups * ( ( (size_t) k * g->n[1] + j ) * g->n[0] + i );
					for ( int group = need; group < kGroups; )
					{
						int last = group;
						while ( last + 1 < kGroups && ( ( last + 1 ) | need ) == last + 1 )
						{
							last += 1;
						}
						found += crossings_run( w, start[group], start[last + 1], &edge, x, y, z );
						group = ( last + 1 ) | need; /* the next superset of need */
					}
				}
			}
		}
		total += found;
	}
	*count = total;
	return SERE_OK;
}

sere_status sere_crossings_set_threads( sere_crossings* crossings, int32_t threads )
{
	return crossings == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &crossings->threads, threads );
}

sere_status sere_crossings_count_once( const float* x, const float* y, const float* z, int32_t vertex_count,
									   const int32_t* tri, int32_t triangle_count, int64_t* count, int32_t threads )
{
	if ( count != NULL )
	{
		*count = 0;
	}
	sere_crossings* c;
	sere_status status = sere_crossings_create( tri, triangle_count, vertex_count, &c );
	if ( status != SERE_OK )
	{
		return status;
	}
	status = sere_crossings_set_threads( c, threads );
	status = status == SERE_OK ? sere_crossings_count( c, x, y, z, count ) : status;
	sere_crossings_destroy( c );
	return status;
}
