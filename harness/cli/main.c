/* sere — the command-line driver. Every subcommand lives in its own cmd_*.c. */
#include "cli/commands.h"
#include "core/base.h"

#include <stdio.h>
#include <string.h>

typedef struct command
{
	const char* name;
	int ( *run )( int argc, char** argv );
	const char* summary;
} command;

static const command commands[] = {
	{ "model", sere_cmd_model, "build a leaf's triangle-Voronoi double layer; print counts and mesh quality" },
	{ "osmosis", sere_cmd_osmosis,
	  "osmotic water flow alone: CG iterations, residuals, water per layer; --dump the system" },
	{ "run", sere_cmd_run, "dry a leaf (Algorithm 1): frames, statistics, summary and pictures" },
	{ "table1", sere_cmd_table1, "the three Table 1 leaves: our ms per frame beside the paper's" },
	{ "season", sere_cmd_season,
	  "seasonal leaves on an L-system tree (seed 002): Markov chain of leaf states under a weather schedule" },
	{ "wilt", sere_cmd_wilt, "wilt a leaf or a plant on a stem (venation skeleton, seed 003): PLY/VTK/PNG frames" },
	{ "litter", sere_cmd_litter,
	  "N leaves drying on the ground as one scene: per-leaf files, resumable, a PLY, a picture" },
	{ "topo", sere_cmd_topo, "show the hwloc topology and how threads are bound" },
};

static void usage( FILE* f )
{
	fprintf( f, "sere — drying, wilting and seasonal leaves, fast\n\nusage: sere COMMAND [options]\n\ncommands:\n" );
	for ( size_t i = 0; i < sizeof( commands ) / sizeof( commands[0] ); ++i )
	{
		fprintf( f, "  %-9s %s\n", commands[i].name, commands[i].summary );
	}
	fprintf( f, "\n'sere COMMAND --help' describes a command's options; 'sere --version' prints the version,\n"
				"the commit it was built from and the SIMD path compiled in.\n"
				"\nenvironment:\n"
				"  SERE_DATA   directory searched first for presets, leaves, seasons, masks and skeletons\n"
				"              (given by name, e.g. --preset maple-red); then PREFIX/share/sere beside this\n"
				"              binary (PREFIX/bin/sere, found at run time, so an installed tree can be moved),\n"
				"              then ./data\n" );
}

/* The commit is known when the Makefile built from a git checkout. */
#ifndef SERE_GIT_COMMIT
#define SERE_GIT_COMMIT "unknown"
#endif

/* The compiler of the command (the library's own flags decide its SIMD path). */
#if defined( __clang__ )
#define SERE_COMPILER __VERSION__
#elif defined( __GNUC__ )
#define SERE_COMPILER "gcc " __VERSION__
#else
#define SERE_COMPILER "unknown"
#endif

static void version( FILE* f )
{
	fprintf( f, "sere %s\ncommit: %s\nsimd: %s\ncompiler: %s\n", sere_version(), SERE_GIT_COMMIT, sere_simd_path(),
			 SERE_COMPILER );
}

int main( int argc, char** argv )
{
	if ( argc < 2 || strcmp( argv[1], "--help" ) == 0 || strcmp( argv[1], "-h" ) == 0 ||
		 strcmp( argv[1], "help" ) == 0 )
	{
		usage( argc < 2 ? stderr : stdout );
		return argc < 2 ? 2 : 0;
	}
	if ( strcmp( argv[1], "--version" ) == 0 || strcmp( argv[1], "-V" ) == 0 || strcmp( argv[1], "version" ) == 0 )
	{
		version( stdout );
		return 0;
	}
	for ( size_t i = 0; i < sizeof( commands ) / sizeof( commands[0] ); ++i )
	{
		if ( strcmp( argv[1], commands[i].name ) == 0 )
		{
			return commands[i].run( argc - 1, argv + 1 );
		}
	}
	fprintf( stderr, "sere: unknown command '%s' (sere --help lists them)\n", argv[1] );
	return 2;
}
