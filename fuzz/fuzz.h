/* sere fuzz — what every target shares: the input as a file the readers can open by path, stderr
 * silenced, and a check that stops the run like a sanitizer would. Each target defines
 * _GNU_SOURCE (memfd_create) before including this. */
#pragma once

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

/* A broken promise of a reader (a documented contract, not a memory error) is a finding too:
 * abort() is reported by libFuzzer as a crash with the input saved. */
#define FUZZ_CHECK( condition )                                                                                        \
	do                                                                                                                 \
	{                                                                                                                  \
		if ( !( condition ) )                                                                                          \
		{                                                                                                              \
			fprintf( fuzz_report(), "fuzz check failed at %s:%d: %s\n", __FILE__, __LINE__, #condition );              \
			abort();                                                                                                   \
		}                                                                                                              \
	} while ( 0 )

/* The stderr libFuzzer and the checks print to (the readers' own stderr is /dev/null). */
static FILE* fuzz_stderr;

static inline FILE* fuzz_report( void )
{
	return fuzz_stderr != NULL ? fuzz_stderr : stderr;
}

/* The readers print one line per rejected input to stderr (the season and wilt readers do);
 * millions of them would fill the log and slow the run. Sanitizer reports and libFuzzer's own
 * output do not go through this FILE (they write to fd 2 or keep the FILE they saw at start), so
 * they stay. SERE_FUZZ_VERBOSE=1 keeps the readers' messages, for replaying one input. */
static inline void fuzz_quiet( void )
{
	fuzz_stderr = stderr;
	if ( getenv( "SERE_FUZZ_VERBOSE" ) == NULL )
	{
		FILE* null = fopen( "/dev/null", "w" );
		if ( null != NULL )
		{
			stderr = null;
		}
	}
}

/* The input as a regular file, /proc/self/fd/N of one memfd rewritten for every input: the
 * readers take a path and open it themselves, as they do for the command. */
static inline const char* fuzz_file( const uint8_t* data, size_t size )
{
	static int fd = -1;
	static char path[64];
	if ( fd < 0 )
	{
		fd = memfd_create( "sere-fuzz", 0 );
		if ( fd < 0 )
		{
			perror( "memfd_create" );
			abort();
		}
		snprintf( path, sizeof( path ), "/proc/self/fd/%d", fd );
	}
	if ( ftruncate( fd, 0 ) != 0 )
	{
		perror( "ftruncate" );
		abort();
	}
	size_t done = 0;
	while ( done < size )
	{
		ssize_t wrote = pwrite( fd, data + done, size - done, (off_t) done );
		if ( wrote <= 0 )
		{
			perror( "pwrite" );
			abort();
		}
		done += (size_t) wrote;
	}
	return path;
}

/* The input as a C string (cut at its first NUL), malloc'd. */
static inline char* fuzz_string( const uint8_t* data, size_t size )
{
	char* text = malloc( size + 1 );
	if ( text == NULL )
	{
		abort();
	}
	for ( size_t k = 0; k < size; ++k )
	{
		text[k] = (char) data[k];
	}
	text[size] = '\0';
	return text;
}

int LLVMFuzzerInitialize( int* argc, char*** argv );
int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size );
