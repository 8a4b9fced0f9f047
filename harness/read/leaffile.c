#include "read/leaffile.h"

#include "common/io.h"
#include "core/array.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sere_leaf_file_destroy( sere_leaf_file* leaf )
{
	free( leaf->outline_xy );
	free( leaf->vein_xy );
	free( leaf->veins );
	free( leaf->outline_line );
	free( leaf->vein_line );
	memset( leaf, 0, sizeof( *leaf ) );
}

#define MAX_TOKENS 4

typedef struct reader
{
	FILE* f;
	const char* path;
	int32_t line;	 /* number of the current line (1-based) */
	char text[1024]; /* the current line without its comment and outer blanks */
	char split[1024];
	const char* token[MAX_TOKENS]; /* blank-separated words of text, in split */
	int token_count;			   /* every word, though only MAX_TOKENS are kept */
	const char* rest;			   /* text after its first word */
	char* err;
	size_t err_size;
} reader;

static sere_status fail( reader* r, int32_t line, sere_status status, const char* format, ... )
{
	va_list args;
	va_start( args, format );
	sere_fail_at( status, r->err, r->err_size, r->path, (int) line, format, args );
	va_end( args );
	return status;
}

static int blank( char c )
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/* Trims r->text and splits a copy of it into words. */
static void tokenize( reader* r )
{
	char* start = r->text;
	while ( blank( *start ) )
	{
		++start;
	}
	size_t length = strlen( start );
	while ( length > 0 && blank( start[length - 1] ) )
	{
		--length;
	}
	memmove( r->text, start, length );
	r->text[length] = '\0';
	memcpy( r->split, r->text, length + 1 );
	r->token_count = 0;
	r->rest = r->text + length;
	char* p = r->split;
	while ( *p != '\0' )
	{
		if ( blank( *p ) )
		{
			*p++ = '\0';
			continue;
		}
		if ( r->token_count == 1 )
		{
			r->rest = r->text + ( p - r->split );
		}
		if ( r->token_count < MAX_TOKENS )
		{
			r->token[r->token_count] = p;
		}
		r->token_count += 1;
		while ( *p != '\0' && !blank( *p ) )
		{
			++p;
		}
	}
}

/* Reads the next line holding anything but blanks and a comment: 1 with r->text tokenized, 0 at
 * the end of the file, -1 on an error (written to err). */
static int next_line( reader* r, sere_status* status )
{
	for ( ;; )
	{
		if ( fgets( r->text, sizeof( r->text ), r->f ) == NULL )
		{
			if ( ferror( r->f ) )
			{
				*status = fail( r, 0, SERE_ERR_ARGUMENT, "cannot read: %s", strerror( errno ) );
				return -1;
			}
			return 0;
		}
		r->line += 1;
		size_t length = strlen( r->text );
		char* hash = strchr( r->text, '#' );
		if ( length + 1 == sizeof( r->text ) && r->text[length - 1] != '\n' )
		{
			/* A longer line is fine only if what does not fit is comment. */
			int c;
			do
			{
				c = fgetc( r->f );
			} while ( c != EOF && c != '\n' );
			if ( hash == NULL )
			{
				*status = fail( r, r->line, SERE_ERR_ARGUMENT, "line longer than %d characters",
								(int) sizeof( r->text ) - 2 );
				return -1;
			}
		}
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		/* A UTF-8 byte order mark some editors write is not part of the first keyword. */
		if ( r->line == 1 && strncmp( r->text, "\xEF\xBB\xBF", 3 ) == 0 )
		{
			memmove( r->text, r->text + 3, strlen( r->text + 3 ) + 1 );
		}
		tokenize( r );
		if ( r->token_count > 0 )
		{
			return 1;
		}
	}
}

/* One token as a finite double: 0, or -1 not a number, -2 NaN/infinity, -3 overflow. */
static int parse_double( const char* text, double* value )
{
	char* end;
	errno = 0;
	double v = strtod( text, &end );
	if ( end == text || ( *end != '\0' && !blank( *end ) ) )
	{
		return -1;
	}
	if ( isnan( v ) || ( isinf( v ) && errno != ERANGE ) )
	{
		return -2;
	}
	if ( errno == ERANGE && isinf( v ) )
	{
		return -3;
	}
	*value = v; /* an underflow to (nearly) zero is still the number written */
	return 0;
}

