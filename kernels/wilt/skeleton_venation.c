/* sere — The venation skeleton (Sec. 4.2): built from drawn veins or generated. Seed 003: Lu, Zhao, Guo 2009. */
#include "wilt/internal/skeleton_shared.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Venation skeleton (Sec. 4.2). */

void sere_skeleton_destroy( sere_skeleton* skeleton )
{
	void* arrays[] = { skeleton->x,	  skeleton->y,	  skeleton->z,	  skeleton->parent,
					   skeleton->end, skeleton->vein, skeleton->bend, skeleton->delay };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	memset( skeleton, 0, sizeof( *skeleton ) );
}

sere_status sere_skel_create( sere_skeleton* s, int32_t joint_count )
{
	memset( s, 0, sizeof( *s ) );
	size_t n = (size_t) sere_pad( joint_count > 0 ? joint_count : 1 );
	float** position[] = { &s->x, &s->y, &s->z };
	float** shape[] = { &s->bend, &s->delay };
	bool allocated = sere_alloc_floats( position, 3, n );
	s->parent = sere_alloc( n * sizeof( int32_t ) );
	s->end = sere_alloc( n * sizeof( int32_t ) );
	s->vein = sere_alloc( n * sizeof( int32_t ) );
	allocated = sere_alloc_floats( shape, 2, n ) && allocated;
	if ( !allocated || s->parent == NULL || s->end == NULL || s->vein == NULL )
	{
		sere_skeleton_destroy( s );
		return SERE_ERR_MEMORY;
	}
	s->joint_count = joint_count;
	return SERE_OK;
}

/* Joints as the veins list them, before the depth-first reordering. */
typedef struct raw_joints
{
	double* xy;
	int32_t* parent;
	int32_t* vein;
	float* bend;
} raw_joints;

static void raw_joints_free( raw_joints* r )
{
	free( r->xy );
	free( r->parent );
	free( r->vein );
	free( r->bend );
}

/* Depth-first preorder (children in their listed order) makes every subtree a contiguous range,
 * which the droop limit of sere_skeleton_pose walks. delay is 1 − (path length from the root) /
 * (longest such path): the seed rotates "from the boundary to root" (Sec. 7). */
static sere_status skeleton_order( const raw_joints* r, int32_t n, int32_t vein_count, sere_skeleton* out )
{
	int32_t* first_child = malloc( (size_t) ( n + 1 ) * sizeof( int32_t ) );
	int32_t* children = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* stack = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* new_index = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* old_index = malloc( (size_t) n * sizeof( int32_t ) );
	double* path = malloc( (size_t) n * sizeof( double ) );
	sere_status status = SERE_ERR_MEMORY;
	if ( first_child == NULL || children == NULL || stack == NULL || new_index == NULL || old_index == NULL ||
		 path == NULL )
	{
		goto done;
	}
	memset( first_child, 0, (size_t) ( n + 1 ) * sizeof( int32_t ) );
	for ( int32_t i = 1; i < n; ++i )
	{
		++first_child[r->parent[i] + 1];
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		first_child[i + 1] += first_child[i];
	}
	int32_t* fill = stack; /* reused as fill cursors before the traversal */
	memcpy( fill, first_child, (size_t) n * sizeof( int32_t ) );
	for ( int32_t i = 1; i < n; ++i )
	{
		children[fill[r->parent[i]]++] = i;
	}
	int32_t size = 0, next = 0;
	stack[size++] = 0;
	while ( size > 0 )
	{
		int32_t i = stack[--size];
		new_index[i] = next;
		old_index[next++] = i;
		for ( int32_t k = first_child[i + 1] - 1; k >= first_child[i]; --k )
		{
			stack[size++] = children[k];
		}
	}
	status = sere_skel_create( out, n );
	if ( status != SERE_OK )
	{
		goto done;
	}
	out->vein_count = vein_count;
	double longest = 0.0;
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = old_index[k];
		out->x[k] = (float) r->xy[2 * i];
		out->y[k] = (float) r->xy[2 * i + 1];
		out->z[k] = 0.0f;
		out->parent[k] = i == 0 ? -1 : new_index[r->parent[i]];
		out->vein[k] = r->vein[i];
		out->bend[k] = r->bend[i];
		out->end[k] = k + 1;
		path[k] = i == 0 ? 0.0 : path[out->parent[k]] + sere_skel_dist2d( r->xy + 2 * i, r->xy + 2 * r->parent[i] );
		longest = path[k] > longest ? path[k] : longest;
	}
	for ( int32_t k = n - 1; k > 0; --k )
	{
		int32_t p = out->parent[k];
		out->end[p] = out->end[k] > out->end[p] ? out->end[k] : out->end[p];
	}
	for ( int32_t k = 0; k < n; ++k )
	{
		out->delay[k] = longest > 0.0 ? (float) ( 1.0 - path[k] / longest ) : 0.0f;
	}
