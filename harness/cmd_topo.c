#include "commands.h"
#include "topo.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int sere_cmd_topo( int argc, char** argv )
{
	int threads = 0;
	for ( int i = 1; i < argc; ++i )
	{
		if ( strcmp( argv[i], "--help" ) == 0 || strcmp( argv[i], "-h" ) == 0 )
		{
			printf( "usage: sere topo [--threads T]\n\n"
					"Prints the machine topology as hwloc sees it and how sere binds its OpenMP threads:\n"
					"thread i runs on core i (one PU of it). T = 0 (default) uses one thread per core.\n" );
			return 0;
		}
		if ( strcmp( argv[i], "--threads" ) == 0 && i + 1 < argc )
		{
			char* end;
			threads = (int) strtol( argv[++i], &end, 10 );
			if ( *end != '\0' || threads < 0 || threads > 256 )
			{
				fprintf( stderr, "sere topo: --threads takes a whole number from 0 to 256, not '%s'\n", argv[i] );
				return 2;
			}
			continue;
		}
		fprintf( stderr, "sere topo: unknown option '%s' (see sere topo --help)\n", argv[i] );
		return 2;
	}
	sere_topo_print( stdout );
	printf( "\nphysical cores: %d\nbinding:\n", sere_topo_cores() );
	sere_topo_bind( threads, stdout );
	printf( "OpenMP threads: %d\n", omp_get_max_threads() );
	return 0;
}
