#include "mesh/sample.h"

#include "core/array.h"
#include "core/geometry.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Squared distance from (px, py) to the segment a–b. */
static double segment_distance2( double px, double py, double ax, double ay, double bx, double by )
{
	const double p[2] = { px, py }, a[2] = { ax, ay }, b[2] = { bx, by };
	double dx, dy;
	sere_segment_offset( p, a, b, &dx, &dy );
	return dx * dx + dy * dy;
}

/* A growable point list; vein marks the points placed on a vein or at the outline's base. */
typedef struct sample_point
{
	double x, y;
	uint8_t vein;
} sample_point;

typedef struct point_list
{
	sample_point* p;
	int32_t count, capacity;
} point_list;

/* Index of the new point, or -1 when out of memory. */
static int32_t point_push( point_list* list, double x, double y, uint8_t vein )
{
	const sample_point point = { x, y, vein };
	sample_point* p = sere_array_append( list->p, &list->count, &list->capacity, 256, &point, sizeof( point ) );
	list->p = p != NULL ? p : list->p;
	return p != NULL ? list->count - 1 : -1;
}

typedef struct segment_list
{
	int32_t* pairs;
	int32_t count, capacity;
} segment_list;

/* Cumulative arc length of a polyline of count points. */
static double* arc_lengths( const double* xy, int32_t count, int closed )
{
	double* s = malloc( sizeof( double ) * (size_t) ( count + 1 ) );
	if ( s == NULL )
	{
		return NULL;
	}
	s[0] = 0.0;
	int32_t edges = closed ? count : count - 1;
	for ( int32_t i = 0; i < edges; ++i )
	{
		int32_t j = ( i + 1 ) % count;
		s[i + 1] = s[i] + hypot( xy[2 * j] - xy[2 * i], xy[2 * j + 1] - xy[2 * i + 1] );
	}
	return s;
}

/* The point at arc length a along a polyline with cumulative lengths s over its edges. */
static void point_at( const double* xy, const double* s, int32_t count, int32_t edges, double a, double* px,
					  double* py )
{
	int32_t lo = 0, hi = edges;
	while ( hi - lo > 1 )
	{
		int32_t mid = ( lo + hi ) / 2;
		if ( s[mid] <= a )
		{
			lo = mid;
		}
		else
		{
			hi = mid;
		}
	}
	int32_t j = ( lo + 1 ) % count;
	double length = s[lo + 1] - s[lo];
	double t = length > 0.0 ? ( a - s[lo] ) / length : 0.0;
	t = fmin( 1.0, fmax( 0.0, t ) );
	*px = xy[2 * lo] + t * ( xy[2 * j] - xy[2 * lo] );
	*py = xy[2 * lo + 1] + t * ( xy[2 * j + 1] - xy[2 * lo + 1] );
}

/* Arc length of the point of a polyline closest to (px, py). */
static double project_on( const double* xy, const double* s, int32_t count, int32_t edges, double px, double py )
{
	double best = INFINITY, best_a = 0.0;
	for ( int32_t i = 0; i < edges; ++i )
	{
		int32_t j = ( i + 1 ) % count;
		double ex = xy[2 * j] - xy[2 * i], ey = xy[2 * j + 1] - xy[2 * i + 1];
		double length2 = ex * ex + ey * ey;
		double t = length2 > 0.0 ? ( ( px - xy[2 * i] ) * ex + ( py - xy[2 * i + 1] ) * ey ) / length2 : 0.0;
		t = fmin( 1.0, fmax( 0.0, t ) );
		double dx = xy[2 * i] + t * ex - px, dy = xy[2 * i + 1] + t * ey - py;
		double d2 = dx * dx + dy * dy;
		if ( d2 < best )
		{
			best = d2;
			best_a = s[i] + t * ( s[i + 1] - s[i] );
		}
	}
	return best_a;
}

/* A uniform grid of cell lists over the leaf's bounding box, for nearest-point and
 * nearest-segment queries during the interior fill. */
typedef struct grid
{
	double x0, y0, cell;
	int32_t nx, ny;
	int32_t* head; /* nx * ny */
	int32_t* next; /* per item */
	int32_t capacity;
} grid;

