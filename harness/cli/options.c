#include "cli/options.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const sere_option* find_option( const sere_option* options, int count, const char* name )
{
	for ( int k = 0; k < count; ++k )
	{
		if ( strcmp( options[k].name, name ) == 0 )
		{
			return options + k;
		}
	}
	return NULL;
}

/* Stores one option's value; SERE_ERR_ARGUMENT after the message when it does not fit. */
static sere_status take_value( const char* command, const sere_option* o, const char* text )
{
	switch ( o->kind )
	{
		case SERE_OPTION_COUNT:
		{
			char* end;
			errno = 0;
			long long v = strtoll( text, &end, 10 );
			if ( *text == '\0' || *end != '\0' || errno != 0 || (double) v < o->lo || (double) v > o->hi )
			{
				fprintf( stderr, "sere %s: %s takes a whole number from %.0f to %.0f, not '%s'\n", command, o->name,
						 o->lo, o->hi, text );
				return SERE_ERR_ARGUMENT;
			}
			*(long long*) o->value = v;
			return SERE_OK;
		}
		case SERE_OPTION_REAL:
		{
			char* end;
			double v = strtod( text, &end );
			if ( *text == '\0' || *end != '\0' || !isfinite( v ) || v < o->lo || v > o->hi )
			{
				fprintf( stderr, "sere %s: %s takes a number from %g to %g, not '%s'\n", command, o->name, o->lo, o->hi,
						 text );
				return SERE_ERR_ARGUMENT;
			}
			*(double*) o->value = v;
			return SERE_OK;
		}
		case SERE_OPTION_DIR:
			if ( *text == '\0' )
			{
				fprintf( stderr, "sere %s: %s needs a directory name, not an empty string\n", command, o->name );
				return SERE_ERR_ARGUMENT;
			}
			*(const char**) o->value = text;
			return SERE_OK;
		case SERE_OPTION_LIST:
		{
			sere_option_list* list = o->value;
			if ( list->count == SERE_OPTION_LIST_MAX )
			{
				fprintf( stderr, "sere %s: at most %d %s options\n", command, SERE_OPTION_LIST_MAX, o->name );
				return SERE_ERR_ARGUMENT;
			}
			list->items[list->count++] = text;
			return SERE_OK;
		}
		case SERE_OPTION_CHOICE:
			for ( int k = 0; o->choices[k] != NULL; ++k )
			{
				if ( strcmp( o->choices[k], text ) == 0 )
				{
					*(int*) o->value = k;
					return SERE_OK;
				}
			}
			fprintf( stderr, "sere %s: %s takes one of", command, o->name );
			for ( int k = 0; o->choices[k] != NULL; ++k )
			{
				fprintf( stderr, "%s '%s'", k == 0 ? "" : ",", o->choices[k] );
			}
			fprintf( stderr, ", not '%s'\n", text );
			return SERE_ERR_ARGUMENT;
		case SERE_OPTION_TEXT:
		default:
			*(const char**) o->value = text;
			return SERE_OK;
	}
}

sere_status sere_options_parse( const char* command, int argc, char** argv, const sere_option* options,
								int option_count, int positional_max, const char* positional_name,
								sere_options_result* result )
{
	*result = ( sere_options_result ){ 0 };
	const int room = (int) ( sizeof( result->positional ) / sizeof( result->positional[0] ) );
	positional_max = positional_max < room ? positional_max : room;
	for ( int i = 1; i < argc; ++i )
	{
		const char* a = argv[i];
		if ( strcmp( a, "--help" ) == 0 || strcmp( a, "-h" ) == 0 )
		{
			result->help = 1;
			return SERE_OK;
		}
		if ( a[0] != '-' || a[1] == '\0' )
		{
			if ( result->positional_count == positional_max )
			{
				if ( positional_max == 0 )
				{
					fprintf( stderr, "sere %s: unexpected argument '%s' (see sere %s --help)\n", command, a, command );
				}
				else
				{
					fprintf( stderr, "sere %s: %s %s only, got '%s' and '%s'\n", command,
							 positional_max == 1 ? "one" : "these", positional_name,
							 result->positional[result->positional_count - 1], a );
				}
				return SERE_ERR_ARGUMENT;
			}
			result->positional[result->positional_count++] = a;
			continue;
		}
		const sere_option* o = find_option( options, option_count, a );
		if ( o == NULL )
		{
			fprintf( stderr, "sere %s: unknown option '%s' (see sere %s --help)\n", command, a, command );
			return SERE_ERR_ARGUMENT;
		}
		if ( o->kind == SERE_OPTION_FLAG )
		{
			*(int*) o->value = 1;
			continue;
		}
		if ( i + 1 >= argc )
		{
			fprintf( stderr, "sere %s: %s needs a value (see sere %s --help)\n", command, a, command );
			return SERE_ERR_ARGUMENT;
		}
		sere_status status = take_value( command, o, argv[++i] );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	return SERE_OK;
}

int sere_options_read( const char* command, int argc, char** argv, const sere_option* options, int option_count,
					   const char* positional_name, const char** positional, void ( *help )( void ) )
{
	sere_options_result result;
	if ( sere_options_parse( command, argc, argv, options, option_count, positional_name != NULL ? 1 : 0,
							 positional_name, &result ) != SERE_OK )
	{
		return 2;
	}
	if ( result.help )
	{
		help();
		return 0;
	}
	if ( positional != NULL )
	{
		*positional = result.positional_count > 0 ? result.positional[0] : NULL;
	}
	return SERE_OPTIONS_GO;
}

sere_option sere_option_threads( long long* threads )
{
	return ( sere_option ){ "--threads", SERE_OPTION_COUNT, threads, 0, SERE_MAX_THREADS, NULL };
}

sere_option sere_option_out( const char** dir )
{
	return ( sere_option ){ "--out", SERE_OPTION_DIR, dir, 0, 0, NULL };
}

sere_option sere_option_preset( const char** name )
{
	return ( sere_option ){ "--preset", SERE_OPTION_TEXT, name, 0, 0, NULL };
}

sere_option sere_option_sets( sere_option_list* sets )
{
	return ( sere_option ){ "--set", SERE_OPTION_LIST, sets, 0, 0, NULL };
}

sere_option sere_option_json( int* json )
{
	return ( sere_option ){ "--json", SERE_OPTION_FLAG, json, 0, 0, NULL };
}

sere_option sere_option_points( long long* points )
{
	return ( sere_option ){ "--points", SERE_OPTION_COUNT, points, 10, 10000000, NULL };
}

sere_option sere_option_particles( long long* particles )
{
	return ( sere_option ){ "--particles", SERE_OPTION_COUNT, particles, 4, 100000000, NULL };
}

sere_option sere_option_springs( long long* springs )
{
	return ( sere_option ){ "--springs", SERE_OPTION_COUNT, springs, 1, 400000000, NULL };
}

int sere_options_counts_paired( const char* command, long long particles, long long springs )
{
	if ( ( particles < 0 ) != ( springs < 0 ) )
	{
		fprintf( stderr, "sere %s: --particles and --springs go together\n", command );
		return 0;
	}
	return 1;
}
