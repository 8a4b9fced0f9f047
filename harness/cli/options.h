/* sere harness — one command-line parser for every command: each command lists its options in
 * a table (name, kind, where the value goes, range) and sere_options_parse does the rest, with
 * the same messages everywhere. */
#pragma once

#include "core/base.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

typedef enum sere_option_kind
{
	SERE_OPTION_FLAG,  /* int*: set to 1 when present */
	SERE_OPTION_COUNT, /* long long*: a whole number in [lo, hi] */
	SERE_OPTION_REAL,  /* double*: a finite number in [lo, hi] */
	SERE_OPTION_TEXT,  /* const char**: the next argument, as given */
	SERE_OPTION_DIR,   /* const char**: an output directory (not an empty string) */
	SERE_OPTION_LIST,  /* sere_option_list*: the value of every occurrence, in order */
	SERE_OPTION_CHOICE /* int*: the index of the value in the NULL-terminated `choices` */
} sere_option_kind;

#define SERE_OPTION_LIST_MAX 64

typedef struct sere_option_list
{
	const char* items[SERE_OPTION_LIST_MAX];
	int count;
} sere_option_list;

typedef struct sere_option
{
	const char* name; /* "--frames" */
	sere_option_kind kind;
	void* value;
	double lo, hi;				/* COUNT and REAL */
	const char* const* choices; /* CHOICE */
} sere_option;

/* What a parse found besides the options. */
typedef struct sere_options_result
{
	int help;				   /* --help or -h was given: print the usage and exit 0 */
	const char* positional[8]; /* the arguments that are not options, in order */
	int positional_count;
} sere_options_result;

/* Parses argv[1 ..] of `sere COMMAND` against the table. At most positional_max arguments may
 * stand alone (named `positional_name` in messages, e.g. "LEAF"). SERE_OK, or
 * SERE_ERR_ARGUMENT after one line "sere COMMAND: ..." on stderr (the command then exits 2).
 * Stops at --help, leaving the other arguments unread. */
sere_status sere_options_parse( const char* command, int argc, char** argv, const sere_option* options,
								int option_count, int positional_max, const char* positional_name,
								sere_options_result* result );

/* The rows several commands share, so each option has one range everywhere. */
sere_option sere_option_threads( long long* threads );	   /* --threads T, 0 (one per core) to SERE_MAX_THREADS */
sere_option sere_option_out( const char** dir );		   /* --out DIR */
sere_option sere_option_preset( const char** name );	   /* --preset NAME or a path */
sere_option sere_option_sets( sere_option_list* sets );	   /* --set key=value, repeated */
sere_option sere_option_json( int* json );				   /* --json */
sere_option sere_option_points( long long* points );	   /* --points N, 10 to 10^7 */
sere_option sere_option_particles( long long* particles ); /* --particles N, 4 to 10^8 */
sere_option sere_option_springs( long long* springs );	   /* --springs N, 1 to 4 10^8 */

/* Whether --particles and --springs were given together or not at all (both -1 when not given);
 * when not, prints "sere COMMAND: --particles and --springs go together" first. */
int sere_options_counts_paired( const char* command, long long particles, long long springs );

/* What sere_options_read returns when the command goes on; an exit code is 0 or more. */
#define SERE_OPTIONS_GO ( -1 )

/* The start of every command: sere_options_parse with at most one positional argument (named
 * positional_name, NULL for none; *positional is NULL when it is not given), then help() on
 * --help. SERE_OPTIONS_GO, or the command's exit code: 0 after the usage, 2 after the message
 * of a bad argument. */
int sere_options_read( const char* command, int argc, char** argv, const sere_option* options, int option_count,
					   const char* positional_name, const char** positional, void ( *help )( void ) );

#ifdef __cplusplus
}
#endif
