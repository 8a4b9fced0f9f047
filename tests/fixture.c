#define _POSIX_C_SOURCE 200809L
#include "fixture.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

double sere_test_unit( uint64_t* state )
{
	return sere_splitmix_unit( state );
}

void sere_test_plane_grid( sere_test_plane* plane, int32_t nx, int32_t ny, double width, double height, double jitter,
						   int vein_row, uint64_t seed )
{
	int32_t n = ( nx + 1 ) * ( ny + 1 );
	int32_t* index = malloc( sizeof( int32_t ) * (size_t) n );
	plane->x = malloc( sizeof( double ) * (size_t) n );
	plane->y = malloc( sizeof( double ) * (size_t) n );
	plane->tri = malloc( sizeof( int32_t ) * 6 * (size_t) nx * (size_t) ny );
	plane->veins = malloc( sizeof( int32_t ) * 2 * (size_t) ( nx + 1 ) );
	int32_t next = 0;
	/* boundary first, counter-clockwise */
	for ( int32_t i = 0; i < nx; ++i )
	{
		index[0 * ( nx + 1 ) + i] = next++;
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		index[j * ( nx + 1 ) + nx] = next++;
	}
	for ( int32_t i = nx; i > 0; --i )
	{
		index[ny * ( nx + 1 ) + i] = next++;
	}
	for ( int32_t j = ny; j > 0; --j )
	{
		index[j * ( nx + 1 ) + 0] = next++;
	}
	int32_t boundary = next;
	for ( int32_t j = 1; j < ny; ++j )
	{
		for ( int32_t i = 1; i < nx; ++i )
		{
			index[j * ( nx + 1 ) + i] = next++;
		}
	}
	uint64_t state = seed;
	double dx = width / nx, dy = height / ny;
	for ( int32_t j = 0; j <= ny; ++j )
	{
		for ( int32_t i = 0; i <= nx; ++i )
		{
			int32_t k = index[j * ( nx + 1 ) + i];
			int interior = i > 0 && i < nx && j > 0 && j < ny && !( vein_row && j == ny / 2 );
			double jx = interior ? jitter * ( sere_test_unit( &state ) - 0.5 ) * dx : 0.0;
			double jy = interior ? jitter * ( sere_test_unit( &state ) - 0.5 ) * dy : 0.0;
			plane->x[k] = i * dx + jx;
			plane->y[k] = j * dy + jy;
		}
	}
	int32_t t = 0;
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t a = index[j * ( nx + 1 ) + i], b = index[j * ( nx + 1 ) + i + 1];
			int32_t c = index[( j + 1 ) * ( nx + 1 ) + i + 1], d = index[( j + 1 ) * ( nx + 1 ) + i];
			int32_t* q = plane->tri + 6 * t++;
			q[0] = a, q[1] = b, q[2] = c, q[3] = a, q[4] = c, q[5] = d;
		}
	}
	int32_t vein_count = 0;
	if ( vein_row )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			plane->veins[2 * vein_count] = index[( ny / 2 ) * ( nx + 1 ) + i];
			plane->veins[2 * vein_count + 1] = index[( ny / 2 ) * ( nx + 1 ) + i + 1];
			vein_count += 1;
		}
	}
	plane->mesh = ( sere_plane_mesh ){
		.x = plane->x,
		.y = plane->y,
		.point_count = n,
		.boundary_count = boundary,
		.tri = plane->tri,
		.triangle_count = 2 * nx * ny,
		.vein_segments = plane->veins,
		.vein_segment_count = vein_count,
		.base = index[( ny / 2 ) * ( nx + 1 )],
	};
	free( index );
}

void sere_test_plane_free( sere_test_plane* plane )
{
	free( plane->x );
	free( plane->y );
	free( plane->tri );
	free( plane->veins );
}

const char* sere_test_bin( void )
{
	const char* bin = getenv( "SERE_BIN" );
	return bin != NULL ? bin : "build/sere";
}

