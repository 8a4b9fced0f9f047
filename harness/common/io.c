#define _POSIX_C_SOURCE 200809L
#include "common/io.h"

#include "core/array.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

FILE* sere_atomic_open( sere_atomic_file* file, const char* path )
{
	file->f = NULL;
	size_t length = strlen( path );
	if ( length + 5 > sizeof( file->tmp_path ) )
	{
		errno = ENAMETOOLONG;
		return NULL;
	}
	memcpy( file->path, path, length + 1 );
	memcpy( file->tmp_path, path, length );
	memcpy( file->tmp_path + length, ".tmp", 5 );
	file->f = fopen( file->tmp_path, "wb" );
	return file->f;
}

sere_status sere_atomic_commit( sere_atomic_file* file )
{
	if ( file->f == NULL )
	{
		errno = EBADF;
		return SERE_ERR_IO;
	}
	/* The first failure's errno is the reason; a stream error set by an earlier write left its
	 * errno in place unless something else failed since. */
	int error = 0;
	if ( ferror( file->f ) )
	{
		error = errno != 0 ? errno : EIO;
	}
	if ( fflush( file->f ) != 0 && error == 0 )
	{
		error = errno;
	}
	if ( fsync( fileno( file->f ) ) != 0 && error == 0 )
	{
		error = errno;
	}
	if ( fclose( file->f ) != 0 && error == 0 )
	{
		error = errno;
	}
	file->f = NULL;
	if ( error == 0 && rename( file->tmp_path, file->path ) != 0 )
	{
		error = errno;
	}
	if ( error != 0 )
	{
		remove( file->tmp_path );
		errno = error;
		return SERE_ERR_IO;
	}
	return SERE_OK;
}

void sere_atomic_abort( sere_atomic_file* file )
{
	if ( file->f != NULL )
	{
		fclose( file->f );
		file->f = NULL;
	}
	remove( file->tmp_path );
}

sere_status sere_dir_create( const char* dir )
{
	char path[4096];
	size_t length = strlen( dir );
	if ( length == 0 )
	{
		errno = ENOENT;
		return SERE_ERR_IO;
	}
	if ( length >= sizeof( path ) )
	{
		errno = ENAMETOOLONG;
		return SERE_ERR_IO;
	}
	memcpy( path, dir, length + 1 );
	for ( size_t i = 1; i <= length; ++i )
	{
		if ( path[i] == '/' || path[i] == '\0' )
		{
			char saved = path[i];
			path[i] = '\0';
			if ( mkdir( path, 0755 ) != 0 && errno != EEXIST )
			{
				return SERE_ERR_IO;
			}
			path[i] = saved;
		}
	}
	struct stat info;
	if ( stat( dir, &info ) != 0 )
	{
		return SERE_ERR_IO;
	}
	if ( !S_ISDIR( info.st_mode ) )
	{
		errno = ENOTDIR;
		return SERE_ERR_IO;
	}
	return SERE_OK;
}

sere_status sere_outputs_check( const char* dir, const char* const* names, int count, char* err, size_t err_size )
{
	for ( int k = 0; k < count; ++k )
	{
		char path[4200];
		snprintf( path, sizeof( path ), "%s/%s", dir, names[k] );
		struct stat info;
		if ( stat( path, &info ) == 0 && S_ISDIR( info.st_mode ) )
		{
			snprintf( err, err_size, "%s is a directory, not a file", path );
			return SERE_ERR_IO;
		}
	}
	return SERE_OK;
}

/* Length of the UTF-8 character at s (1 to 4), or 0 when s does not start a valid one. */
static int utf8_length( const unsigned char* s )
{
	unsigned char c = s[0];
	int length = c < 0x80				  ? 1
				 : c >= 0xC2 && c <= 0xDF ? 2
				 : c >= 0xE0 && c <= 0xEF ? 3
				 : c >= 0xF0 && c <= 0xF4 ? 4
										  : 0;
	if ( length > 1 )
	{
		/* the second byte's range excludes overlong forms, surrogates and code points past U+10FFFF */
		unsigned char lo = c == 0xE0 ? 0xA0 : c == 0xF0 ? 0x90 : 0x80;
		unsigned char hi = c == 0xED ? 0x9F : c == 0xF4 ? 0x8F : 0xBF;
		if ( s[1] < lo || s[1] > hi )
		{
			return 0;
		}
		for ( int k = 2; k < length; ++k )
		{
			if ( s[k] < 0x80 || s[k] > 0xBF )
			{
				return 0;
			}
		}
	}
	return length;
}

