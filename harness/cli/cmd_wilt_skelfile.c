/* sere wilt — skeleton files: the text format of `sere wilt --help`, read with the line of every
 * point kept for messages. */
#include "cli/cmd_wilt_shared.h"
#include "common/params.h"
#include "core/array.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------- */
/* Skeleton files. */

static const char* const curve_names[3] = { "left boundary curve", "right boundary curve", "midvein" };

void wilt_skeleton_free( skeleton_file* s )
{
	for ( int k = 0; k < 3; ++k )
	{
		free( s->curve[k].xy );
		free( s->curve[k].line );
	}
	for ( int32_t k = 0; k < s->vein_count; ++k )
	{
		free( s->vein[k].xy );
		free( s->vein[k].line );
	}
}

static int point_push( point_list* p, double x, double y, int32_t line )
{
	if ( p->count == p->capacity )
	{
		int32_t capacity = sere_array_capacity( p->capacity, (int64_t) p->count + 1, 16 );
		double* xy = capacity > 0 ? sere_array_resize( p->xy, capacity, 2 * sizeof( double ) ) : NULL;
		p->xy = xy != NULL ? xy : p->xy;
		int32_t* lines = xy != NULL ? sere_array_resize( p->line, capacity, sizeof( int32_t ) ) : NULL;
		if ( lines == NULL )
		{
			return -1;
		}
		p->line = lines;
		p->capacity = capacity;
	}
	p->xy[2 * p->count] = x;
	p->xy[2 * p->count + 1] = y;
	p->line[p->count++] = line;
	return 0;
}

/* Finds NAME as a path or as data/skeletons/NAME.skel. */
static int skeleton_locate( const char* name, char* path, size_t size )
{
	FILE* f = fopen( name, "r" );
	if ( f != NULL )
	{
		fclose( f );
		snprintf( path, size, "%s", name );
		return 0;
	}
	char relative[512];
	snprintf( relative, sizeof( relative ), "skeletons/%s.skel", name );
	return sere_data_find( relative, path, size );
}

/* A 'vein PARENT SEGMENTS BEND_DEGREES' line: opens the vein's block. */
static int skeleton_vein_line( skeleton_file* s, const char* rest, int32_t number, point_list** block, char* err,
							   size_t err_size )
{
	long parent, segments;
	double bend;
	char extra[8];
	if ( sscanf( rest, " %ld %ld %lf %7s", &parent, &segments, &bend, extra ) != 3 || !isfinite( bend ) )
	{
		snprintf( err, err_size, "%s:%d: 'vein' takes PARENT SEGMENTS BEND_DEGREES, e.g. 'vein 0 6 60'", s->path,
				  number );
		return -1;
	}
	if ( s->vein_count == MAX_VEINS )
	{
		snprintf( err, err_size, "%s:%d: more than %d veins", s->path, number, MAX_VEINS );
		return -1;
	}
	int32_t k = s->vein_count++;
	s->vein_line[k] = number;
	s->vein_parent[k] = parent < -1 || parent > MAX_VEINS ? MAX_VEINS : (int32_t) parent;
	s->vein_segments[k] = segments < 0 || segments > 1000000 ? -1 : (int32_t) segments;
	s->vein_bend[k] = bend;
	*block = s->vein + k;
	return 0;
}

/* An 'x y' line: a point of the open block. */
static int skeleton_point_line( skeleton_file* s, const char* word, const char* rest, int32_t number, point_list* block,
								char* err, size_t err_size )
{
	char* end;
	double x = strtod( word, &end );
	if ( *end != '\0' )
	{
		snprintf( err, err_size,
				  "%s:%d: unknown keyword '%s' (expected name, left, right, midvein, vein, or an 'x y' point)", s->path,
				  number, word );
		return -1;
	}
	double y;
	char extra[8];
	if ( sscanf( rest, " %lf %7s", &y, extra ) != 1 || !isfinite( x ) || !isfinite( y ) )
	{
		snprintf( err, err_size, "%s:%d: a point is two finite numbers 'x y'", s->path, number );
		return -1;
	}
	if ( block == NULL )
	{
		snprintf( err, err_size, "%s:%d: point outside a left, right, midvein or vein block", s->path, number );
		return -1;
	}
	if ( point_push( block, x, y, number ) != 0 )
	{
		snprintf( err, err_size, "%s: out of memory", s->path );
		return -1;
	}
	return 0;
}

/* One line of a skeleton file (comment already cut): a keyword that opens a block or names the
 * leaf, or a point of the open *block. */
