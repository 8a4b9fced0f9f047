#include "leaffile.h"

#include "io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sere_leaf_file_free( sere_leaf_file* leaf )
{
	free( leaf->outline_xy );
	free( leaf->vein_xy );
	free( leaf->veins );
	free( leaf->outline_line );
	free( leaf->vein_line );
	memset( leaf, 0, sizeof( *leaf ) );
}

typedef struct reader
{
	FILE* f;
	const char* path;
	int line;
	char text[1024];
	char* err;
	size_t err_size;
} reader;

/* The next line that is not blank or a comment, with the comment stripped; 0 at the end. */
static int next_line( reader* r )
{
	while ( fgets( r->text, sizeof( r->text ), r->f ) != NULL )
	{
		r->line += 1;
		char* hash = strchr( r->text, '#' );
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		size_t length = strlen( r->text );
		while ( length > 0 && strchr( " \t\r\n", r->text[length - 1] ) != NULL )
		{
			r->text[--length] = '\0';
		}
		char* start = r->text;
		while ( *start == ' ' || *start == '\t' )
		{
			++start;
		}
		if ( *start != '\0' )
		{
			memmove( r->text, start, strlen( start ) + 1 );
			return 1;
		}
	}
	return 0;
}

static sere_status error_at( reader* r, int line, sere_status status, const char* what )
{
	if ( line > 0 )
	{
		snprintf( r->err, r->err_size, "%s:%d: %s", r->path, line, what );
	}
	else
	{
		snprintf( r->err, r->err_size, "%s: %s", r->path, what );
	}
	return status;
}

/* Parses exactly count numbers from text; -1 names a non-number, -2 a NaN/inf, -3 the count. */
static int parse_numbers( const char* text, double* values, int count )
{
	const char* p = text;
	for ( int k = 0; k < count; ++k )
	{
		char* end;
		errno = 0;
		double v = strtod( p, &end );
		if ( end == p )
		{
			return *p == '\0' ? -3 : -1;
		}
		if ( !isfinite( v ) || errno == ERANGE )
		{
			return -2;
		}
		values[k] = v;
		p = end;
	}
	while ( *p == ' ' || *p == '\t' )
	{
		++p;
	}
	return *p == '\0' ? 0 : ( strchr( "+-.0123456789", *p ) != NULL ? -3 : -1 );
}

static int parse_int( const char* text, long* value )
{
	char* end;
	errno = 0;
	long v = strtol( text, &end, 10 );
	if ( end == text || errno == ERANGE )
	{
		return -1;
	}
	*value = v;
	return (int) ( end - text );
}

static sere_status read_points( reader* r, int32_t count, double* xy, int32_t* lines, const char* what )
{
	for ( int32_t i = 0; i < count; ++i )
	{
		if ( !next_line( r ) )
		{
			char message[256];
			snprintf( message, sizeof( message ), "file ends after %d of %d %s points", i, count, what );
			return error_at( r, r->line, SERE_ERR_ARGUMENT, message );
		}
		int result = parse_numbers( r->text, xy + 2 * i, 2 );
		if ( result != 0 )
		{
			char message[300];
			if ( result == -2 )
			{
				snprintf( message, sizeof( message ), "NaN or infinite coordinate in %s point %d", what, i + 1 );
				return error_at( r, r->line, SERE_ERR_NONFINITE, message );
			}
			if ( result == -3 )
			{
				snprintf( message, sizeof( message ), "%s point %d must be two numbers 'x y', got '%.80s'", what, i + 1,
						  r->text );
			}
			else
			{
				snprintf( message, sizeof( message ), "non-numeric value in %s point %d: '%.80s' (wrong point count?)",
						  what, i + 1, r->text );
			}
			return error_at( r, r->line, SERE_ERR_ARGUMENT, message );
		}
		lines[i] = r->line;
	}
	return SERE_OK;
}

static int grow_array( void** array, size_t element, int32_t count, int32_t extra )
{
	void* bigger = realloc( *array, element * (size_t) ( count + extra ) );
	if ( bigger == NULL )
	{
		return -1;
	}
	*array = bigger;
	return 0;
}