done:
	free( first_child );
	free( children );
	free( stack );
	free( new_index );
	free( old_index );
	free( path );
	return status;
}

/* Every vein spec is usable (Sec. 4.2); counts the joints and the longest polyline. */
static sere_status check_vein_specs( const sere_vein_spec* veins, int32_t vein_count, int64_t* joint_count,
									 int32_t* longest_polyline, sere_skeleton_check* check )
{
	*joint_count = 1;
	*longest_polyline = 0;
	for ( int32_t k = 0; k < vein_count; ++k )
	{
		const sere_vein_spec* v = veins + k;
		if ( k == 0 ? v->parent != -1 : ( v->parent < 0 || v->parent >= k ) )
		{
			return sere_skel_report( check, SERE_SKELETON_BAD_PARENT, k, -1 );
		}
		if ( v->segments < 1 || v->segments > SERE_MAX_SEGMENTS )
		{
			return sere_skel_report( check, SERE_SKELETON_BAD_SEGMENTS, k, -1 );
		}
		if ( !isfinite( v->bend ) )
		{
			return sere_skel_report( check, SERE_SKELETON_NONFINITE, k, -1 );
		}
		if ( v->bend < 0.0f || v->bend > (float) PI )
		{
			return sere_skel_report( check, SERE_SKELETON_BAD_BEND, k, -1 );
		}
		int32_t point;
		sere_skeleton_problem problem = sere_skel_check_curve( v->xy, v->point_count, &point );
		if ( problem == SERE_SKELETON_OK && v->point_count > MAX_CURVE_POINTS )
		{
			problem = SERE_SKELETON_FEW_POINTS;
		}
		if ( problem != SERE_SKELETON_OK )
		{
			return sere_skel_report( check, problem, k, point );
		}
		*joint_count += v->segments;
		*longest_polyline = v->point_count > *longest_polyline ? v->point_count : *longest_polyline;
	}
	if ( *joint_count > ( 1 << 24 ) )
	{
		return sere_skel_report( check, SERE_SKELETON_BAD_SEGMENTS, -1, -1 );
	}
	return SERE_OK;
}

/* Scratch of the joint placement: where each vein hangs and its first joint, one vein's
 * polyline and its cut points. */
typedef struct vein_scratch
{
	int32_t* attach;
	int32_t* first;
	double* polyline;
	double* cut;
} vein_scratch;

/* Cuts each vein into its segments and lists their end joints in vein order, each hanging from
 * the joint before it or, for a vein's first, from its attachment joint. */
static sere_status place_vein_joints( const sere_vein_spec* veins, int32_t vein_count, raw_joints* r,
									  const vein_scratch* w, sere_skeleton_check* check )
{
	r->xy[0] = veins[0].xy[0];
	r->xy[1] = veins[0].xy[1];
	r->parent[0] = -1;
	r->vein[0] = 0;
	r->bend[0] = 0.0f;
	int32_t count = 1;
	for ( int32_t k = 0; k < vein_count; ++k )
	{
		const sere_vein_spec* v = veins + k;
		/* The joint the vein hangs from: the root for the midvein, else the nearest joint of the
		 * parent vein (its own joints or the joint it hangs from), the lower index on ties. */
		int32_t a = 0;
		if ( k > 0 )
		{
			int32_t p = v->parent;
			a = w->attach[p];
			double best = sere_skel_dist2d( r->xy + 2 * a, v->xy );
			for ( int32_t j = w->first[p]; j < w->first[p] + veins[p].segments; ++j )
			{
				double d = sere_skel_dist2d( r->xy + 2 * j, v->xy );
				if ( d < best )
				{
					best = d;
					a = j;
				}
			}
			if ( best > sere_skel_polyline_length( v->xy, v->point_count ) )
			{
				return sere_skel_report( check, SERE_SKELETON_DETACHED, k, 0 );
			}
		}
		w->attach[k] = a;
		w->first[k] = count;
		/* The start moves onto the attachment joint, so the vein leaves its parent there without
		 * doubling back to where the user clicked. */
		memcpy( w->polyline, v->xy, 2 * (size_t) v->point_count * sizeof( double ) );
		w->polyline[0] = r->xy[2 * a];
		w->polyline[1] = r->xy[2 * a + 1];
		if ( sere_skel_polyline_length( w->polyline, v->point_count ) == 0.0 )
		{
			return sere_skel_report( check, SERE_SKELETON_REPEATED_POINT, k, 1 );
		}
		sere_skel_resample( w->polyline, v->point_count, v->segments, w->cut );
		for ( int32_t s = 1; s <= v->segments; ++s )
		{
			r->xy[2 * count] = w->cut[2 * s];
			r->xy[2 * count + 1] = w->cut[2 * s + 1];
			r->parent[count] = s == 1 ? a : count - 1;
			r->vein[count] = k;
			r->bend[count] = v->bend / (float) v->segments;
			++count;
		}
	}
	return SERE_OK;
}