static int grid_init( grid* g, double x0, double y0, double x1, double y1, double cell, int32_t capacity )
{
	g->x0 = x0;
	g->y0 = y0;
	g->cell = cell;
	g->nx = (int32_t) ceil( ( x1 - x0 ) / cell ) + 1;
	g->ny = (int32_t) ceil( ( y1 - y0 ) / cell ) + 1;
	g->head = malloc( sizeof( int32_t ) * (size_t) g->nx * (size_t) g->ny );
	g->next = malloc( sizeof( int32_t ) * (size_t) capacity );
	g->capacity = capacity;
	if ( g->head == NULL || g->next == NULL )
	{
		return -1;
	}
	for ( int32_t i = 0; i < g->nx * g->ny; ++i )
	{
		g->head[i] = -1;
	}
	return 0;
}

static void grid_free( grid* g )
{
	free( g->head );
	free( g->next );
}

static int32_t grid_cell( const grid* g, double x, double y )
{
	int32_t i = (int32_t) floor( ( x - g->x0 ) / g->cell );
	int32_t j = (int32_t) floor( ( y - g->y0 ) / g->cell );
	i = i < 0 ? 0 : ( i >= g->nx ? g->nx - 1 : i );
	j = j < 0 ? 0 : ( j >= g->ny ? g->ny - 1 : j );
	return j * g->nx + i;
}

static void grid_insert( grid* g, int32_t cell, int32_t item )
{
	g->next[item] = g->head[cell];
	g->head[cell] = item;
}

/* Squared distance from (x, y) to the nearest point of the list within radius cells. */
static double nearest_point2( const grid* g, const point_list* points, double x, double y, int32_t radius )
{
	int32_t cell = grid_cell( g, x, y );
	int32_t ci = cell % g->nx, cj = cell / g->nx;
	double best = INFINITY;
	for ( int32_t j = cj - radius; j <= cj + radius; ++j )
	{
		for ( int32_t i = ci - radius; i <= ci + radius; ++i )
		{
			if ( i < 0 || j < 0 || i >= g->nx || j >= g->ny )
			{
				continue;
			}
			for ( int32_t k = g->head[j * g->nx + i]; k >= 0; k = g->next[k] )
			{
				double dx = points->p[k].x - x, dy = points->p[k].y - y;
				best = fmin( best, dx * dx + dy * dy );
			}
		}
	}
	return best;
}

static double nearest_segment2( const grid* g, const double* sx, const double* sy, double x, double y )
{
	int32_t cell = grid_cell( g, x, y );
	int32_t ci = cell % g->nx, cj = cell / g->nx;
	double best = INFINITY;
	for ( int32_t j = cj - 1; j <= cj + 1; ++j )
	{
		for ( int32_t i = ci - 1; i <= ci + 1; ++i )
		{
			if ( i < 0 || j < 0 || i >= g->nx || j >= g->ny )
			{
				continue;
			}
			for ( int32_t k = g->head[j * g->nx + i]; k >= 0; k = g->next[k] )
			{
				best = fmin( best, segment_distance2( x, y, sx[2 * k], sy[2 * k], sx[2 * k + 1], sy[2 * k + 1] ) );
			}
		}
	}
	return best;
}

/* Where each vein but the midvein branches off its parent: the arc length along the parent of
 * the point nearest the vein's first point. */
static void branch_points( const sere_leaf_shape* shape, double* const* lengths, double* branch_at )
{
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		if ( vein->parent >= 0 )
		{
			const sere_vein* parent = shape->veins + vein->parent;
			const double* xy = shape->vein_xy + 2 * vein->first;
			branch_at[v] = project_on( shape->vein_xy + 2 * parent->first, lengths[vein->parent], parent->count,
									   parent->count - 1, xy[0], xy[1] );
		}
	}
}

