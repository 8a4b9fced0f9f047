#include "cli/commands.h"
#include "cli/options.h"
#include "common/topo.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void topo_help( void )
{
	printf( "usage: sere topo [--threads T]\n\n"
			"Prints the machine topology as hwloc sees it and how sere binds its OpenMP threads:\n"
			"thread i runs on core i (one PU of it). T = 0 (default) uses one thread per core.\n" );
}

int sere_cmd_topo( int argc, char** argv )
{
	long long threads = 0;
	const sere_option options[] = { sere_option_threads( &threads ) };
	int code = sere_options_read( "topo", argc, argv, options, 1, NULL, NULL, topo_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	sere_topo_print( stdout );
	printf( "\nphysical cores: %d\nbinding:\n", sere_topo_cores() );
	sere_topo_bind( (int) threads, stdout );
	printf( "OpenMP threads: %d\n", omp_get_max_threads() );
	return 0;
}
