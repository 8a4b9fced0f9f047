/* The machine facts every result carries (harness/common/machine.h): the JSON member is valid JSON
 * (checked by a strict RFC 8259 parser below, not by looking for braces), has every field, and
 * says what the library and the caller say: the SIMD path of sere_simd_path(), the version of
 * sere_version(), the thread count passed, the cores sere_topo_bind bound the threads to.
 * `sere table1 --json` carries the same object. SERE_BIN names the binary under test. */
#define _DEFAULT_SOURCE
#include "common/io.h"
#include "common/machine.h"
#include "common/topo.h"
#include "core/base.h"
#include "fixture.h"

#include <criterion/criterion.h>
#include <hwloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

/* ---- a strict JSON checker (RFC 8259): one value, nothing after it but white space ---- */

typedef struct json_cursor
{
	const char* at;
	const char* error; /* the first thing wrong, NULL while all is well */
	int depth;
} json_cursor;

static int json_fail( json_cursor* c, const char* what )
{
	if ( c->error == NULL )
	{
		c->error = what;
	}
	return 0;
}

static void json_space( json_cursor* c )
{
	while ( *c->at == ' ' || *c->at == '\t' || *c->at == '\n' || *c->at == '\r' )
	{
		++c->at;
	}
}

static int json_digit( char ch )
{
	return ch >= '0' && ch <= '9';
}

static int json_hex( char ch )
{
	return json_digit( ch ) || ( ch >= 'a' && ch <= 'f' ) || ( ch >= 'A' && ch <= 'F' );
}

static int json_value( json_cursor* c );

static int json_string( json_cursor* c )
{
	if ( *c->at != '"' )
	{
		return json_fail( c, "a string must start with '\"'" );
	}
	++c->at;
	for ( ;; )
	{
		unsigned char ch = (unsigned char) *c->at;
		if ( ch == '\0' )
		{
			return json_fail( c, "unterminated string" );
		}
		if ( ch < 0x20 )
		{
			return json_fail( c, "raw control character in a string" );
		}
		++c->at;
		if ( ch == '"' )
		{
			return 1;
		}
		if ( ch == '\\' )
		{
			char e = *c->at++;
			if ( e == 'u' )
			{
				for ( int k = 0; k < 4; ++k )
				{
					if ( !json_hex( *c->at++ ) )
					{
						return json_fail( c, "\\u needs four hex digits" );
					}
				}
			}
			else if ( strchr( "\"\\/bfnrt", e ) == NULL || e == '\0' )
			{
				return json_fail( c, "unknown escape in a string" );
			}
		}
	}
}

static int json_number( json_cursor* c )
{
	if ( *c->at == '-' )
	{
		++c->at;
	}
	if ( *c->at == '0' )
	{
		++c->at;
	}
	else if ( json_digit( *c->at ) )
	{
		while ( json_digit( *c->at ) )
		{
			++c->at;
		}
	}
	else
	{
		return json_fail( c, "a number needs digits" );
	}
	if ( *c->at == '.' )
	{
		++c->at;
		if ( !json_digit( *c->at ) )
		{
			return json_fail( c, "digits must follow a decimal point" );
		}
		while ( json_digit( *c->at ) )
		{
			++c->at;
		}
	}
	if ( *c->at == 'e' || *c->at == 'E' )
	{
		++c->at;
		if ( *c->at == '+' || *c->at == '-' )
		{
			++c->at;
		}
		if ( !json_digit( *c->at ) )
		{
			return json_fail( c, "digits must follow an exponent" );
		}
		while ( json_digit( *c->at ) )
		{
			++c->at;
		}
	}
	return 1;
}

static int json_literal( json_cursor* c, const char* word )
{
	size_t n = strlen( word );
	if ( strncmp( c->at, word, n ) != 0 )
	{
		return json_fail( c, "unexpected character" );
	}
	c->at += n;
	return 1;
}

/* open '{' or '[', close '}' or ']'; members are "key": value in objects. */
static int json_container( json_cursor* c, char close )
{
	if ( ++c->depth > 64 )
	{
		return json_fail( c, "nested too deep" );
	}
	++c->at;
	json_space( c );
	if ( *c->at == close )
	{
		++c->at;
		--c->depth;
		return 1;
	}
	for ( ;; )
	{
		json_space( c );
		if ( close == '}' )
		{
			if ( !json_string( c ) )
			{
				return json_fail( c, "an object member needs a string key" );
			}
			json_space( c );
			if ( *c->at != ':' )
			{
				return json_fail( c, "':' must follow an object key" );
			}
			++c->at;
		}
		if ( !json_value( c ) )
		{
			return 0;
		}
		json_space( c );
		if ( *c->at == ',' )
		{
			++c->at;
			continue;
		}
		if ( *c->at == close )
		{
			++c->at;
			--c->depth;
			return 1;
		}
		return json_fail( c, close == '}' ? "',' or '}' expected in an object" : "',' or ']' expected in an array" );
	}
}