static sere_status place_veins( const sere_leaf_shape* shape, double spacing, point_list* points,
								segment_list* segments )
{
	int32_t veins = shape->vein_count;
	if ( veins == 0 )
	{
		return SERE_OK;
	}
	sere_status status = SERE_OK;
	double** lengths = calloc( (size_t) veins, sizeof( double* ) );
	double* branch_at = malloc( sizeof( double ) * (size_t) veins );
	int32_t* start_vertex = malloc( sizeof( int32_t ) * (size_t) veins );
	/* The veins branching off one vein, keyed by where along it they branch, ties by index. */
	sere_sort_item* branches = malloc( sizeof( sere_sort_item ) * (size_t) veins );
	if ( !lengths || !branch_at || !start_vertex || !branches )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	for ( int32_t v = 0; v < veins; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		lengths[v] = arc_lengths( shape->vein_xy + 2 * vein->first, vein->count, 0 );
		if ( lengths[v] == NULL )
		{
			status = SERE_ERR_MEMORY;
			goto done;
		}
		start_vertex[v] = vein->parent < 0 ? 0 : -1;
	}
	branch_points( shape, lengths, branch_at );
	/* Parents come before their children (the shape validator checks parent < index). */
	for ( int32_t v = 0; v < veins; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		const double* xy = shape->vein_xy + 2 * vein->first;
		const double* s = lengths[v];
		double total = s[vein->count - 1];
		int32_t count = 0;
		for ( int32_t c = v + 1; c < veins; ++c )
		{
			if ( shape->veins[c].parent == v )
			{
				branches[count++] = ( sere_sort_item ){ sere_sort_key_double( fmin( branch_at[c], total ) ), c, 0 };
			}
		}
		sere_sort_items( branches, count );
		if ( start_vertex[v] < 0 )
		{
			status = SERE_ERR_GEOMETRY;
			goto done;
		}
		int32_t previous = start_vertex[v];
		double previous_a = 0.0;
		/* The anchors after the vein's start: each branch point, then the vein's end. */
		for ( int32_t k = 0; k <= count; ++k )
		{
			int32_t child = k < count ? branches[k].index : -1;
			double a = k < count ? fmin( branch_at[child], total ) : total;
			/* Branches closer than half a spacing to the previous anchor share its vertex. */
			if ( a - previous_a < 0.5 * spacing && k < count )
			{
				start_vertex[child] = previous;
				continue;
			}
			if ( k == count && a - previous_a < 0.5 * spacing )
			{
				break; /* the vein ends within half a spacing of its last vertex */
			}
			int32_t pieces = (int32_t) fmax( 1.0, round( ( a - previous_a ) / spacing ) );
			for ( int32_t q = 1; q <= pieces; ++q )
			{
				double px, py;
				point_at( xy, s, vein->count, vein->count - 1, previous_a + ( a - previous_a ) * q / pieces, &px, &py );
				int32_t vertex = point_push( points, px, py, 1 );
				const int32_t segment[2] = { previous, vertex };
				int32_t* pairs = vertex < 0 ? NULL
											: sere_array_append( segments->pairs, &segments->count, &segments->capacity,
																 256, segment, sizeof( segment ) );
				if ( pairs == NULL )
				{
					status = SERE_ERR_MEMORY;
					goto done;
				}
				segments->pairs = pairs;
				previous = vertex;
			}
			previous_a = a;
			if ( child >= 0 )
			{
				start_vertex[child] = previous;
			}
		}
		/* Children that merged into the vein's end anchor. */
		for ( int32_t k = 0; k < count; ++k )
		{
			if ( start_vertex[branches[k].index] < 0 )
			{
				start_vertex[branches[k].index] = previous;
			}
		}
	}
done:
	if ( lengths != NULL )
	{
		for ( int32_t v = 0; v < veins; ++v )
		{
			free( lengths[v] );
		}
	}
	free( lengths );
	free( branch_at );
	free( start_vertex );
	free( branches );
	return status;
}

void sere_samples_destroy( sere_samples* samples )
{
	void* arrays[] = { samples->x, samples->y, samples->vein, samples->segments };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	memset( samples, 0, sizeof( *samples ) );
}

/* Every constraint segment stored in each cell of the grid its bounding box covers (segments
 * are about one spacing long, so a few cells each); the grid's items are slots, and *slot_x,
 * *slot_y hold each slot's segment end points so the query reads them directly. */
