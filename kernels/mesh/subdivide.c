#include "mesh/subdivide.h"

#include "core/array.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

sere_status sere_tri_mesh_create( sere_tri_mesh* mesh, int32_t vertex_count, int32_t triangle_count )
{
	memset( mesh, 0, sizeof( *mesh ) );
	if ( vertex_count < 0 || triangle_count < 0 || vertex_count > INT32_MAX - SERE_PAD ||
		 triangle_count > INT32_MAX / 3 - SERE_PAD )
	{
		return SERE_ERR_ARGUMENT;
	}
	size_t n = (size_t) sere_pad( vertex_count > 0 ? vertex_count : 1 );
	size_t t = (size_t) sere_pad( 3 * ( triangle_count > 0 ? triangle_count : 1 ) );
	float** columns[] = { &mesh->x, &mesh->y, &mesh->z, &mesh->u, &mesh->v };
	bool allocated = sere_alloc_floats( columns, 5, n );
	mesh->tri = sere_alloc( t * sizeof( int32_t ) );
	if ( !allocated || mesh->tri == NULL )
	{
		sere_tri_mesh_destroy( mesh );
		return SERE_ERR_MEMORY;
	}
	mesh->vertex_count = vertex_count;
	mesh->triangle_count = triangle_count;
	return SERE_OK;
}

void sere_tri_mesh_destroy( sere_tri_mesh* mesh )
{
	void* arrays[] = { mesh->x, mesh->y, mesh->z, mesh->u, mesh->v, mesh->tri };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	memset( mesh, 0, sizeof( *mesh ) );
}

static double distance( const sere_tri_mesh* m, int32_t a, int32_t b )
{
	double dx = (double) m->x[a] - (double) m->x[b];
	double dy = (double) m->y[a] - (double) m->y[b];
	double dz = (double) m->z[a] - (double) m->z[b];
	return sqrt( dx * dx + dy * dy + dz * dz );
}

static int32_t* put( int32_t* out, int32_t a, int32_t b, int32_t c )
{
	out[0] = a;
	out[1] = b;
	out[2] = c;
	return out + 3;
}

/* One pass. mid[slot] receives the midpoint vertex of each corner's edge or -1. */
/* Each triangle with its cut edges' midpoints (mid: per corner slot, -1 for an edge kept
 * whole) as one, two, three or four triangles of out, in input order. */
static void split_triangles( const sere_tri_mesh* in, const int32_t* mid, sere_tri_mesh* out )
{
	int32_t f = in->triangle_count;
	int32_t* o = out->tri;
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* c = in->tri + 3 * t;
		const int32_t* m = mid + 3 * t;
		int cut = ( m[0] >= 0 ) + ( m[1] >= 0 ) + ( m[2] >= 0 );
		if ( cut == 0 )
		{
			o = put( o, c[0], c[1], c[2] );
		}
		else if ( cut == 3 )
		{
			o = put( o, c[0], m[0], m[2] );
			o = put( o, m[0], c[1], m[1] );
			o = put( o, m[2], m[1], c[2] );
			o = put( o, m[0], m[1], m[2] );
		}
		else if ( cut == 1 )
		{
			int k = m[0] >= 0 ? 0 : ( m[1] >= 0 ? 1 : 2 );
			int32_t a = c[k], b = c[( k + 1 ) % 3], d = c[( k + 2 ) % 3];
			o = put( o, a, m[k], d );
			o = put( o, m[k], b, d );
		}
		else
		{
			/* Edge k (a→b) stays whole; b→d and d→a are cut at mb and md. The corner at d is one
			 * triangle; the quad a, b, mb, md is cut along its shorter diagonal. */
			int k = m[0] < 0 ? 0 : ( m[1] < 0 ? 1 : 2 );
			int32_t a = c[k], b = c[( k + 1 ) % 3], d = c[( k + 2 ) % 3];
			int32_t mb = m[( k + 1 ) % 3], md = m[( k + 2 ) % 3];
			o = put( o, mb, d, md );
			if ( distance( out, a, mb ) <= distance( out, b, md ) )
			{
				o = put( o, a, b, mb );
				o = put( o, a, mb, md );
			}
			else
			{
				o = put( o, a, b, md );
				o = put( o, b, mb, md );
			}
		}
	}
}