int sere_test_shell( const char* command, char* out, size_t out_size )
{
	out[0] = '\0';
	FILE* pipe = popen( command, "r" );
	if ( pipe == NULL )
	{
		snprintf( out, out_size, "cannot run %s", command );
		return 128;
	}
	size_t used = fread( out, 1, out_size - 1, pipe );
	out[used] = '\0';
	/* Drain what did not fit: a command whose pipe closes early dies of SIGPIPE, and its
	 * status would then say nothing about the command. */
	char rest[4096];
	while ( fread( rest, 1, sizeof( rest ), pipe ) > 0 )
	{
	}
	int status = pclose( pipe );
	return WIFEXITED( status ) ? WEXITSTATUS( status ) : 128;
}

int sere_test_run( const char* args, char* err, size_t err_size )
{
	char command[2048];
	snprintf( command, sizeof( command ), "%s %s 2>&1 >/dev/null", sere_test_bin(), args );
	return sere_test_shell( command, err, err_size );
}

int sere_test_stdout( const char* args, char* out, size_t out_size )
{
	char command[4096];
	snprintf( command, sizeof( command ), "%s %s 2>/dev/null", sere_test_bin(), args );
	return sere_test_shell( command, out, out_size );
}

void sere_test_crumple_make( sere_test_crumple* field, double amplitude, uint64_t seed )
{
	const double pi = 3.14159265358979323846;
	field->state = seed;
	for ( int m = 0; m < 8; ++m )
	{
		double angle = 2.0 * pi * sere_test_unit( &field->state );
		double k = 2.0 * pi * ( 2.0 + 3.0 * sere_test_unit( &field->state ) );
		field->wave[m][0] = k * cos( angle ), field->wave[m][1] = k * sin( angle );
		field->wave[m][2] = 2.0 * pi * sere_test_unit( &field->state );
		for ( int a = 0; a < 3; ++a )
		{
			field->wave[m][3 + a] =
				( a == 2 ? 0.25 : 0.125 ) * amplitude * ( 2.0 * sere_test_unit( &field->state ) - 1.0 );
		}
	}
}

void sere_test_crumple_point( sere_test_crumple* field, double u, double v, double noise, float* x, float* y, float* z )
{
	double d[3] = { 0.0, 0.0, 0.0 };
	for ( int m = 0; m < 8; ++m )
	{
		double phase = sin( field->wave[m][0] * u + field->wave[m][1] * v + field->wave[m][2] );
		for ( int a = 0; a < 3; ++a )
		{
			d[a] += field->wave[m][3 + a] * phase;
		}
	}
	*x = (float) ( u + d[0] + noise * ( sere_test_unit( &field->state ) - 0.5 ) );
	*y = (float) ( v + d[1] + noise * ( sere_test_unit( &field->state ) - 0.5 ) );
	*z = (float) ( d[2] + noise * ( sere_test_unit( &field->state ) - 0.5 ) );
}

int sere_test_remove_tree( const char* dir )
{
	char command[1100];
	snprintf( command, sizeof( command ), "rm -rf '%s'", dir );
	return system( command );
}

int sere_test_run_in( const char* format, const char* dir, char* err, size_t err_size )
{
	char args[2048];
	snprintf( args, sizeof( args ), format, dir );
	return sere_test_run( args, err, err_size );
}

char* sere_test_scratch( const char* name )
{
	char* dir = malloc( 64 );
	snprintf( dir, 64, "/tmp/sere-%s-XXXXXX", name );
	cr_assert_not_null( mkdtemp( dir ), "cannot make %s", dir );
	return dir;
}

void sere_test_scratch_remove( char* dir )
{
	cr_expect_eq( sere_test_remove_tree( dir ), 0, "cannot remove %s", dir );
	free( dir );
}

void sere_test_expect_one_line( const char* what, const char* err )
{
	const char* newline = strchr( err, '\n' );
	cr_expect( newline != NULL && newline[1] == '\0', "%s: not one line: %s", what, err );
}

