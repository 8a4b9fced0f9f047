#define _POSIX_C_SOURCE 200809L
#include "render/glb.h"
#include "common/io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The sRGB transfer function undone: glTF vertex colors are linear. */
static float linear_of( uint8_t srgb )
{
	double c = srgb / 255.0;
	return (float) ( c <= 0.04045 ? c / 12.92 : pow( ( c + 0.055 ) / 1.055, 2.4 ) );
}

static void put_u32( FILE* f, uint32_t value )
{
	/* glTF is little endian, as is every machine sere targets (x86-64, aarch64) */
	fwrite( &value, sizeof( value ), 1, f );
}

/* Unit vertex normals: the area-weighted sum of the triangles' normals around each vertex. */
static void vertex_normals( const sere_glb_mesh* m, float* normal )
{
	int32_t n = m->vertex_count, t = m->triangle_count;
	for ( int32_t f = 0; f < t; ++f )
	{
		const int32_t* v = m->tri + 3 * f;
		double ax = m->x[v[1]] - m->x[v[0]], ay = m->y[v[1]] - m->y[v[0]], az = m->z[v[1]] - m->z[v[0]];
		double bx = m->x[v[2]] - m->x[v[0]], by = m->y[v[2]] - m->y[v[0]], bz = m->z[v[2]] - m->z[v[0]];
		/* the cross product's length is twice the area: an area-weighted sum */
		double c[3] = { ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx };
		for ( int corner = 0; corner < 3; ++corner )
		{
			for ( int k = 0; k < 3; ++k )
			{
				normal[3 * v[corner] + k] += (float) c[k];
			}
		}
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		float* a = normal + 3 * i;
		double length = sqrt( (double) a[0] * a[0] + (double) a[1] * a[1] + (double) a[2] * a[2] );
		if ( length > 0.0 && isfinite( length ) )
		{
			a[0] = (float) ( a[0] / length ), a[1] = (float) ( a[1] / length ), a[2] = (float) ( a[2] / length );
		}
		else
		{
			/* glTF normals must be unit: a vertex whose triangles cancel faces up */
			a[0] = 0.0f, a[1] = 0.0f, a[2] = 1.0f;
		}
	}
}

sere_status sere_glb_write( const char* path, const sere_glb_mesh* m, char* err, size_t err_size )
{
	int32_t n = m->vertex_count, t = m->triangle_count;
	if ( n < 1 || t < 1 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size,
						  "%s: a glTF mesh needs a vertex and a triangle, not %d and %d", path, n, t );
	}
	for ( size_t k = 0; k < 3 * (size_t) t; ++k )
	{
		if ( m->tri[k] < 0 || m->tri[k] >= n )
		{
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: triangle %zu has vertex %d of %d", path, k / 3,
							  m->tri[k], n );
		}
	}
	/* One buffer: positions, normals, colors (3 floats each per vertex), then the indices; every
	 * view starts on a multiple of 4 as glTF asks. */
	size_t vec3_bytes = 12 * (size_t) n, index_bytes = 12 * (size_t) t;
	size_t buffer_bytes = 3 * vec3_bytes + index_bytes;
	if ( buffer_bytes > UINT32_MAX - 4096 )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: %zu bytes is more than a .glb holds", path,
						  buffer_bytes );
	}
	float* normal = calloc( 3 * (size_t) n, sizeof( float ) );
	float* color = malloc( sizeof( float ) * 3 * (size_t) n );
	if ( normal == NULL || color == NULL )
	{
		free( normal ), free( color );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory for %d vertices", path, n );
	}
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	for ( int32_t i = 0; i < n; ++i )
	{
		float p[3] = { m->x[i], m->y[i], m->z[i] };
		for ( int k = 0; k < 3; ++k )
		{
			lo[k] = fminf( lo[k], p[k] ), hi[k] = fmaxf( hi[k], p[k] );
			color[3 * i + k] = linear_of( m->rgb[3 * i + k] );
		}
	}
	vertex_normals( m, normal );
	char json[4096];
	int length =
		snprintf( json, sizeof( json ),
				  "{\"asset\":{\"version\":\"2.0\",\"generator\":\"sere\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
				  "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,"
				  "\"COLOR_0\":2},\"indices\":3,\"material\":0,\"mode\":4}]}],"
				  "\"materials\":[{\"doubleSided\":true,\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],"
				  "\"metallicFactor\":0,\"roughnessFactor\":0.9}}],"
				  "\"buffers\":[{\"byteLength\":%zu}],\"bufferViews\":["
				  "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%zu,\"target\":34962},"
				  "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34962},"
				  "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34962},"
				  "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu,\"target\":34963}],\"accessors\":["
				  "{\"bufferView\":0,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\","
				  "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]},"
				  "{\"bufferView\":1,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"},"
				  "{\"bufferView\":2,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"},"
				  "{\"bufferView\":3,\"componentType\":5125,\"count\":%zu,\"type\":\"SCALAR\"}]}",
				  buffer_bytes, vec3_bytes, vec3_bytes, vec3_bytes, 2 * vec3_bytes, vec3_bytes, 3 * vec3_bytes,
				  index_bytes, n, (double) lo[0], (double) lo[1], (double) lo[2], (double) hi[0], (double) hi[1],
				  (double) hi[2], n, n, 3 * (size_t) t );
	/* the JSON chunk is padded with spaces to a multiple of 4 (the BIN chunk needs no padding:
	 * every part of it is a multiple of 4 bytes) */
	size_t json_bytes = ( (size_t) length + 3 ) & ~(size_t) 3;
	memset( json + length, ' ', json_bytes - (size_t) length );
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		int error = errno;
		free( normal ), free( color );
		return sere_fail( SERE_ERR_IO, err, err_size, "cannot write %s: %s", path, strerror( error ) );
	}
	put_u32( f, 0x46546C67u ); /* "glTF" */
	put_u32( f, 2 );
	put_u32( f, (uint32_t) ( 12 + 8 + json_bytes + 8 + buffer_bytes ) );
	put_u32( f, (uint32_t) json_bytes );
	put_u32( f, 0x4E4F534Au ); /* "JSON" */
	fwrite( json, 1, json_bytes, f );
	put_u32( f, (uint32_t) buffer_bytes );
	put_u32( f, 0x004E4942u ); /* "BIN" */
	for ( int32_t i = 0; i < n; ++i )
	{
		float p[3] = { m->x[i], m->y[i], m->z[i] };
		fwrite( p, sizeof( float ), 3, f );
	}
	fwrite( normal, sizeof( float ), 3 * (size_t) n, f );
	fwrite( color, sizeof( float ), 3 * (size_t) n, f );
	fwrite( m->tri, sizeof( int32_t ), 3 * (size_t) t, f );
	free( normal ), free( color );
	if ( sere_atomic_commit( &file ) != 0 )
	{
		return sere_fail( SERE_ERR_IO, err, err_size, "cannot write %s: %s", path, strerror( errno ) );
	}
	return SERE_OK;
}
