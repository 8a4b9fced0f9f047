/* sere harness — every simulation parameter by name: defaults, Table 2 presets, --set overrides. */
#pragma once

#include "drying/layers.h"
#include "drying/leaf.h"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* The kernels' own parameter structs, filled in place by the table in params.c, plus the few
 * settings only the harness reads. A kernel parameter's default is its kernel's *_default(). */
typedef struct sere_sim_params
{
	sere_layer_params layer; /* the model builder's: h_vein, h_surf, omega_*, D, m_min, m_max, mu0 */
	sere_leaf_params leaf;	 /* the drying kernel's, handed to sere_leaf_step as it is */
	float crease;			 /* Sec. 3.1 initial shaping: Voronoi vein springs shortened by this fraction */
	float curl;				 /* ... and the other Voronoi springs lengthened by this fraction */
	int face_down;			 /* the leaf lies on the face its Voronoi layer is offset to (+n): mirrored through z */
	uint32_t seed;			 /* sampling seed of the model builder */
} sere_sim_params;

typedef enum sere_param_type
{
	SERE_PARAM_DOUBLE,
	SERE_PARAM_FLOAT,
	SERE_PARAM_INT32,
	SERE_PARAM_UINT32,
	SERE_PARAM_BOOL, /* an int holding 0 or 1 (the kernels' flags are ints) */
} sere_param_type;

/* One row of the parameter table: the one place a parameter is named, typed, placed, bounded
 * and documented. */
typedef struct sere_param
{
	const char* name;	/* the key of presets, --set and summary.json */
	const char* symbol; /* the paper's symbol, "" where the paper has none */
	sere_param_type type;
	size_t offset; /* where it lives in sere_sim_params */
	size_t also;   /* a second place the same value lives (m_min: builder and shrink), or 0 */
	double lo, hi; /* the accepted range, inclusive */
	const char* doc;
} sere_param;

/* The table, count rows. */
const sere_param* sere_params_table( int* count );

/* The value of row in params, as a double (exact for every type the table holds). */
double sere_params_get( const sere_sim_params* params, const sere_param* row );

sere_sim_params sere_sim_params_default( void );

/* Sets one "key=value"; SERE_OK, else SERE_ERR_PARSE (not key=value, not a number) or
 * SERE_ERR_ARGUMENT (an unknown key, a value out of range) with a one-line message in err naming
 * the key. */
sere_status sere_params_set( sere_sim_params* params, const char* assignment, char* err, size_t err_size );

/* Loads a preset by name (data/presets/NAME.preset, searched in SERE_DATA, ./data and the
 * install prefix) or by path; SERE_OK, else SERE_ERR_IO (not found, unreadable) or the status
 * of its first bad line, with a one-line message. */
sere_status sere_params_load_preset( sere_sim_params* params, const char* name_or_path, char* err, size_t err_size );

/* A preset (may be NULL) then each "key=value" in order, the way every command applies its
 * --preset and --set options; SERE_OK, else the first failure's status with a one-line message. */
sere_status sere_params_apply( sere_sim_params* params, const char* preset, const char* const* sets, int set_count,
							   char* err, size_t err_size );

/* The shortest decimal that reads back as value, as a double: the number a user wrote for a
 * float parameter (0.002 for 0.002f), for the harness's time axis and measures, which were
 * always computed in double from what was written. */
double sere_params_decimal( float value );

/* Writes every key = value, one per line, for summaries and --help. */
void sere_params_print_json( const sere_sim_params* params, FILE* f, const char* indent );
/* Every key with its description, default and range, for --help. */
void sere_params_describe( FILE* f );

/* Finds a data file (relative to SERE_DATA, ./data, or SERE_DATA_DIR compiled in); writes the
 * full path and returns SERE_OK, or SERE_ERR_IO when it does not exist. */
sere_status sere_data_find( const char* relative, char* path, size_t path_size );

/* A path that opens as given is used as given; else a relative one is looked up like a data file
 * (sere_data_find) into buffer. Returns the path to open (path itself when neither finds it). */
const char* sere_data_resolve( const char* path, char* buffer, size_t size );

#ifdef __cplusplus
}
#endif
