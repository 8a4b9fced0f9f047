/* sere — Banding (Sec. 5.2): every mesh vertex to its nearest joint. Seed 003: Lu, Zhao, Guo 2009. */
/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "wilt/internal/skeleton_shared.h"

#include "core/array.h"
#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Banding (Sec. 5.2): a uniform grid over the joints, searched ring by ring. */

struct sere_joint_grid
{
	int32_t threads; /* sere_joint_grid_set_threads */
	int32_t count;
	int32_t dim[3];
	float lo[3];
	float inv_h;
	double h;
	double slack;	  /* rounding allowance of the cell bounds */
	int32_t* start;	  /* cell c holds items [start[c], start[c + 1]) */
	int32_t* items;	  /* joint indices, ascending within a cell */
	float *x, *y, *z; /* joint positions in item order, so a cell is read contiguously */
	/* Per cell, every joint that can be nearest to a point inside it (ascending, with its
	 * position); an empty list sends the query to the ring search. */
	int32_t* candidate_start;
	int32_t* candidate;
	float *cx, *cy, *cz;
	/* The floor's record (sere_joint_grid_record_band): per query, the rings its search opened (0
	 * when its candidate list answered). */
	uint8_t* walk_rings;
	int32_t walk_count;	   /* queries recorded, -1 for none */
	int32_t walk_capacity; /* entries walk_rings holds */
	int32_t one;		   /* 1, where the compiler cannot see it: the floor stores joint * one */
	uint32_t sink;		   /* the floor's sum of what it read, kept so the loads are not dropped */
};

/* A cell keeps a candidate list only up to this length; cells far from every joint (where the
 * list would be long) use the ring search instead. */
#define GRID_CANDIDATES 48

static int32_t cell_of( float p, float lo, float inv_h, int32_t dim )
{
	float f = ( p - lo ) * inv_h;
	if ( !( f >= 0.0f ) )
	{
		return 0;
	}
	if ( f >= (float) dim )
	{
		return dim - 1;
	}
	return (int32_t) f;
}

void sere_joint_grid_destroy( sere_joint_grid* grid )
{
	if ( grid == NULL )
	{
		return;
	}
	sere_free( grid->start );
	sere_free( grid->items );
	sere_free( grid->x );
	sere_free( grid->y );
	sere_free( grid->z );
	sere_free( grid->candidate_start );
	sere_free( grid->candidate );
	sere_free( grid->cx );
	sere_free( grid->cy );
	sere_free( grid->cz );
	free( grid->walk_rings );
	free( grid );
}

/* How a query's walk over the grid runs (one body, inlined with a constant mode, so the search
 * pays for neither of the others): GRID_SEARCH finds the nearest joint; GRID_RECORD finds it too
 * and counts in a grid_walk what it opened; GRID_TOUCH, the floor, replays a recorded walk with
 * the same loops and loads, sums of the records' bits in place of the distances and the recorded
 * ring count in place of the test of when to stop. */
enum
{
	GRID_SEARCH,
	GRID_RECORD,
	GRID_TOUCH
};

typedef struct grid_walk
{
	int32_t rings;	/* rings the ring search opened, 0 when the cell's candidate list answered
					 * (GRID_RECORD sets it, GRID_TOUCH replays it) */
	int32_t listed; /* 1 when the candidate list answered */
	int32_t cells;	/* cells the ring search opened */
	int32_t joints; /* joint records read: the candidates scanned, the opened cells' joints */
	uint32_t bits;	/* GRID_TOUCH: the sum of the records' bits */
} grid_walk;

#define WALK static inline __attribute__( ( always_inline ) )

/* Exact nearest joint by rings of cells around the query's (clamped) cell, stopping once the
 * nearest face of the visited block is farther than the best joint found. */
