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
 * with B matched to the outline. Returns 0, or -1 with one line in err. */
int sere_harness_build( const char* path, long long particles, long long springs, long long points,
						const sere_sim_params* params, sere_model* model, sere_build_report* report, char* name,
						size_t name_size, char* err, size_t err_size );

/* The same from a leaf already read (path names it in messages). */
int sere_harness_build_leaf( const sere_leaf_source* leaf, const char* path, long long particles, long long springs,
							 long long points, const sere_sim_params* params, sere_model* model,
							 sere_build_report* report, char* name, size_t name_size, char* err, size_t err_size );

#ifdef __cplusplus
}
#endif
