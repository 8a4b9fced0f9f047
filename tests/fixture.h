/* Test fixtures shared by several test files: small plane meshes built without the leaf
 * pipeline, so each kernel can be tested alone. */
#pragma once

#include "drying/layers.h"

#include <stddef.h>

/* A rectangle [0, width] x [0, height] as a grid of nx x ny cells, each cut into two
 * triangles, with jitter (fraction of a cell) on interior points from a fixed seed. The
 * boundary points come first, counter-clockwise from (0, 0); the horizontal middle row, if
 * vein_row is nonzero, is flagged as a vein. The caller frees with sere_test_plane_free. */
typedef struct sere_test_plane
{
	double* x;
	double* y;
	int32_t* tri;
	int32_t* veins;
	sere_plane_mesh mesh;
} sere_test_plane;

void sere_test_plane_grid( sere_test_plane* plane, int32_t nx, int32_t ny, double width, double height, double jitter,
						   int vein_row, uint64_t seed );
void sere_test_plane_free( sere_test_plane* plane );

/* splitmix64 in [0, 1) (sere_splitmix_unit): the fixed-seed generator of every fixture. */
double sere_test_unit( uint64_t* state );

/* Crumpled sheets: a smooth random displacement field (eight plane waves of wavelength 0.2 to
 * 0.5 in all three axes) of the given amplitude, from a fixed seed. Large amplitudes fold a unit
 * sheet through itself many times. */
typedef struct sere_test_crumple
{
	double wave[8][6];
	uint64_t state; /* draws the per-point noise after the waves */
} sere_test_crumple;

void sere_test_crumple_make( sere_test_crumple* field, double amplitude, uint64_t seed );
/* The displaced point of rest position (u, v, 0), plus noise · (uniform − 0.5) per axis, into
 * *x, *y, *z (a sheet's arrays at the point's index). */
void sere_test_crumple_point( sere_test_crumple* field, double u, double v, double noise, float* x, float* y,
							  float* z );

/* One object's thread setter, through one signature. */
typedef sere_status sere_test_set_fn( void* object, int32_t threads );

/* Expects the one limit of every thread setter (docs/DESIGN.md §4): −1, SERE_MAX_THREADS + 1 and
 * NULL refused, SERE_MAX_THREADS, 3, 1 and 0 taken; name labels the failures. */
void sere_test_expect_thread_range( const char* name, void* object, sere_test_set_fn* set );

/* The sere binary under test: $SERE_BIN (make test sets it), else build/sere. */
const char* sere_test_bin( void );

/* Runs command through the shell with its stdout captured into out (NUL terminated, cut at
 * out_size − 1; the rest is read and dropped); returns the exit status, 128 when it did not exit or could not start
 * (out then says so). */
int sere_test_shell( const char* command, char* out, size_t out_size );

/* Runs "BIN ARGS" through the shell with stdout captured into out and stderr discarded (for
 * --json and --help output); the exit status as sere_test_shell. */
int sere_test_stdout( const char* args, char* out, size_t out_size );

/* Runs "BIN ARGS" through the shell with stdout discarded and stderr captured into err (NUL
 * terminated, cut at err_size − 1); returns the exit status, 128 when it did not exit. */
int sere_test_run( const char* args, char* err, size_t err_size );

/* sere_test_run of ARGS = format with dir for its one %s (an output directory). */
int sere_test_run_in( const char* format, const char* dir, char* err, size_t err_size );

/* Removes a test's scratch directory and all in it (rm -rf); the shell's status, 0 when done. */
int sere_test_remove_tree( const char* dir );

/* A fresh scratch directory /tmp/sere-NAME-XXXXXX (mkdtemp, asserted), its path malloc'd. */
char* sere_test_scratch( const char* name );
/* Expects the scratch directory removed (sere_test_remove_tree) and frees its path. */
void sere_test_scratch_remove( char* dir );

/* Expects err to be one line ending in a newline (the CLI's error style); what names the run. */
void sere_test_expect_one_line( const char* what, const char* err );

/* Runs "BIN ARGS" (sere_test_run) and expects stderr to be one line that contains phrase;
 * returns the exit status for the caller to check. */
int sere_test_expect_error( const char* args, const char* phrase );

/* A frustrated sheet for the step solvers: nx × ny particles of spacing 0.05, waved in z, with
 * structural springs at their length and the springs of one diagonal at 0.8 of theirs, so that no
 * shape meets them all and the springs turn during a step (docs/DESIGN.md §8). Inverse masses
 * 1..3 so that the masses matter; the prediction t* is the starting shape. The caller frees with
 * sere_test_sheet_free. */
typedef struct sere_test_sheet
{
	int32_t n, count;
	float *x, *y, *z, *inv_m;
	float *tx, *ty, *tz;
	int32_t *a, *b;
	float* rest;
} sere_test_sheet;

#define SERE_TEST_SHEET_SPACING 0.05

sere_test_sheet sere_test_sheet_make( int32_t nx, int32_t ny );
void sere_test_sheet_free( sere_test_sheet* sheet );