WALK int32_t ring_nearest( const sere_joint_grid* g, float x, float y, float z, int mode, grid_walk* w )
{
	float q[3] = { x, y, z };
	int32_t c[3];
	for ( int a = 0; a < 3; ++a )
	{
		c[a] = cell_of( q[a], g->lo[a], g->inv_h, g->dim[a] );
	}
	int32_t best = -1;
	float best_d2 = INFINITY;
	for ( int32_t r = 0;; ++r )
	{
		int32_t lo[3], hi[3];
		for ( int a = 0; a < 3; ++a )
		{
			lo[a] = c[a] - r > 0 ? c[a] - r : 0;
			hi[a] = c[a] + r < g->dim[a] - 1 ? c[a] + r : g->dim[a] - 1;
		}
		/* The shell of cells at Chebyshev distance exactly r from the query's cell. */
		for ( int32_t iz = lo[2]; iz <= hi[2]; ++iz )
		{
			for ( int32_t iy = lo[1]; iy <= hi[1]; ++iy )
			{
				int on_shell = abs( iz - c[2] ) == r || abs( iy - c[1] ) == r;
				int32_t step = on_shell || hi[0] - lo[0] < 1 ? 1 : hi[0] - lo[0];
				for ( int32_t ix = lo[0]; ix <= hi[0]; ix += step )
				{
					if ( !on_shell && abs( ix - c[0] ) != r )
					{
						continue;
					}
					int32_t cell = ( iz * g->dim[1] + iy ) * g->dim[0] + ix;
					int32_t begin = g->start[cell], end = g->start[cell + 1];
					if ( mode != GRID_SEARCH )
					{
						++w->cells;
						w->joints += end - begin;
					}
					for ( int32_t k = begin; k < end; ++k )
					{
						if ( mode == GRID_TOUCH )
						{
							w->bits += sere_skel_float_bits( g->x[k] ) + sere_skel_float_bits( g->y[k] ) +
									   sere_skel_float_bits( g->z[k] ) + (uint32_t) g->items[k];
							continue;
						}
						float dx = x - g->x[k], dy = y - g->y[k], dz = z - g->z[k];
						float d2 = dx * dx + dy * dy + dz * dz;
						int32_t j = g->items[k];
						if ( d2 < best_d2 || ( d2 == best_d2 && j < best ) )
						{
							best_d2 = d2;
							best = j;
						}
					}
				}
			}
		}
		if ( mode == GRID_TOUCH )
		{
			if ( r + 1 >= w->rings )
			{
				return best;
			}
			continue;
		}
		if ( mode == GRID_RECORD )
		{
			w->rings = r + 1;
		}
		/* Every unvisited cell lies beyond a face of the visited block that is not on the grid
		 * boundary; the nearest such face bounds the distance to any joint not yet seen. */
		double bound = INFINITY;
		for ( int a = 0; a < 3; ++a )
		{
			if ( lo[a] > 0 )
			{
				bound = fmin( bound, (double) q[a] - ( (double) g->lo[a] + lo[a] * g->h ) );
			}
			if ( hi[a] < g->dim[a] - 1 )
			{
				bound = fmin( bound, (double) g->lo[a] + ( hi[a] + 1 ) * g->h - (double) q[a] );
			}
		}
		if ( bound == INFINITY )
		{
			return best;
		}
		bound -= g->slack;
		if ( best >= 0 && bound > 0.0 && (double) best_d2 < bound * bound * ( 1.0 - 1e-6 ) )
		{
			return best;
		}
	}
}

/* Candidate lists are built from the cells within this Chebyshev radius of a cell; cells with no
 * joint that close, or whose list would reach farther, keep no list. */
#define GRID_REACH 4

/* The candidate list of one cell: with D the distance from the cell centre c to some joint and r
 * the half-diagonal, a point q of the cell has its nearest joint J within |q − c| + D ≤ r + D of
 * q, so |c − J| ≤ D + 2r. The radius is widened by 1e-5 relative and the rounding slack, so the
 * joint a float brute-force scan would pick is always in the list. */
