/* sere harness — the two steps the drying commands (model, osmosis, run, table1) take before
 * they run: the parameters from --preset and --set, and the model of the leaf. Each prints
 * "sere COMMAND: why" to stderr when it fails. And the words for a drying step that failed.
 * Private to harness/cli. */
#pragma once

#include "cli/options.h"
#include "read/build.h"

#include <stddef.h>

/* --preset (may be NULL) and then every --set onto params (sere_params_apply); 1, or 0 after the
 * message. */
int command_params_apply( const char* command, sere_sim_params* params, const char* preset,
						  const sere_option_list* sets );

/* The model of the leaf at path with the counts of sere_harness_build (particles and springs -1:
 * points); report (may be NULL) gets the build's report and name the leaf's name. 1, or 0 after
 * the message. */
int command_model_build( const char* command, const char* path, long long particles, long long springs,
						 long long points, const sere_sim_params* params, sere_model* model, sere_build_report* report,
						 char* name, size_t name_size );

/* Why sere_leaf_step failed with status, into text: a step's input is the previous steps' state,
 * so a NaN or infinity there means the solve diverged, which the words say (with the Chebyshev
 * extrapolation on, naming its ρ, the usual cause). */
void command_step_error( const sere_sim_params* params, sere_status status, char* text, size_t size );
