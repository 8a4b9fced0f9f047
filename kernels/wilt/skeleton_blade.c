/* sere — The leaf skeleton (Sec. 4.1) and the blade mesh made from it (Sec. 5.1). Seed 003: Lu, Zhao, Guo 2009. */
#include "core/geometry.h"
#include "mesh/triangulate.h"
#include "wilt/internal/skeleton_shared.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Leaf skeleton (Sec. 4.1). */

sere_status sere_leaf_skeleton_generate( double length, double width, int32_t feature_count, double* left_xy,
										 double* right_xy, double* mid_xy )
{
	if ( !isfinite( length ) || !isfinite( width ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( length <= 0.0 || width <= 0.0 || feature_count < 3 || feature_count > MAX_CURVE_POINTS || left_xy == NULL ||
		 right_xy == NULL || mid_xy == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* Half-width sqrt(ξ)(1 − ξ), scaled to 1 at its maximum ξ = 1/3: a vertical tangent at the
	 * base (rounded) and a straight approach to the tip (pointed), the ovate blade of Fig. 2. */
	double peak = sqrt( 1.0 / 3.0 ) * ( 2.0 / 3.0 );
	for ( int32_t i = 0; i < feature_count; ++i )
	{
		double xi = (double) i / ( feature_count - 1 );
		double half = 0.5 * width * sqrt( xi ) * ( 1.0 - xi ) / peak;
		mid_xy[2 * i] = left_xy[2 * i] = right_xy[2 * i] = length * xi;
		mid_xy[2 * i + 1] = 0.0;
		left_xy[2 * i + 1] = half;
		right_xy[2 * i + 1] = -half;
	}
	return SERE_OK;
}

void sere_skel_leaf_curves_destroy( sere_skel_leaf_curves* c )
{
	free( c->outline );
	free( c->mid );
	memset( c, 0, sizeof( *c ) );
}

sere_skeleton_problem sere_skel_check_curve( const double* p, int32_t n, int32_t* point )
{
	if ( p == NULL || n < 2 )
	{
		*point = -1;
		return SERE_SKELETON_FEW_POINTS;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		*point = i;
		if ( !isfinite( p[2 * i] ) || !isfinite( p[2 * i + 1] ) )
		{
			return SERE_SKELETON_NONFINITE;
		}
		if ( i > 0 && p[2 * i] == p[2 * i - 2] && p[2 * i + 1] == p[2 * i - 1] )
		{
			return SERE_SKELETON_REPEATED_POINT;
		}
	}
	*point = -1;
	return SERE_SKELETON_OK;
}

/* The feature points are usable and the sampling interval fits the leaf; sets c->size, the
 * diagonal of the points' bounding box. */
static sere_status check_feature_points( const double* const curves[3], const int32_t counts[3], double spacing,
										 sere_skel_leaf_curves* c, sere_skeleton_check* check )
{
	for ( int k = 0; k < 3; ++k )
	{
		int32_t point;
		sere_skeleton_problem problem = sere_skel_check_curve( curves[k], counts[k], &point );
		if ( problem == SERE_SKELETON_OK && counts[k] > MAX_CURVE_POINTS )
		{
			problem = SERE_SKELETON_FEW_POINTS;
		}
		if ( problem != SERE_SKELETON_OK )
		{
			return sere_skel_report( check, problem, k, point );
		}
	}
	if ( !isfinite( spacing ) )
	{
		return sere_skel_report( check, SERE_SKELETON_NONFINITE, -1, -1 );
	}
	double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
	for ( int k = 0; k < 3; ++k )
	{
		for ( int32_t i = 0; i < counts[k]; ++i )
		{
			for ( int a = 0; a < 2; ++a )
			{
				lo[a] = fmin( lo[a], curves[k][2 * i + a] );
				hi[a] = fmax( hi[a], curves[k][2 * i + a] );
			}
		}
	}
	c->size = hypot( hi[0] - lo[0], hi[1] - lo[1] );
	if ( !( spacing > 0.0 ) || c->size / spacing > 0.25 * MAX_CURVE_POINTS || c->size == 0.0 )
	{
		return sere_skel_report( check, SERE_SKELETON_BAD_SPACING, -1, -1 );
	}
	return SERE_OK;
}

/* The three curves meet at the base and at the tip; small gaps (digitizing noise) are closed
 * later by moving the ends onto the left curve's. */
static sere_status check_ends_meet( const double* const curves[3], const int32_t counts[3], double size,
									sere_skeleton_check* check )
{
	const double* base = curves[0];
	const double* tip = curves[0] + 2 * ( counts[0] - 1 );
	double tolerance = 0.01 * size;
	for ( int k = 1; k < 3; ++k )
	{
		if ( sere_skel_dist2d( curves[k], base ) > tolerance )
		{
			return sere_skel_report( check, SERE_SKELETON_ENDS_APART, k, 0 );
		}
		if ( sere_skel_dist2d( curves[k] + 2 * ( counts[k] - 1 ), tip ) > tolerance )
		{
			return sere_skel_report( check, SERE_SKELETON_ENDS_APART, k, counts[k] - 1 );
		}
	}
	if ( sere_skel_dist2d( base, tip ) <= tolerance )
	{
		return sere_skel_report( check, SERE_SKELETON_ENDS_APART, 0, counts[0] - 1 );
	}
	return SERE_OK;
}

/* Each curve with its ends moved onto the left curve's base and tip, sampled every `spacing`.
 * On failure nothing is left to free. */
static sere_status sample_curves( const double* const curves[3], const int32_t counts[3], double spacing,
								  double* sampled[3], int32_t sampled_count[3], sere_skeleton_check* check )
{
	const double* base = curves[0];
	const double* tip = curves[0] + 2 * ( counts[0] - 1 );
	for ( int k = 0; k < 3; ++k )
	{
		double* copy = malloc( 2 * (size_t) counts[k] * sizeof( double ) );
		if ( copy == NULL )
		{
			free( sampled[0] );
			free( sampled[1] );
			return SERE_ERR_MEMORY;
		}
		memcpy( copy, curves[k], 2 * (size_t) counts[k] * sizeof( double ) );
		copy[0] = base[0];
		copy[1] = base[1];
		copy[2 * counts[k] - 2] = tip[0];
		copy[2 * counts[k] - 1] = tip[1];
		int32_t point;
		if ( sere_skel_check_curve( copy, counts[k], &point ) != SERE_SKELETON_OK )
		{
			free( copy );
			free( sampled[0] );
			free( sampled[1] );
			return sere_skel_report( check, SERE_SKELETON_REPEATED_POINT, k, point );
		}
		sampled[k] = sere_skel_curve_sample( copy, counts[k], spacing, 2, &sampled_count[k] );
		free( copy );
		if ( sampled[k] == NULL )
		{
			free( sampled[0] );
			free( sampled[1] );
			return SERE_ERR_MEMORY;
		}
	}
	return SERE_OK;
}

/* Outline: one boundary base → tip, the other tip → base without repeating the ends, turned
 * counter-clockwise with the base first. Takes the sampled midvein into c and frees the two
 * sampled boundaries. */
static sere_status join_outline( double* sampled[3], const int32_t sampled_count[3], sere_skel_leaf_curves* c )
{
	int32_t nl = sampled_count[0], nr = sampled_count[1];
	int32_t n = nl + nr - 2;
	c->outline = malloc( 2 * (size_t) n * sizeof( double ) );
	c->mid = sampled[2];
	c->mid_count = sampled_count[2];
	if ( c->outline == NULL )
	{
		free( sampled[0] );
		free( sampled[1] );
		sere_skel_leaf_curves_destroy( c );
		return SERE_ERR_MEMORY;
	}
	memcpy( c->outline, sampled[1], 2 * (size_t) nr * sizeof( double ) );
	for ( int32_t i = nl - 2; i >= 1; --i )
	{
		c->outline[2 * ( nr + nl - 2 - i )] = sampled[0][2 * i];
		c->outline[2 * ( nr + nl - 2 - i ) + 1] = sampled[0][2 * i + 1];
	}
	c->outline_count = n;
	c->tip = nr - 1;
	free( sampled[0] );
	free( sampled[1] );
	if ( sere_polygon_area( c->outline, n ) < 0.0 )
	{
		/* Clockwise: reverse all but the base so the base stays first. */
		for ( int32_t i = 1, j = n - 1; i < j; ++i, --j )
		{
			double tx = c->outline[2 * i], ty = c->outline[2 * i + 1];
			c->outline[2 * i] = c->outline[2 * j];
			c->outline[2 * i + 1] = c->outline[2 * j + 1];
			c->outline[2 * j] = tx;
			c->outline[2 * j + 1] = ty;
		}
		c->tip = n - c->tip;
	}
	return SERE_OK;
}

/* Simple outline: no two non-adjacent edges meet, and it encloses an area. */
static int outline_is_simple( const sere_skel_leaf_curves* c )
{
	int32_t n = c->outline_count;
	if ( !( fabs( sere_polygon_area( c->outline, n ) ) > 1e-12 * c->size * c->size ) )
	{
		return 0;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t j = i + 2; j < n; ++j )
		{
			if ( i == 0 && j == n - 1 )
			{
				continue;
			}
			if ( sere_skel_segments_meet( c->outline + 2 * i, c->outline + 2 * ( i + 1 ), c->outline + 2 * j,
										  c->outline + 2 * ( ( j + 1 ) % n ) ) )
			{
				return 0;
			}
		}
	}
	return 1;
}

/* The midvein runs inside: its interior points are inside the outline and no midvein segment
 * meets an outline edge away from the base and the tip. */
static int midvein_is_inside( const sere_skel_leaf_curves* c )
{
	int32_t n = c->outline_count;
	for ( int32_t i = 1; i + 1 < c->mid_count; ++i )
	{
		if ( !sere_point_in_polygon( c->outline, n, c->mid[2 * i], c->mid[2 * i + 1] ) )
		{
			return 0;
		}
	}
	for ( int32_t i = 0; i + 1 < c->mid_count; ++i )
	{
		for ( int32_t j = 0; j < n; ++j )
		{
			int32_t j1 = ( j + 1 ) % n;
			int touches_base = i == 0 && ( j == 0 || j1 == 0 );
			int touches_tip = i + 2 == c->mid_count && ( j == c->tip || j1 == c->tip );
			if ( touches_base || touches_tip )
			{
				continue;
			}
			if ( sere_skel_segments_meet( c->mid + 2 * i, c->mid + 2 * i + 2, c->outline + 2 * j,
										  c->outline + 2 * j1 ) )
			{
				return 0;
			}
		}
	}
	return 1;
}

/* The hexagonal lattice sere_leaf_skeleton_mesh fills the outline with: its box, row height and
 * counts. */
typedef struct lattice
{
	double lo[2], hi[2];
	double row, columns, rows;
} lattice;

static lattice lattice_of( const sere_skel_leaf_curves* c, double spacing )
{
	lattice l = { { INFINITY, INFINITY }, { -INFINITY, -INFINITY }, spacing * sqrt( 3.0 ) / 2.0, 0.0, 0.0 };
	for ( int32_t i = 0; i < c->outline_count; ++i )
	{
		for ( int a = 0; a < 2; ++a )
		{
			l.lo[a] = fmin( l.lo[a], c->outline[2 * i + a] );
			l.hi[a] = fmax( l.hi[a], c->outline[2 * i + a] );
		}
	}
	l.columns = floor( ( l.hi[0] - l.lo[0] ) / spacing ) + 2.0;
	l.rows = floor( ( l.hi[1] - l.lo[1] ) / l.row ) + 2.0;
	return l;
}

sere_status sere_skel_leaf_curves_build( const sere_leaf_skeleton* leaf, double spacing, sere_skel_leaf_curves* c,
										 sere_skeleton_check* check )
{
	memset( c, 0, sizeof( *c ) );
	if ( leaf == NULL )
	{
		return sere_skel_report( check, SERE_SKELETON_FEW_POINTS, -1, -1 );
	}
	const double* const curves[3] = { leaf->left_xy, leaf->right_xy, leaf->mid_xy };
	const int32_t counts[3] = { leaf->left_count, leaf->right_count, leaf->mid_count };
	sere_status status = check_feature_points( curves, counts, spacing, c, check );
	if ( status == SERE_OK )
	{
		status = check_ends_meet( curves, counts, c->size, check );
	}
	double* sampled[3] = { NULL, NULL, NULL };
	int32_t sampled_count[3] = { 0, 0, 0 };
	if ( status == SERE_OK )
	{
		status = sample_curves( curves, counts, spacing, sampled, sampled_count, check );
	}
	if ( status == SERE_OK )
	{
		status = join_outline( sampled, sampled_count, c );
	}
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( !outline_is_simple( c ) )
	{
		sere_skel_leaf_curves_destroy( c );
		return sere_skel_report( check, SERE_SKELETON_SELF_INTERSECTING, -1, -1 );
	}
	if ( !midvein_is_inside( c ) )
	{
		sere_skel_leaf_curves_destroy( c );
		return sere_skel_report( check, SERE_SKELETON_MIDVEIN_OUTSIDE, 2, -1 );
	}
	/* The mesh's points, lattice and curves, within the bound that keeps its allocation honest:
	 * checked here so that validation refuses every spacing the mesh would. */
	lattice l = lattice_of( c, spacing );
	if ( l.columns * l.rows + c->outline_count + c->mid_count > MAX_CURVE_POINTS )
	{
		sere_skel_leaf_curves_destroy( c );
		return sere_skel_report( check, SERE_SKELETON_BAD_SPACING, -1, -1 );
	}
	return sere_skel_report( check, SERE_SKELETON_OK, -1, -1 );
}

sere_status sere_leaf_skeleton_validate( const sere_leaf_skeleton* leaf, double spacing, sere_skeleton_check* check )
{
	sere_skel_leaf_curves c;
	sere_status status = sere_skel_leaf_curves_build( leaf, spacing, &c, check );
	if ( status == SERE_OK )
	{
		sere_skel_leaf_curves_destroy( &c );
	}
	return status;
}

sere_status sere_leaf_skeleton_mesh( const sere_leaf_skeleton* leaf, double spacing, sere_tri_mesh* mesh,
									 sere_skeleton_check* check )
{
	if ( mesh == NULL )
	{
		sere_skel_report( check, SERE_SKELETON_OK, -1, -1 );
		return SERE_ERR_ARGUMENT;
	}
	memset( mesh, 0, sizeof( *mesh ) );
	sere_skel_leaf_curves c;
	sere_status status = sere_skel_leaf_curves_build( leaf, spacing, &c, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t b = c.outline_count;
	int32_t inner_mid = c.mid_count - 2;
	/* the lattice's count is within MAX_CURVE_POINTS (sere_skel_leaf_curves_build) */
	const lattice l = lattice_of( &c, spacing );
	const double* lo = l.lo;
	const double* hi = l.hi;
	const double row = l.row, columns = l.columns, rows = l.rows;
	int32_t capacity = (int32_t) ( columns * rows ) + b + c.mid_count;
	double* x = malloc( (size_t) capacity * sizeof( double ) );
	double* y = malloc( (size_t) capacity * sizeof( double ) );
	int32_t* segments = malloc( 2 * (size_t) c.mid_count * sizeof( int32_t ) );
	if ( x == NULL || y == NULL || segments == NULL )
	{
		free( x );
		free( y );
		free( segments );
		sere_skel_leaf_curves_destroy( &c );
		return SERE_ERR_MEMORY;
	}
	int32_t count = 0;
	for ( int32_t i = 0; i < b; ++i )
	{
		x[count] = c.outline[2 * i];
		y[count++] = c.outline[2 * i + 1];
	}
	for ( int32_t i = 1; i + 1 < c.mid_count; ++i )
	{
		x[count] = c.mid[2 * i];
		y[count++] = c.mid[2 * i + 1];
	}
	for ( int32_t j = 0; j < (int32_t) rows; ++j )
	{
		for ( int32_t i = 0; i < (int32_t) columns; ++i )
		{
			double p[2] = { lo[0] + ( i + ( ( j & 1 ) ? 0.5 : 0.0 ) ) * spacing, lo[1] + ( j + 0.5 ) * row };
			if ( sere_point_in_polygon( c.outline, b, p[0], p[1] ) &&
				 sere_skel_polyline_distance( p, c.outline, b, 1 ) >= 0.5 * spacing &&
				 sere_skel_polyline_distance( p, c.mid, c.mid_count, 0 ) >= 0.5 * spacing )
			{
				x[count] = p[0];
				y[count++] = p[1];
			}
		}
	}
	/* The midvein is a chain of constrained edges from the base (point 0) to the tip. */
	int32_t segment_count = 0;
	int32_t previous = 0;
	for ( int32_t i = 0; i < inner_mid; ++i )
	{
		segments[2 * segment_count] = previous;
		segments[2 * segment_count++ + 1] = b + i;
		previous = b + i;
	}
	segments[2 * segment_count] = previous;
	segments[2 * segment_count++ + 1] = c.tip;

	sere_cdt_input input = { x, y, count, b, segments, segment_count };
	sere_triangulation triangulation = { 0 };
	status = sere_triangulate( &input, &triangulation );
	if ( status == SERE_OK && triangulation.merged_count != 0 )
	{
		status = SERE_ERR_GEOMETRY;
	}
	if ( status == SERE_OK )
	{
		status = sere_tri_mesh_create( mesh, count, triangulation.triangle_count );
	}
	if ( status == SERE_OK )
	{
		for ( int32_t i = 0; i < count; ++i )
		{
			mesh->x[i] = (float) x[i];
			mesh->y[i] = (float) y[i];
			mesh->u[i] = (float) ( ( x[i] - lo[0] ) / ( hi[0] - lo[0] ) );
			mesh->v[i] = (float) ( ( y[i] - lo[1] ) / ( hi[1] - lo[1] ) );
		}
		memcpy( mesh->tri, triangulation.tri, 3 * (size_t) triangulation.triangle_count * sizeof( int32_t ) );
	}
	sere_triangulation_destroy( &triangulation );
	free( x );
	free( y );
	free( segments );
	sere_skel_leaf_curves_destroy( &c );
	return status;
}