sere_status sere_skeleton_create( const sere_vein_spec* veins, int32_t vein_count, sere_skeleton* skeleton,
								  sere_skeleton_check* check )
{
	if ( skeleton == NULL )
	{
		sere_skel_report( check, SERE_SKELETON_OK, -1, -1 );
		return SERE_ERR_ARGUMENT;
	}
	memset( skeleton, 0, sizeof( *skeleton ) );
	if ( veins == NULL || vein_count < 1 )
	{
		return sere_skel_report( check, SERE_SKELETON_NO_VEINS, -1, -1 );
	}
	int64_t joint_count;
	int32_t longest_polyline;
	sere_status status = check_vein_specs( veins, vein_count, &joint_count, &longest_polyline, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t n = (int32_t) joint_count;
	raw_joints r;
	r.xy = malloc( 2 * (size_t) n * sizeof( double ) );
	r.parent = malloc( (size_t) n * sizeof( int32_t ) );
	r.vein = malloc( (size_t) n * sizeof( int32_t ) );
	r.bend = malloc( (size_t) n * sizeof( float ) );
	vein_scratch w;
	w.attach = malloc( (size_t) vein_count * sizeof( int32_t ) );
	w.first = malloc( (size_t) vein_count * sizeof( int32_t ) );
	w.polyline = malloc( 2 * (size_t) longest_polyline * sizeof( double ) );
	w.cut = malloc( 2 * (size_t) ( SERE_MAX_SEGMENTS + 1 ) * sizeof( double ) );
	status = SERE_ERR_MEMORY;
	if ( r.xy != NULL && r.parent != NULL && r.vein != NULL && r.bend != NULL && w.attach != NULL && w.first != NULL &&
		 w.polyline != NULL && w.cut != NULL )
	{
		status = place_vein_joints( veins, vein_count, &r, &w, check );
		if ( status == SERE_OK )
		{
			status = skeleton_order( &r, n, vein_count, skeleton );
		}
		if ( status == SERE_OK )
		{
			sere_skel_report( check, SERE_SKELETON_OK, -1, -1 );
		}
	}
	raw_joints_free( &r );
	free( w.attach );
	free( w.first );
	free( w.polyline );
	free( w.cut );
	return status;
}

sere_venation_params sere_venation_params_default( void )
{
	sere_venation_params p;
	p.mid_segments = 20;
	p.secondary_count = 8;
	p.secondary_segments = 8;
	p.angle = (float) ( 45.0 * PI / 180.0 );
	p.mid_bend = (float) ( 80.0 * PI / 180.0 );
	p.secondary_bend = (float) ( 50.0 * PI / 180.0 );
	p.start = 0.1f;
	p.stop = 0.6f;
	return p;
}

/* First positive ray parameter at which o + λ d meets the closed polygon, or INFINITY. */
static double ray_polygon( const double* o, const double* d, const double* poly, int32_t n )
{
	double best = INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		const double* a = poly + 2 * i;
		const double* b = poly + 2 * ( ( i + 1 ) % n );
		double ex = b[0] - a[0], ey = b[1] - a[1];
		double den = d[0] * ey - d[1] * ex;
		if ( den == 0.0 )
		{
			continue;
		}
		double wx = a[0] - o[0], wy = a[1] - o[1];
		double lambda = ( wx * ey - wy * ex ) / den;
		double mu = ( wx * d[1] - wy * d[0] ) / den;
		if ( lambda > 0.0 && mu >= 0.0 && mu <= 1.0 && lambda < best )
		{
			best = lambda;
		}
	}
	return best;
}