long sere_utf8_invalid_at( const char* text )
{
	const unsigned char* s = (const unsigned char*) text;
	for ( long at = 0; s[at] != '\0'; )
	{
		int length = utf8_length( s + at );
		if ( length == 0 )
		{
			return at;
		}
		at += length;
	}
	return -1;
}

const char* sere_json_escape( char* out, size_t size, const char* text )
{
	if ( size == 0 )
	{
		return out;
	}
	size_t used = 0;
	const unsigned char* s = (const unsigned char*) ( text != NULL ? text : "" );
	while ( *s != '\0' )
	{
		char piece[8];
		int consumed = 1;
		int length = utf8_length( s );
		if ( *s == '"' || *s == '\\' )
		{
			piece[0] = '\\', piece[1] = (char) *s, piece[2] = '\0';
		}
		else if ( *s == '\n' || *s == '\t' || *s == '\r' )
		{
			piece[0] = '\\', piece[1] = *s == '\n' ? 'n' : *s == '\t' ? 't' : 'r', piece[2] = '\0';
		}
		else if ( *s < 0x20 || *s == 0x7F )
		{
			snprintf( piece, sizeof( piece ), "\\u%04x", (unsigned) *s );
		}
		else if ( length == 0 )
		{
			snprintf( piece, sizeof( piece ), "\\ufffd" );
		}
		else
		{
			memcpy( piece, s, (size_t) length );
			piece[length] = '\0';
			consumed = length;
		}
		size_t piece_length = strlen( piece );
		if ( used + piece_length + 1 > size )
		{
			break;
		}
		memcpy( out + used, piece, piece_length );
		used += piece_length;
		s += consumed;
	}
	out[used] = '\0';
	return out;
}

sere_status sere_ply_write( const char* path, const float* x, const float* y, const float* z, int32_t vertex_count,
							const int32_t* tri, int32_t triangle_count, const uint8_t* rgb,
							const sere_vertex_property* properties, int32_t property_count )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return SERE_ERR_IO;
	}
	fprintf( f, "ply\nformat binary_little_endian 1.0\ncomment sere\nelement vertex %d\n", vertex_count );
	fprintf( f, "property float x\nproperty float y\nproperty float z\n" );
	if ( rgb != NULL )
	{
		fprintf( f, "property uchar red\nproperty uchar green\nproperty uchar blue\n" );
	}
	for ( int32_t k = 0; k < property_count; ++k )
	{
		fprintf( f, "property float %s\n", properties[k].name );
	}
	fprintf( f, "element face %d\nproperty list uchar int vertex_indices\nend_header\n", triangle_count );
	/* PLY binary is little endian, as is every machine sere targets (x86-64, aarch64). */
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		float p[3] = { x[i], y[i], z[i] };
		fwrite( p, sizeof( float ), 3, f );
		if ( rgb != NULL )
		{
			fwrite( rgb + 3 * i, 1, 3, f );
		}
		for ( int32_t k = 0; k < property_count; ++k )
		{
			fwrite( properties[k].values + i, sizeof( float ), 1, f );
		}
	}
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		uint8_t three = 3;
		fwrite( &three, 1, 1, f );
		fwrite( tri + 3 * t, sizeof( int32_t ), 3, f );
	}
	return sere_atomic_commit( &file );
}

sere_status sere_vtp_write( const char* path, const float* x, const float* y, const float* z, int32_t vertex_count,
							const int32_t* tri, int32_t triangle_count, const sere_vertex_property* properties,
							int32_t property_count )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return SERE_ERR_IO;
	}
	fprintf( f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n" );
	fprintf( f, "<PolyData>\n<Piece NumberOfPoints=\"%d\" NumberOfPolys=\"%d\">\n", vertex_count, triangle_count );
	fprintf( f, "<PointData>\n" );
	for ( int32_t k = 0; k < property_count; ++k )
	{
		fprintf( f, "<DataArray type=\"Float32\" Name=\"%s\" format=\"ascii\">\n", properties[k].name );
		for ( int32_t i = 0; i < vertex_count; ++i )
		{
			fprintf( f, "%.9g\n", (double) properties[k].values[i] );
		}
		fprintf( f, "</DataArray>\n" );
	}
	fprintf( f, "</PointData>\n<Points>\n<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n" );
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		fprintf( f, "%.9g %.9g %.9g\n", (double) x[i], (double) y[i], (double) z[i] );
	}
	fprintf( f,
			 "</DataArray>\n</Points>\n<Polys>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n" );
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		fprintf( f, "%d %d %d\n", tri[3 * t], tri[3 * t + 1], tri[3 * t + 2] );
	}
	fprintf( f, "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n" );
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		fprintf( f, "%d\n", 3 * ( t + 1 ) );
	}
	fprintf( f, "</DataArray>\n</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n" );
	return sere_atomic_commit( &file );
}