static int32_t cell_candidates( const sere_joint_grid* g, int32_t ix, int32_t iy, int32_t iz, int32_t* out )
{
	double centre[3];
	int32_t at[3] = { ix, iy, iz }, lo[3], hi[3];
	for ( int a = 0; a < 3; ++a )
	{
		centre[a] = (double) g->lo[a] + ( at[a] + 0.5 ) * g->h;
		lo[a] = at[a] - GRID_REACH > 0 ? at[a] - GRID_REACH : 0;
		hi[a] = at[a] + GRID_REACH < g->dim[a] - 1 ? at[a] + GRID_REACH : g->dim[a] - 1;
	}
	double nearest = INFINITY;
	for ( int pass = 0; pass < 2; ++pass )
	{
		double radius = ( nearest + sqrt( 3.0 ) * g->h ) * ( 1.0 + 1e-5 ) + 4.0 * g->slack;
		if ( pass == 1 && !( radius <= ( GRID_REACH - 1 ) * g->h ) )
		{
			/* Too far from every joint for a short list: the ring search answers here. */
			return 0;
		}
		int32_t count = 0;
		for ( int32_t jz = lo[2]; jz <= hi[2]; ++jz )
		{
			for ( int32_t jy = lo[1]; jy <= hi[1]; ++jy )
			{
				for ( int32_t jx = lo[0]; jx <= hi[0]; ++jx )
				{
					int32_t cell = ( jz * g->dim[1] + jy ) * g->dim[0] + jx;
					for ( int32_t m = g->start[cell]; m < g->start[cell + 1]; ++m )
					{
						double e = sqrt( pow( g->x[m] - centre[0], 2 ) + pow( g->y[m] - centre[1], 2 ) +
										 pow( g->z[m] - centre[2], 2 ) );
						if ( pass == 0 )
						{
							nearest = e < nearest ? e : nearest;
						}
						else if ( e <= radius )
						{
							if ( count == GRID_CANDIDATES )
							{
								return 0;
							}
							out[count++] = g->items[m];
						}
					}
				}
			}
		}
		if ( pass == 1 )
		{
			/* Ascending joint order, so ties resolve as in a brute-force scan. */
			for ( int32_t a = 1; a < count; ++a )
			{
				int32_t v = out[a], b = a;
				while ( b > 0 && out[b - 1] > v )
				{
					out[b] = out[b - 1];
					--b;
				}
				out[b] = v;
			}
			return count;
		}
	}
	return 0;
}

/* The joints' bounding box; SERE_ERR_NONFINITE for a coordinate that is not finite. */
static sere_status joint_bounds( const float* const p[3], int32_t joint_count, float lo[3], float hi[3] )
{
	for ( int a = 0; a < 3; ++a )
	{
		lo[a] = INFINITY;
		hi[a] = -INFINITY;
	}
	for ( int32_t i = 0; i < joint_count; ++i )
	{
		for ( int a = 0; a < 3; ++a )
		{
			if ( !isfinite( p[a][i] ) )
			{
				return SERE_ERR_NONFINITE;
			}
			lo[a] = fminf( lo[a], p[a][i] );
			hi[a] = fmaxf( hi[a], p[a][i] );
		}
	}
	return SERE_OK;
}

/* About one joint per cell over the axes the joints actually spread along (a leaf's joints
 * are planar, a vein's nearly linear): h is the k-th root of the k-dimensional extent per
 * joint, at least a 128th of the largest extent so the grid stays small. The box is padded
 * by two cells along those axes (half a cell along the others) so the blade around the
 * veins falls inside it and takes the candidate-list path. Sets the cell size, origin,
 * dimensions and rounding slack of g; returns the number of cells. */
static int64_t grid_layout( sere_joint_grid* g, const float lo[3], const float hi[3], int32_t joint_count )
{
	double extent[3], largest = 0.0, product = 1.0;
	int active = 0;
	for ( int a = 0; a < 3; ++a )
	{
		extent[a] = (double) hi[a] - (double) lo[a];
		largest = extent[a] > largest ? extent[a] : largest;
	}
	for ( int a = 0; a < 3; ++a )
	{
		if ( extent[a] > 1e-6 * largest )
		{
			product *= extent[a];
			++active;
		}
	}
	double h = active > 0 ? pow( product / joint_count, 1.0 / active ) : 1.0;
	h = h > largest / 128.0 ? h : largest / 128.0;
	h = h > 0.0 ? h : 1.0;
	g->count = joint_count;
	g->h = h;
	g->inv_h = (float) ( 1.0 / h );
	int64_t cells = 1;
	double magnitude = h;
	for ( int a = 0; a < 3; ++a )
	{
		double pad = ( extent[a] > 1e-6 * largest ? 2.0 : 0.5 ) * h;
		g->lo[a] = (float) ( lo[a] - pad );
		double d = ceil( ( extent[a] + 2.0 * pad ) / h );
		g->dim[a] = d < 1.0 ? 1 : ( d > 192.0 ? 192 : (int32_t) d );
		cells *= g->dim[a];
		magnitude = fmax( magnitude, fabs( (double) g->lo[a] ) + extent[a] + 2.0 * pad );
	}
	g->slack = 8.0 * FLT_EPSILON * magnitude;
	return cells;
}

