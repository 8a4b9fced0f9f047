/* sere harness — a model from a leaf path and the command-line counts, shared by commands. */
#pragma once

#include "common/params.h"
#include "drying/leaf.h"
#include "drying/model.h"
#include "read/leafload.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* particles/springs (both >= 0) ask for exact counts; otherwise points triangle-layer points
 * with B matched to the outline. Returns SERE_OK, or the reader's or the builder's status
 * (SERE_ERR_COUNTS, SERE_ERR_GEOMETRY, ...) with one line in err. report may be NULL. */
sere_status sere_harness_build( const char* path, long long particles, long long springs, long long points,
								const sere_sim_params* params, sere_model* model, sere_build_report* report, char* name,
								size_t name_size, char* err, size_t err_size );

/* The same from a leaf already read (path names it in messages). */
sere_status sere_harness_build_leaf( const sere_leaf_source* leaf, const char* path, long long particles,
									 long long springs, long long points, const sere_sim_params* params,
									 sere_model* model, sere_build_report* report, char* name, size_t name_size,
									 char* err, size_t err_size );

#ifdef __cplusplus
}
#endif