static int json_value( json_cursor* c )
{
	json_space( c );
	switch ( *c->at )
	{
		case '{':
			return json_container( c, '}' );
		case '[':
			return json_container( c, ']' );
		case '"':
			return json_string( c );
		case 't':
			return json_literal( c, "true" );
		case 'f':
			return json_literal( c, "false" );
		case 'n':
			return json_literal( c, "null" );
		default:
			return json_number( c );
	}
}

/* NULL when text is one valid JSON value in UTF-8, else what is wrong (with where in *offset). */
static const char* json_check( const char* text, long* offset )
{
	json_cursor c = { text, NULL, 0 };
	*offset = sere_utf8_invalid_at( text );
	if ( *offset >= 0 )
	{
		return "not UTF-8";
	}
	if ( json_value( &c ) )
	{
		json_space( &c );
		if ( *c.at != '\0' )
		{
			json_fail( &c, "text after the value" );
		}
	}
	*offset = (long) ( c.at - text );
	return c.error;
}

static void expect_valid_json( const char* text )
{
	long offset = 0;
	const char* error = json_check( text, &offset );
	cr_expect_null( error, "invalid JSON (%s at byte %ld): %s", error ? error : "", offset, text );
}

/* The raw value of member key inside the "machine" object as our writer lays it out (one member a
 * line), copied into out without the line's ",". 0 when the member is missing. */
static int machine_member( const char* json, const char* key, char* out, size_t size )
{
	const char* machine = strstr( json, "\"machine\": {" );
	if ( machine == NULL )
	{
		return 0;
	}
	const char* end = strchr( machine, '}' );
	char pattern[64];
	snprintf( pattern, sizeof( pattern ), "\"%s\": ", key );
	const char* at = strstr( machine, pattern );
	if ( at == NULL || end == NULL || at > end )
	{
		return 0;
	}
	at += strlen( pattern );
	size_t length = strcspn( at, "\n" );
	if ( length > 0 && at[length - 1] == ',' )
	{
		--length;
	}
	if ( length >= size )
	{
		length = size - 1;
	}
	memcpy( out, at, length );
	out[length] = '\0';
	return 1;
}

/* "{\n" + the machine member written by write + "\n}\n", as one string the caller frees. */
static char* machine_document( const char* indent, int threads, const sere_machine* facts )
{
	char* text = NULL;
	size_t size = 0;
	FILE* f = open_memstream( &text, &size );
	cr_assert_not_null( f );
	fprintf( f, "{\n" );
	if ( facts != NULL )
	{
		sere_machine_write_json( f, indent, facts );
	}
	else
	{
		sere_machine_json( f, indent, threads );
	}
	fprintf( f, "\n}\n" );
	cr_assert_eq( fclose( f ), 0 );
	return text;
}

static const char* const fields[] = { "cpu", "simd", "threads", "binding", "cores", "version", "commit", "compiler" };

static void expect_every_field( const char* json )
{
	char value[1024];
	for ( size_t k = 0; k < sizeof( fields ) / sizeof( fields[0] ); ++k )
	{
		cr_expect( machine_member( json, fields[k], value, sizeof( value ) ), "no \"%s\" in: %s", fields[k], json );
	}
}

Test( machine, json_is_valid_with_every_field )
{
	char* json = machine_document( "  ", 2, NULL );
	expect_valid_json( json );
	expect_every_field( json );
	char value[1024], expected[256];
	cr_assert( machine_member( json, "simd", value, sizeof( value ) ) );
	snprintf( expected, sizeof( expected ), "\"%s\"", sere_simd_path() );
	cr_expect_str_eq( value, expected );
	cr_assert( machine_member( json, "version", value, sizeof( value ) ) );
	snprintf( expected, sizeof( expected ), "\"%s\"", sere_version() );
	cr_expect_str_eq( value, expected );
	cr_assert( machine_member( json, "cores", value, sizeof( value ) ) );
	cr_expect_eq( atoi( value ), sere_topo_cores() );
	/* the CPU model and the commit are never empty: "unknown" at worst */
	cr_assert( machine_member( json, "cpu", value, sizeof( value ) ) );
	cr_expect( strlen( value ) > 2, "empty cpu: %s", json );
	cr_assert( machine_member( json, "commit", value, sizeof( value ) ) );
	cr_expect( strlen( value ) > 2, "empty commit: %s", json );
	cr_assert( machine_member( json, "compiler", value, sizeof( value ) ) );
	cr_expect( strlen( value ) > 2, "empty compiler: %s", json );
	free( json );
}

