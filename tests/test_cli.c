/* The sere command as a user meets it: bad input gives one clear line and a non-zero exit;
 * an interrupted run leaves complete outputs. SERE_BIN names the binary under test. */
#define _DEFAULT_SOURCE
#include "fixture.h"

#include <criterion/criterion.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static void expect_error( const char* args, const char* phrase )
{
	cr_expect_neq( sere_test_expect_error( args, phrase ), 0, "'%s' should fail", args );
}

Test( cli, bad_input_one_clear_line )
{
	expect_error( "run data/leaves/maple.leaf --preset autumn --frames 2 --out /tmp/sere-cli",
				  "unknown preset 'autumn'" );
	expect_error( "run data/leaves/nope.leaf --frames 2 --out /tmp/sere-cli", "data/leaves/nope.leaf: cannot open" );
	expect_error( "run data/leaves/maple.leaf --frames -3 --out /tmp/sere-cli", "--frames takes a whole number" );
	expect_error( "run data/leaves/maple.leaf --frames 2 --set wetness=3 --out /tmp/sere-cli",
				  "unknown parameter 'wetness'" );
	expect_error( "run data/leaves/maple.leaf --frames 2 --set vein_compliance=0 --out /tmp/sere-cli",
				  "vein_compliance = 0 makes those springs rigid, which the descent step cannot take" );
	expect_error( "run data/leaves/maple.leaf --frames 2 --set stiffness=2 --out /tmp/sere-cli",
				  "stiffness = 2 is out of range" );
	expect_error( "run data/leaves/maple.leaf --frames 2 --set dt=abc --out /tmp/sere-cli",
				  "dt: 'abc' is not a number" );
	expect_error( "run data/leaves/maple.leaf --bogus", "unknown option '--bogus'" );
	/* one thread limit for every command and kernel: SERE_MAX_THREADS (core/base.h) */
	expect_error( "table1 --threads 257", "--threads takes a whole number from 0 to 256" );
	expect_error( "table1 --leaf oak", "--leaf takes one of 'all', 'maple', 'plane', 'wisteria', not 'oak'" );
	expect_error( "table1 --rounds 0", "--rounds takes a whole number from 1 to 1000, not '0'" );
	expect_error( "wilt --threads 257", "--threads takes a whole number from 0 to 256" );
	expect_error( "model data/leaves/maple.leaf --particles 100 --springs 7", "no triangulation has 100 particles" );
	expect_error( "frobnicate", "unknown command 'frobnicate'" );
}

/* A step whose solve diverges says so, with the frame and the extrapolation's ρ that caused it,
 * not the status's "NaN or infinity in the input": the input was the leaf's own state. */
Test( cli, diverging_solve_names_its_cause, .timeout = 60 )
{
	/* XPBD's sweeps extrapolated that far diverge; the descent's stay finite and run to the cap */
	expect_error(
		"table1 --threads 2 --leaf maple --frames 40 --set descent=0 --set chebyshev_rho=0.99 --set chebyshev_delay=2",
		"the leaf's state became NaN or infinite: the solve diverged (chebyshev_rho = 0.99" );
}

Test( cli, help_describes_every_command )
{
	const char* commands[] = { "model", "run", "osmosis", "table1", "topo", "wilt", "season", "litter" };
	for ( size_t k = 0; k < sizeof( commands ) / sizeof( commands[0] ); ++k )
	{
		char args[64];
		static char out[32768]; /* run's help lists every parameter: over 8 KB */
		snprintf( args, sizeof( args ), "%s --help", commands[k] );
		cr_expect_eq( sere_test_stdout( args, out, sizeof( out ) ), 0, "%s --help", commands[k] );
		cr_expect_not_null( strstr( out, "usage: sere" ), "%s --help", commands[k] );
	}
}

/* The README says `sere run --help` lists every option: these are the ones parse_run_options
 * accepts (cmd_run.c), --until-dry once among them unlisted. */
Test( cli, run_help_names_every_run_option )
{
	static char out[32768];
	cr_assert_eq( sere_test_stdout( "run --help", out, sizeof( out ) ), 0 );
	const char* options[] = { "--preset", "--frames",	 "--until-dry", "--out",	 "--every",
							  "--points", "--particles", "--springs",	"--threads", "--set" };
	for ( size_t k = 0; k < sizeof( options ) / sizeof( options[0] ); ++k )
	{
		cr_expect_not_null( strstr( out, options[k] ), "run --help does not name %s", options[k] );
	}
}