/* Sorts the joints into their cells (counting sort in joint order, which keeps each cell's
 * joints ascending). cell and fill are scratch of joint_count and `cells` entries. */
static void grid_sort_joints( sere_joint_grid* g, const float* x, const float* y, const float* z, int64_t cells,
							  int32_t* cell, int32_t* fill )
{
	for ( int32_t i = 0; i < g->count; ++i )
	{
		int32_t cx = cell_of( x[i], g->lo[0], g->inv_h, g->dim[0] );
		int32_t cy = cell_of( y[i], g->lo[1], g->inv_h, g->dim[1] );
		int32_t cz = cell_of( z[i], g->lo[2], g->inv_h, g->dim[2] );
		cell[i] = ( cz * g->dim[1] + cy ) * g->dim[0] + cx;
		++g->start[cell[i] + 1];
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		g->start[c + 1] += g->start[c];
	}
	memcpy( fill, g->start, (size_t) cells * sizeof( int32_t ) );
	for ( int32_t i = 0; i < g->count; ++i )
	{
		int32_t k = fill[cell[i]]++;
		g->items[k] = i;
		g->x[k] = x[i];
		g->y[k] = y[i];
		g->z[k] = z[i];
	}
}

/* Candidate lists, cell by cell in parallel (each cell writes its own slot of list, fill
 * counts them), then packed with their positions. */
static sere_status grid_list_candidates( sere_joint_grid* g, const float* x, const float* y, const float* z,
										 int64_t cells, int32_t* fill, int32_t* list )
{
#pragma omp parallel for num_threads( sere_team_for( g->threads ) ) schedule( dynamic, 16 )
	for ( int64_t c = 0; c < cells; ++c )
	{
		int32_t ix = (int32_t) ( c % g->dim[0] ), iy = (int32_t) ( ( c / g->dim[0] ) % g->dim[1] );
		int32_t iz = (int32_t) ( c / ( (int64_t) g->dim[0] * g->dim[1] ) );
		fill[c] = cell_candidates( g, ix, iy, iz, list + c * GRID_CANDIDATES );
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		g->candidate_start[c + 1] = g->candidate_start[c] + fill[c];
	}
	size_t total = (size_t) g->candidate_start[cells];
	g->candidate = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( int32_t ) );
	g->cx = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	g->cy = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	g->cz = sere_alloc( ( total > 0 ? total : 1 ) * sizeof( float ) );
	if ( g->candidate == NULL || g->cx == NULL || g->cy == NULL || g->cz == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int64_t c = 0; c < cells; ++c )
	{
		for ( int32_t k = 0; k < fill[c]; ++k )
		{
			int32_t j = list[c * GRID_CANDIDATES + k];
			int32_t at = g->candidate_start[c] + k;
			g->candidate[at] = j;
			g->cx[at] = x[j];
			g->cy[at] = y[j];
			g->cz[at] = z[j];
		}
	}
	return SERE_OK;
}

