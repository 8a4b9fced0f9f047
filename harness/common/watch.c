#include "common/watch.h"

#include "drying/leaf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct sere_watch
{
	int32_t threads;
	sere_crossings* crossings;
	float *x, *y, *z; /* every particle at the previous frame */
	int32_t count;
	double ground;
	double length;
	double centroid0[3], normal0[3];
	double mass_shift[3];
};

void sere_watch_destroy( sere_watch* watch )
{
	if ( watch == NULL )
	{
		return;
	}
	sere_crossings_destroy( watch->crossings );
	free( watch->x ), free( watch->y ), free( watch->z );
	free( watch );
}

static void remember( sere_watch* watch, const sere_model* model )
{
	size_t bytes = sizeof( float ) * (size_t) watch->count;
	memcpy( watch->x, model->p.x, bytes );
	memcpy( watch->y, model->p.y, bytes );
	memcpy( watch->z, model->p.z, bytes );
}

sere_status sere_watch_create( const sere_model* model, double ground, int32_t threads, sere_watch** out )
{
	sere_watch* watch = calloc( 1, sizeof( *watch ) );
	if ( watch == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	watch->count = model->p.count;
	watch->ground = ground;
	watch->threads = threads;
	size_t bytes = sizeof( float ) * (size_t) watch->count;
	watch->x = malloc( bytes ), watch->y = malloc( bytes ), watch->z = malloc( bytes );
	sere_status status = watch->x && watch->y && watch->z ? SERE_OK : SERE_ERR_MEMORY;
	if ( status == SERE_OK )
	{
		status =
			sere_crossings_create( model->tri, model->triangle_count, model->triangle_particles, &watch->crossings );
	}
	if ( status == SERE_OK )
	{
		status = sere_crossings_set_threads( watch->crossings, threads );
	}
	sere_shape shape;
	if ( status == SERE_OK )
	{
		sere_shape_input in = sere_leaf_shape_input( model, ground );
		in.threads = threads;
		status = sere_shape_measure( &in, &shape );
	}
	if ( status != SERE_OK )
	{
		sere_watch_destroy( watch );
		return status;
	}
	watch->length = shape.extent;
	memcpy( watch->centroid0, shape.centroid, sizeof( watch->centroid0 ) );
	memcpy( watch->normal0, shape.mean_normal, sizeof( watch->normal0 ) );
	remember( watch, model );
	*out = watch;
	return SERE_OK;
}

double sere_watch_length( const sere_watch* watch )
{
	return watch->length;
}

sere_status sere_watch_step( sere_watch* watch, const sere_model* model, sere_watch_frame* out )
{
	if ( model->p.count != watch->count )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = sere_crossings_count( watch->crossings, model->p.x, model->p.y, model->p.z, &out->crossings );
	if ( status != SERE_OK )
	{
		return status;
	}
	sere_shape_input in = sere_leaf_shape_input( model, watch->ground );
	in.skip_extent = true;
	in.pose_only = true;
	in.threads = watch->threads;
	sere_shape shape;
	status = sere_shape_measure( &in, &shape );
	if ( status != SERE_OK )
	{
		return status;
	}
	const sere_particles* p = &model->p;
	double mass = 0.0, shift[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t i = 0; i < p->count; ++i )
	{
		mass += p->m[i];
		shift[0] += p->m[i] * ( (double) p->x[i] - watch->x[i] );
		shift[1] += p->m[i] * ( (double) p->y[i] - watch->y[i] );
		shift[2] += p->m[i] * ( (double) p->z[i] - watch->z[i] );
	}
	double moved = 0.0, drift = 0.0, dot = 0.0, n0 = 0.0, n1 = 0.0;
	for ( int k = 0; k < 3; ++k )
	{
		watch->mass_shift[k] += mass > 0.0 ? shift[k] / mass : 0.0;
		moved += watch->mass_shift[k] * watch->mass_shift[k];
		drift += ( shape.centroid[k] - watch->centroid0[k] ) * ( shape.centroid[k] - watch->centroid0[k] );
		dot += shape.mean_normal[k] * watch->normal0[k];
		n0 += watch->normal0[k] * watch->normal0[k];
		n1 += shape.mean_normal[k] * shape.mean_normal[k];
	}
	out->drift = sqrt( drift ) / watch->length;
	out->mass_drift = sqrt( moved ) / watch->length;
	/* the leaf is both layers: it may rest on its Voronoi particles (the veins' ribs below it) */
	float low = INFINITY;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		low = p->z[i] < low ? p->z[i] : low;
	}
	out->ground_gap = isfinite( watch->ground ) ? (double) low - watch->ground : NAN;
	out->normal_z = shape.mean_normal[2] / ( n1 > 0.0 ? sqrt( n1 ) : 1.0 );
	double cosine = n0 > 0.0 && n1 > 0.0 ? dot / sqrt( n0 * n1 ) : 1.0;
	out->tilt_degrees = acos( fmax( -1.0, fmin( 1.0, cosine ) ) ) * 180.0 / 3.14159265358979323846;
	out->roll_tip = shape.roll_tip;
	out->roll_base = shape.roll_base;
	remember( watch, model );
	return SERE_OK;
}