Test( cli, model_json_table1_counts )
{
	char command[512], out[8192];
	snprintf( command, sizeof( command ), "%s model data/leaves/wisteria.leaf --particles 12750 --springs 50436 --json",
			  sere_test_bin() );
	FILE* pipe = popen( command, "r" );
	size_t used = fread( out, 1, sizeof( out ) - 1, pipe );
	out[used] = '\0';
	cr_assert_eq( pclose( pipe ), 0 );
	cr_expect_not_null( strstr( out, "\"particles\": 12750" ), "%s", out );
	cr_expect_not_null( strstr( out, "\"springs\": 50436" ), "%s", out );
	cr_expect_not_null( strstr( out, "\"min_angle_deg\"" ) );
}

static long file_size( const char* path )
{
	struct stat info;
	return stat( path, &info ) == 0 ? (long) info.st_size : -1;
}

Test( cli, interrupted_run_leaves_complete_outputs )
{
	char* dir = sere_test_scratch( "interrupt" );
	pid_t pid = fork();
	cr_assert_geq( pid, 0 );
	if ( pid == 0 )
	{
		freopen( "/dev/null", "w", stdout );
		freopen( "/dev/null", "w", stderr );
		execl( sere_test_bin(), sere_test_bin(), "run", "data/leaves/hickory.leaf", "--points", "600", "--frames",
			   "100000", "--every", "5", "--out", dir, (char*) NULL );
		_exit( 127 );
	}
	/* Wait until a few frames are on disk, then interrupt. */
	char probe[512];
	snprintf( probe, sizeof( probe ), "%s/frames/frame_00010.ply", dir );
	for ( int k = 0; k < 600 && file_size( probe ) <= 0; ++k )
	{
		nanosleep( &( struct timespec ){ 0, 50000000 }, NULL );
	}
	cr_assert_gt( file_size( probe ), 0, "no frame written in 30 s" );
	kill( pid, SIGINT );
	int status;
	waitpid( pid, &status, 0 );
	cr_expect( WIFEXITED( status ) && WEXITSTATUS( status ) == 130, "exit %d", WEXITSTATUS( status ) );
	char path[512], text[65536];
	snprintf( path, sizeof( path ), "%s/summary.json", dir );
	FILE* f = fopen( path, "r" );
	cr_assert_not_null( f, "no summary.json" );
	size_t used = fread( text, 1, sizeof( text ) - 1, f );
	text[used] = '\0';
	fclose( f );
	cr_expect_not_null( strstr( text, "\"interrupted\": true" ) );
	cr_expect( used > 2 && text[used - 2] == '}', "summary is not closed: ...%s",
			   text + ( used > 40 ? used - 40 : 0 ) );
	/* the parameters are JSON members: "key": number (or null for the ground's −inf), commas
	 * between them and none after the last */
	const char* line = strstr( text, "\"parameters\": {\n" );
	cr_assert_not_null( line, "no parameters block" );
	line = strchr( line, '\n' ) + 1;
	int members = 0;
	while ( strncmp( line, "  }", 3 ) != 0 )
	{
		char key[64];
		int at = 0;
		cr_assert_eq( sscanf( line, "    \"%63[A-Za-z0-9_]\": %n", key, &at ), 1, "not a member: %.60s", line );
		const char* value = line + at;
		char* end = (char*) value;
		if ( strncmp( value, "null", 4 ) == 0 )
		{
			end += 4;
		}
		else
		{
			strtod( value, &end );
		}
		cr_assert( end > value, "%s: not a number: %.30s", key, value );
		const char* next = strchr( line, '\n' ) + 1;
		bool last = strncmp( next, "  }", 3 ) == 0;
		cr_assert( *end == ( last ? '\n' : ',' ), "%s: %s comma", key, last ? "trailing" : "missing" );
		members += 1;
		line = next;
	}
	cr_expect_gt( members, 30, "only %d parameters", members );
	const char* expected[] = { "stats.csv", "drying.png", "curves.png", "leaf.pvd" };
	for ( size_t k = 0; k < sizeof( expected ) / sizeof( expected[0] ); ++k )
	{
		snprintf( path, sizeof( path ), "%s/%s", dir, expected[k] );
		cr_expect_gt( file_size( path ), 0, "%s missing", expected[k] );
	}
	/* No temporary file survives: every output was renamed into place whole. */
	snprintf( path, sizeof( path ), "ls %s %s/frames | grep -c '\\.tmp$'", dir, dir );
	FILE* pipe = popen( path, "r" );
	int tmp_count = -1;
	cr_assert_eq( fscanf( pipe, "%d", &tmp_count ), 1 );
	pclose( pipe );
	cr_expect_eq( tmp_count, 0 );
	sere_test_scratch_remove( dir );
}