/* One token as a whole number in [lo, hi]: 0, or -1 not a whole number, -2 out of range. */
static int parse_count( const char* text, long lo, long hi, long* value )
{
	char* end;
	errno = 0;
	long v = strtol( text, &end, 10 );
	if ( end == text || ( *end != '\0' && !blank( *end ) ) )
	{
		return -1;
	}
	if ( errno == ERANGE || v < lo || v > hi )
	{
		return -2;
	}
	*value = v;
	return 0;
}

static int is_keyword( const char* text )
{
	const char* words[] = { "name", "base", "outline", "vein" };
	for ( size_t k = 0; k < sizeof( words ) / sizeof( words[0] ); ++k )
	{
		size_t length = strlen( words[k] );
		if ( strncmp( text, words[k], length ) == 0 && ( text[length] == '\0' || blank( text[length] ) ) )
		{
			return 1;
		}
	}
	return 0;
}

/* Two numbers "x y" in words [first, first + 2) of the current line, which has no others: point
 * index of count in the block `what` whose header is on header_line (the base passes count 0). */
static sere_status parse_xy( reader* r, int first, const char* what, int32_t index, int32_t count, int32_t header_line,
							 double* xy )
{
	if ( count > 0 && is_keyword( r->text ) )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT,
					 "%s point %d of %d expected, found '%.40s': the count on line %d is larger than the points "
					 "given",
					 what, (int) index + 1, (int) count, r->text, (int) header_line );
	}
	if ( r->token_count != first + 2 )
	{
		if ( count > 0 )
		{
			return fail( r, r->line, SERE_ERR_ARGUMENT, "%s point %d must be two numbers 'x y', found '%.60s'", what,
						 (int) index + 1, r->text );
		}
		return fail( r, r->line, SERE_ERR_ARGUMENT, "base must be 'base X Y', found '%.60s'", r->text );
	}
	for ( int k = 0; k < 2; ++k )
	{
		const char* t = r->token[first + k];
		int result = parse_double( t, xy + k );
		if ( result == -1 )
		{
			return fail( r, r->line, SERE_ERR_ARGUMENT, "non-numeric value '%.40s' in %s point %d", t, what,
						 (int) index + 1 );
		}
		if ( result == -2 )
		{
			return fail( r, r->line, SERE_ERR_NONFINITE, "NaN or infinite coordinate '%.40s' in %s point %d", t, what,
						 (int) index + 1 );
		}
		if ( result == -3 )
		{
			return fail( r, r->line, SERE_ERR_NONFINITE,
						 "coordinate '%.40s' in %s point %d is too large (NaN or infinite as a double)", t, what,
						 (int) index + 1 );
		}
	}
	return SERE_OK;
}

static sere_status read_points( reader* r, const char* what, int32_t count, int32_t header_line, double* xy,
								int32_t* lines )
{
	for ( int32_t i = 0; i < count; ++i )
	{
		sere_status status = SERE_OK;
		int got = next_line( r, &status );
		if ( got < 0 )
		{
			return status;
		}
		if ( got == 0 )
		{
			return fail( r, r->line, SERE_ERR_ARGUMENT,
						 "file ends after %d of %d %s points (the count is on line %d; is the file truncated?)",
						 (int) i, (int) count, what, (int) header_line );
		}
		status = parse_xy( r, 0, what, i, count, header_line, xy + 2 * i );
		if ( status != SERE_OK )
		{
			return status;
		}
		lines[i] = r->line;
	}
	return SERE_OK;
}

/* Grows *array to hold at least need elements, doubling. */
static int reserve( void** array, size_t element, int32_t* capacity, int64_t need )
{
	if ( need <= *capacity )
	{
		return 0;
	}
	int32_t grown = sere_array_capacity( *capacity, need, 16 );
	void* bigger = grown > 0 ? sere_array_resize( *array, grown, element ) : NULL;
	if ( bigger == NULL )
	{
		return -1;
	}
	*array = bigger;
	*capacity = grown;
	return 0;
}