static sere_status bucket_segments( grid* segment_grid, const double* flat_x, const double* flat_y,
									int32_t segment_count, int32_t cells_per_segment, double** slot_x_out,
									double** slot_y_out )
{
	/* Store every segment in each cell its bounding box covers (segments are about one
	 * spacing long, so a few cells each); a larger segment is split into more slots. */
	int32_t slot = 0;
	int32_t* slot_segment = malloc( sizeof( int32_t ) * (size_t) segment_count * (size_t) cells_per_segment );
	if ( slot_segment == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < segment_count; ++k )
	{
		int32_t c0 = grid_cell( segment_grid, fmin( flat_x[2 * k], flat_x[2 * k + 1] ),
								fmin( flat_y[2 * k], flat_y[2 * k + 1] ) );
		int32_t c1 = grid_cell( segment_grid, fmax( flat_x[2 * k], flat_x[2 * k + 1] ),
								fmax( flat_y[2 * k], flat_y[2 * k + 1] ) );
		for ( int32_t j = c0 / segment_grid->nx; j <= c1 / segment_grid->nx; ++j )
		{
			for ( int32_t i = c0 % segment_grid->nx; i <= c1 % segment_grid->nx; ++i )
			{
				if ( slot < segment_grid->capacity )
				{
					slot_segment[slot] = k;
					grid_insert( segment_grid, j * segment_grid->nx + i, slot++ );
				}
			}
		}
	}
	/* Segment coordinates indexed by slot, so the query reads them directly. */
	double* slot_x = malloc( sizeof( double ) * 2 * (size_t) ( slot > 0 ? slot : 1 ) );
	double* slot_y = malloc( sizeof( double ) * 2 * (size_t) ( slot > 0 ? slot : 1 ) );
	if ( slot_x == NULL || slot_y == NULL )
	{
		free( slot_segment ), free( slot_x ), free( slot_y );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < slot; ++k )
	{
		int32_t q = slot_segment[k];
		slot_x[2 * k] = flat_x[2 * q], slot_x[2 * k + 1] = flat_x[2 * q + 1];
		slot_y[2 * k] = flat_y[2 * q], slot_y[2 * k + 1] = flat_y[2 * q + 1];
	}
	free( slot_segment );
	*slot_x_out = slot_x;
	*slot_y_out = slot_y;
	return SERE_OK;
}

/* Mitchell's best candidate: of several uniform candidates inside the outline keep the one
 * farthest from every placed point and, weighted, from every constraint segment; fill points. */
static sere_status best_candidates( const sere_sample_params* params, int32_t fill, const double* polygon, int32_t b,
									point_list* points, grid* point_grid, const grid* segment_grid,
									const double* slot_x, const double* slot_y, double x0, double y0, double x1,
									double y1 )
{
	const int32_t candidates = params->candidates > 0 ? params->candidates : 24;
	uint64_t state = params->seed ^ 0x5eedull;
	int64_t attempts_left = (int64_t) fill * candidates * 64 + 1024; /* past int32_t at large candidates */
	for ( int32_t placed = 0; placed < fill; ++placed )
	{
		double best_score = -1.0, best_x = 0.0, best_y = 0.0;
		for ( int32_t c = 0; c < candidates && attempts_left > 0; --attempts_left )
		{
			double cx = x0 + ( x1 - x0 ) * sere_splitmix_unit( &state );
			double cy = y0 + ( y1 - y0 ) * sere_splitmix_unit( &state );
			if ( !sere_point_in_polygon( polygon, b, cx, cy ) )
			{
				continue;
			}
			c += 1;
			double dp = sqrt( nearest_point2( point_grid, points, cx, cy, 2 ) );
			double ds = sqrt( nearest_segment2( segment_grid, slot_x, slot_y, cx, cy ) );
			double score = fmin( dp, 1.5 * ds );
			if ( score > best_score )
			{
				best_score = score, best_x = cx, best_y = cy;
			}
		}
		if ( best_score < 0.0 )
		{
			return SERE_ERR_GEOMETRY; /* no point inside the outline could be found */
		}
		int32_t k = point_push( points, best_x, best_y, 0 );
		if ( k < 0 )
		{
			return SERE_ERR_MEMORY;
		}
		grid_insert( point_grid, grid_cell( point_grid, best_x, best_y ), k );
	}
	return SERE_OK;
}