sere_status sere_skeleton_generate( const sere_leaf_skeleton* leaf, const sere_venation_params* params,
									sere_skeleton* skeleton, sere_skeleton_check* check )
{
	/* a refused call leaves no problem of an earlier call in check */
	sere_skel_report( check, SERE_SKELETON_OK, -1, -1 );
	if ( skeleton == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( skeleton, 0, sizeof( *skeleton ) );
	if ( params == NULL || leaf == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !isfinite( params->angle ) || !isfinite( params->mid_bend ) || !isfinite( params->secondary_bend ) ||
		 !isfinite( params->start ) || !isfinite( params->stop ) )
	{
		return sere_skel_report( check, SERE_SKELETON_NONFINITE, -1, -1 );
	}
	if ( params->secondary_count < 0 || params->secondary_count > 1024 || !( params->angle > 0.0f ) ||
		 !( params->angle < (float) PI ) || params->start < 0.0f || params->stop > 1.0f ||
		 params->start > params->stop )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( leaf->mid_xy == NULL || leaf->mid_count < 2 || !isfinite( leaf->mid_xy[0] ) || !isfinite( leaf->mid_xy[1] ) ||
		 !isfinite( leaf->mid_xy[2 * leaf->mid_count - 2] ) || !isfinite( leaf->mid_xy[2 * leaf->mid_count - 1] ) )
	{
		return sere_skel_report(
			check, leaf->mid_xy == NULL || leaf->mid_count < 2 ? SERE_SKELETON_FEW_POINTS : SERE_SKELETON_NONFINITE, 2,
			-1 );
	}
	/* Fine sampling (a 200th of the base–tip distance) so generated veins follow the curves. */
	double chord = sere_skel_dist2d( leaf->mid_xy, leaf->mid_xy + 2 * ( leaf->mid_count - 1 ) );
	sere_skel_leaf_curves c;
	sere_status status = sere_skel_leaf_curves_build( leaf, chord > 0.0 ? chord / 200.0 : 1.0, &c, check );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t count = 1 + params->secondary_count;
	sere_vein_spec* specs = calloc( (size_t) count, sizeof( sere_vein_spec ) );
	double* ends = malloc( 4 * (size_t) count * sizeof( double ) );
	if ( specs == NULL || ends == NULL )
	{
		free( specs );
		free( ends );
		sere_skel_leaf_curves_destroy( &c );
		return SERE_ERR_MEMORY;
	}
	specs[0] = ( sere_vein_spec ){ -1, params->mid_segments, params->mid_bend, c.mid_count, c.mid };
	double length = sere_skel_polyline_length( c.mid, c.mid_count );
	int32_t pairs = ( params->secondary_count + 1 ) / 2;
	for ( int32_t j = 0; j < params->secondary_count; ++j )
	{
		/* Right (−) then left (+), pair by pair from the base toward the tip. */
		double side = ( j % 2 == 0 ) ? -1.0 : 1.0;
		/* Each starts at a joint of the midvein (its segments are equal in arc length), so the
		 * vein leaves the midvein without a kink. */
		double f = params->start + ( params->stop - params->start ) * ( j / 2 + 0.5 ) / pairs;
		double joint = round( f * params->mid_segments );
		joint = joint < 1.0 ? 1.0 : ( joint > params->mid_segments - 1 ? params->mid_segments - 1 : joint );
		double target = params->mid_segments > 1 ? joint / params->mid_segments * length : f * length;
		double walked = 0.0;
		int32_t i = 0;
		while ( i + 2 < c.mid_count && walked + sere_skel_dist2d( c.mid + 2 * i, c.mid + 2 * i + 2 ) < target )
		{
			walked += sere_skel_dist2d( c.mid + 2 * i, c.mid + 2 * i + 2 );
			++i;
		}
		const double* a = c.mid + 2 * i;
		const double* b = a + 2;
		double piece = sere_skel_dist2d( a, b );
		double g = ( target - walked ) / piece;
		g = g < 0.0 ? 0.0 : ( g > 1.0 ? 1.0 : g );
		double* s = ends + 4 * j;
		s[0] = a[0] + g * ( b[0] - a[0] );
		s[1] = a[1] + g * ( b[1] - a[1] );
		double tx = ( b[0] - a[0] ) / piece, ty = ( b[1] - a[1] ) / piece;
		double ca = cos( params->angle ), sa = side * sin( params->angle );
		double d[2] = { ca * tx - sa * ty, sa * tx + ca * ty };
		double lambda = ray_polygon( s, d, c.outline, c.outline_count );
		if ( !isfinite( lambda ) )
		{
			free( specs );
			free( ends );
			sere_skel_leaf_curves_destroy( &c );
			return sere_skel_report( check, SERE_SKELETON_MIDVEIN_OUTSIDE, 2, -1 );
		}
		s[2] = s[0] + 0.9 * lambda * d[0];
		s[3] = s[1] + 0.9 * lambda * d[1];
		specs[1 + j] = ( sere_vein_spec ){ 0, params->secondary_segments, params->secondary_bend, 2, s };
	}
	status = sere_skeleton_create( specs, count, skeleton, check );
	free( specs );
	free( ends );
	sere_skel_leaf_curves_destroy( &c );
	return status;
}