typedef struct blocks
{
	int32_t name_line, base_line, outline_line; /* where each keyword was, 0 if not yet */
	const char* last;							/* "outline" or "vein": the block read last */
	int32_t last_line, last_count;
	int32_t vein_capacity, point_capacity, line_capacity;
} blocks;

static sere_status read_name( reader* r, blocks* b, sere_leaf_file* leaf )
{
	if ( b->name_line > 0 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "a second 'name' (the first is on line %d)", (int) b->name_line );
	}
	if ( r->token_count < 2 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "name needs a value: 'name NAME'" );
	}
	if ( strlen( r->rest ) >= sizeof( leaf->name ) )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "name longer than %d characters", (int) sizeof( leaf->name ) - 1 );
	}
	long bad = sere_utf8_invalid_at( r->rest );
	if ( bad >= 0 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "name is not UTF-8 text (byte 0x%02X at character %ld)",
					 (unsigned) (unsigned char) r->rest[bad], bad + 1 );
	}
	snprintf( leaf->name, sizeof( leaf->name ), "%s", r->rest );
	b->name_line = r->line;
	return SERE_OK;
}

static sere_status read_outline( reader* r, blocks* b, sere_leaf_file* leaf )
{
	if ( b->outline_line > 0 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "a second 'outline' (the first is on line %d)",
					 (int) b->outline_line );
	}
	long count = 0;
	int result = r->token_count == 2 ? parse_count( r->token[1], 0, SERE_LEAF_MAX_POINTS, &count ) : -1;
	if ( result == -1 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "outline must be 'outline COUNT' with a whole number COUNT" );
	}
	if ( result == -2 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "outline count must be between 3 and %d",
					 (int) SERE_LEAF_MAX_POINTS );
	}
	if ( count < 3 )
	{
		return fail( r, r->line, SERE_ERR_GEOMETRY, "outline has fewer than 3 points (%ld)", count );
	}
	b->outline_line = r->line;
	leaf->outline_xy = malloc( sizeof( double ) * 2 * (size_t) count );
	leaf->outline_line = malloc( sizeof( int32_t ) * (size_t) count );
	if ( leaf->outline_xy == NULL || leaf->outline_line == NULL )
	{
		return fail( r, 0, SERE_ERR_MEMORY, "out of memory for %ld outline points", count );
	}
	leaf->shape.outline_count = (int32_t) count;
	b->last = "outline";
	b->last_line = r->line;
	b->last_count = (int32_t) count;
	return read_points( r, "outline", (int32_t) count, r->line, leaf->outline_xy, leaf->outline_line );
}

static sere_status read_vein( reader* r, blocks* b, sere_leaf_file* leaf )
{
	const int32_t v = leaf->shape.vein_count;
	long values[3] = { 0, 0, 0 };
	if ( r->token_count != 4 )
	{
		return fail( r, r->line, SERE_ERR_ARGUMENT, "vein must be 'vein ORDER PARENT COUNT' (three whole numbers)" );
	}
	const char* names[3] = { "ORDER", "PARENT", "COUNT" };
	const long lo[3] = { 1, -1, 2 }, hi[3] = { 1000000, v - 1, SERE_LEAF_MAX_POINTS };
	for ( int k = 0; k < 3; ++k )
	{
		const char* text = r->token[k + 1];
		int result = parse_count( text, lo[k], hi[k], values + k );
		if ( result == -1 )
		{
			return fail( r, r->line, SERE_ERR_ARGUMENT, "vein %s '%.40s' is not a whole number", names[k], text );
		}
		if ( result == -2 && k == 1 )
		{
			return v == 0 ? fail( r, r->line, SERE_ERR_ARGUMENT,
								  "vein 0: PARENT %.40s must be -1 (the first vein starts at the base)", text )
						  : fail( r, r->line, SERE_ERR_ARGUMENT,
								  "vein %d: PARENT %.40s must be -1 (starts at the base) or an earlier vein (0 to %d)",
								  (int) v, text, (int) v - 1 );
		}
		if ( result == -2 )
		{
			return fail( r, r->line, SERE_ERR_ARGUMENT, "vein %d: %s %.40s must be between %ld and %ld", (int) v,
						 names[k], text, lo[k], hi[k] );
		}
	}
	const int32_t count = (int32_t) values[2], first = leaf->shape.vein_point_count;
	if ( reserve( (void**) &leaf->veins, sizeof( sere_vein ), &b->vein_capacity, (int64_t) v + 1 ) != 0 ||
		 reserve( (void**) &leaf->vein_xy, 2 * sizeof( double ), &b->point_capacity, (int64_t) first + count ) != 0 ||
		 reserve( (void**) &leaf->vein_line, sizeof( int32_t ), &b->line_capacity, (int64_t) first + count ) != 0 )
	{
		return fail( r, 0, SERE_ERR_MEMORY, "out of memory for the veins" );
	}
	leaf->veins[v] =
		( sere_vein ){ .first = first, .count = count, .order = (int32_t) values[0], .parent = (int32_t) values[1] };
	b->last = "vein";
	b->last_line = r->line;
	b->last_count = count;
	sere_status status = read_points( r, "vein", count, r->line, leaf->vein_xy + 2 * first, leaf->vein_line + first );
	if ( status == SERE_OK )
	{
		leaf->shape.vein_count = v + 1;
		leaf->shape.vein_point_count = first + count;
	}
	return status;
}