Test( machine, threads_are_the_ones_passed )
{
	const int counts[] = { 1, 2, 3, 7 };
	for ( size_t k = 0; k < sizeof( counts ) / sizeof( counts[0] ); ++k )
	{
		char* json = machine_document( "    ", counts[k], NULL );
		expect_valid_json( json );
		char value[1024];
		cr_assert( machine_member( json, "threads", value, sizeof( value ) ) );
		cr_expect_eq( atoi( value ), counts[k], "%s", json );
		/* the binding lists one entry per thread, or says "unbound" */
		cr_assert( machine_member( json, "binding", value, sizeof( value ) ) );
		if ( strcmp( value, "\"unbound\"" ) != 0 )
		{
			int entries = value[0] == '[' && value[1] != ']';
			for ( const char* p = value; *p; ++p )
			{
				entries += *p == ',';
			}
			cr_expect_eq( entries, counts[k], "binding %s for %d threads", value, counts[k] );
		}
		free( json );
	}
	/* the indent is used as given, and NULL means none */
	char* json = machine_document( NULL, 1, NULL );
	expect_valid_json( json );
	cr_expect_not_null( strstr( json, "{\n\"machine\": {\n  \"cpu\": " ), "%s", json );
	free( json );
}

/* After sere_topo_bind the binding is the cores it bound thread i to (i mod cores; hwloc logical
 * index), as long as the system let it bind. */
Test( machine, binding_is_what_topo_bound )
{
	int threads = 2;
	char* log = NULL;
	size_t log_size = 0;
	FILE* f = open_memstream( &log, &log_size );
	cr_assert_not_null( f );
	int bound = sere_topo_bind( threads, f );
	fclose( f );
	cr_assert_eq( bound, threads );
	int cores = sere_topo_cores();
	sere_machine machine;
	sere_machine_read( &machine, bound );
	if ( strstr( log, "refused" ) == NULL && strstr( log, "could not" ) == NULL )
	{
		cr_expect( machine.bound, "threads bound (%s) but the facts say unbound", log );
		for ( int i = 0; i < threads; ++i )
		{
			cr_expect_eq( machine.core_of[i], i % cores, "thread %d: core %d, topo: %s", i, machine.core_of[i], log );
		}
		char* json = machine_document( "  ", bound, &machine );
		char value[1024], expected[64];
		cr_assert( machine_member( json, "binding", value, sizeof( value ) ) );
		snprintf( expected, sizeof( expected ), "[0, %d]", 1 % cores );
		cr_expect_str_eq( value, expected );
		free( json );
		char text[256];
		snprintf( expected, sizeof( expected ), "0,%d", 1 % cores );
		cr_expect_str_eq( sere_machine_binding_text( &machine, text, sizeof( text ) ), expected );
	}
	else
	{
		cr_log_warn( "binding refused here; only the form is checked: %s", log );
	}
	free( log );
}

/* Before any binding, a process that may run on the whole machine has unbound threads. */
Test( machine, unbound_before_binding )
{
	hwloc_topology_t topology;
	cr_assert_eq( hwloc_topology_init( &topology ), 0 );
	cr_assert_eq( hwloc_topology_load( topology ), 0 );
	hwloc_cpuset_t set = hwloc_bitmap_alloc();
	int whole = hwloc_get_cpubind( topology, set, HWLOC_CPUBIND_PROCESS ) == 0 &&
				hwloc_bitmap_isequal( set, hwloc_topology_get_topology_cpuset( topology ) ) &&
				hwloc_get_nbobjs_by_type( topology, HWLOC_OBJ_CORE ) > 1;
	hwloc_bitmap_free( set );
	hwloc_topology_destroy( topology );
	/* the OpenMP runtime binds its threads itself when told to */
	const char* runtime_binding[] = { "OMP_PROC_BIND", "OMP_PLACES", "GOMP_CPU_AFFINITY" };
	for ( size_t k = 0; k < sizeof( runtime_binding ) / sizeof( runtime_binding[0] ); ++k )
	{
		const char* value = getenv( runtime_binding[k] );
		whole = whole && ( value == NULL || value[0] == '\0' || strcmp( value, "false" ) == 0 );
	}
	if ( !whole )
	{
		cr_log_warn( "this process or its OpenMP runtime binds threads already (or it has one core); skipped" );
		return;
	}
	sere_machine machine;
	sere_machine_read( &machine, 2 );
	cr_expect_not( machine.bound );
	char text[64];
	cr_expect_str_eq( sere_machine_binding_text( &machine, text, sizeof( text ) ), "unbound" );
	char* json = machine_document( "  ", 2, &machine );
	expect_valid_json( json );
	char value[1024];
	cr_assert( machine_member( json, "binding", value, sizeof( value ) ) );
	cr_expect_str_eq( value, "\"unbound\"" );
	free( json );
}