/* The samples handed out in sere_alloc'd arrays. */
static sere_status copy_out( const point_list* points, const segment_list* segments, int32_t b, sere_samples* out )
{
	out->point_count = points->count;
	out->boundary_count = b;
	out->segment_count = segments->count;
	out->x = sere_alloc( sizeof( double ) * (size_t) points->count );
	out->y = sere_alloc( sizeof( double ) * (size_t) points->count );
	out->vein = sere_alloc( (size_t) points->count );
	out->segments = sere_alloc( sizeof( int32_t ) * 2 * (size_t) ( segments->count > 0 ? segments->count : 1 ) );
	if ( !out->x || !out->y || !out->vein || !out->segments )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < points->count; ++k )
	{
		out->x[k] = points->p[k].x;
		out->y[k] = points->p[k].y;
		out->vein[k] = points->p[k].vein;
	}
	if ( segments->count > 0 )
	{
		memcpy( out->segments, segments->pairs, sizeof( int32_t ) * 2 * (size_t) segments->count );
	}
	return SERE_OK;
}

/* Outline: b points at equal arc length, the base first (it lies on the outline). 0, or -1 when
 * out of memory. */
static int place_outline( const sere_leaf_shape* shape, const double* outline_s, double perimeter, int32_t b,
						  point_list* points )
{
	double base_a = project_on( shape->outline_xy, outline_s, shape->outline_count, shape->outline_count, shape->base_x,
								shape->base_y );
	for ( int32_t k = 0; k < b; ++k )
	{
		double a = fmod( base_a + perimeter * k / b, perimeter );
		double px, py;
		point_at( shape->outline_xy, outline_s, shape->outline_count, shape->outline_count, a, &px, &py );
		if ( point_push( points, px, py, k == 0 && shape->vein_count > 0 ) < 0 )
		{
			return -1;
		}
	}
	return 0;
}

/* The first b points (the resampled outline) as a polygon, and its box x0, y0, x1, y1; NULL with
 * *status set when out of memory or a vein point lies outside the resampled outline. */
static double* outline_polygon( const point_list* points, int32_t b, double box[4], sere_status* status )
{
	double* polygon = malloc( sizeof( double ) * 2 * (size_t) b );
	if ( polygon == NULL )
	{
		*status = SERE_ERR_MEMORY;
		return NULL;
	}
	double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
	for ( int32_t k = 0; k < b; ++k )
	{
		polygon[2 * k] = points->p[k].x;
		polygon[2 * k + 1] = points->p[k].y;
		x0 = fmin( x0, points->p[k].x ), x1 = fmax( x1, points->p[k].x );
		y0 = fmin( y0, points->p[k].y ), y1 = fmax( y1, points->p[k].y );
	}
	for ( int32_t k = b; k < points->count; ++k )
	{
		if ( !sere_point_in_polygon( polygon, b, points->p[k].x, points->p[k].y ) )
		{
			free( polygon );
			*status = SERE_ERR_GEOMETRY; /* a vein point outside the resampled outline */
			return NULL;
		}
	}
	box[0] = x0, box[1] = y0, box[2] = x1, box[3] = y1;
	return polygon;
}

/* The arguments sere_sample_leaf refuses; out, when there is one, is cleared first. */
static bool sample_arguments_valid( const sere_leaf_shape* shape, const sere_sample_params* params, sere_samples* out )
{
	if ( out != NULL )
	{
		memset( out, 0, sizeof( *out ) );
	}
	return out != NULL && shape != NULL && params != NULL && shape->outline_count >= 3 && params->boundary_count >= 3 &&
		   params->point_count >= params->boundary_count;
}

