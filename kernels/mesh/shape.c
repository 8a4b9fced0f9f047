#include "mesh/shape.h"

#include "core/geometry.h"

#include <math.h>
#include <stdlib.h>

const char* sere_shape_problem_text( sere_shape_problem problem )
{
	switch ( problem )
	{
		case SERE_SHAPE_OK:
			return "ok";
		case SERE_SHAPE_FEW_OUTLINE_POINTS:
			return "outline has fewer than 3 points";
		case SERE_SHAPE_NONFINITE:
			return "NaN or infinite coordinate";
		case SERE_SHAPE_SELF_INTERSECTING:
			return "outline intersects itself";
		case SERE_SHAPE_VEIN_OUTSIDE:
			return "vein point outside the outline";
		case SERE_SHAPE_VEIN_DISCONNECTED:
			return "vein not connected to the base (a vein without parent starts at the base, a branch on its "
				   "parent vein)";
		case SERE_SHAPE_BAD_VEIN:
			return "vein with fewer than 2 points, a parent that is not an earlier vein, or an order below 1";
		case SERE_SHAPE_BASE_OFF_OUTLINE:
			return "base does not lie on the outline";
		case SERE_SHAPE_CLOCKWISE:
			return "outline must be counter-clockwise (this one runs clockwise)";
		case SERE_SHAPE_REPEATED_POINT:
			return "point repeats the one before it (an outline must not repeat its first point at the end)";
		case SERE_SHAPE_VEIN_CROSSES_OUTLINE:
			return "vein crosses the outline";
		case SERE_SHAPE_VEINS_CROSS:
			return "veins cross or touch (a vein may meet another only at its own first point)";
	}
	return "unknown problem";
}

double sere_shape_area( const sere_leaf_shape* shape )
{
	const double* p = shape->outline_xy;
	int32_t n = shape->outline_count;
	double twice = 0.0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		twice += p[2 * j] * p[2 * i + 1] - p[2 * i] * p[2 * j + 1];
	}
	return 0.5 * twice;
}

double sere_shape_perimeter( const sere_leaf_shape* shape )
{
	const double* p = shape->outline_xy;
	int32_t n = shape->outline_count;
	double length = 0.0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		length += hypot( p[2 * i] - p[2 * j], p[2 * i + 1] - p[2 * j + 1] );
	}
	return length;
}

static double orient( const double* a, const double* b, const double* c )
{
	return ( b[0] - a[0] ) * ( c[1] - a[1] ) - ( b[1] - a[1] ) * ( c[0] - a[0] );
}

/* c lies in the bounding box of a-b (used once c is known to be collinear with a-b). */
static int within_box( const double* a, const double* b, const double* c )
{
	return c[0] >= fmin( a[0], b[0] ) && c[0] <= fmax( a[0], b[0] ) && c[1] >= fmin( a[1], b[1] ) &&
		   c[1] <= fmax( a[1], b[1] );
}

/* Closed segments a-b and c-d share at least one point (touching and collinear overlap count). */
static int segments_meet( const double* a, const double* b, const double* c, const double* d )
{
	double o1 = orient( a, b, c ), o2 = orient( a, b, d ), o3 = orient( c, d, a ), o4 = orient( c, d, b );
	if ( ( ( o1 > 0 && o2 < 0 ) || ( o1 < 0 && o2 > 0 ) ) && ( ( o3 > 0 && o4 < 0 ) || ( o3 < 0 && o4 > 0 ) ) )
	{
		return 1;
	}
	return ( o1 == 0 && within_box( a, b, c ) ) || ( o2 == 0 && within_box( a, b, d ) ) ||
		   ( o3 == 0 && within_box( c, d, a ) ) || ( o4 == 0 && within_box( c, d, b ) );
}

/* Every segment of the shape in one index space: outline edge i runs from point i to point
 * i + 1 (the last one back to 0); then the segments of each vein in vein order. */
typedef struct segment
{
	const double* a;
	const double* b;
	int32_t vein; /* -1 for an outline edge */
	int32_t k;	  /* edge index, or segment index within the vein */
	int32_t end;  /* index of b among the outline or vein points */
	int32_t cell_x0, cell_y0, cell_x1, cell_y1;
} segment;

typedef struct crossing
{
	sere_shape_problem problem;
	int32_t later, earlier; /* segment indices; the pair whose later segment comes first wins */
} crossing;

static void keep_first( crossing* best, sere_shape_problem problem, int32_t later, int32_t earlier )
{
	if ( best->problem == SERE_SHAPE_OK || later < best->later || ( later == best->later && earlier < best->earlier ) )
	{
		*best = ( crossing ){ problem, later, earlier };
	}
}

/* Vein segment s starts its vein and meets segment t only at the vein's first point: a branch
 * leaving its parent, a vein leaving the base, siblings leaving one point. Its far end must
 * stay off t, so a first segment running along t is not excused. */