/* Names from the machine are text we do not control: quotes, backslashes, control characters
 * and bytes that are not UTF-8 come out as valid JSON; a thread not bound to one core is null. */
Test( machine, strings_are_escaped_and_partial_binding_is_null )
{
	sere_machine machine;
	sere_machine_read( &machine, 2 );
	snprintf( machine.cpu, sizeof( machine.cpu ), "Odd \"CPU\" \\ model\t\x01 \xc3\xa9 \xff end" );
	machine.commit = "abc\"def\n";
	machine.compiler = "cc \\ 1.0";
	machine.bound = 1;
	machine.core_of[0] = 1;
	machine.core_of[1] = -1;
	char* json = machine_document( "\t", 2, &machine );
	expect_valid_json( json );
	cr_expect_not_null( strstr( json, "\"binding\": [1, null]" ), "%s", json );
	cr_expect_not_null( strstr( json, "Odd \\\"CPU\\\" \\\\ model\\t\\u0001 \xc3\xa9 \\ufffd end" ), "%s", json );
	cr_expect_not_null( strstr( json, "\"commit\": \"abc\\\"def\\n\"" ), "%s", json );
	char text[64];
	cr_expect_str_eq( sere_machine_binding_text( &machine, text, sizeof( text ) ), "1,-" );
	free( json );
	/* the checker itself rejects what it must */
	long offset;
	cr_expect_not_null( json_check( "{\"a\": 1,}", &offset ) );
	cr_expect_not_null( json_check( "{\"a\": \"x\ty\"}", &offset ) );
	cr_expect_not_null( json_check( "{\"a\": 01}", &offset ) );
	cr_expect_not_null( json_check( "{\"a\": [1 2]}", &offset ) );
	cr_expect_not_null( json_check( "{\"a\": 1} x", &offset ) );
	cr_expect_not_null( json_check( "{\"a\": \"\\q\"}", &offset ) );
	cr_expect_null( json_check( "{\"a\": [1, -2.5e3, true, null, {\"b\": \"\\u00e9\"}]}", &offset ) );
}

/* Reads all of a command's stdout; its exit status into *code. The caller frees. */
static char* command_output( const char* args, int* code )
{
	char command[1024];
	snprintf( command, sizeof( command ), "%s %s", sere_test_bin(), args );
	FILE* pipe = popen( command, "r" );
	cr_assert_not_null( pipe );
	size_t size = 0, used = 0;
	char* out = NULL;
	for ( ;; )
	{
		if ( used + 4096 + 1 > size )
		{
			size = 2 * size + 4096 + 1;
			out = realloc( out, size );
			cr_assert_not_null( out );
		}
		size_t got = fread( out + used, 1, 4096, pipe );
		used += got;
		if ( got == 0 )
		{
			break;
		}
	}
	out[used] = '\0';
	int status = pclose( pipe );
	*code = WIFEXITED( status ) ? WEXITSTATUS( status ) : 128;
	return out;
}