static sere_status subdivide_once( const sere_tri_mesh* in, double min_edge, sere_tri_mesh* out, int* changed )
{
	int32_t f = in->triangle_count;
	int32_t slots = 3 * f;
	/* A triangle corner's edge keyed by its sorted endpoints so both triangles of an edge meet;
	 * the index is the slot 3 * triangle + corner, the edge from corner to corner + 1. */
	sere_sort_item* edges = malloc( (size_t) ( slots > 0 ? slots : 1 ) * sizeof( sere_sort_item ) );
	int32_t* mid = malloc( (size_t) ( slots > 0 ? slots : 1 ) * sizeof( int32_t ) );
	if ( edges == NULL || mid == NULL )
	{
		free( edges );
		free( mid );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t s = 0; s < slots; ++s )
	{
		int32_t t = s / 3, k = s % 3;
		uint32_t a = (uint32_t) in->tri[3 * t + k];
		uint32_t b = (uint32_t) in->tri[3 * t + ( k + 1 ) % 3];
		edges[s].key = a < b ? ( (uint64_t) a << 32 ) | b : ( (uint64_t) b << 32 ) | a;
		edges[s].index = s;
	}
	sere_sort_items( edges, slots );

	/* Midpoints are numbered in sorted edge order, so the result depends only on the input. */
	int64_t next = in->vertex_count;
	for ( int32_t s = 0; s < slots; )
	{
		int32_t e = s;
		while ( e < slots && edges[e].key == edges[s].key )
		{
			++e;
		}
		int32_t a = (int32_t) ( edges[s].key >> 32 );
		int32_t b = (int32_t) ( edges[s].key & 0xffffffffu );
		int32_t m = -1;
		if ( 0.5 * distance( in, a, b ) >= min_edge )
		{
			m = (int32_t) next++;
		}
		for ( int32_t q = s; q < e; ++q )
		{
			mid[edges[q].index] = m;
		}
		s = e;
	}
	if ( next > INT32_MAX - SERE_PAD )
	{
		free( edges );
		free( mid );
		return SERE_ERR_CAPACITY;
	}

	int64_t triangles = 0;
	for ( int32_t t = 0; t < f; ++t )
	{
		triangles += 1 + ( mid[3 * t] >= 0 ) + ( mid[3 * t + 1] >= 0 ) + ( mid[3 * t + 2] >= 0 );
	}
	if ( triangles > INT32_MAX / 4 )
	{
		free( edges );
		free( mid );
		return SERE_ERR_CAPACITY;
	}
	sere_status status = sere_tri_mesh_create( out, (int32_t) next, (int32_t) triangles );
	if ( status != SERE_OK )
	{
		free( edges );
		free( mid );
		return status;
	}
	size_t n0 = (size_t) in->vertex_count;
	memcpy( out->x, in->x, n0 * sizeof( float ) );
	memcpy( out->y, in->y, n0 * sizeof( float ) );
	memcpy( out->z, in->z, n0 * sizeof( float ) );
	memcpy( out->u, in->u, n0 * sizeof( float ) );
	memcpy( out->v, in->v, n0 * sizeof( float ) );
	for ( int32_t s = 0; s < slots; ++s )
	{
		int32_t m = mid[s];
		if ( m >= 0 )
		{
			int32_t t = s / 3, k = s % 3;
			int32_t a = in->tri[3 * t + k];
			int32_t b = in->tri[3 * t + ( k + 1 ) % 3];
			out->x[m] = (float) ( 0.5 * ( (double) in->x[a] + (double) in->x[b] ) );
			out->y[m] = (float) ( 0.5 * ( (double) in->y[a] + (double) in->y[b] ) );
			out->z[m] = (float) ( 0.5 * ( (double) in->z[a] + (double) in->z[b] ) );
			out->u[m] = (float) ( 0.5 * ( (double) in->u[a] + (double) in->u[b] ) );
			out->v[m] = (float) ( 0.5 * ( (double) in->v[a] + (double) in->v[b] ) );
		}
	}

	split_triangles( in, mid, out );
	*changed = next > in->vertex_count;
	free( edges );
	free( mid );
	return SERE_OK;
}

sere_status sere_subdivide( const sere_tri_mesh* in, int32_t iterations, float min_edge, sere_tri_mesh* out )
{
	memset( out, 0, sizeof( *out ) );
	if ( in == NULL || iterations < 0 || iterations > 8 || in->vertex_count < 0 || in->triangle_count < 0 ||
		 isnan( min_edge ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !sere_array_indices_valid( in->tri, 3 * (int64_t) in->triangle_count, in->vertex_count ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const float* coordinates[] = { in->x, in->y, in->z, in->u, in->v };
	if ( !sere_array_finite( coordinates, 5, in->vertex_count, 1 ) )
	{
		return SERE_ERR_NONFINITE;
	}
	sere_tri_mesh current;
	sere_status status = sere_tri_mesh_create( &current, in->vertex_count, in->triangle_count );
	if ( status != SERE_OK )
	{
		return status;
	}
	size_t n = (size_t) in->vertex_count;
	memcpy( current.x, in->x, n * sizeof( float ) );
	memcpy( current.y, in->y, n * sizeof( float ) );
	memcpy( current.z, in->z, n * sizeof( float ) );
	memcpy( current.u, in->u, n * sizeof( float ) );
	memcpy( current.v, in->v, n * sizeof( float ) );
	memcpy( current.tri, in->tri, 3 * (size_t) in->triangle_count * sizeof( int32_t ) );
	for ( int32_t pass = 0; pass < iterations; ++pass )
	{
		sere_tri_mesh next;
		int changed = 0;
		status = subdivide_once( &current, min_edge > 0.0f ? (double) min_edge : 0.0, &next, &changed );
		if ( status != SERE_OK )
		{
			sere_tri_mesh_destroy( &current );
			return status;
		}
		sere_tri_mesh_destroy( &current );
		current = next;
		if ( !changed )
		{
			break;
		}
	}
	*out = current;
	return SERE_OK;
}
