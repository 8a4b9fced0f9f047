#include "mesh/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Edge–triangle crossings */

static inline void sub3( const double u[3], const double v[3], double out[3] )
{
	out[0] = u[0] - v[0], out[1] = u[1] - v[1], out[2] = u[2] - v[2];
}

static inline void cross3( const double u[3], const double v[3], double out[3] )
{
	out[0] = u[1] * v[2] - u[2] * v[1];
	out[1] = u[2] * v[0] - u[0] * v[2];
	out[2] = u[0] * v[1] - u[1] * v[0];
}

static inline double dot3( const double u[3], const double v[3] )
{
	return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

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
	double d[3], pa[3], pb[3], pc[3], w[3];
	sub3( q, p, d );
	sub3( a, p, pa );
	sub3( b, p, pb );
	sub3( c, p, pc );
	cross3( pa, pb, w );
	double s0 = dot3( d, w );
	cross3( pb, pc, w );
	double s1 = dot3( d, w );
	cross3( pc, pa, w );
	double s2 = dot3( d, w );
	return ( s0 > 0.0 && s1 > 0.0 && s2 > 0.0 ) || ( s0 < 0.0 && s1 < 0.0 && s2 < 0.0 );
}

typedef struct crossing_box
{
	float lo[3], hi[3];
} crossing_box;

/* A triangle as listed in one grid cell, with everything the edge loop reads before the
 * predicate, so a cell's candidates are one contiguous stream. */
typedef struct crossing_entry
{
	float lo[3], hi[3]; /* its box */
	int32_t v[3];		/* its corners */
	int32_t cell[3];	/* the cell of its box's low corner */
} crossing_entry;

struct sere_crossings
{
	int32_t triangle_count;
	int32_t vertex_count;
	int32_t edge_count;
	int32_t* tri;
	int32_t *edge_a, *edge_b;
	crossing_box* box; /* per triangle, at the current positions */
	/* The grid: the triangles overlapping cell c are entry[cell_start[c] .. cell_start[c + 1] − 1] */
	int32_t cell_capacity;
	int32_t entry_capacity;
	int32_t* cell_start;
	crossing_entry* entry;
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
	sere_free( c->entry );
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
	/* 3 T triangle indices and 8 T + 64 grid entries must fit in int32 */
	if ( tri == NULL || triangle_count <= 0 || vertex_count <= 0 || triangle_count > ( INT32_MAX - 64 ) / 8 )
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
	c->cell_start = sere_alloc( sizeof( int32_t ) * ( (size_t) c->cell_capacity + 1 ) );
	c->entry = sere_alloc( sizeof( crossing_entry ) * (size_t) c->entry_capacity );
	int failed = c->tri == NULL || c->box == NULL || c->cell_start == NULL || c->entry == NULL;
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
			/* checked before fminf, which would pass over a NaN */
			if ( !isfinite( p[0][a] ) || !isfinite( p[1][a] ) || !isfinite( p[2][a] ) )
			{
				return false;
			}
			blo[a] = fminf( p[0][a], fminf( p[1][a], p[2][a] ) );
			bhi[a] = fmaxf( p[0][a], fmaxf( p[1][a], p[2][a] ) );
			lo[a] = fminf( lo[a], blo[a] );
			hi[a] = fmaxf( hi[a], bhi[a] );
			longest = fmaxf( longest, bhi[a] - blo[a] );
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

/* Counting sort of (cell, triangle) entries: cell_start[c] first counts the entries of cells
 * up to c, then each entry is placed by decrementing it, which leaves the start of every cell. */
static void crossings_fill( sere_crossings* c, const crossing_grid* g )
{
	int32_t cells = g->n[0] * g->n[1] * g->n[2];
	memset( c->cell_start, 0, sizeof( int32_t ) * ( (size_t) cells + 1 ) );
	for ( int pass = 0; pass < 2; ++pass )
	{
		for ( int32_t t = 0; t < c->triangle_count; ++t )
		{
			const crossing_box* b = c->box + t;
			int32_t x0 = grid_cell( g, 0, b->lo[0] ), x1 = grid_cell( g, 0, b->hi[0] );
			int32_t y0 = grid_cell( g, 1, b->lo[1] ), y1 = grid_cell( g, 1, b->hi[1] );
			int32_t z0 = grid_cell( g, 2, b->lo[2] ), z1 = grid_cell( g, 2, b->hi[2] );
			const int32_t* v = c->tri + 3 * (size_t) t;
			crossing_entry entry = {
				{ b->lo[0], b->lo[1], b->lo[2] }, { b->hi[0], b->hi[1], b->hi[2] }, { v[0], v[1], v[2] }, { x0, y0, z0 }
			};
			for ( int32_t k = z0; k <= z1; ++k )
			{
				for ( int32_t j = y0; j <= y1; ++j )
				{
					for ( int32_t i = x0; i <= x1; ++i )
					{
						int32_t cell = ( k * g->n[1] + j ) * g->n[0] + i;
						if ( pass == 0 )
						{
							c->cell_start[cell] += 1;
						}
						else
						{
							c->entry[--c->cell_start[cell]] = entry;
						}
					}
				}
			}
		}
		if ( pass == 0 )
		{
			for ( int32_t cell = 1; cell <= cells; ++cell )
			{
				c->cell_start[cell] += c->cell_start[cell - 1];
			}
		}
	}
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
#pragma omp parallel for schedule( dynamic, 256 ) reduction( + : total )
	for ( int32_t e = 0; e < w->edge_count; ++e )
	{
		int32_t ea = w->edge_a[e], eb = w->edge_b[e];
		float elo[3] = { fminf( x[ea], x[eb] ), fminf( y[ea], y[eb] ), fminf( z[ea], z[eb] ) };
		float ehi[3] = { fmaxf( x[ea], x[eb] ), fmaxf( y[ea], y[eb] ), fmaxf( z[ea], z[eb] ) };
		double p[3] = { x[ea], y[ea], z[ea] }, q[3] = { x[eb], y[eb], z[eb] };
		int32_t x0 = grid_cell( g, 0, elo[0] ), x1 = grid_cell( g, 0, ehi[0] );
		int32_t y0 = grid_cell( g, 1, elo[1] ), y1 = grid_cell( g, 1, ehi[1] );
		int32_t z0 = grid_cell( g, 2, elo[2] ), z1 = grid_cell( g, 2, ehi[2] );
		int64_t found = 0;
		for ( int32_t k = z0; k <= z1; ++k )
		{
			for ( int32_t j = y0; j <= y1; ++j )
			{
				for ( int32_t i = x0; i <= x1; ++i )
				{
					int32_t cell = ( k * g->n[1] + j ) * g->n[0] + i;
					for ( int32_t s = w->cell_start[cell]; s < w->cell_start[cell + 1]; ++s )
					{
						const crossing_entry* t = w->entry + s;
						/* The pair is tested only in the cell holding the low corner of the
						 * overlap of the two boxes: that corner lies in both boxes, so exactly
						 * one cell both visit contains it; grid_cell is monotone, so its cell is
						 * the larger of the two low cells on each axis. */
						if ( ( x0 > t->cell[0] ? x0 : t->cell[0] ) != i || ( y0 > t->cell[1] ? y0 : t->cell[1] ) != j ||
							 ( z0 > t->cell[2] ? z0 : t->cell[2] ) != k )
						{
							continue;
						}
						if ( t->lo[0] > ehi[0] || t->hi[0] < elo[0] || t->lo[1] > ehi[1] || t->hi[1] < elo[1] ||
							 t->lo[2] > ehi[2] || t->hi[2] < elo[2] )
						{
							continue;
						}
						const int32_t* v = t->v;
						if ( v[0] == ea || v[1] == ea || v[2] == ea || v[0] == eb || v[1] == eb || v[2] == eb )
						{
							continue;
						}
						double a[3] = { x[v[0]], y[v[0]], z[v[0]] };
						double b[3] = { x[v[1]], y[v[1]], z[v[1]] };
						double cc[3] = { x[v[2]], y[v[2]], z[v[2]] };
						found += sere_segment_crosses_triangle( p, q, a, b, cc );
					}
				}
			}
		}
		total += found;
	}
	*count = total;
	return SERE_OK;
}

sere_status sere_count_crossings( const float* x, const float* y, const float* z, int32_t vertex_count,
								  const int32_t* tri, int32_t triangle_count, int64_t* count )
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
	status = sere_crossings_count( c, x, y, z, count );
	sere_crossings_destroy( c );
	return status;
}