sere_status sere_leaf_read( const char* path, sere_leaf_file* leaf, char* err, size_t err_size )
{
	memset( leaf, 0, sizeof( *leaf ) );
	reader r = { .f = fopen( path, "r" ), .path = path, .line = 0, .err = err, .err_size = err_size };
	if ( r.f == NULL )
	{
		snprintf( err, err_size, "%s: cannot open: %s", path, strerror( errno ) );
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = SERE_OK;
	int have_base = 0, have_outline = 0, base_line = 0;
	double base[2] = { 0.0, 0.0 };
	int32_t vein_points = 0, vein_count = 0;
	while ( next_line( &r ) )
	{
		char keyword[32] = { 0 };
		int used = 0;
		if ( sscanf( r.text, "%31s%n", keyword, &used ) != 1 )
		{
			continue;
		}
		const char* rest = r.text + used;
		while ( *rest == ' ' || *rest == '\t' )
		{
			++rest;
		}
		if ( strcmp( keyword, "name" ) == 0 )
		{
			snprintf( leaf->name, sizeof( leaf->name ), "%s", rest );
		}
		else if ( strcmp( keyword, "base" ) == 0 )
		{
			int result = parse_numbers( rest, base, 2 );
			if ( result != 0 )
			{
				status = error_at( &r, r.line, result == -2 ? SERE_ERR_NONFINITE : SERE_ERR_ARGUMENT,
								   result == -2 ? "NaN or infinite base coordinate" : "base must be 'base x y'" );
				goto fail;
			}
			have_base = 1;
			base_line = r.line;
		}
		else if ( strcmp( keyword, "outline" ) == 0 )
		{
			long count;
			int used_count = parse_int( rest, &count );
			if ( have_outline || used_count < 0 || rest[used_count] != '\0' || count < 0 || count > 10000000 )
			{
				status = error_at( &r, r.line, SERE_ERR_ARGUMENT,
								   have_outline ? "a second outline" : "outline must be 'outline COUNT'" );
				goto fail;
			}
			if ( count < 3 )
			{
				status = error_at( &r, r.line, SERE_ERR_GEOMETRY, "an outline needs at least 3 points" );
				goto fail;
			}
			leaf->outline_xy = malloc( sizeof( double ) * 2 * (size_t) count );
			leaf->outline_line = malloc( sizeof( int32_t ) * (size_t) count );
			if ( leaf->outline_xy == NULL || leaf->outline_line == NULL )
			{
				status = error_at( &r, 0, SERE_ERR_MEMORY, "out of memory" );
				goto fail;
			}
			leaf->shape.outline_count = (int32_t) count;
			status = read_points( &r, (int32_t) count, leaf->outline_xy, leaf->outline_line, "outline" );
			if ( status != SERE_OK )
			{
				goto fail;
			}
			have_outline = 1;
		}
		else if ( strcmp( keyword, "vein" ) == 0 )
		{
			long order, parent, count;
			int a = parse_int( rest, &order );
			int b = a > 0 ? parse_int( rest + a, &parent ) : -1;
			int c = b > 0 ? parse_int( rest + a + b, &count ) : -1;
			if ( c < 0 || rest[a + b + c] != '\0' )
			{
				status = error_at( &r, r.line, SERE_ERR_ARGUMENT, "vein must be 'vein ORDER PARENT COUNT'" );
				goto fail;
			}
			if ( order < 1 || parent < -1 || parent >= vein_count || count < 2 || count > 10000000 )
			{
				char message[200];
				snprintf( message, sizeof( message ),
						  "vein %d: order must be >= 1, parent -1 or an earlier vein (0..%d), at least 2 points",
						  vein_count, vein_count - 1 );
				status = error_at( &r, r.line, SERE_ERR_ARGUMENT, message );
				goto fail;
			}
			if ( grow_array( (void**) &leaf->veins, sizeof( sere_vein ), vein_count, 1 ) != 0 ||
				 grow_array( (void**) &leaf->vein_xy, 2 * sizeof( double ), vein_points, (int32_t) count ) != 0 ||
				 grow_array( (void**) &leaf->vein_line, sizeof( int32_t ), vein_points, (int32_t) count ) != 0 )
			{
				status = error_at( &r, 0, SERE_ERR_MEMORY, "out of memory" );
				goto fail;
			}
			leaf->veins[vein_count] = ( sere_vein ){
				.first = vein_points, .count = (int32_t) count, .order = (int32_t) order, .parent = (int32_t) parent
			};
			status = read_points( &r, (int32_t) count, leaf->vein_xy + 2 * vein_points, leaf->vein_line + vein_points,
								  "vein" );
			if ( status != SERE_OK )
			{
				goto fail;
			}
			vein_count += 1;
			vein_points += (int32_t) count;
		}
		else
		{
			char message[128];
			snprintf( message, sizeof( message ), "unknown keyword '%.40s' (expected name, base, outline or vein)",
					  keyword );
			status = error_at( &r, r.line, SERE_ERR_ARGUMENT, message );
			goto fail;
		}
	}
	if ( !have_outline )
	{
		status = error_at( &r, 0, SERE_ERR_ARGUMENT, "no outline" );
		goto fail;
	}
	if ( !have_base )
	{
		status = error_at( &r, 0, SERE_ERR_ARGUMENT, "no base point" );
		goto fail;
	}
	if ( leaf->name[0] == '\0' )
	{
		const char* slash = strrchr( path, '/' );
		snprintf( leaf->name, sizeof( leaf->name ), "%s", slash ? slash + 1 : path );
	}
	leaf->shape = ( sere_leaf_shape ){
		.base_x = base[0],
		.base_y = base[1],
		.outline_count = leaf->shape.outline_count,
		.outline_xy = leaf->outline_xy,
		.vein_count = vein_count,
		.veins = leaf->veins,
		.vein_point_count = vein_points,
		.vein_xy = leaf->vein_xy,
	};
	sere_shape_check check;
	status = sere_shape_validate( &leaf->shape, &check );
	if ( status != SERE_OK )
	{
		int line = 0;
		if ( check.problem == SERE_SHAPE_BASE_OFF_OUTLINE )
		{
			line = base_line;
		}
		else if ( check.vein >= 0 || check.problem == SERE_SHAPE_VEIN_OUTSIDE )
		{
			line = check.point >= 0 ? leaf->vein_line[check.point] : 0;
		}
		else if ( check.problem == SERE_SHAPE_NONFINITE )
		{
			line = base_line;
		}
		else if ( check.point >= 0 )
		{
			line = leaf->outline_line[check.point];
		}
		status = error_at( &r, line, status, sere_shape_problem_text( check.problem ) );
		goto fail;
	}
	fclose( r.f );
	return SERE_OK;

fail:
	fclose( r.f );
	sere_leaf_file_free( leaf );
	return status;
}

int sere_leaf_write( const char* path, const sere_leaf_shape* shape, const char* name )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	fprintf( f, "# sere leaf: outline counter-clockwise, base on the outline, veins from the base\n" );
	fprintf( f, "name %s\nbase %.9g %.9g\noutline %d\n", name, shape->base_x, shape->base_y, shape->outline_count );
	for ( int32_t i = 0; i < shape->outline_count; ++i )
	{
		fprintf( f, "%.9g %.9g\n", shape->outline_xy[2 * i], shape->outline_xy[2 * i + 1] );
	}
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		fprintf( f, "vein %d %d %d\n", vein->order, vein->parent, vein->count );
		for ( int32_t k = 0; k < vein->count; ++k )
		{
			fprintf( f, "%.9g %.9g\n", shape->vein_xy[2 * ( vein->first + k )],
					 shape->vein_xy[2 * ( vein->first + k ) + 1] );
		}
	}
	return sere_atomic_commit( &file );
}