int sere_test_expect_error( const char* args, const char* phrase )
{
	char err[4096];
	int code = sere_test_run( args, err, sizeof( err ) );
	cr_expect_not_null( strstr( err, phrase ), "'%s': expected '%s' in: %s", args, phrase, err );
	sere_test_expect_one_line( args, err );
	return code;
}

static void sheet_spring( sere_test_sheet* s, int32_t i, int32_t j, float scale )
{
	float dx = s->x[j] - s->x[i], dy = s->y[j] - s->y[i], dz = s->z[j] - s->z[i];
	s->a[s->count] = i, s->b[s->count] = j;
	s->rest[s->count] = scale * sqrtf( dx * dx + dy * dy + dz * dz );
	s->count += 1;
}

sere_test_sheet sere_test_sheet_make( int32_t nx, int32_t ny )
{
	sere_test_sheet s = { 0 };
	s.n = nx * ny;
	float** columns[] = { &s.x, &s.y, &s.z, &s.inv_m, &s.tx, &s.ty, &s.tz };
	for ( size_t k = 0; k < sizeof( columns ) / sizeof( columns[0] ); ++k )
	{
		*columns[k] = calloc( (size_t) s.n, sizeof( float ) );
		cr_assert_not_null( *columns[k] );
	}
	s.a = calloc( 3 * (size_t) s.n, sizeof( int32_t ) );
	s.b = calloc( 3 * (size_t) s.n, sizeof( int32_t ) );
	s.rest = calloc( 3 * (size_t) s.n, sizeof( float ) );
	cr_assert( s.a != NULL && s.b != NULL && s.rest != NULL );
	const float h = (float) SERE_TEST_SHEET_SPACING;
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t p = j * nx + i;
			s.x[p] = h * (float) i, s.y[p] = h * (float) j;
			s.z[p] = 0.01f * sinf( 0.7f * (float) i ) * cosf( 0.5f * (float) j );
			s.inv_m[p] = 1.0f + (float) ( ( i + 2 * j ) % 3 );
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t p = j * nx + i;
			if ( i + 1 < nx )
			{
				sheet_spring( &s, p, p + 1, 1.0f );
			}
			if ( j + 1 < ny )
			{
				sheet_spring( &s, p, p + nx, 1.0f );
			}
			if ( i + 1 < nx && j + 1 < ny )
			{
				sheet_spring( &s, p, p + nx + 1, 0.8f );
			}
		}
	}
	memcpy( s.tx, s.x, sizeof( float ) * (size_t) s.n );
	memcpy( s.ty, s.y, sizeof( float ) * (size_t) s.n );
	memcpy( s.tz, s.z, sizeof( float ) * (size_t) s.n );
	return s;
}

void sere_test_sheet_free( sere_test_sheet* s )
{
	free( s->x ), free( s->y ), free( s->z ), free( s->inv_m ), free( s->tx ), free( s->ty ), free( s->tz );
	free( s->a ), free( s->b ), free( s->rest );
}

void sere_test_expect_thread_range( const char* name, void* object, sere_test_set_fn* set )
{
	cr_expect_eq( set( object, -1 ), SERE_ERR_ARGUMENT, "%s: -1 threads", name );
	cr_expect_eq( set( object, SERE_MAX_THREADS + 1 ), SERE_ERR_ARGUMENT, "%s: %d threads", name,
				  SERE_MAX_THREADS + 1 );
	cr_expect_eq( set( NULL, 1 ), SERE_ERR_ARGUMENT, "%s: NULL", name );
	const int32_t good[] = { SERE_MAX_THREADS, 3, 1, 0 };
	for ( size_t k = 0; k < sizeof( good ) / sizeof( good[0] ); ++k )
	{
		cr_expect_eq( set( object, good[k] ), SERE_OK, "%s: %d threads", name, good[k] );
	}
}
