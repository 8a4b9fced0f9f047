/* sere harness — files that are never half-written, mesh writers and a progress bar. */
#pragma once

#include "core/base.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>

/* A file written to "<path>.tmp" and renamed over path on commit, so an interrupted run never
 * leaves a truncated output behind. */
typedef struct sere_atomic_file
{
	FILE* f;
	char tmp_path[4096];
	char path[4096];
} sere_atomic_file;

/* Opens the temporary file; NULL (with errno set) on failure. */
FILE* sere_atomic_open( sere_atomic_file* file, const char* path );
/* Flushes, closes and renames; SERE_OK, or SERE_ERR_IO on any error (the temporary is removed and errno
 * holds the first error's reason, EIO when a write failed without one). */
sere_status sere_atomic_commit( sere_atomic_file* file );
/* Closes and removes the temporary without touching path. */
void sere_atomic_abort( sere_atomic_file* file );

/* mkdir -p; SERE_OK, else SERE_ERR_IO with errno set (ENOENT for an empty name, ENOTDIR when a
 * component exists but is not a directory). */
sere_status sere_dir_create( const char* dir );

/* Checks that none of dir/NAME for the count names exists as a directory, where a file is to be
 * written (rename would fail only at the end of a long run). SERE_OK, or SERE_ERR_IO with one line
 * "DIR/NAME is a directory, not a file" in err. */
sere_status sere_outputs_check( const char* dir, const char* const* names, int count, char* err, size_t err_size );

/* The contents of a JSON string (without the quotes) for text: '"', '\\' and control characters
 * escaped, bytes that are not UTF-8 written as \ufffd; cut at a whole character to fit size
 * (6 bytes per input byte, plus one, always suffice). Returns out. Every JSON writer of sere
 * passes user-given text (leaf, state and preset names, paths) through it. */
const char* sere_json_escape( char* out, size_t size, const char* text );

/* Formats one line into err (when err is not NULL and err_size > 0) and returns status: the error
 * return of every harness function that reports through (err, err_size). */
sere_status sere_fail( sere_status status, char* err, size_t err_size, const char* format, ... )
	__attribute__( ( format( printf, 4, 5 ) ) );

/* sere_fail for a reader: "path:line: message" (line > 0) or "path: message", the message cut at
 * 511 bytes. */
sere_status sere_fail_at( sere_status status, char* err, size_t err_size, const char* path, int line,
						  const char* format, va_list args ) __attribute__( ( format( printf, 6, 0 ) ) );

/* The offset of the first byte of text that does not start a valid UTF-8 character, or -1 when
 * all of it is UTF-8 (cairo draws only UTF-8; names go into titles). */
long sere_utf8_invalid_at( const char* text );

/* A named per-vertex float property for the mesh writers. */
typedef struct sere_vertex_property
{
	const char* name;
	const float* values;
} sere_vertex_property;

/* Binary little-endian PLY of a triangle mesh with optional per-vertex colors (rgb: 3 bytes per
 * vertex, may be NULL) and float properties; written atomically. SERE_OK, or SERE_ERR_IO. */
sere_status sere_ply_write( const char* path, const float* x, const float* y, const float* z, int32_t vertex_count,
							const int32_t* tri, int32_t triangle_count, const uint8_t* rgb,
							const sere_vertex_property* properties, int32_t property_count );

/* VTK XML PolyData (.vtp, ASCII) with float point data; written atomically. SERE_OK, or
 * SERE_ERR_IO. */
sere_status sere_vtp_write( const char* path, const float* x, const float* y, const float* z, int32_t vertex_count,
							const int32_t* tri, int32_t triangle_count, const sere_vertex_property* properties,
							int32_t property_count );

/* ParaView collection of files (relative names) at the given times; written atomically.
 * SERE_OK, or SERE_ERR_IO. */
sere_status sere_pvd_write( const char* path, const char* const* files, const double* times, int32_t count );

/* A growing time series of files for a .pvd: no limit on its length but memory. */
typedef struct sere_pvd_series
{
	char** files;
	double* times;
	int32_t count, capacity;
} sere_pvd_series;

/* Appends file (a name relative to the .pvd) at time and rewrites path atomically; SERE_OK, or
 * SERE_ERR_MEMORY or SERE_ERR_IO with errno set. */
sere_status sere_pvd_append( sere_pvd_series* series, const char* path, const char* file, double time );
void sere_pvd_destroy( sere_pvd_series* series );

/* A progress bar on stderr, drawn only when stderr is a terminal. */
typedef struct sere_progress
{
	const char* label;
	int64_t total;
	int64_t shown;
	double start;
	int active;
} sere_progress;

void sere_progress_begin( sere_progress* progress, const char* label, int64_t total );
void sere_progress_update( sere_progress* progress, int64_t done );
void sere_progress_end( sere_progress* progress );

/* Wall-clock seconds from a monotonic clock. */
double sere_now( void );