sere_status sere_joint_grid_create( const float* x, const float* y, const float* z, int32_t joint_count,
									sere_joint_grid** grid )
{
	*grid = NULL;
	if ( x == NULL || y == NULL || z == NULL || joint_count < 1 || joint_count > ( 1 << 24 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	float lo[3], hi[3];
	const float* const p[3] = { x, y, z };
	if ( joint_bounds( p, joint_count, lo, hi ) != SERE_OK )
	{
		return SERE_ERR_NONFINITE;
	}
	sere_joint_grid* g = calloc( 1, sizeof( sere_joint_grid ) );
	if ( g == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	g->walk_count = -1;
	int64_t cells = grid_layout( g, lo, hi, joint_count );
	g->start = sere_alloc( (size_t) ( cells + 1 ) * sizeof( int32_t ) );
	g->items = sere_alloc( (size_t) joint_count * sizeof( int32_t ) );
	g->x = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->y = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->z = sere_alloc( (size_t) joint_count * sizeof( float ) );
	g->candidate_start = sere_alloc( (size_t) ( cells + 1 ) * sizeof( int32_t ) );
	int32_t* cell = malloc( (size_t) joint_count * sizeof( int32_t ) );
	int32_t* fill = malloc( (size_t) cells * sizeof( int32_t ) );
	int32_t* list = malloc( (size_t) cells * GRID_CANDIDATES * sizeof( int32_t ) );
	sere_status status = SERE_ERR_MEMORY;
	if ( g->start != NULL && g->items != NULL && g->x != NULL && g->y != NULL && g->z != NULL &&
		 g->candidate_start != NULL && cell != NULL && fill != NULL && list != NULL )
	{
		grid_sort_joints( g, x, y, z, cells, cell, fill );
		status = grid_list_candidates( g, x, y, z, cells, fill, list );
	}
	free( fill );
	free( list );
	free( cell );
	if ( status != SERE_OK )
	{
		sere_joint_grid_destroy( g );
		return status;
	}
	*grid = g;
	return SERE_OK;
}

/* The nearest joint to (x, y, z): its cell's candidate list when it has one, else the ring
 * search. */
WALK int32_t grid_nearest( const sere_joint_grid* g, float x, float y, float z, int mode, grid_walk* w )
{
	float fx = ( x - g->lo[0] ) * g->inv_h, fy = ( y - g->lo[1] ) * g->inv_h, fz = ( z - g->lo[2] ) * g->inv_h;
	if ( fx >= 0.0f && fy >= 0.0f && fz >= 0.0f && fx < (float) g->dim[0] && fy < (float) g->dim[1] &&
		 fz < (float) g->dim[2] )
	{
		int32_t c = ( (int32_t) fz * g->dim[1] + (int32_t) fy ) * g->dim[0] + (int32_t) fx;
		int32_t begin = g->candidate_start[c], end = g->candidate_start[c + 1];
		if ( mode == GRID_TOUCH )
		{
			/* the search reads the list's bounds whether it is empty or not */
			w->bits += (uint32_t) begin + (uint32_t) end;
		}
		if ( mode == GRID_TOUCH ? w->rings == 0 : begin < end )
		{
			if ( mode != GRID_SEARCH )
			{
				w->listed = 1;
				w->joints += end - begin;
			}
			int32_t best = -1;
			float best_d2 = INFINITY;
			for ( int32_t k = begin; k < end; ++k )
			{
				if ( mode == GRID_TOUCH )
				{
					w->bits += sere_skel_float_bits( g->cx[k] ) + sere_skel_float_bits( g->cy[k] ) +
							   sere_skel_float_bits( g->cz[k] );
					continue;
				}
				float dx = x - g->cx[k], dy = y - g->cy[k], dz = z - g->cz[k];
				float d2 = dx * dx + dy * dy + dz * dz;
				/* ascending joints: the first of equal distances is the lower index */
				if ( d2 < best_d2 )
				{
					best_d2 = d2;
					best = g->candidate[k];
				}
			}
			return best;
		}
	}
	return ring_nearest( g, x, y, z, mode, w );
}

int32_t sere_joint_grid_nearest( const sere_joint_grid* g, float x, float y, float z )
{
	return grid_nearest( g, x, y, z, GRID_SEARCH, NULL );
}

sere_status sere_joint_grid_set_threads( sere_joint_grid* grid, int32_t threads )
{
	return grid == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &grid->threads, threads );
}

/* The checks and the finiteness pass of every banding. */
static sere_status band_inputs( const sere_joint_grid* grid, const float* x, const float* y, const float* z,
								int32_t vertex_count, const int32_t* joint )
{
	if ( grid == NULL || x == NULL || y == NULL || z == NULL || joint == NULL || vertex_count < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !sere_array_finite( ( const float* const[] ){ x, y, z }, 3, vertex_count, grid->threads ) )
	{
		return SERE_ERR_NONFINITE;
	}
	return SERE_OK;
}

sere_status sere_joint_grid_band( const sere_joint_grid* grid, const float* jx, const float* jy, const float* jz,
								  const float* x, const float* y, const float* z, int32_t vertex_count, int32_t* joint,
								  float* ox, float* oy, float* oz )
{
	if ( ox != NULL && ( oy == NULL || oz == NULL || jx == NULL || jy == NULL || jz == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = band_inputs( grid, x, y, z, vertex_count, joint );
	if ( status != SERE_OK )
	{
		return status;
	}
#pragma omp parallel for num_threads( sere_team_for( grid->threads ) ) schedule( static )
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		int32_t j = grid_nearest( grid, x[i], y[i], z[i], GRID_SEARCH, NULL );
		joint[i] = j;
		if ( ox != NULL )
		{
			ox[i] = x[i] - jx[j];
			oy[i] = y[i] - jy[j];
			oz[i] = z[i] - jz[j];
		}
	}
	return SERE_OK;
}

sere_status sere_joint_grid_record_band( sere_joint_grid* grid, const float* x, const float* y, const float* z,
										 int32_t vertex_count, int32_t* joint, sere_joint_grid_traffic* traffic )
{
	sere_status status = band_inputs( grid, x, y, z, vertex_count, joint );
	if ( status != SERE_OK )
	{
		return status;
	}
	grid->walk_count = -1;
	if ( vertex_count > grid->walk_capacity )
	{
		uint8_t* rings = sere_array_resize( grid->walk_rings, vertex_count, sizeof( uint8_t ) );
		if ( rings == NULL )
		{
			return SERE_ERR_MEMORY;
		}
		grid->walk_rings = rings;
		grid->walk_capacity = vertex_count;
	}
	uint8_t* rings = grid->walk_rings;
	int64_t listed = 0, cells = 0, joints = 0;
	/* A ring search ends by the time its block covers the grid, so it opens at most 192 rings
	 * (the largest dimension) and the count fits a byte. */
#pragma omp parallel for num_threads( sere_team_for( grid->threads ) ) schedule( static ) \
	reduction( + : listed, cells, joints )
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		grid_walk w = { 0, 0, 0, 0, 0 };
		joint[i] = grid_nearest( grid, x[i], y[i], z[i], GRID_RECORD, &w );
		rings[i] = (uint8_t) w.rings;
		listed += w.listed;
		cells += w.cells;
		joints += w.joints;
	}
	grid->walk_count = vertex_count;
	grid->one = 1;
	if ( traffic != NULL )
	{
		*traffic = ( sere_joint_grid_traffic ){ listed, cells, joints };
	}
	return SERE_OK;
}

sere_status sere_joint_grid_touch_band( sere_joint_grid* grid, const float* x, const float* y, const float* z,
										int32_t vertex_count, int32_t* joint, sere_joint_grid_traffic* traffic )
{
	sere_status status = band_inputs( grid, x, y, z, vertex_count, joint );
	if ( status != SERE_OK || grid->walk_count != vertex_count )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	const uint8_t* rings = grid->walk_rings;
	const int32_t one = grid->one;
	int64_t listed = 0, cells = 0, joints = 0;
	uint32_t bits = 0;
#pragma omp parallel for num_threads( sere_team_for( grid->threads ) ) schedule( static ) \
	reduction( + : listed, cells, joints, bits )
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		grid_walk w = { rings[i], 0, 0, 0, 0 };
		grid_nearest( grid, x[i], y[i], z[i], GRID_TOUCH, &w );
		joint[i] *= one;
		listed += w.listed;
		cells += w.cells;
		joints += w.joints;
		bits += w.bits;
	}
	grid->sink += bits;
	if ( traffic != NULL )
	{
		*traffic = ( sere_joint_grid_traffic ){ listed, cells, joints };
	}
	return SERE_OK;
}