static int meets_at_start( const segment* s, const segment* t, double tolerance )
{
	return s->vein >= 0 && s->k == 0 && s->vein != t->vein &&
		   sere_point_segment_distance( s->a, t->a, t->b ) <= tolerance &&
		   sere_point_segment_distance( s->b, t->a, t->b ) > tolerance;
}

/* Adjacent segments share a point; they are wrong only when the second folds back onto the first. */
static int folds_back( const double* a, const double* shared, const double* b )
{
	double dot = ( a[0] - shared[0] ) * ( b[0] - shared[0] ) + ( a[1] - shared[1] ) * ( b[1] - shared[1] );
	return orient( a, shared, b ) == 0.0 && dot > 0.0;
}

/* Outline crossings go to outline_best, vein crossings to vein_best: the outline is checked
 * (and reported) before anything that needs an inside. */
static void classify( const segment* segments, int32_t n, int32_t s, int32_t t, double tolerance,
					  crossing* outline_best, crossing* vein_best )
{
	/* s < t: t comes later in the arrays. */
	const segment* a = segments + s;
	const segment* b = segments + t;
	if ( a->vein < 0 && b->vein < 0 )
	{
		int adjacent = t == s + 1 || ( s == 0 && t == n - 1 );
		int bad = adjacent ? ( t == s + 1 ? folds_back( a->a, a->b, b->b ) : folds_back( b->a, b->b, a->b ) )
						   : segments_meet( a->a, a->b, b->a, b->b );
		if ( bad )
		{
			keep_first( outline_best, SERE_SHAPE_SELF_INTERSECTING, t, s );
		}
	}
	else if ( a->vein == b->vein && b->k == a->k + 1 )
	{
		if ( folds_back( a->a, a->b, b->b ) )
		{
			keep_first( vein_best, SERE_SHAPE_VEINS_CROSS, t, s );
		}
	}
	else if ( segments_meet( a->a, a->b, b->a, b->b ) && !meets_at_start( a, b, tolerance ) &&
			  !meets_at_start( b, a, tolerance ) )
	{
		keep_first( vein_best, a->vein < 0 ? SERE_SHAPE_VEIN_CROSSES_OUTLINE : SERE_SHAPE_VEINS_CROSS, t, s );
	}
}

/* Tests every pair of segments whose bounding boxes share a cell of a uniform grid, each pair
 * once: in the lowest cell of the overlap of their cell ranges. */
static sere_status find_crossings( segment* segments, int32_t count, int32_t n, double tolerance,
								   crossing* outline_best, crossing* vein_best )
{
	double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
	for ( int32_t s = 0; s < count; ++s )
	{
		x0 = fmin( x0, fmin( segments[s].a[0], segments[s].b[0] ) );
		x1 = fmax( x1, fmax( segments[s].a[0], segments[s].b[0] ) );
		y0 = fmin( y0, fmin( segments[s].a[1], segments[s].b[1] ) );
		y1 = fmax( y1, fmax( segments[s].a[1], segments[s].b[1] ) );
	}
	/* About one segment per cell along each axis for a curve: sqrt(count) cells a side. */
	int32_t side = (int32_t) fmin( 1024.0, fmax( 1.0, ceil( sqrt( (double) count ) ) ) );
	double cell = fmax( x1 - x0, y1 - y0 ) / side;
	if ( !( cell > 0.0 ) )
	{
		cell = 1.0;
	}
	int64_t total = 0;
	for ( int32_t s = 0; s < count; ++s )
	{
		segment* g = segments + s;
		g->cell_x0 = (int32_t) fmin( side - 1, ( fmin( g->a[0], g->b[0] ) - x0 ) / cell );
		g->cell_x1 = (int32_t) fmin( side - 1, ( fmax( g->a[0], g->b[0] ) - x0 ) / cell );
		g->cell_y0 = (int32_t) fmin( side - 1, ( fmin( g->a[1], g->b[1] ) - y0 ) / cell );
		g->cell_y1 = (int32_t) fmin( side - 1, ( fmax( g->a[1], g->b[1] ) - y0 ) / cell );
		total += (int64_t) ( g->cell_x1 - g->cell_x0 + 1 ) * ( g->cell_y1 - g->cell_y0 + 1 );
	}
	int32_t cells = side * side;
	int64_t* start = calloc( (size_t) cells + 1, sizeof( int64_t ) );
	int32_t* members = malloc( sizeof( int32_t ) * (size_t) total );
	if ( start == NULL || members == NULL )
	{
		free( start );
		free( members );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t s = 0; s < count; ++s )
	{
		for ( int32_t cy = segments[s].cell_y0; cy <= segments[s].cell_y1; ++cy )
		{
			for ( int32_t cx = segments[s].cell_x0; cx <= segments[s].cell_x1; ++cx )
			{
				start[cy * side + cx + 1] += 1;
			}
		}
	}
	for ( int32_t c = 0; c < cells; ++c )
	{
		start[c + 1] += start[c];
	}
	for ( int32_t s = 0; s < count; ++s )
	{
		for ( int32_t cy = segments[s].cell_y0; cy <= segments[s].cell_y1; ++cy )
		{
			for ( int32_t cx = segments[s].cell_x0; cx <= segments[s].cell_x1; ++cx )
			{
				/* Filling in segment order keeps every cell's list sorted. */
				members[start[cy * side + cx]++] = s;
			}
		}
	}
	for ( int32_t c = cells; c > 0; --c )
	{
		start[c] = start[c - 1];
	}
	start[0] = 0;
	for ( int32_t c = 0; c < cells; ++c )
	{
		int32_t cx = c % side, cy = c / side;
		for ( int64_t i = start[c]; i < start[c + 1]; ++i )
		{
			const segment* a = segments + members[i];
			for ( int64_t j = i + 1; j < start[c + 1]; ++j )
			{
				const segment* b = segments + members[j];
				if ( cx == ( a->cell_x0 > b->cell_x0 ? a->cell_x0 : b->cell_x0 ) &&
					 cy == ( a->cell_y0 > b->cell_y0 ? a->cell_y0 : b->cell_y0 ) )
				{
					classify( segments, n, members[i], members[j], tolerance, outline_best, vein_best );
				}
			}
		}
	}
	free( start );
	free( members );
	return SERE_OK;
}

