#include "cli/cmd_leaf.h"

#include <stdio.h>

int command_params_apply( const char* command, sere_sim_params* params, const char* preset,
						  const sere_option_list* sets )
{
	char err[1024];
	if ( sere_params_apply( params, preset, sets->items, sets->count, err, sizeof( err ) ) != SERE_OK )
	{
		fprintf( stderr, "sere %s: %s\n", command, err );
		return 0;
	}
	return 1;
}

int command_model_build( const char* command, const char* path, long long particles, long long springs,
						 long long points, const sere_sim_params* params, sere_model* model, sere_build_report* report,
						 char* name, size_t name_size )
{
	char err[1024];
	if ( sere_harness_build( path, particles, springs, points, params, model, report, name, name_size, err,
							 sizeof( err ) ) != SERE_OK )
	{
		fprintf( stderr, "sere %s: %s\n", command, err );
		return 0;
	}
	return 1;
}

void command_step_error( const sere_sim_params* params, sere_status status, char* text, size_t size )
{
	const int descent = params->leaf.descent;
	const float rho = descent ? params->leaf.descent_rho : params->leaf.pbd.chebyshev_rho;
	if ( status != SERE_ERR_NONFINITE )
	{
		snprintf( text, size, "%s", sere_status_text( status ) );
	}
	else if ( rho > 0.0f )
	{
		snprintf( text, size,
				  "the leaf's state became NaN or infinite: the solve diverged (%s = %g extrapolates "
				  "too far for this leaf: try a smaller one, or 0)",
				  descent ? "descent_rho" : "chebyshev_rho", (double) rho );
	}
	else
	{
		snprintf( text, size, "the leaf's state became NaN or infinite: the solve diverged" );
	}
}