static int32_t vein_of_point( const sere_leaf_shape* shape, int32_t point )
{
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		if ( point >= shape->veins[v].first && point < shape->veins[v].first + shape->veins[v].count )
		{
			return v;
		}
	}
	return -1;
}

/* One line for a shape the validator rejected, at the line of the offending point. */
static sere_status explain( reader* r, const blocks* b, const sere_leaf_file* leaf, const sere_shape_check* check,
							sere_status status )
{
	const sere_leaf_shape* shape = &leaf->shape;
	const char* text = sere_shape_problem_text( check->problem );
	const int32_t n = shape->outline_count;
	const int32_t* ol = leaf->outline_line;
	const int32_t* vl = leaf->vein_line;
	const int32_t p = check->point, q = check->other;
	switch ( check->problem )
	{
		case SERE_SHAPE_SELF_INTERSECTING:
		{
			/* Edges are named by their end points; an edge runs from the point before. */
			int32_t a0 = ol[( p + n - 1 ) % n], a1 = ol[p], b0 = ol[( q + n - 1 ) % n], b1 = ol[q];
			return fail( r, a0 > a1 ? a0 : a1, status,
						 "%s: the edge from line %d to line %d meets the edge from line %d to line %d", text, (int) a0,
						 (int) a1, (int) b0, (int) b1 );
		}
		case SERE_SHAPE_CLOCKWISE:
		case SERE_SHAPE_FEW_OUTLINE_POINTS:
			return fail( r, b->outline_line, status, "%s", text );
		case SERE_SHAPE_BASE_OFF_OUTLINE:
			return fail( r, b->base_line, status,
						 "%s (it must be one of its points, or on an edge within %g of the leaf's size)", text,
						 SERE_SHAPE_TOLERANCE );
		case SERE_SHAPE_REPEATED_POINT:
			if ( check->vein < 0 )
			{
				return fail( r, ol[p], status, "outline %s", text );
			}
			return fail( r, vl[p], status, "vein %d: %s", (int) check->vein, text );
		case SERE_SHAPE_VEIN_DISCONNECTED:
		{
			int32_t parent = shape->veins[check->vein].parent;
			if ( parent < 0 )
			{
				return fail( r, vl[p], status,
							 "vein %d not connected to the base: a vein without parent (-1) must start at the base "
							 "point",
							 (int) check->vein );
			}
			return fail( r, vl[p], status,
						 "vein %d not connected to the base: its first point must lie on its parent, vein %d "
						 "(within %g of the leaf's size)",
						 (int) check->vein, (int) parent, SERE_SHAPE_TOLERANCE );
		}
		case SERE_SHAPE_VEIN_OUTSIDE:
			return fail( r, vl[p], status, "%s (vein %d, point %d)", text, (int) check->vein,
						 (int) ( p - shape->veins[check->vein].first + 1 ) );
		case SERE_SHAPE_VEIN_CROSSES_OUTLINE:
			return fail( r, vl[p], status,
						 "vein %d crosses the outline: its segment from line %d to line %d meets the outline edge from "
						 "line %d to line %d",
						 (int) check->vein, (int) vl[p - 1], (int) vl[p], (int) ol[( q + n - 1 ) % n], (int) ol[q] );
		case SERE_SHAPE_VEINS_CROSS:
			return fail( r, vl[p], status,
						 "%s: vein %d, segment from line %d to line %d, meets vein %d, segment from line %d to "
						 "line %d",
						 text, (int) check->vein, (int) vl[p - 1], (int) vl[p], (int) vein_of_point( shape, q ),
						 (int) vl[q - 1], (int) vl[q] );
		default:
			return fail( r, check->vein >= 0 && p >= 0 ? vl[p] : 0, status, "%s", text );
	}
}