static sere_status fail( sere_shape_check* check, sere_shape_problem problem, int32_t vein, int32_t point )
{
	check->problem = problem;
	check->vein = vein;
	check->point = point;
	return problem == SERE_SHAPE_NONFINITE ? SERE_ERR_NONFINITE : SERE_ERR_GEOMETRY;
}

static int32_t vein_of_point( const sere_leaf_shape* shape, int32_t point )
{
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		if ( point >= shape->veins[v].first && point < shape->veins[v].first + shape->veins[v].count )
		{
			return v;
		}
	}
	return -1;
}

/* The points: enough of them on the outline, all finite, the veins' ranges valid, no point
 * repeated at once; *extent is the outline's larger side, the scale of the tolerance. */
static sere_status check_points( const sere_leaf_shape* shape, sere_shape_check* check, double* extent )
{
	const int32_t n = shape->outline_count;
	const double* xy = shape->outline_xy;
	if ( n < 3 )
	{
		return fail( check, SERE_SHAPE_FEW_OUTLINE_POINTS, -1, -1 );
	}
	double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( !isfinite( xy[2 * i] ) || !isfinite( xy[2 * i + 1] ) )
		{
			return fail( check, SERE_SHAPE_NONFINITE, -1, i );
		}
		x0 = fmin( x0, xy[2 * i] ), x1 = fmax( x1, xy[2 * i] );
		y0 = fmin( y0, xy[2 * i + 1] ), y1 = fmax( y1, xy[2 * i + 1] );
	}
	for ( int32_t i = 0; i < 2 * shape->vein_point_count; ++i )
	{
		if ( !isfinite( shape->vein_xy[i] ) )
		{
			return fail( check, SERE_SHAPE_NONFINITE, vein_of_point( shape, i / 2 ), i / 2 );
		}
	}
	if ( !isfinite( shape->base_x ) || !isfinite( shape->base_y ) )
	{
		return fail( check, SERE_SHAPE_NONFINITE, -1, -1 );
	}
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		if ( vein->count < 2 || vein->first < 0 || vein->first > shape->vein_point_count - vein->count ||
			 vein->parent >= v || vein->parent < -1 || vein->order < 1 )
		{
			return fail( check, SERE_SHAPE_BAD_VEIN, v, vein->first >= 0 ? vein->first : -1 );
		}
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t j = ( i + 1 ) % n;
		if ( xy[2 * i] == xy[2 * j] && xy[2 * i + 1] == xy[2 * j + 1] )
		{
			return fail( check, SERE_SHAPE_REPEATED_POINT, -1, j > i ? j : i );
		}
	}
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const double* p = shape->vein_xy + 2 * shape->veins[v].first;
		for ( int32_t k = 1; k < shape->veins[v].count; ++k )
		{
			if ( p[2 * k] == p[2 * k - 2] && p[2 * k + 1] == p[2 * k - 1] )
			{
				return fail( check, SERE_SHAPE_REPEATED_POINT, v, shape->veins[v].first + k );
			}
		}
	}
	*extent = fmax( x1 - x0, y1 - y0 );
	return SERE_OK;
}

/* Each vein starts at the base (a main vein) or on its parent, within the tolerance, and its
 * other points lie inside the outline. */