static int skeleton_line( skeleton_file* s, const char* text, int32_t number, point_list** block, char* err,
						  size_t err_size )
{
	char word[64];
	int used = 0;
	if ( sscanf( text, " %63s%n", word, &used ) != 1 )
	{
		return 0;
	}
	const char* rest = text + used;
	char extra[8];
	int curve = strcmp( word, "left" ) == 0		 ? 0
				: strcmp( word, "right" ) == 0	 ? 1
				: strcmp( word, "midvein" ) == 0 ? 2
												 : -1;
	if ( curve >= 0 )
	{
		int status = 0;
		if ( sscanf( rest, " %7s", extra ) == 1 )
		{
			snprintf( err, err_size, "%s:%d: '%s' takes no value; its points follow on their own lines", s->path,
					  number, word );
			status = -1;
		}
		else if ( s->curve_line[curve] != 0 )
		{
			snprintf( err, err_size, "%s:%d: second '%s' block (the first is on line %d)", s->path, number, word,
					  s->curve_line[curve] );
			status = -1;
		}
		s->curve_line[curve] = number;
		*block = s->curve + curve;
		return status;
	}
	if ( strcmp( word, "name" ) == 0 )
	{
		char value[64];
		*block = NULL;
		if ( sscanf( rest, " %63s %7s", value, extra ) != 1 )
		{
			snprintf( err, err_size, "%s:%d: 'name' takes one word", s->path, number );
			return -1;
		}
		snprintf( s->name, sizeof( s->name ), "%s", value );
		return 0;
	}
	if ( strcmp( word, "vein" ) == 0 )
	{
		return skeleton_vein_line( s, rest, number, block, err, err_size );
	}
	return skeleton_point_line( s, word, rest, number, *block, err, err_size );
}

/* Every curve block is present with at least 2 points. */
static int skeleton_curves_complete( const skeleton_file* s, char* err, size_t err_size )
{
	static const char* const keyword[3] = { "left", "right", "midvein" };
	for ( int k = 0; k < 3; ++k )
	{
		if ( s->curve_line[k] == 0 )
		{
			snprintf( err, err_size, "%s: no '%s' block (the %s)", s->path, keyword[k], curve_names[k] );
			return -1;
		}
		if ( s->curve[k].count < 2 )
		{
			/* build_leaf measures the leaf from the midvein's first and last points */
			snprintf( err, err_size, "%s:%d: the '%s' block has %d point%s; the %s needs at least 2", s->path,
					  s->curve_line[k], keyword[k], s->curve[k].count, s->curve[k].count == 1 ? "" : "s",
					  curve_names[k] );
			return -1;
		}
	}
	return 0;
}

int wilt_skeleton_load( const char* name, skeleton_file* s, char* err, size_t err_size )
{
	memset( s, 0, sizeof( *s ) );
	if ( skeleton_locate( name, s->path, sizeof( s->path ) ) != 0 )
	{
		snprintf( err, err_size, "cannot find skeleton '%s' (a file path, or a name in data/skeletons)", name );
		return -1;
	}
	FILE* f = fopen( s->path, "r" );
	if ( f == NULL )
	{
		snprintf( err, err_size, "%s: %s", s->path, strerror( errno ) );
		return -1;
	}
	snprintf( s->name, sizeof( s->name ), "%s", name );
	char text[1024];
	int32_t number = 0;
	point_list* block = NULL;
	int status = 0;
	while ( status == 0 && fgets( text, sizeof( text ), f ) != NULL )
	{
		++number;
		if ( strchr( text, '\n' ) == NULL && !feof( f ) )
		{
			snprintf( err, err_size, "%s:%d: line longer than %zu characters", s->path, number, sizeof( text ) - 2 );
			status = -1;
			break;
		}
		char* hash = strchr( text, '#' );
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		status = skeleton_line( s, text, number, &block, err, err_size );
	}
	if ( status == 0 && ferror( f ) )
	{
		snprintf( err, err_size, "%s: %s", s->path, strerror( errno ) );
		status = -1;
	}
	fclose( f );
	if ( status == 0 )
	{
		status = skeleton_curves_complete( s, err, err_size );
	}
	if ( status != 0 )
	{
		wilt_skeleton_free( s );
	}
	return status;
}

/* "FILE:LINE: " for a problem the kernels found, located by curve or vein and point. */
void wilt_skeleton_where( const skeleton_file* s, const sere_skeleton_check* check, int veins, char* out, size_t size )
{
	if ( s == NULL )
	{
		snprintf( out, size, "parametric leaf: " );
		return;
	}
	int32_t line = 0;
	const char* what = "";
	char label[64] = "";
	if ( veins && check->vein >= 0 && check->vein < s->vein_count )
	{
		const point_list* p = s->vein + check->vein;
		line = check->point >= 0 && check->point < p->count ? p->line[check->point] : s->vein_line[check->vein];
		snprintf( label, sizeof( label ), "vein %d", check->vein );
		what = label;
	}
	else if ( !veins && check->vein >= 0 && check->vein < 3 )
	{
		const point_list* p = s->curve + check->vein;
		line = check->point >= 0 && check->point < p->count ? p->line[check->point] : s->curve_line[check->vein];
		what = curve_names[check->vein];
	}
	if ( line > 0 )
	{
		snprintf( out, size, "%s:%d: %s: ", s->path, line, what );
	}
	else
	{
		snprintf( out, size, "%s: ", s->path );
	}
}