sere_status sere_pvd_write( const char* path, const char* const* files, const double* times, int32_t count )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return SERE_ERR_IO;
	}
	fprintf( f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n" );
	for ( int32_t i = 0; i < count; ++i )
	{
		fprintf( f, "<DataSet timestep=\"%.9g\" part=\"0\" file=\"%s\"/>\n", times[i], files[i] );
	}
	fprintf( f, "</Collection>\n</VTKFile>\n" );
	return sere_atomic_commit( &file );
}

sere_status sere_pvd_append( sere_pvd_series* series, const char* path, const char* file, double time )
{
	if ( series->count == series->capacity )
	{
		int32_t capacity = sere_array_capacity( series->capacity, (int64_t) series->count + 1, 64 );
		char** files = capacity > 0 ? sere_array_resize( series->files, capacity, sizeof( char* ) ) : NULL;
		series->files = files != NULL ? files : series->files;
		double* times = files != NULL ? sere_array_resize( series->times, capacity, sizeof( double ) ) : NULL;
		if ( times == NULL )
		{
			errno = ENOMEM;
			return SERE_ERR_MEMORY;
		}
		series->times = times;
		series->capacity = capacity;
	}
	char* copy = strdup( file );
	if ( copy == NULL )
	{
		errno = ENOMEM;
		return SERE_ERR_MEMORY;
	}
	series->files[series->count] = copy;
	series->times[series->count] = time;
	series->count += 1;
	return sere_pvd_write( path, (const char* const*) series->files, series->times, series->count );
}

void sere_pvd_destroy( sere_pvd_series* series )
{
	for ( int32_t k = 0; k < series->count; ++k )
	{
		free( series->files[k] );
	}
	free( series->files );
	free( series->times );
	memset( series, 0, sizeof( *series ) );
}

double sere_now( void )
{
	struct timespec ts;
	clock_gettime( CLOCK_MONOTONIC, &ts );
	return (double) ts.tv_sec + 1e-9 * (double) ts.tv_nsec;
}

static void progress_draw( sere_progress* progress, int64_t done )
{
	const int width = 30;
	int filled = progress->total > 0 ? (int) ( width * done / progress->total ) : width;
	double elapsed = sere_now() - progress->start;
	double eta = done > 0 ? elapsed * (double) ( progress->total - done ) / (double) done : 0.0;
	char bar[64];
	for ( int i = 0; i < width; ++i )
	{
		bar[i] = i < filled ? '#' : '.';
	}
	bar[width] = '\0';
	fprintf( stderr, "\r%s [%s] %lld/%lld  %.1fs elapsed, %.1fs left ", progress->label, bar, (long long) done,
			 (long long) progress->total, elapsed, eta );
	fflush( stderr );
}

void sere_progress_begin( sere_progress* progress, const char* label, int64_t total )
{
	progress->label = label;
	progress->total = total;
	progress->shown = -1;
	progress->start = sere_now();
	progress->active = isatty( fileno( stderr ) );
	if ( progress->active )
	{
		progress_draw( progress, 0 );
	}
}

void sere_progress_update( sere_progress* progress, int64_t done )
{
	if ( progress->active && done != progress->shown )
	{
		progress->shown = done;
		progress_draw( progress, done );
	}
}

void sere_progress_end( sere_progress* progress )
{
	if ( progress->active )
	{
		progress_draw( progress, progress->total );
		fputc( '\n', stderr );
	}
}

sere_status sere_fail( sere_status status, char* err, size_t err_size, const char* format, ... )
{
	if ( err != NULL && err_size > 0 )
	{
		va_list args;
		va_start( args, format );
		vsnprintf( err, err_size, format, args );
		va_end( args );
	}
	return status;
}

sere_status sere_fail_at( sere_status status, char* err, size_t err_size, const char* path, int line,
						  const char* format, va_list args )
{
	char message[512];
	vsnprintf( message, sizeof( message ), format, args );
	if ( line > 0 )
	{
		return sere_fail( status, err, err_size, "%s:%d: %s", path, line, message );
	}
	return sere_fail( status, err, err_size, "%s: %s", path, message );
}