static sere_status check_vein_roots( const sere_leaf_shape* shape, const double base[2], double tolerance,
									 sere_shape_check* check )
{
	const int32_t n = shape->outline_count;
	const double* xy = shape->outline_xy;
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vn = shape->veins + v;
		const double* p = shape->vein_xy + 2 * vn->first;
		double d = INFINITY;
		if ( vn->parent < 0 )
		{
			d = hypot( p[0] - base[0], p[1] - base[1] );
		}
		else
		{
			const sere_vein* parent = shape->veins + vn->parent;
			const double* q = shape->vein_xy + 2 * parent->first;
			for ( int32_t k = 0; k + 1 < parent->count; ++k )
			{
				d = fmin( d, sere_point_segment_distance( p, q + 2 * k, q + 2 * k + 2 ) );
			}
		}
		if ( d > tolerance )
		{
			return fail( check, SERE_SHAPE_VEIN_DISCONNECTED, v, vn->first );
		}
		for ( int32_t k = 1; k < vn->count; ++k )
		{
			if ( !sere_point_in_polygon( xy, n, p[2 * k], p[2 * k + 1] ) )
			{
				return fail( check, SERE_SHAPE_VEIN_OUTSIDE, v, vn->first + k );
			}
		}
	}
	return SERE_OK;
}

sere_status sere_shape_validate( const sere_leaf_shape* shape, sere_shape_check* check )
{
	if ( check == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	check->problem = SERE_SHAPE_OK;
	check->vein = -1;
	check->point = -1;
	check->other = -1;
	if ( shape == NULL || shape->outline_count < 0 || shape->vein_count < 0 || shape->vein_point_count < 0 ||
		 ( shape->outline_count > 0 && shape->outline_xy == NULL ) ||
		 ( shape->vein_count > 0 && shape->veins == NULL ) ||
		 ( shape->vein_point_count > 0 && shape->vein_xy == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = shape->outline_count;
	const double* xy = shape->outline_xy;
	double extent;
	sere_status status = check_points( shape, check, &extent );
	if ( status != SERE_OK )
	{
		return status;
	}
	const double tolerance = SERE_SHAPE_TOLERANCE * extent;
	const double base[2] = { shape->base_x, shape->base_y };

	/* Every pair of pieces that meet: outline edges, then vein segments. */
	int32_t count = n;
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		count += shape->veins[v].count - 1;
	}
	segment* segments = malloc( sizeof( segment ) * (size_t) count );
	if ( segments == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t j = ( i + 1 ) % n;
		segments[i] = ( segment ){ .a = xy + 2 * i, .b = xy + 2 * j, .vein = -1, .k = i, .end = j };
	}
	for ( int32_t v = 0, s = n; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		for ( int32_t k = 0; k + 1 < vein->count; ++k, ++s )
		{
			const double* p = shape->vein_xy + 2 * ( vein->first + k );
			segments[s] = ( segment ){ .a = p, .b = p + 2, .vein = v, .k = k, .end = vein->first + k + 1 };
		}
	}
	crossing outline_best = { SERE_SHAPE_OK, -1, -1 }, vein_best = { SERE_SHAPE_OK, -1, -1 };
	status = find_crossings( segments, count, n, tolerance, &outline_best, &vein_best );
	const crossing* found = outline_best.problem != SERE_SHAPE_OK ? &outline_best : &vein_best;
	int32_t point = found->problem != SERE_SHAPE_OK ? segments[found->later].end : -1;
	int32_t other = found->problem != SERE_SHAPE_OK ? segments[found->earlier].end : -1;
	int32_t vein = found->problem != SERE_SHAPE_OK ? segments[found->later].vein : -1;
	free( segments );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( outline_best.problem != SERE_SHAPE_OK )
	{
		check->other = other;
		return fail( check, SERE_SHAPE_SELF_INTERSECTING, -1, point );
	}

	/* A simple polygon has a non-zero signed area whose sign is its orientation. */
	if ( sere_shape_area( shape ) < 0.0 )
	{
		return fail( check, SERE_SHAPE_CLOCKWISE, -1, -1 );
	}
	double nearest = INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		nearest = fmin( nearest, sere_point_segment_distance( base, xy + 2 * i, xy + 2 * ( ( i + 1 ) % n ) ) );
	}
	if ( nearest > tolerance )
	{
		return fail( check, SERE_SHAPE_BASE_OFF_OUTLINE, -1, -1 );
	}
	status = check_vein_roots( shape, base, tolerance, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	/* Points inside, but a segment may still cut through a notch of the outline or another vein. */
	if ( vein_best.problem != SERE_SHAPE_OK )
	{
		check->other = other;
		return fail( check, vein_best.problem, vein, point );
	}
	return SERE_OK;
}
