/* sere — the shape measures that follow the leaf across its sections and along its main
 * veins: roll (sere_shape_roll) and the creases and rolls about the main veins. */
#include "mesh/measure.h"

#include "mesh/internal/measure_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
	sere_measure_position( in, v[0], p0 );
	sere_measure_position( in, v[1], p1 );
	sere_measure_position( in, v[2], p2 );
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
		sere_measure_unit_normal( in, tris[k], n );
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
			sere_measure_unit_normal( in, tris[k], n );
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
double sere_measure_band_roll( const sere_shape_input* in, double v_fraction, int32_t* tris, double* lateral )
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
double sere_measure_axis_curl( const sere_shape_input* in, double from, double to )
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
	sere_status status = sere_measure_validate( in );
	if ( status != SERE_OK || roll == NULL || !isfinite( v_fraction ) )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int32_t* tris = malloc( sizeof( int32_t ) * (size_t) in->triangle_count );
	double* lateral = malloc( sizeof( double ) * (size_t) in->triangle_count );
	if ( tris != NULL && lateral != NULL )
	{
		*roll = sere_measure_band_roll( in, v_fraction, tris, lateral );
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
/* sere_shape::crease_main and crease_blade: the mean |dihedral| of the interior edges within
 * one fresh edge length (the mean) of a main vein, and of those two or more away. */
static void vein_creases( const sere_shape_input* in, const int32_t* edge_tri, const double* dihedral, sere_shape* out )
{
	const sere_leaf_shape* shape = in->veins;
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
}

/* Each triangle's nearest main vein (its lobe, for a lobed leaf) and its foot on that vein. */
static void vein_owners( const sere_shape_input* in, int32_t* owner, vein_foot* foot )
{
	const sere_leaf_shape* shape = in->veins;
	int32_t tc = in->triangle_count;
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
}

/* sere_shape::vein_roll_tip and vein_roll_base: the mean |roll| of the sections across each
 * main vein over its lobe's triangles between 70 and 95 % of the vein's length, and between 20
 * and 45 %. */
static void vein_rolls( const sere_shape_input* in, const int32_t* owner, const vein_foot* foot, int32_t* tris,
						double* lateral, sere_shape* out )
{
	const sere_leaf_shape* shape = in->veins;
	int32_t tc = in->triangle_count;
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
}

bool sere_measure_main_veins( const sere_shape_input* in, const int32_t* edge_tri, const double* dihedral,
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

	vein_creases( in, edge_tri, dihedral, out );
	vein_owners( in, owner, foot );
	vein_rolls( in, owner, foot, tris, lateral, out );
	free( owner ), free( foot ), free( tris ), free( lateral );
	return true;
}