sere_status sere_leaf_file_read( const char* path, sere_leaf_file* leaf, char* err, size_t err_size )
{
	memset( leaf, 0, sizeof( *leaf ) );
	reader r = { .f = NULL, .path = path, .line = 0, .err = err, .err_size = err_size };
	if ( path == NULL || err == NULL || err_size == 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	r.f = fopen( path, "r" );
	if ( r.f == NULL )
	{
		return fail( &r, 0, SERE_ERR_ARGUMENT, "cannot open: %s", strerror( errno ) );
	}
	blocks b = { 0 };
	double base[2] = { 0.0, 0.0 };
	sere_status status = SERE_OK;
	for ( ;; )
	{
		int got = next_line( &r, &status );
		if ( got <= 0 )
		{
			break;
		}
		const char* keyword = r.token[0];
		if ( strcmp( keyword, "name" ) == 0 )
		{
			status = read_name( &r, &b, leaf );
		}
		else if ( strcmp( keyword, "base" ) == 0 )
		{
			status = b.base_line > 0 ? fail( &r, r.line, SERE_ERR_ARGUMENT, "a second 'base' (the first is on line %d)",
											 (int) b.base_line )
									 : parse_xy( &r, 1, "base", 0, 0, r.line, base );
			b.base_line = r.line;
		}
		else if ( strcmp( keyword, "outline" ) == 0 )
		{
			status = read_outline( &r, &b, leaf );
		}
		else if ( strcmp( keyword, "vein" ) == 0 )
		{
			status = read_vein( &r, &b, leaf );
		}
		else
		{
			double ignored;
			if ( parse_double( keyword, &ignored ) != -1 && b.last != NULL )
			{
				status = fail( &r, r.line, SERE_ERR_ARGUMENT,
							   "a point where a keyword was expected: the %s on line %d has more points than its "
							   "count (%d)",
							   b.last, (int) b.last_line, (int) b.last_count );
			}
			else
			{
				status = fail( &r, r.line, SERE_ERR_ARGUMENT,
							   "unknown keyword '%.40s' (expected name, base, outline or vein)", keyword );
			}
		}
		if ( status != SERE_OK )
		{
			break;
		}
	}
	if ( status == SERE_OK && b.outline_line == 0 )
	{
		status = r.line > 0 ? fail( &r, r.line, SERE_ERR_ARGUMENT, "file ends without an 'outline COUNT' block" )
							: fail( &r, 0, SERE_ERR_ARGUMENT, "file is empty" );
	}
	if ( status == SERE_OK && b.base_line == 0 )
	{
		status = fail( &r, r.line, SERE_ERR_ARGUMENT, "file ends without a 'base X Y' line" );
	}
	if ( status == SERE_OK )
	{
		leaf->shape.base_x = base[0];
		leaf->shape.base_y = base[1];
		leaf->shape.outline_xy = leaf->outline_xy;
		leaf->shape.veins = leaf->veins;
		leaf->shape.vein_xy = leaf->vein_xy;
		sere_shape_check check;
		status = sere_shape_validate( &leaf->shape, &check );
		if ( status == SERE_ERR_MEMORY )
		{
			fail( &r, 0, status, "out of memory while checking the shape" );
		}
		else if ( status != SERE_OK )
		{
			status = explain( &r, &b, leaf, &check, status );
		}
	}
	fclose( r.f );
	if ( status != SERE_OK )
	{
		sere_leaf_file_destroy( leaf );
		return status;
	}
	if ( b.name_line == 0 )
	{
		/* The file name without directory and extension. */
		const char* slash = strrchr( path, '/' );
		const char* start = slash != NULL ? slash + 1 : path;
		const char* dot = strrchr( start, '.' );
		int length = dot != NULL && dot != start ? (int) ( dot - start ) : (int) strlen( start );
		snprintf( leaf->name, sizeof( leaf->name ), "%.*s", length, start );
		/* a file name need not be UTF-8; the name goes into picture titles, which must be */
		for ( long bad; ( bad = sere_utf8_invalid_at( leaf->name ) ) >= 0; )
		{
			leaf->name[bad] = '?';
		}
	}
	return SERE_OK;
}

/* The fewest significant digits that read back to exactly v. */
static void shortest( double v, char* text, size_t size )
{
	for ( int digits = 1; digits <= 17; ++digits )
	{
		snprintf( text, size, "%.*g", digits, v );
		if ( strtod( text, NULL ) == v )
		{
			return;
		}
	}
}

static void write_xy( FILE* f, const double* xy )
{
	char x[32], y[32];
	shortest( xy[0], x, sizeof( x ) );
	shortest( xy[1], y, sizeof( y ) );
	fprintf( f, "%s %s\n", x, y );
}

sere_status sere_leaf_file_write( const char* path, const sere_leaf_shape* shape, const char* name, char* err,
								  size_t err_size )
{
	if ( path == NULL || shape == NULL || err == NULL || err_size == 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_shape_check check;
	sere_status status = sere_shape_validate( shape, &check );
	if ( status != SERE_OK )
	{
		snprintf( err, err_size, "%s: not written, the shape is not usable: %s", path,
				  status == SERE_ERR_MEMORY ? "out of memory" : sere_shape_problem_text( check.problem ) );
		return status;
	}
	size_t length = name != NULL ? strlen( name ) : 0;
	int usable = length < sizeof( ( (sere_leaf_file*) NULL )->name ) &&
				 ( length == 0 || ( !blank( name[0] ) && !blank( name[length - 1] ) ) );
	for ( size_t k = 0; k < length && usable; ++k )
	{
		usable = name[k] != '#' && (unsigned char) name[k] >= 0x20 && name[k] != 0x7F;
	}
	if ( !usable )
	{
		snprintf( err, err_size,
				  "%s: not written, the name must be at most 127 characters without '#', control characters or "
				  "leading and trailing blanks",
				  path );
		return SERE_ERR_ARGUMENT;
	}
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		snprintf( err, err_size, "%s: cannot write: %s", path, strerror( errno ) );
		return SERE_ERR_ARGUMENT;
	}
	fprintf( f, "# sere leaf (data/leaves/FORMAT.md): outline counter-clockwise, veins from the base\n" );
	if ( length > 0 )
	{
		fprintf( f, "name %s\n", name );
	}
	double base[2] = { shape->base_x, shape->base_y };
	fprintf( f, "base " );
	write_xy( f, base );
	fprintf( f, "outline %d\n", (int) shape->outline_count );
	for ( int32_t i = 0; i < shape->outline_count; ++i )
	{
		write_xy( f, shape->outline_xy + 2 * i );
	}
	for ( int32_t v = 0; v < shape->vein_count; ++v )
	{
		const sere_vein* vein = shape->veins + v;
		fprintf( f, "vein %d %d %d\n", (int) vein->order, (int) vein->parent, (int) vein->count );
		for ( int32_t k = 0; k < vein->count; ++k )
		{
			write_xy( f, shape->vein_xy + 2 * ( vein->first + k ) );
		}
	}
	if ( sere_atomic_commit( &file ) != 0 )
	{
		snprintf( err, err_size, "%s: cannot write: %s", path, strerror( errno ) );
		return SERE_ERR_ARGUMENT;
	}
	return SERE_OK;
}