/* ---------------------------------------------------------------------------------------------
 * Shape measures */

sere_shape_input sere_shape_input_default( void )
{
	sere_shape_input in;
	memset( &in, 0, sizeof( in ) );
	in.ground = -INFINITY;
	in.wrinkle_threshold = 0.05;
	in.band = 0.03;
	in.main_order = 2;
	return in;
}

static sere_status shape_validate( const sere_shape_input* in )
{
	if ( in == NULL || in->x == NULL || in->y == NULL || in->z == NULL || in->u == NULL || in->v == NULL ||
		 in->tri == NULL || in->edge_a == NULL || in->edge_b == NULL || in->boundary == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( in->veins != NULL &&
		 ( in->main_order < 1 || in->veins->vein_count < 0 ||
		   ( in->veins->vein_count > 0 && ( in->veins->veins == NULL || in->veins->vein_xy == NULL ) ) ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( in->vertex_count <= 0 || in->triangle_count <= 0 || in->edge_count <= 0 || in->midvein_count < 0 ||
		 ( in->midvein_count > 0 && in->midvein == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* -inf is "no ground"; a NaN or +inf ground is a mistake, not a choice */
	if ( isnan( in->ground ) || in->ground == INFINITY || !( in->wrinkle_threshold >= 0.0 ) ||
		 !isfinite( in->wrinkle_threshold ) || !( in->band > 0.0 ) || !isfinite( in->band ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( size_t k = 0; k < 3 * (size_t) in->triangle_count; ++k )
	{
		if ( in->tri[k] < 0 || in->tri[k] >= in->vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		if ( in->edge_a[e] < 0 || in->edge_a[e] >= in->vertex_count || in->edge_b[e] < 0 ||
			 in->edge_b[e] >= in->vertex_count || in->edge_a[e] == in->edge_b[e] )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	for ( int32_t k = 0; k < in->midvein_count; ++k )
	{
		if ( in->midvein[k] < 0 || in->midvein[k] >= in->vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		if ( !isfinite( in->x[i] ) || !isfinite( in->y[i] ) || !isfinite( in->z[i] ) || !isfinite( in->u[i] ) ||
			 !isfinite( in->v[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	return SERE_OK;
}

typedef struct edge_key
{
	uint64_t key;
	int32_t edge;
} edge_key;

static int compare_edge_key( const void* a, const void* b )
{
	uint64_t u = ( (const edge_key*) a )->key, v = ( (const edge_key*) b )->key;
	return ( u > v ) - ( u < v );
}

static inline uint64_t pair_key( int32_t i, int32_t j )
{
	uint32_t lo = (uint32_t) ( i < j ? i : j ), hi = (uint32_t) ( i < j ? j : i );
	return ( (uint64_t) lo << 32 ) | hi;
}

/* edge_tri[2 e] is the triangle running along edge e from edge_a to edge_b (counter-clockwise),
 * edge_tri[2 e + 1] the one running back, −1 where there is none; tri_edge[3 t + k] is the edge
 * from corner k to corner k + 1 of triangle t. */
static sere_status shape_adjacency( const sere_shape_input* in, int32_t* edge_tri, int32_t* tri_edge )
{
	int32_t ec = in->edge_count;
	edge_key* keys = malloc( sizeof( edge_key ) * (size_t) ec );
	if ( keys == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t e = 0; e < ec; ++e )
	{
		keys[e] = ( edge_key ){ pair_key( in->edge_a[e], in->edge_b[e] ), e };
		edge_tri[2 * e] = -1, edge_tri[2 * e + 1] = -1;
	}
	qsort( keys, (size_t) ec, sizeof( edge_key ), compare_edge_key );
	sere_status status = SERE_OK;
	for ( int32_t e = 1; e < ec && status == SERE_OK; ++e )
	{
		if ( keys[e].key == keys[e - 1].key )
		{
			status = SERE_ERR_ARGUMENT; /* an edge listed twice */
		}
	}
	for ( int32_t t = 0; t < in->triangle_count && status == SERE_OK; ++t )
	{
		for ( int k = 0; k < 3 && status == SERE_OK; ++k )
		{
			int32_t i = in->tri[3 * (size_t) t + k], j = in->tri[3 * (size_t) t + ( k + 1 ) % 3];
			uint64_t key = pair_key( i, j );
			int32_t lo = 0, hi = ec;
			while ( lo < hi )
			{
				int32_t mid = lo + ( hi - lo ) / 2;
				if ( keys[mid].key < key )
				{
					lo = mid + 1;
				}
				else
				{
					hi = mid;
				}
			}
			if ( lo == ec || keys[lo].key != key )
			{
				status = SERE_ERR_ARGUMENT; /* a triangle edge missing from the list */
				break;
			}
			int32_t e = keys[lo].edge;
			int32_t slot = i == in->edge_a[e] ? 0 : 1;
			if ( edge_tri[2 * e + slot] != -1 )
			{
				status = SERE_ERR_GEOMETRY;
				break;
			}
			edge_tri[2 * e + slot] = t;
			tri_edge[3 * (size_t) t + k] = e;
		}
	}
	free( keys );
	return status;
}

static inline void position( const sere_shape_input* in, int32_t i, double p[3] )
{
	p[0] = in->x[i], p[1] = in->y[i], p[2] = in->z[i];
}

/* (b − a) × (c − a) of triangle t: twice its area times its unit normal. */
static void triangle_cross( const sere_shape_input* in, int32_t t, double n[3] )
{
	const int32_t* v = in->tri + 3 * (size_t) t;
	double a[3], b[3], c[3], ab[3], ac[3];
	position( in, v[0], a );
	position( in, v[1], b );
	position( in, v[2], c );
	sub3( b, a, ab );
	sub3( c, a, ac );
	cross3( ab, ac, n );
}

static void unit_normal( const sere_shape_input* in, int32_t t, double n[3] )
{
	triangle_cross( in, t, n );
	double length = sqrt( dot3( n, n ) );
	for ( int k = 0; k < 3; ++k )
	{
		n[k] = length > 0.0 ? n[k] / length : 0.0;
	}
}

static void dihedrals( const sere_shape_input* in, const int32_t* edge_tri, double* dihedral )
{
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		int32_t t0 = edge_tri[2 * e], t1 = edge_tri[2 * e + 1];
		if ( t0 < 0 || t1 < 0 )
		{
			dihedral[e] = 0.0;
			continue;
		}
		double n0[3], n1[3], a[3], b[3], axis[3], w[3];
		unit_normal( in, t0, n0 );
		unit_normal( in, t1, n1 );
		position( in, in->edge_a[e], a );
		position( in, in->edge_b[e], b );
		sub3( b, a, axis );
		double length = sqrt( dot3( axis, axis ) );
		/* t0 runs a → b, so turning n0 into n1 about a → b by a positive angle lifts t1 to the
		 * side n0 points to: the surface folds towards its normals */
		cross3( n1, n0, w );
		dihedral[e] = length > 0.0 ? atan2( dot3( w, axis ) / length, dot3( n0, n1 ) ) : 0.0;
	}
}

sere_status sere_shape_dihedrals( const sere_shape_input* in, double* dihedral )
{
	sere_status status = shape_validate( in );
	if ( status != SERE_OK || dihedral == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int32_t* edge_tri = malloc( sizeof( int32_t ) * 2 * (size_t) in->edge_count );
	int32_t* tri_edge = malloc( sizeof( int32_t ) * 3 * (size_t) in->triangle_count );
	status = edge_tri == NULL || tri_edge == NULL ? SERE_ERR_MEMORY : shape_adjacency( in, edge_tri, tri_edge );
	if ( status == SERE_OK )
	{
		dihedrals( in, edge_tri, dihedral );
	}
	free( edge_tri );
	free( tri_edge );
	return status;
}

/* Eigen decomposition of a symmetric 3 × 3 matrix m (not modified) by cyclic Jacobi rotations: eigenvalues in w
 * ascending, the unit eigenvector of w[k] in column k of v. Small and exact enough for the
 * covariance matrices of the plane and circle fits. */
static void eigen3( double m[3][3], double w[3], double v[3][3] )
{
	double a[3][3];
	memcpy( a, m, sizeof( a ) );
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = 0; j < 3; ++j )
		{
			v[i][j] = i == j ? 1.0 : 0.0;
		}
	}
	static const int pairs[3][2] = { { 0, 1 }, { 0, 2 }, { 1, 2 } };
	for ( int sweep = 0; sweep < 64; ++sweep )
	{
		double off = fabs( a[0][1] ) + fabs( a[0][2] ) + fabs( a[1][2] );
		double diag = fabs( a[0][0] ) + fabs( a[1][1] ) + fabs( a[2][2] );
		if ( off <= 1e-300 || off <= 1e-18 * diag )
		{
			break;
		}
		for ( int r = 0; r < 3; ++r )
		{
			int p = pairs[r][0], q = pairs[r][1];
			if ( a[p][q] == 0.0 )
			{
				continue;
			}
			double theta = ( a[q][q] - a[p][p] ) / ( 2.0 * a[p][q] );
			double t = fabs( theta ) > 1e150
						   ? 0.5 / theta
						   : ( theta >= 0.0 ? 1.0 : -1.0 ) / ( fabs( theta ) + sqrt( theta * theta + 1.0 ) );
			double c = 1.0 / sqrt( t * t + 1.0 ), s = t * c;
			for ( int k = 0; k < 3; ++k )
			{
				double kp = a[k][p], kq = a[k][q];
				a[k][p] = c * kp - s * kq, a[k][q] = s * kp + c * kq;
			}
			for ( int k = 0; k < 3; ++k )
			{
				double pk = a[p][k], qk = a[q][k];
				a[p][k] = c * pk - s * qk, a[q][k] = s * pk + c * qk;
			}
			for ( int k = 0; k < 3; ++k )
			{
				double kp = v[k][p], kq = v[k][q];
				v[k][p] = c * kp - s * kq, v[k][q] = s * kp + c * kq;
			}
		}
	}
	int order[3] = { 0, 1, 2 };
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = i + 1; j < 3; ++j )
		{
			if ( a[order[j]][order[j]] < a[order[i]][order[i]] )
			{
				int swap = order[i];
				order[i] = order[j], order[j] = swap;
			}
		}
	}
	double vv[3][3];
	for ( int k = 0; k < 3; ++k )
	{
		w[k] = a[order[k]][order[k]];
		for ( int i = 0; i < 3; ++i )
		{
			vv[i][k] = v[i][order[k]];
		}
	}
	memcpy( v, vv, sizeof( vv ) );
}

/* Mean and covariance of the selected points: every vertex i with select == NULL or select[i]
 * == want, or the listed indices when list != NULL. Returns the point count. */
static int32_t point_moments( const sere_shape_input* in, const uint8_t* select, int want, const int32_t* list,
							  int32_t list_count, double mean[3], double cov[3][3] )
{
	int32_t n = list != NULL ? list_count : in->vertex_count;
	int32_t used = 0;
	double sum[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = list != NULL ? list[k] : k;
		if ( select != NULL && ( select[i] != 0 ) != want )
		{
			continue;
		}
		double p[3];
		position( in, i, p );
		for ( int a = 0; a < 3; ++a )
		{
			sum[a] += p[a];
		}
		used += 1;
	}
	memset( cov, 0, sizeof( double ) * 9 );
	for ( int a = 0; a < 3; ++a )
	{
		mean[a] = used > 0 ? sum[a] / used : 0.0;
	}
	/* second pass about the mean: no cancellation for a leaf far from the origin */
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = list != NULL ? list[k] : k;
		if ( select != NULL && ( select[i] != 0 ) != want )
		{
			continue;
		}
		double p[3], d[3];
		position( in, i, p );
		sub3( p, mean, d );
		for ( int a = 0; a < 3; ++a )
		{
			for ( int b = 0; b < 3; ++b )
			{
				cov[a][b] += d[a] * d[b];
			}
		}
	}
	return used;
}

static double margin_lift( const sere_shape_input* in, const double mean_normal[3] )
{
	double mean[3], cov[3][3], w[3], v[3][3];
	int32_t interior = point_moments( in, in->boundary, 0, NULL, 0, mean, cov );
	if ( interior < 3 || interior == in->vertex_count )
	{
		return NAN;
	}
	eigen3( cov, w, v );
	double n[3] = { v[0][0], v[1][0], v[2][0] }; /* least variance: the plane's normal */
	if ( dot3( n, mean_normal ) < 0.0 )
	{
		n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
	}
	double sum = 0.0;
	int32_t count = 0;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		if ( in->boundary[i] != 0 )
		{
			double p[3], d[3];
			position( in, i, p );
			sub3( p, mean, d );
			sum += dot3( n, d );
			count += 1;
		}
	}
	return sum / count;
}

/* Solves the 3 × 3 system m x = r by Gaussian elimination with partial pivoting; false when a
 * pivot vanishes. */
static bool solve3( double m[3][3], double r[3], double x[3] )
{
	for ( int col = 0; col < 3; ++col )
	{
		int pivot = col;
		for ( int row = col + 1; row < 3; ++row )
		{
			if ( fabs( m[row][col] ) > fabs( m[pivot][col] ) )
			{
				pivot = row;
			}
		}
		if ( !( fabs( m[pivot][col] ) > 0.0 ) )
		{
			return false;
		}
		for ( int k = 0; k < 3; ++k )
		{
			double swap = m[col][k];
			m[col][k] = m[pivot][k], m[pivot][k] = swap;
		}
		double swap = r[col];
		r[col] = r[pivot], r[pivot] = swap;
		for ( int row = col + 1; row < 3; ++row )
		{
			double f = m[row][col] / m[col][col];
			for ( int k = col; k < 3; ++k )
			{
				m[row][k] -= f * m[col][k];
			}
			r[row] -= f * r[col];
		}
	}
	for ( int row = 2; row >= 0; --row )
	{
		double s = r[row];
		for ( int k = row + 1; k < 3; ++k )
		{
			s -= m[row][k] * x[k];
		}
		x[row] = s / m[row][row];
	}
	return true;
}

static double midvein_curvature( const sere_shape_input* in )
{
	if ( in->midvein == NULL || in->midvein_count < 3 )
	{
		return 0.0;
	}
	double mean[3], cov[3][3], w[3], v[3][3];
	point_moments( in, NULL, 0, in->midvein, in->midvein_count, mean, cov );
	eigen3( cov, w, v );
	/* Points in a line within rounding of float positions (relative variance ~1e-14) bend
	 * nowhere; a real bend of sagitta s over length L has a variance ratio of order (s / L)². */
	if ( !( w[1] > 1e-12 * w[2] ) )
	{
		return 0.0;
	}
	/* coordinates in the best plane, scaled to unit spread so the fit is well conditioned */
	double scale = sqrt( w[2] / in->midvein_count );
	double e1[3] = { v[0][2], v[1][2], v[2][2] }, e2[3] = { v[0][1], v[1][1], v[2][1] };
	/* Kåsa's algebraic fit: least squares of s² + t² + D s + E t + F over the points */
	double m[3][3] = { { 0.0 } }, r[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t k = 0; k < in->midvein_count; ++k )
	{
		double p[3], d[3];
		position( in, in->midvein[k], p );
		sub3( p, mean, d );
		double row[3] = { dot3( d, e1 ) / scale, dot3( d, e2 ) / scale, 1.0 };
		double rhs = -( row[0] * row[0] + row[1] * row[1] );
		for ( int i = 0; i < 3; ++i )
		{
			for ( int j = 0; j < 3; ++j )
			{
				m[i][j] += row[i] * row[j];
			}
			r[i] += row[i] * rhs;
		}
	}
	double x[3];
	if ( !solve3( m, r, x ) )
	{
		return 0.0;
	}
	double radius2 = 0.25 * ( x[0] * x[0] + x[1] * x[1] ) - x[2];
	return radius2 > 0.0 ? 1.0 / ( sqrt( radius2 ) * scale ) : 0.0;
}

/* Rolling of a cross-section (sere_shape_roll): the turning of the normal across a band of
 * triangles. Each triangle's deformation gradient J (3 × 2) maps fresh (u, v) directions to
 * current ones; the band's current axis is the area-weighted J a of its fresh axis a, its mean
 * normal is taken perpendicular to that, and each triangle's normal angle θ is measured about
 * the axis. A least-squares line θ(lateral) over the fresh lateral coordinate gives the turning
 * rate; times the band's fresh width it is the angle the normal turns through from one margin to
 * the other. Fresh areas weight everything, so a crumpled triangle counts as much as it did. */
typedef struct section_sums
{
	double axis[3], normal[3], side[3];
} section_sums;

/* J a for triangle t and fresh direction a; false for a triangle degenerate at rest. */
static bool fresh_map( const sere_shape_input* in, int32_t t, const double a[2], double out[3], double* area0 )
{
	const int32_t* v = in->tri + 3 * (size_t) t;
	double du1 = (double) in->u[v[1]] - in->u[v[0]], dv1 = (double) in->v[v[1]] - in->v[v[0]];
	double du2 = (double) in->u[v[2]] - in->u[v[0]], dv2 = (double) in->v[v[2]] - in->v[v[0]];
	double det = du1 * dv2 - du2 * dv1;
	if ( !( fabs( det ) > 0.0 ) )
	{
		return false;
	}
	/* a = s e1 + r e2 in the fresh edge basis, so J a = s E1 + r E2 with the current edges */
	double s = ( a[0] * dv2 - a[1] * du2 ) / det, r = ( du1 * a[1] - dv1 * a[0] ) / det;
	double p0[3], p1[3], p2[3];
	position( in, v[0], p0 );
	position( in, v[1], p1 );
	position( in, v[2], p2 );
	for ( int k = 0; k < 3; ++k )
	{
		out[k] = s * ( p1[k] - p0[k] ) + r * ( p2[k] - p0[k] );
	}
	*area0 = 0.5 * fabs( det );
	return true;
}

static void normalize3( double v[3] )
{
	double length = sqrt( dot3( v, v ) );
	for ( int k = 0; k < 3; ++k )
	{
		v[k] = length > 0.0 ? v[k] / length : 0.0;
	}
}

/* The roll of the triangles tris[0 .. count), with fresh axis direction axis2 (unit), fresh
 * lateral coordinate lateral[k] of each one's centroid along the axis's right-hand side
 * (axis2[1], −axis2[0]) and the band's fresh width. NaN when the
 * band is too small or degenerate to say. */
static double section_roll( const sere_shape_input* in, const int32_t* tris, const double* lateral, int32_t count,
							const double axis2[2], double width )
{
	if ( count < 3 || !( width > 0.0 ) )
	{
		return NAN;
	}
	const double side2[2] = { axis2[1], -axis2[0] }; /* the fresh right-hand side, where lateral grows */
	section_sums sum;
	memset( &sum, 0, sizeof( sum ) );
	for ( int32_t k = 0; k < count; ++k )
	{
		double ja[3], js[3], n[3], area0;
		if ( !fresh_map( in, tris[k], axis2, ja, &area0 ) || !fresh_map( in, tris[k], side2, js, &area0 ) )
		{
			continue;
		}
		unit_normal( in, tris[k], n );
		for ( int c = 0; c < 3; ++c )
		{
			sum.axis[c] += area0 * ja[c], sum.normal[c] += area0 * n[c], sum.side[c] += area0 * js[c];
		}
	}
	double* axis = sum.axis;
	double* normal = sum.normal;
	double* side = sum.side;
	normalize3( axis );
	double along = dot3( normal, axis );
	for ( int c = 0; c < 3; ++c )
	{
		normal[c] -= along * axis[c];
	}
	normalize3( normal );
	double a_part = dot3( side, axis ), n_part = dot3( side, normal );
	for ( int c = 0; c < 3; ++c )
	{
		side[c] -= a_part * axis[c] + n_part * normal[c];
	}
	normalize3( side );
	if ( dot3( axis, axis ) == 0.0 || dot3( normal, normal ) == 0.0 || dot3( side, side ) == 0.0 )
	{
		return NAN;
	}
	/* weighted least squares of θ over the lateral coordinate, about the means */
	double w_sum = 0.0, x_sum = 0.0, t_sum = 0.0;
	for ( int pass = 0; pass < 2; ++pass )
	{
		double x_mean = w_sum > 0.0 ? x_sum / w_sum : 0.0, t_mean = w_sum > 0.0 ? t_sum / w_sum : 0.0;
		double sxx = 0.0, sxt = 0.0;
		for ( int32_t k = 0; k < count; ++k )
		{
			double ja[3], n[3], area0;
			if ( !fresh_map( in, tris[k], axis2, ja, &area0 ) )
			{
				continue;
			}
			unit_normal( in, tris[k], n );
			double theta = atan2( dot3( n, side ), dot3( n, normal ) );
			if ( pass == 0 )
			{
				w_sum += area0, x_sum += area0 * lateral[k], t_sum += area0 * theta;
			}
			else
			{
				sxx += area0 * ( lateral[k] - x_mean ) * ( lateral[k] - x_mean );
				sxt += area0 * ( lateral[k] - x_mean ) * ( theta - t_mean );
			}
		}
		if ( pass == 1 )
		{
			/* a normal turning towards −side as the lateral coordinate grows is a margin lifted
			 * towards the normals' side: positive */
			return sxx > 0.0 ? -sxt / sxx * width : NAN;
		}
	}
	return NAN;
}

/* Roll of the band of triangles whose fresh centroid lies within ±band of fresh v = v_min +
 * v_fraction (v_max − v_min); scratch holds 2 × triangle_count entries. */
static double band_roll( const sere_shape_input* in, double v_fraction, int32_t* tris, double* lateral )
{
	float v_min = INFINITY, v_max = -INFINITY;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		v_min = fminf( v_min, in->v[i] ), v_max = fmaxf( v_max, in->v[i] );
	}
	double range = (double) v_max - v_min;
	double centre = v_min + v_fraction * range, half = in->band * range;
	int32_t count = 0;
	double lo = INFINITY, hi = -INFINITY;
	for ( int32_t t = 0; t < in->triangle_count; ++t )
	{
		const int32_t* v = in->tri + 3 * (size_t) t;
		double cv = ( (double) in->v[v[0]] + in->v[v[1]] + in->v[v[2]] ) / 3.0;
		if ( fabs( cv - centre ) <= half )
		{
			tris[count] = t;
			lateral[count++] = ( (double) in->u[v[0]] + in->u[v[1]] + in->u[v[2]] ) / 3.0;
			for ( int k = 0; k < 3; ++k )
			{
				lo = fmin( lo, in->u[v[k]] ), hi = fmax( hi, in->u[v[k]] );
			}
		}
	}
	const double axis2[2] = { 0.0, 1.0 };
	return section_roll( in, tris, lateral, count, axis2, hi - lo );
}

/* The current direction of the fresh axis (+v) over the band at v_fraction: the fresh-area
 * weighted J (0, 1) of its triangles, unit; false for an empty or degenerate band. */
static bool band_axis( const sere_shape_input* in, double v_fraction, double axis[3] )
{
	float v_min = INFINITY, v_max = -INFINITY;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		v_min = fminf( v_min, in->v[i] ), v_max = fmaxf( v_max, in->v[i] );
	}
	double range = (double) v_max - v_min;
	double centre = v_min + v_fraction * range, half = in->band * range;
	const double up[2] = { 0.0, 1.0 };
	axis[0] = axis[1] = axis[2] = 0.0;
	for ( int32_t t = 0; t < in->triangle_count; ++t )
	{
		const int32_t* v = in->tri + 3 * (size_t) t;
		double cv = ( (double) in->v[v[0]] + in->v[v[1]] + in->v[v[2]] ) / 3.0, ja[3], area0;
		if ( fabs( cv - centre ) <= half && fresh_map( in, t, up, ja, &area0 ) )
		{
			for ( int c = 0; c < 3; ++c )
			{
				axis[c] += area0 * ja[c];
			}
		}
	}
	normalize3( axis );
	return dot3( axis, axis ) > 0.0;
}

/* The angle the leaf's axis turns through between the bands at fractions from and to. */
static double axis_curl( const sere_shape_input* in, double from, double to )
{
	double a[3], b[3];
	if ( !band_axis( in, from, a ) || !band_axis( in, to, b ) )
	{
		return NAN;
	}
	double c[3];
	cross3( a, b, c );
	return atan2( sqrt( dot3( c, c ) ), dot3( a, b ) );
}

sere_status sere_shape_roll( const sere_shape_input* in, double v_fraction, double* roll )
{
	if ( roll != NULL )
	{
		*roll = NAN;
	}
	sere_status status = shape_validate( in );
	if ( status != SERE_OK || roll == NULL || !isfinite( v_fraction ) )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int32_t* tris = malloc( sizeof( int32_t ) * (size_t) in->triangle_count );
	double* lateral = malloc( sizeof( double ) * (size_t) in->triangle_count );
	if ( tris != NULL && lateral != NULL )
	{
		*roll = band_roll( in, v_fraction, tris, lateral );
	}
	free( tris );
	free( lateral );
	return tris != NULL && lateral != NULL ? SERE_OK : SERE_ERR_MEMORY;
}

/* The nearest point of a vein polyline to (x, y): distance, arc length from the vein's start,
 * signed lateral offset (positive to the right of the vein's direction, as section_roll wants)
 * and unit direction of the segment it lies on. */
typedef struct vein_foot
{
	double distance, arc, lateral, dx, dy;
} vein_foot;

static vein_foot vein_nearest( const sere_leaf_shape* shape, int32_t vein, double x, double y )
{
	const sere_vein* v = shape->veins + vein;
	const double* xy = shape->vein_xy + 2 * (size_t) v->first;
	vein_foot best = { INFINITY, 0.0, 0.0, 1.0, 0.0 };
	double arc = 0.0;
	for ( int32_t k = 0; k + 1 < v->count; ++k )
	{
		double ax = xy[2 * k], ay = xy[2 * k + 1], bx = xy[2 * k + 2], by = xy[2 * k + 3];
		double ex = bx - ax, ey = by - ay, length = hypot( ex, ey );
		if ( !( length > 0.0 ) )
		{
			continue;
		}
		double t = fmax( 0.0, fmin( 1.0, ( ( x - ax ) * ex + ( y - ay ) * ey ) / ( length * length ) ) );
		double qx = ax + t * ex, qy = ay + t * ey, d = hypot( x - qx, y - qy );
		if ( d < best.distance )
		{
			best = ( vein_foot ){ d, arc + t * length, ( ( x - qx ) * ey - ( y - qy ) * ex ) / length, ex / length,
								  ey / length };
		}
		arc += length;
	}
	return best;
}

static double vein_length( const sere_leaf_shape* shape, int32_t vein )
{
	const sere_vein* v = shape->veins + vein;
	const double* xy = shape->vein_xy + 2 * (size_t) v->first;
	double length = 0.0;
	for ( int32_t k = 0; k + 1 < v->count; ++k )
	{
		length += hypot( xy[2 * k + 2] - xy[2 * k], xy[2 * k + 3] - xy[2 * k + 1] );
	}
	return length;
}

/* Creases along and between the main veins, and the roll of the sections across them near their
 * tips and their bases (sere_shape::crease_main ... vein_roll_base). Returns false when out of
 * memory. */
static bool main_vein_measures( const sere_shape_input* in, const int32_t* edge_tri, const double* dihedral,
								sere_shape* out )
{
	out->crease_main = out->crease_blade = NAN;
	out->vein_roll_tip = out->vein_roll_base = NAN;
	const sere_leaf_shape* shape = in->veins;
	if ( shape == NULL )
	{
		return true;
	}
	int32_t main_count = 0;
	for ( int32_t k = 0; k < shape->vein_count; ++k )
	{
		main_count += shape->veins[k].order <= in->main_order;
	}
	if ( main_count == 0 )
	{
		return true;
	}
	int32_t tc = in->triangle_count;
	int32_t* owner = malloc( sizeof( int32_t ) * (size_t) tc );
	vein_foot* foot = malloc( sizeof( vein_foot ) * (size_t) tc );
	int32_t* tris = malloc( sizeof( int32_t ) * (size_t) tc );
	double* lateral = malloc( sizeof( double ) * (size_t) tc );
	if ( owner == NULL || foot == NULL || tris == NULL || lateral == NULL )
	{
		free( owner ), free( foot ), free( tris ), free( lateral );
		return false;
	}

	/* spacing: the mean fresh edge length */
	double spacing = 0.0;
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		spacing += hypot( (double) in->u[in->edge_b[e]] - in->u[in->edge_a[e]],
						  (double) in->v[in->edge_b[e]] - in->v[in->edge_a[e]] );
	}
	spacing /= in->edge_count;
	double near_sum = 0.0, far_sum = 0.0;
	int32_t near_count = 0, far_count = 0;
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		if ( edge_tri[2 * e] < 0 || edge_tri[2 * e + 1] < 0 )
		{
			continue;
		}
		double x = 0.5 * ( (double) in->u[in->edge_a[e]] + in->u[in->edge_b[e]] );
		double y = 0.5 * ( (double) in->v[in->edge_a[e]] + in->v[in->edge_b[e]] );
		double d = INFINITY;
		for ( int32_t k = 0; k < shape->vein_count; ++k )
		{
			d = shape->veins[k].order <= in->main_order ? fmin( d, vein_nearest( shape, k, x, y ).distance ) : d;
		}
		if ( d <= spacing )
		{
			near_sum += fabs( dihedral[e] ), near_count += 1;
		}
		else if ( d >= 2.0 * spacing )
		{
			far_sum += fabs( dihedral[e] ), far_count += 1;
		}
	}
	out->crease_main = near_count > 0 ? near_sum / near_count : NAN;
	out->crease_blade = far_count > 0 ? far_sum / far_count : NAN;

	/* each triangle belongs to the nearest main vein (its lobe, for a lobed leaf) */
	for ( int32_t t = 0; t < tc; ++t )
	{
		const int32_t* v = in->tri + 3 * (size_t) t;
		double x = ( (double) in->u[v[0]] + in->u[v[1]] + in->u[v[2]] ) / 3.0;
		double y = ( (double) in->v[v[0]] + in->v[v[1]] + in->v[v[2]] ) / 3.0;
		owner[t] = -1;
		for ( int32_t k = 0; k < shape->vein_count; ++k )
		{
			if ( shape->veins[k].order > in->main_order )
			{
				continue;
			}
			vein_foot f = vein_nearest( shape, k, x, y );
			if ( owner[t] < 0 || f.distance < foot[t].distance )
			{
				owner[t] = k, foot[t] = f;
			}
		}
	}
	static const double windows[2][2] = { { 0.70, 0.95 }, { 0.20, 0.45 } };
	double sums[2] = { 0.0, 0.0 };
	int32_t counts[2] = { 0, 0 };
	for ( int32_t k = 0; k < shape->vein_count; ++k )
	{
		if ( shape->veins[k].order > in->main_order )
		{
			continue;
		}
		double length = vein_length( shape, k );
		for ( int w = 0; w < 2; ++w )
		{
			int32_t count = 0;
			double axis2[2] = { 0.0, 0.0 }, lo = INFINITY, hi = -INFINITY;
			for ( int32_t t = 0; t < tc; ++t )
			{
				double at = length > 0.0 ? foot[t].arc / length : 0.0;
				if ( owner[t] != k || at < windows[w][0] || at > windows[w][1] )
				{
					continue;
				}
				tris[count] = t;
				lateral[count++] = foot[t].lateral;
				axis2[0] += foot[t].dx, axis2[1] += foot[t].dy;
				/* the band's fresh width: its corners' lateral offsets */
				const int32_t* v = in->tri + 3 * (size_t) t;
				double cx = ( (double) in->u[v[0]] + in->u[v[1]] + in->u[v[2]] ) / 3.0;
				double cy = ( (double) in->v[v[0]] + in->v[v[1]] + in->v[v[2]] ) / 3.0;
				for ( int c = 0; c < 3; ++c )
				{
					double offset =
						foot[t].lateral + ( in->u[v[c]] - cx ) * foot[t].dy - ( in->v[v[c]] - cy ) * foot[t].dx;
					lo = fmin( lo, offset ), hi = fmax( hi, offset );
				}
			}
			double norm = hypot( axis2[0], axis2[1] );
			if ( count < 6 || !( norm > 0.0 ) )
			{
				continue;
			}
			axis2[0] /= norm, axis2[1] /= norm;
			double roll = section_roll( in, tris, lateral, count, axis2, hi - lo );
			if ( isfinite( roll ) )
			{
				sums[w] += fabs( roll ), counts[w] += 1;
			}
		}
	}
	out->vein_roll_tip = counts[0] > 0 ? sums[0] / counts[0] : NAN;
	out->vein_roll_base = counts[1] > 0 ? sums[1] / counts[1] : NAN;
	free( owner ), free( foot ), free( tris ), free( lateral );
	return true;
}

/* Largest squared distance over all vertex pairs: an exact max, so any thread count agrees. */
static double diameter2( const sere_shape_input* in )
{
	int32_t n = in->vertex_count;
	const float *x = in->x, *y = in->y, *z = in->z;
	double best = 0.0;
#pragma omp parallel for schedule( dynamic, 32 ) reduction( max : best )
	for ( int32_t i = 0; i < n; ++i )
	{
		double xi = x[i], yi = y[i], zi = z[i];
		for ( int32_t j = i + 1; j < n; ++j )
		{
			double dx = x[j] - xi, dy = y[j] - yi, dz = z[j] - zi;
			double d2 = dx * dx + dy * dy + dz * dz;
			best = d2 > best ? d2 : best;
		}
	}
	return best;
}

/* Everything after validation and adjacency; the scratch arrays are the caller's. */
static void shape_measure_all( const sere_shape_input* in, const int32_t* edge_tri, const int32_t* tri_edge,
							   double* dihedral, int32_t* tris, double* lateral, sere_shape* out )
{
	int32_t ec = in->edge_count, tc = in->triangle_count;

	/* area, centroid and mean normal: sums over triangles of area-weighted quantities */
	double area = 0.0, moment[3] = { 0.0, 0.0, 0.0 }, normal[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t t = 0; t < tc; ++t )
	{
		const int32_t* v = in->tri + 3 * (size_t) t;
		double a[3], b[3], c[3], ab[3], ac[3], n[3];
		position( in, v[0], a );
		position( in, v[1], b );
		position( in, v[2], c );
		sub3( b, a, ab );
		sub3( c, a, ac );
		cross3( ab, ac, n );
		double at = 0.5 * sqrt( dot3( n, n ) );
		for ( int k = 0; k < 3; ++k )
		{
			moment[k] += at * ( ( a[k] + b[k] + c[k] ) / 3.0 );
			normal[k] += 0.5 * n[k]; /* area · unit normal */
		}
		area += at;
	}
	out->area = area;
	for ( int k = 0; k < 3; ++k )
	{
		out->centroid[k] = area > 0.0 ? moment[k] / area : 0.0;
		out->mean_normal[k] = area > 0.0 ? normal[k] / area : 0.0;
	}
	out->flip = out->mean_normal[2] < 0.0;
	out->extent = in->skip_extent ? NAN : sqrt( diameter2( in ) );

	double min_z = INFINITY, max_z = -INFINITY;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		min_z = fmin( min_z, in->z[i] ), max_z = fmax( max_z, in->z[i] );
	}
	out->min_z = min_z, out->max_z = max_z;
	out->ground_gap = in->ground == -INFINITY ? NAN : min_z - in->ground;

	/* creases: mean |dihedral| over interior edges, veins apart */
	dihedrals( in, edge_tri, dihedral );
	double vein_sum = 0.0, surf_sum = 0.0;
	for ( int32_t e = 0; e < ec; ++e )
	{
		if ( edge_tri[2 * e] < 0 || edge_tri[2 * e + 1] < 0 )
		{
			continue;
		}
		if ( in->edge_vein != NULL && in->edge_vein[e] != 0 )
		{
			vein_sum += fabs( dihedral[e] ), out->vein_edges += 1;
		}
		else
		{
			surf_sum += fabs( dihedral[e] ), out->surf_edges += 1;
		}
	}
	out->crease_vein = out->vein_edges > 0 ? vein_sum / out->vein_edges : 0.0;
	out->crease_surf = out->surf_edges > 0 ? surf_sum / out->surf_edges : 0.0;

	/* wrinkles: a ridge and a valley meeting in one triangle */
	int64_t changes = 0;
	for ( int32_t t = 0; t < tc; ++t )
	{
		int sign[3];
		for ( int k = 0; k < 3; ++k )
		{
			int32_t e = tri_edge[3 * (size_t) t + k];
			bool interior = edge_tri[2 * e] >= 0 && edge_tri[2 * e + 1] >= 0;
			double d = dihedral[e];
			sign[k] = !interior || !( fabs( d ) > in->wrinkle_threshold ) ? 0 : ( d > 0.0 ? 1 : -1 );
		}
		changes += ( sign[0] * sign[1] < 0 ) + ( sign[1] * sign[2] < 0 ) + ( sign[2] * sign[0] < 0 );
	}
	out->wrinkle_sign_changes = changes;

	out->margin_lift = margin_lift( in, out->mean_normal );
	out->roll_tip = band_roll( in, 0.85, tris, lateral );
	out->roll_base = band_roll( in, 0.25, tris, lateral );
	out->curl_tip = axis_curl( in, 0.55, 0.93 );
	out->curl_base = axis_curl( in, 0.07, 0.45 );
	out->midvein_curvature = midvein_curvature( in );
}

sere_status sere_shape_measure( const sere_shape_input* in, sere_shape* out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( out, 0, sizeof( *out ) );
	sere_status status = shape_validate( in );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t* edge_tri = malloc( sizeof( int32_t ) * 2 * (size_t) in->edge_count );
	int32_t* tri_edge = malloc( sizeof( int32_t ) * 3 * (size_t) in->triangle_count );
	double* dihedral = malloc( sizeof( double ) * (size_t) in->edge_count );
	int32_t* tris = malloc( sizeof( int32_t ) * (size_t) in->triangle_count );
	double* lateral = malloc( sizeof( double ) * (size_t) in->triangle_count );
	if ( edge_tri == NULL || tri_edge == NULL || dihedral == NULL || tris == NULL || lateral == NULL )
	{
		status = SERE_ERR_MEMORY;
	}
	else
	{
		status = shape_adjacency( in, edge_tri, tri_edge );
	}
	if ( status == SERE_OK )
	{
		shape_measure_all( in, edge_tri, tri_edge, dihedral, tris, lateral, out );
		if ( !main_vein_measures( in, edge_tri, dihedral, out ) )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	free( edge_tri );
	free( tri_edge );
	free( dihedral );
	free( tris );
	free( lateral );
	return status;
}
