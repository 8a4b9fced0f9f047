/* sere — A plant of wilting leaves (Sec. 7). Seed 003: Lu, Zhao, Guo 2009. */
/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "wilt/internal/skeleton_shared.h"

#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Plant (Sec. 7). */

void sere_plant_destroy( sere_plant* plant )
{
	if ( plant == NULL )
	{
		return;
	}
	sere_free( plant->joint_first );
	sere_free( plant->vertex_first );
	sere_free( plant->triangle_first );
	sere_free( plant->onset );
	sere_free( plant->leaf_t );
	sere_skeleton_destroy( &plant->joints );
	sere_joint_frames_destroy( &plant->frames );
	sere_free( plant->joint );
	void* arrays[] = {
		plant->ox, plant->oy, plant->oz, plant->x,	plant->y,  plant->z,  plant->rx,  plant->ry,
		plant->rz, plant->u,  plant->v,	 plant->tx, plant->ty, plant->tz, plant->tri, plant->leaf_stats
	};
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	sere_pierce_destroy( plant->pierce );
	free( plant );
}

static sere_status check_template( const sere_leaf_template* t )
{
	if ( t->mesh == NULL || t->skeleton == NULL || t->mesh->vertex_count < 3 || t->mesh->triangle_count < 1 ||
		 t->skeleton->joint_count < 2 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < 3 * t->mesh->triangle_count; ++i )
	{
		if ( t->mesh->tri[i] < 0 || t->mesh->tri[i] >= t->mesh->vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return SERE_OK;
}

/* Every placement names a template and is finite with a positive scale; sums the joints,
 * vertices and triangles of the plant. */
static sere_status check_placements( const sere_leaf_template* templates, int32_t template_count,
									 const sere_leaf_placement* leaves, int32_t leaf_count, int64_t total[3] )
{
	total[0] = total[1] = total[2] = 0;
	for ( int32_t k = 0; k < leaf_count; ++k )
	{
		const sere_leaf_placement* l = leaves + k;
		if ( l->template_index < 0 || l->template_index >= template_count )
		{
			return SERE_ERR_ARGUMENT;
		}
		if ( !isfinite( l->base[0] ) || !isfinite( l->base[1] ) || !isfinite( l->base[2] ) || !isfinite( l->azimuth ) ||
			 !isfinite( l->elevation ) || !isfinite( l->scale ) || !isfinite( l->onset ) )
		{
			return SERE_ERR_NONFINITE;
		}
		if ( !( l->scale > 0.0f ) )
		{
			return SERE_ERR_ARGUMENT;
		}
		const sere_leaf_template* t = templates + l->template_index;
		total[0] += t->skeleton->joint_count;
		total[1] += t->mesh->vertex_count;
		total[2] += t->mesh->triangle_count;
	}
	if ( total[0] > ( 1 << 24 ) || total[1] > INT32_MAX / 4 || total[2] > INT32_MAX / 4 )
	{
		return SERE_ERR_CAPACITY;
	}
	return SERE_OK;
}

/* The plant's arrays for its leaves, joints, vertices and triangles. */
static sere_status plant_alloc( sere_plant* p, int32_t leaf_count, int32_t joints, int32_t vertices, int32_t triangles )
{
	p->leaf_count = leaf_count;
	p->vertex_count = vertices;
	p->triangle_count = triangles;
	size_t nl = (size_t) sere_pad( leaf_count + 1 );
	size_t nv = (size_t) sere_pad( vertices );
	p->joint_first = sere_alloc( nl * sizeof( int32_t ) );
	p->vertex_first = sere_alloc( nl * sizeof( int32_t ) );
	p->triangle_first = sere_alloc( nl * sizeof( int32_t ) );
	float** leaf[] = { &p->onset, &p->leaf_t };
	bool leaves_allocated = sere_alloc_floats( leaf, 2, nl );
	p->leaf_stats = sere_alloc( nl * sizeof( sere_pose_stats ) );
	p->joint = sere_alloc( nv * sizeof( int32_t ) );
	float** arrays[] = { &p->ox, &p->oy, &p->oz, &p->x, &p->y,	&p->z,	&p->rx,
						 &p->ry, &p->rz, &p->u,	 &p->v, &p->tx, &p->ty, &p->tz };
	bool allocated = sere_alloc_floats( arrays, (int32_t) ( sizeof( arrays ) / sizeof( arrays[0] ) ), nv );
	p->tri = sere_alloc( (size_t) sere_pad( 3 * triangles ) * sizeof( int32_t ) );
	if ( !allocated || !leaves_allocated || p->joint_first == NULL || p->vertex_first == NULL ||
		 p->triangle_first == NULL || p->leaf_stats == NULL || p->joint == NULL || p->tri == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sere_status status = sere_skel_create( &p->joints, joints );
	if ( status == SERE_OK )
	{
		status = sere_joint_frames_create( &p->frames, joints );
	}
	p->joints.vein_count = 0;
	return status;
}

/* One template's vertex and triangle order in the plant: each vertex's joint (banding), its
 * rank in the leaf (by joint, stably) and the triangles in their new order. */
typedef struct template_layout
{
	int32_t* banding;
	int32_t* rank;
	int32_t* order;
} template_layout;

/* Triangles follow their lowest vertex (stably), so consecutive triangles are neighbours too
 * and share BVH walks in the piercing check. */
static sere_status order_triangles( const sere_tri_mesh* m, template_layout* layout )
{
	layout->order = malloc( (size_t) m->triangle_count * sizeof( int32_t ) );
	int32_t* count = calloc( (size_t) m->vertex_count + 1, sizeof( int32_t ) );
	if ( layout->order == NULL || count == NULL )
	{
		free( count );
		return SERE_ERR_MEMORY;
	}
	const int32_t* rank = layout->rank;
	for ( int32_t t = 0; t < m->triangle_count; ++t )
	{
		const int32_t* c = m->tri + 3 * t;
		int32_t low = rank[c[0]] < rank[c[1]] ? rank[c[0]] : rank[c[1]];
		low = rank[c[2]] < low ? rank[c[2]] : low;
		++count[low + 1];
	}
	for ( int32_t i = 0; i < m->vertex_count; ++i )
	{
		count[i + 1] += count[i];
	}
	for ( int32_t t = 0; t < m->triangle_count; ++t )
	{
		const int32_t* c = m->tri + 3 * t;
		int32_t low = rank[c[0]] < rank[c[1]] ? rank[c[0]] : rank[c[1]];
		low = rank[c[2]] < low ? rank[c[2]] : low;
		layout->order[count[low]++] = t;
	}
	free( count );
	return SERE_OK;
}

/* Banding happens once per template in leaf coordinates; every leaf made from it reuses the
 * joint of each vertex, so leaves never band to a neighbour's joints. Each leaf's vertices are
 * ordered by joint (stable), so skinning streams runs of one joint and a joint's region is
 * contiguous in memory. */
static sere_status layout_template( const sere_leaf_template* t, template_layout* layout )
{
	const sere_tri_mesh* m = t->mesh;
	const sere_skeleton* s = t->skeleton;
	sere_joint_grid* grid = NULL;
	layout->banding = malloc( (size_t) m->vertex_count * sizeof( int32_t ) );
	layout->rank = malloc( (size_t) m->vertex_count * sizeof( int32_t ) );
	int32_t* first = calloc( (size_t) s->joint_count + 1, sizeof( int32_t ) );
	sere_status status = layout->banding == NULL || layout->rank == NULL || first == NULL
							 ? SERE_ERR_MEMORY
							 : sere_joint_grid_create( s->x, s->y, s->z, s->joint_count, &grid );
	if ( status == SERE_OK )
	{
		status = sere_joint_grid_band( grid, NULL, NULL, NULL, m->x, m->y, m->z, m->vertex_count, layout->banding, NULL,
									   NULL, NULL );
	}
	if ( status == SERE_OK )
	{
		for ( int32_t i = 0; i < m->vertex_count; ++i )
		{
			++first[layout->banding[i] + 1];
		}
		for ( int32_t j = 0; j < s->joint_count; ++j )
		{
			first[j + 1] += first[j];
		}
		for ( int32_t i = 0; i < m->vertex_count; ++i )
		{
			layout->rank[i] = first[layout->banding[i]]++;
		}
		status = order_triangles( m, layout );
	}
	free( first );
	sere_joint_grid_destroy( grid );
	return status;
}

/* Leaf l's joints, vertices and triangles into the plant from joint jf, vertex vf and triangle
 * tf on, in world coordinates (Sec. 7). */
static void place_leaf( sere_plant* p, const sere_leaf_placement* l, const sere_leaf_template* t,
						const template_layout* layout, int32_t jf, int32_t vf, int32_t tf )
{
	const sere_skeleton* s = t->skeleton;
	const sere_tri_mesh* m = t->mesh;
	/* World = base + scale · Rz(azimuth) Ry(−elevation) · leaf: the midvein (+x) is lifted by the
	 * elevation, then turned to its azimuth. */
	double ce = cos( l->elevation ), se = sin( l->elevation );
	double ca = cos( l->azimuth ), sa = sin( l->azimuth );
	double sc = l->scale;
	double rot[9] = { ca * ce, -sa, -ca * se, sa * ce, ca, -sa * se, se, 0.0, ce };
	for ( int32_t i = 0; i < s->joint_count; ++i )
	{
		double local[3] = { s->x[i], s->y[i], s->z[i] };
		double w[3];
		sere_skel_mat_vec( rot, local, w );
		int32_t g = jf + i;
		p->joints.x[g] = (float) ( l->base[0] + sc * w[0] );
		p->joints.y[g] = (float) ( l->base[1] + sc * w[1] );
		p->joints.z[g] = (float) ( l->base[2] + sc * w[2] );
		p->joints.parent[g] = s->parent[i] < 0 ? -1 : jf + s->parent[i];
		p->joints.end[g] = jf + s->end[i];
		p->joints.vein[g] = p->joints.vein_count + s->vein[i];
		p->joints.bend[g] = s->bend[i];
		p->joints.delay[g] = s->delay[i];
	}
	for ( int32_t i = 0; i < m->vertex_count; ++i )
	{
		double local[3] = { m->x[i], m->y[i], m->z[i] };
		double w[3];
		sere_skel_mat_vec( rot, local, w );
		int32_t v = vf + layout->rank[i];
		int32_t j = jf + layout->banding[i];
		p->rx[v] = p->x[v] = (float) ( l->base[0] + sc * w[0] );
		p->ry[v] = p->y[v] = (float) ( l->base[1] + sc * w[1] );
		p->rz[v] = p->z[v] = (float) ( l->base[2] + sc * w[2] );
		p->joint[v] = j;
		p->ox[v] = p->rx[v] - p->joints.x[j];
		p->oy[v] = p->ry[v] - p->joints.y[j];
		p->oz[v] = p->rz[v] - p->joints.z[j];
		p->u[v] = m->u[i];
		p->v[v] = m->v[i];
	}
	for ( int32_t q = 0; q < m->triangle_count; ++q )
	{
		const int32_t* c = m->tri + 3 * layout->order[q];
		for ( int a = 0; a < 3; ++a )
		{
			p->tri[3 * ( tf + q ) + a] = vf + layout->rank[c[a]];
		}
	}
	p->joints.vein_count += s->vein_count;
}

/* Lays out every template, then places every leaf. */
static sere_status place_leaves( sere_plant* p, const sere_leaf_template* templates, int32_t template_count,
								 const sere_leaf_placement* leaves, int32_t leaf_count )
{
	template_layout* layouts = calloc( (size_t) template_count, sizeof( template_layout ) );
	if ( layouts == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sere_status status = SERE_OK;
	for ( int32_t k = 0; k < template_count && status == SERE_OK; ++k )
	{
		status = layout_template( templates + k, layouts + k );
	}
	int32_t jf = 0, vf = 0, tf = 0;
	for ( int32_t k = 0; k < leaf_count && status == SERE_OK; ++k )
	{
		const sere_leaf_placement* l = leaves + k;
		const sere_leaf_template* t = templates + l->template_index;
		p->joint_first[k] = jf;
		p->vertex_first[k] = vf;
		p->triangle_first[k] = tf;
		p->onset[k] = l->onset;
		place_leaf( p, l, t, layouts + l->template_index, jf, vf, tf );
		jf += t->skeleton->joint_count;
		vf += t->mesh->vertex_count;
		tf += t->mesh->triangle_count;
	}
	p->joint_first[leaf_count] = jf;
	p->vertex_first[leaf_count] = vf;
	p->triangle_first[leaf_count] = tf;
	for ( int32_t k = 0; k < template_count; ++k )
	{
		free( layouts[k].banding );
		free( layouts[k].rank );
		free( layouts[k].order );
	}
	free( layouts );
	return status;
}

sere_status sere_plant_create( const sere_leaf_template* templates, int32_t template_count,
							   const sere_leaf_placement* leaves, int32_t leaf_count, sere_plant** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( templates == NULL || leaves == NULL || template_count < 1 || leaf_count < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t k = 0; k < template_count; ++k )
	{
		sere_status status = check_template( templates + k );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	int64_t total[3];
	sere_status status = check_placements( templates, template_count, leaves, leaf_count, total );
	if ( status != SERE_OK )
	{
		return status;
	}
	sere_plant* p = calloc( 1, sizeof( sere_plant ) );
	if ( p == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	status = plant_alloc( p, leaf_count, (int32_t) total[0], (int32_t) total[1], (int32_t) total[2] );
	if ( status == SERE_OK )
	{
		status = place_leaves( p, templates, template_count, leaves, leaf_count );
	}
	if ( status == SERE_OK )
	{
		status =
			sere_pierce_create( p->tri, p->triangle_count, p->vertex_count, p->x, p->y, p->z, p->joint, &p->pierce );
	}
	if ( status != SERE_OK )
	{
		sere_plant_destroy( p );
		return status;
	}
	*out = p;
	return SERE_OK;
}

void sere_plant_reset( sere_plant* plant )
{
	size_t bytes = (size_t) plant->vertex_count * sizeof( float );
	memcpy( plant->x, plant->rx, bytes );
	memcpy( plant->y, plant->ry, bytes );
	memcpy( plant->z, plant->rz, bytes );
	sere_skel_pierce_rest( plant->pierce );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		plant->leaf_t[k] = 0.0f;
	}
}

sere_status sere_plant_set_threads( sere_plant* plant, int32_t threads )
{
	sere_status status = plant == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &plant->threads, threads );
	return status == SERE_OK ? sere_pierce_set_threads( plant->pierce, threads ) : status;
}

sere_status sere_plant_frame( sere_plant* plant, float time, const sere_wilt_params* params, sere_wilt_stats* stats )
{
	sere_status status = sere_skel_check_wilt_params( params );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( plant == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !isfinite( time ) )
	{
		return SERE_ERR_NONFINITE;
	}
	/* The forward kinematics of a leaf is sequential from its root; leaves are independent. */
#pragma omp parallel for num_threads( sere_team_for( plant->threads ) ) schedule( dynamic, 1 )
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		float t = time - plant->onset[k];
		t = t < 0.0f ? 0.0f : ( t > 1.0f ? 1.0f : t );
		plant->leaf_t[k] = t;
		int32_t first = plant->joint_first[k];
		sere_skel_pose_range( &plant->joints, first, plant->joint_first[k + 1] - first, t, params, &plant->frames, NULL,
							  plant->leaf_stats + k );
	}
	sere_wilt_stats st;
	memset( &st, 0, sizeof( st ) );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		st.pose.turning += plant->leaf_stats[k].turning;
		st.pose.droop_limited += plant->leaf_stats[k].droop_limited;
		st.pose.angle_limited += plant->leaf_stats[k].angle_limited;
		st.pose.down_limited += plant->leaf_stats[k].down_limited;
	}
	if ( params->pierce )
	{
		sere_joint_frames_skin( &plant->frames, plant->joint, plant->ox, plant->oy, plant->oz, plant->vertex_count,
								plant->tx, plant->ty, plant->tz, plant->threads );
		status = sere_pierce_step( plant->pierce, plant->x, plant->y, plant->z, plant->tx, plant->ty, plant->tz,
								   params->pierce_margin, &st.pierce );
		if ( status != SERE_OK )
		{
			return status;
		}
		float* swap;
		swap = plant->x, plant->x = plant->tx, plant->tx = swap;
		swap = plant->y, plant->y = plant->ty, plant->ty = swap;
		swap = plant->z, plant->z = plant->tz, plant->tz = swap;
	}
	else
	{
		sere_joint_frames_skin( &plant->frames, plant->joint, plant->ox, plant->oy, plant->oz, plant->vertex_count,
								plant->x, plant->y, plant->z, plant->threads );
	}
	if ( stats != NULL )
	{
		*stats = st;
	}
	return SERE_OK;
}