sere_status sere_sample_leaf( const sere_leaf_shape* shape, const sere_sample_params* params, sere_samples* out )
{
	if ( !sample_arguments_valid( shape, params, out ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n_target = params->point_count;
	const int32_t b = params->boundary_count;
	const double area = fabs( sere_shape_area( shape ) );
	const double perimeter = sere_shape_perimeter( shape );
	if ( !( area > 0.0 ) || !isfinite( area ) )
	{
		return SERE_ERR_GEOMETRY;
	}
	/* F = 2N − B − 2 equilateral triangles of side s tile the area: s² = A / (F √3/4). */
	const double spacing = sqrt( area / ( ( 2.0 * n_target - b - 2.0 ) * sqrt( 3.0 ) / 4.0 ) );
	out->spacing = spacing;

	point_list points = { 0 };
	segment_list segments = { 0 };
	double* outline_s = NULL;
	double* seg_x = NULL;
	double* seg_y = NULL;
	grid point_grid = { 0 }, segment_grid = { 0 };
	sere_status status = SERE_OK;

	outline_s = arc_lengths( shape->outline_xy, shape->outline_count, 1 );
	if ( outline_s == NULL )
	{
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	if ( place_outline( shape, outline_s, perimeter, b, &points ) != 0 )
	{
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	status = place_veins( shape, spacing, &points, &segments );
	if ( status != SERE_OK )
	{
		goto fail;
	}
	out->vein_point_count = points.count - b;
	int32_t fill = n_target - points.count;
	if ( fill < 0 )
	{
		status = SERE_ERR_COUNTS;
		goto fail;
	}

	/* The resampled outline polygon, for the inside test and segment distances. */
	double box[4];
	double* polygon = outline_polygon( &points, b, box, &status );
	if ( polygon == NULL )
	{
		goto fail;
	}
	const double x0 = box[0], y0 = box[1], x1 = box[2], y1 = box[3];

	/* Constraint segments (outline edges, vein segments) bucketed by the cells they touch. */
	int32_t segment_count = b + segments.count;
	seg_x = malloc( sizeof( double ) * 2 * (size_t) segment_count );
	seg_y = malloc( sizeof( double ) * 2 * (size_t) segment_count );
	int32_t cells_per_segment = 16;
	if ( !seg_x || !seg_y || grid_init( &point_grid, x0, y0, x1, y1, spacing, n_target ) != 0 ||
		 grid_init( &segment_grid, x0, y0, x1, y1, spacing, segment_count * cells_per_segment ) != 0 )
	{
		free( polygon );
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	/* Segment grid entries: item = slot, the segment index recovered as slot / cells_per_segment. */
	for ( int32_t k = 0; k < segment_count; ++k )
	{
		int32_t a = k < b ? k : segments.pairs[2 * ( k - b )];
		int32_t c = k < b ? ( k + 1 ) % b : segments.pairs[2 * ( k - b ) + 1];
		seg_x[2 * k] = points.p[a].x, seg_y[2 * k] = points.p[a].y;
		seg_x[2 * k + 1] = points.p[c].x, seg_y[2 * k + 1] = points.p[c].y;
	}
	double *slot_x = NULL, *slot_y = NULL;
	if ( bucket_segments( &segment_grid, seg_x, seg_y, segment_count, cells_per_segment, &slot_x, &slot_y ) != SERE_OK )
	{
		free( polygon );
		status = SERE_ERR_MEMORY;
		goto fail;
	}
	for ( int32_t k = 0; k < points.count; ++k )
	{
		grid_insert( &point_grid, grid_cell( &point_grid, points.p[k].x, points.p[k].y ), k );
	}

	status = best_candidates( params, fill, polygon, b, &points, &point_grid, &segment_grid, slot_x, slot_y, x0, y0, x1,
							  y1 );
	free( polygon ), free( slot_x ), free( slot_y );
	if ( status != SERE_OK )
	{
		goto fail;
	}

	status = copy_out( &points, &segments, b, out );
	if ( status != SERE_OK )
	{
		goto fail;
	}
	free( points.p ), free( segments.pairs ), free( outline_s );
	free( seg_x ), free( seg_y );
	grid_free( &point_grid );
	grid_free( &segment_grid );
	return SERE_OK;

fail:
	free( points.p ), free( segments.pairs ), free( outline_s );
	free( seg_x ), free( seg_y );
	grid_free( &point_grid );
	grid_free( &segment_grid );
	sere_samples_destroy( out );
	return status;
}