Test( cli, osmosis_dump_is_a_solved_system )
{
	char* dir = sere_test_scratch( "dump" );
	char err[4096];
	cr_assert_eq( sere_test_run_in( "osmosis data/leaves/wisteria.leaf --points 300 --steps 2 --dump %s", dir, err,
									sizeof( err ) ),
				  0, "%s", err );
	/* Read A (symmetric, lower triangle), b and x back and check A x = b: CG stopped at a
	 * relative residual of 1e-10 and %.17g round-trips doubles, so 1e-9 leaves room. */
	char path[512];
	snprintf( path, sizeof( path ), "%s/A.mtx", dir );
	FILE* f = fopen( path, "r" );
	cr_assert_not_null( f );
	char line[256];
	int rows = 0, cols = 0, entries = 0;
	while ( fgets( line, sizeof( line ), f ) != NULL && line[0] == '%' )
	{
	}
	cr_assert_eq( sscanf( line, "%d %d %d", &rows, &cols, &entries ), 3 );
	cr_assert( rows > 0 && rows == cols );
	int* ei = malloc( sizeof( int ) * entries );
	int* ej = malloc( sizeof( int ) * entries );
	double* ev = malloc( sizeof( double ) * entries );
	for ( int k = 0; k < entries; ++k )
	{
		cr_assert_eq( fscanf( f, "%d %d %lf", ei + k, ej + k, ev + k ), 3 );
	}
	fclose( f );
	double* vec[2];
	const char* names[2] = { "b.mtx", "x.mtx" };
	for ( int v = 0; v < 2; ++v )
	{
		snprintf( path, sizeof( path ), "%s/%s", dir, names[v] );
		f = fopen( path, "r" );
		cr_assert_not_null( f );
		while ( fgets( line, sizeof( line ), f ) != NULL && line[0] == '%' )
		{
		}
		vec[v] = malloc( sizeof( double ) * rows );
		for ( int i = 0; i < rows; ++i )
		{
			cr_assert_eq( fscanf( f, "%lf", vec[v] + i ), 1 );
		}
		fclose( f );
	}
	double* ax = calloc( rows, sizeof( double ) );
	for ( int k = 0; k < entries; ++k )
	{
		int i = ei[k] - 1, j = ej[k] - 1;
		ax[i] += ev[k] * vec[1][j];
		if ( i != j )
		{
			ax[j] += ev[k] * vec[1][i];
		}
	}
	double r2 = 0.0, b2 = 0.0;
	for ( int i = 0; i < rows; ++i )
	{
		r2 += ( ax[i] - vec[0][i] ) * ( ax[i] - vec[0][i] );
		b2 += vec[0][i] * vec[0][i];
	}
	cr_expect_leq( sqrt( r2 ), 1e-9 * sqrt( b2 ), "relative residual %g", sqrt( r2 / b2 ) );
	snprintf( path, sizeof( path ), "%s/particles.csv", dir );
	cr_expect_gt( file_size( path ), 0 );
	free( ei ), free( ej ), free( ev ), free( vec[0] ), free( vec[1] ), free( ax );
	sere_test_scratch_remove( dir );
}

Test( cli, rerun_replaces_old_frames_only )
{
	char* dir = sere_test_scratch( "rerun" );
	char path[512], args[1024], err[4096];
	snprintf( path, sizeof( path ), "%s/frames", dir );
	cr_assert_eq( mkdir( path, 0755 ), 0 );
	/* a frame a longer earlier run left, and files that are not ours */
	const char* planted[] = { "frame_09999.ply", "frame_09999.vtp", "notes.txt", "frame_1.ply" };
	for ( size_t k = 0; k < 4; ++k )
	{
		snprintf( path, sizeof( path ), "%s/frames/%s", dir, planted[k] );
		FILE* f = fopen( path, "w" );
		cr_assert_not_null( f );
		fputs( "x\n", f );
		fclose( f );
	}
	snprintf( args, sizeof( args ), "run data/leaves/wisteria.leaf --preset wisteria --frames 2 --points 300 --out %s",
			  dir );
	cr_assert_eq( sere_test_run( args, err, sizeof( err ) ), 0, "%s", err );
	for ( size_t k = 0; k < 4; ++k )
	{
		snprintf( path, sizeof( path ), "%s/frames/%s", dir, planted[k] );
		if ( k < 2 )
		{
			cr_expect_lt( file_size( path ), 0, "%s survived the new run", planted[k] );
		}
		else
		{
			cr_expect_gt( file_size( path ), 0, "%s was removed", planted[k] );
		}
	}
	snprintf( path, sizeof( path ), "%s/frames/frame_00002.ply", dir );
	cr_expect_gt( file_size( path ), 0, "the new run's last frame is missing" );
	sere_test_scratch_remove( dir );
}