/* One frame per leaf keeps it short (about a second). */
Test( machine, table1_json_carries_the_machine, .timeout = 300 )
{
	int code;
	char* out = command_output( "table1 --json --frames 1 --threads 1", &code );
	cr_assert_eq( code, 0, "%s", out );
	expect_valid_json( out );
	expect_every_field( out );
	char value[1024], expected[256];
	cr_assert( machine_member( out, "simd", value, sizeof( value ) ) );
	snprintf( expected, sizeof( expected ), "\"%s\"", sere_simd_path() );
	cr_expect_str_eq( value, expected, "the binary and the tests are built with one ARCH" );
	cr_assert( machine_member( out, "threads", value, sizeof( value ) ) );
	cr_expect_str_eq( value, "1" );
	cr_assert( machine_member( out, "binding", value, sizeof( value ) ) );
	cr_expect( strcmp( value, "[0]" ) == 0 || strcmp( value, "\"unbound\"" ) == 0, "binding %s", value );
	cr_expect_not_null( strstr( out, "\"leaves\": [{\"leaf\": \"maple\"" ), "%s", out );
	cr_expect_not_null( strstr( out, "{\"leaf\": \"wisteria\"" ), "%s", out );
	free( out );

	/* the table a person reads names the machine too */
	out = command_output( "table1 --frames 1 --threads 1", &code );
	cr_assert_eq( code, 0, "%s", out );
	snprintf( expected, sizeof( expected ), ", %s, threads ", sere_simd_path() );
	cr_expect_not_null( strstr( out, expected ), "%s", out );
	snprintf( expected, sizeof( expected ), "sere %s (commit ", sere_version() );
	cr_expect_not_null( strstr( out, expected ), "%s", out );
	free( out );

	/* one leaf alone (for a profiler), with its sweeps and CG iterations a frame */
	out = command_output( "table1 --json --frames 2 --threads 1 --leaf wisteria", &code );
	cr_assert_eq( code, 0, "%s", out );
	expect_valid_json( out );
	cr_expect_not_null( strstr( out, "\"leaves\": [{\"leaf\": \"wisteria\"" ), "%s", out );
	cr_expect_null( strstr( out, "maple" ), "%s", out );
	const char* sweeps = strstr( out, "\"pbd_sweeps_per_frame\": " );
	cr_assert_not_null( sweeps, "%s", out );
	cr_expect_geq( atof( sweeps + strlen( "\"pbd_sweeps_per_frame\": " ) ), 1.0, "%s", out );
	cr_expect_not_null( strstr( out, "\"cg_iterations_t_per_frame\": " ), "%s", out );
	cr_expect_not_null( strstr( out, "\"cg_iterations_v_per_frame\": " ), "%s", out );
	free( out );
}

/* --rounds: each leaf dried R times, each cell the median over the rounds. With three rounds the
 * median total is one of the three as printed, to the digit. */
Test( machine, table1_rounds_report_the_median_round, .timeout = 300 )
{
	int code;
	char* out = command_output( "table1 --json --frames 1 --threads 1 --rounds 3 --leaf wisteria", &code );
	cr_assert_eq( code, 0, "%s", out );
	expect_valid_json( out );
	cr_expect_not_null( strstr( out, "\"rounds\": 3" ), "%s", out );
	const char* total = strstr( out, "\"total_ms\": " );
	const char* rounds = strstr( out, "\"round_total_ms\": [" );
	cr_assert( total != NULL && rounds != NULL, "%s", out );
	double median = atof( total + strlen( "\"total_ms\": " ) );
	double round[3];
	cr_assert_eq( sscanf( rounds + strlen( "\"round_total_ms\": [" ), "%lf, %lf, %lf]", round, round + 1, round + 2 ),
				  3, "%s", out );
	int below = 0, above = 0, equal = 0;
	for ( int k = 0; k < 3; ++k )
	{
		below += round[k]<median, above += round[k]> median, equal += round[k] == median;
	}
	cr_expect( equal >= 1 && below <= 1 && above <= 1, "total %.4f is not the median of %.4f %.4f %.4f", median,
			   round[0], round[1], round[2] );
	free( out );

	/* the table a person reads says so, and gives the ratio's range over the rounds */
	out = command_output( "table1 --frames 1 --threads 1 --rounds 2 --leaf wisteria", &code );
	cr_assert_eq( code, 0, "%s", out );
	cr_expect_not_null( strstr( out, "median of 2 rounds" ), "%s", out );
	cr_expect_not_null( strstr( out, "| ratio range" ), "%s", out );
	char* row = strstr( out, "\nwisteria" );
	cr_assert_not_null( row, "%s", out );
	row[strcspn( row + 1, "\n" ) + 1] = '\0';
	double low, high;
	const char* range = strrchr( row, '|' );
	cr_assert( range != NULL && sscanf( range, "| %lf-%lfx", &low, &high ) == 2, "%s", out );
	cr_expect( low <= high && low > 0.0, "%s", out );
	free( out );
}
