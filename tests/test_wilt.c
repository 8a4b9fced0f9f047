/* End-to-end and bad-input tests of `sere wilt` (seed 003): the built command is run through
 * the shell (SERE_BIN holds its path during `make test`); good runs must write their files and
 * report an intersection-free mesh, bad input must give one clear line and a non-zero exit. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef struct wilt_result
{
	int status;
	char out[8192];
	char err[8192];
	int err_lines;
} wilt_result;

static const char* wilt_binary( void )
{
	const char* bin = getenv( "SERE_BIN" );
	if ( bin == NULL || bin[0] == '\0' )
	{
		cr_skip_test( "SERE_BIN is not set (make test sets it to the built sere)" );
	}
	/* Until harness/cli/main.c routes `sere wilt` to sere_cmd_wilt there is nothing to test. */
	char command[1024];
	snprintf( command, sizeof( command ), "'%s' wilt --help >/dev/null 2>&1", bin );
	int raw = system( command );
	if ( raw == -1 || !WIFEXITED( raw ) || WEXITSTATUS( raw ) != 0 )
	{
		cr_skip_test( "%s does not know the wilt command yet", bin );
	}
	return bin;
}

static void read_all( const char* path, char* buffer, size_t size )
{
	buffer[0] = '\0';
	FILE* f = fopen( path, "rb" );
	if ( f != NULL )
	{
		size_t n = fread( buffer, 1, size - 1, f );
		buffer[n] = '\0';
		fclose( f );
	}
}

/* A fresh directory per test, so the parallel test jobs never share files. */
static void make_dir( char* dir, size_t size )
{
	snprintf( dir, size, "/tmp/sere-wilt-test-XXXXXX" );
	cr_assert_not_null( mkdtemp( dir ) );
}

static void run_wilt( const char* dir, const char* args, wilt_result* r )
{
	const char* bin = wilt_binary();
	char command[4096], out[512], err[512];
	snprintf( out, sizeof( out ), "%s/stdout", dir );
	snprintf( err, sizeof( err ), "%s/stderr", dir );
	snprintf( command, sizeof( command ), "'%s' wilt %s >'%s' 2>'%s' </dev/null", bin, args, out, err );
	int raw = system( command );
	cr_assert_neq( raw, -1 );
	r->status = WIFEXITED( raw ) ? WEXITSTATUS( raw ) : 128;
	read_all( out, r->out, sizeof( r->out ) );
	read_all( err, r->err, sizeof( r->err ) );
	r->err_lines = 0;
	for ( const char* c = r->err; *c != '\0'; ++c )
	{
		r->err_lines += *c == '\n';
	}
}

static void write_text( const char* path, const char* text )
{
	FILE* f = fopen( path, "w" );
	cr_assert_not_null( f );
	fputs( text, f );
	fclose( f );
}

static int file_size( const char* dir, const char* name )
{
	char path[512];
	snprintf( path, sizeof( path ), "%s/%s", dir, name );
	struct stat info;
	return stat( path, &info ) == 0 ? (int) info.st_size : -1;
}

/* Runs `sere wilt` on a skeleton file with the given text and expects a failure whose single
 * stderr line contains every fragment. */
static void expect_bad_skeleton( const char* text, const char* fragment, const char* second )
{
	char dir[64], args[256], path[128];
	make_dir( dir, sizeof( dir ) );
	snprintf( path, sizeof( path ), "%s/leaf.skel", dir );
	write_text( path, text );
	snprintf( args, sizeof( args ), "'%s' --frames 2", path );
	wilt_result r;
	run_wilt( dir, args, &r );
	cr_expect_neq( r.status, 0, "%s", text );
	cr_expect_eq( r.err_lines, 1, "one line, got: %s", r.err );
	cr_expect_not_null( strstr( r.err, fragment ), "'%s' not in: %s", fragment, r.err );
	if ( second != NULL )
	{
		cr_expect_not_null( strstr( r.err, second ), "'%s' not in: %s", second, r.err );
	}
	cr_expect_eq( strncmp( r.err, "sere wilt: ", 11 ), 0 );
}

/* A valid leaf skeleton (a rhombus-like blade) that the bad cases below break one at a time. */
#define GOOD_CURVES                                                                                                    \
	"left\n0 0\n3 2\n7 1.5\n10 0\n"                                                                                    \
	"right\n0 0\n3 -2\n7 -1.5\n10 0\n"                                                                                 \
	"midvein\n0 0\n10 0\n"

Test( wilt_cli, help_describes_every_option )
{
	char dir[64];
	make_dir( dir, sizeof( dir ) );
	wilt_result r;
	run_wilt( dir, "--help", &r );
	cr_expect_eq( r.status, 0 );
	const char* options[] = { "--droop",   "--min-angle", "--leaves", "--stagger", "--subdivide", "--min-edge",
							  "--threads", "--out",		  "--json",	  "--frames",  "--speed" };
	for ( size_t k = 0; k < sizeof( options ) / sizeof( options[0] ); ++k )
	{
		cr_expect_not_null( strstr( r.out, options[k] ), "%s", options[k] );
	}
}

Test( wilt_cli, plant_run_writes_frames )
{
	char dir[64], args[256];
	make_dir( dir, sizeof( dir ) );
	snprintf( args, sizeof( args ), "--leaves 3 --frames 4 --every 2 --threads 2 --size 200x150 --out '%s/run'", dir );
	wilt_result r;
	run_wilt( dir, args, &r );
	cr_assert_eq( r.status, 0, "%s", r.err );
	cr_expect_not_null( strstr( r.out, "self-intersecting triangle pairs 0" ), "%s", r.out );
	cr_expect_not_null( strstr( r.out, "3 leaves" ), "%s", r.out );
	char run[128];
	snprintf( run, sizeof( run ), "%s/run", dir );
	/* Frames 0 and 2, and the last frame (3) always. */
	const char* files[] = { "frame_0000.ply", "frame_0002.ply", "frame_0003.ply", "frame_0000.vtp",
							"frame_0003.vtp", "wilt.pvd",		"frame_0000.png", "frame_0003.png" };
	for ( size_t k = 0; k < sizeof( files ) / sizeof( files[0] ); ++k )
	{
		cr_expect_gt( file_size( run, files[k] ), 0, "%s", files[k] );
	}
	cr_expect_eq( file_size( run, "frame_0001.ply" ), -1, "--every 2 skips frame 1" );
	char path[256], head[512];
	snprintf( path, sizeof( path ), "%s/frame_0000.png", run );
	read_all( path, head, 9 );
	cr_expect_eq( memcmp( head, "\x89PNG\r\n\x1a\n", 8 ), 0 );
	snprintf( path, sizeof( path ), "%s/frame_0003.ply", run );
	read_all( path, head, sizeof( head ) );
	cr_expect_not_null( strstr( head, "property float u" ), "texture coordinates are written" );
	snprintf( path, sizeof( path ), "%s/wilt.pvd", run );
	read_all( path, head, sizeof( head ) );
	cr_expect_not_null( strstr( head, "frame_0003.vtp" ) );
	/* Nothing half-written is left behind. */
	snprintf( path, sizeof( path ), "%s/frame_0003.ply.tmp", run );
	cr_expect_neq( access( path, F_OK ), 0 );
}

Test( wilt_cli, json_summary_and_data_skeletons )
{
	char dir[64];
	make_dir( dir, sizeof( dir ) );
	const char* cases[] = { "--frames 3 --json", "cucumber --frames 3 --json", "watermelon --frames 3 --json" };
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		wilt_result r;
		run_wilt( dir, cases[k], &r );
		cr_assert_eq( r.status, 0, "%s: %s", cases[k], r.err );
		cr_expect_eq( r.out[0], '{', "%s", r.out );
		cr_expect_not_null( strstr( r.out, "\"self_intersections\": 0" ), "%s: %s", cases[k], r.out );
	}
	/* The seed's counts: cucumber 20 + 2 × 4 segments, watermelon 30 + 4 × 10. */
	wilt_result r;
	run_wilt( dir, "cucumber --frames 1 --json", &r );
	cr_expect_not_null( strstr( r.out, "\"joints_per_leaf\": 29" ), "%s", r.out );
	run_wilt( dir, "watermelon --frames 1 --json", &r );
	cr_expect_not_null( strstr( r.out, "\"joints_per_leaf\": 71" ), "%s", r.out );
}

Test( wilt_cli, bad_options_give_one_line )
{
	char dir[64];
	make_dir( dir, sizeof( dir ) );
	struct
	{
		const char* args;
		const char* fragment;
	} cases[] = {
		{ "--bogus", "unknown option '--bogus'" },
		{ "--frames 0", "--frames takes a whole number" },
		{ "--frames", "--frames needs a value" },
		{ "--threads abc", "--threads takes a whole number" },
		{ "--format gif", "--format takes" },
		{ "--size 10x10", "--size takes two numbers" },
		{ "--view 0,95", "--view elevation" },
		{ "--spread 1.5", "--spread takes a number" },
		{ "--droop -1", "--droop takes a number" },
		{ "--length nan", "--length takes a number" },
		{ "nosuch-leaf", "cannot find skeleton 'nosuch-leaf'" },
		{ "a.skel b.skel", "one SKELETON only" },
		{ "--spacing 1e-7", "sampling interval" },
	};
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		wilt_result r;
		run_wilt( dir, cases[k].args, &r );
		cr_expect_neq( r.status, 0, "%s", cases[k].args );
		cr_expect_eq( r.err_lines, 1, "%s: %s", cases[k].args, r.err );
		cr_expect_not_null( strstr( r.err, cases[k].fragment ), "%s: %s", cases[k].args, r.err );
	}
}

Test( wilt_cli, bad_skeleton_files_name_line_and_problem )
{
	expect_bad_skeleton( "left\n0 0\nfoo bar\n", ":3: unknown keyword 'foo'", NULL );
	expect_bad_skeleton( "left\n0 zero\n", ":2: a point is two finite numbers", NULL );
	expect_bad_skeleton( "0 0\n", ":1: point outside a left", NULL );
	expect_bad_skeleton( "left\n0 0\n10 0\nright\n0 0\n10 0\n", "no 'midvein' block", NULL );
	/* an empty midvein block (tests/data/bad/empty_midvein.skel, replayed by fuzz_skeleton) */
	expect_bad_skeleton( "left\n0 0\n10 0\nright\n0 0\n10 0\nmidvein\n", ":7: the 'midvein' block has 0 points", NULL );
	expect_bad_skeleton( "left 3\n", ":1: 'left' takes no value", NULL );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20\n", "'vein' takes PARENT SEGMENTS BEND_DEGREES", NULL );
	/* Problems the kernels find, traced back to the line. */
	expect_bad_skeleton( "left\n0 0\n3 2\n7 1.5\n10 0\nright\n0 0\n3 -2\n7 -1.5\n12 0\nmidvein\n0 0\n10 0\n",
						 "do not meet at the base and the tip", "right boundary curve" );
	expect_bad_skeleton( "left\n0 0\n3 2\n7 -4\n10 0\nright\n0 0\n3 -2\n7 -1.5\n10 0\nmidvein\n0 0\n10 0\n",
						 "crosses or touches itself", NULL );
	expect_bad_skeleton( "left\n0 0\n3 2\n7 1.5\n10 0\nright\n0 0\n3 -2\n7 -1.5\n10 0\nmidvein\n0 0\n5 3\n10 0\n",
						 "midvein leaves the outline", ":11: midvein" );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20 80\nvein 0 0 50\n2 0\n4 1.5\n", ":15: vein 1: segment count", NULL );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20 80\nvein 3 4 50\n2 0\n4 1.5\n", "vein 1: bad parent vein", NULL );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20 80\nvein 0 4 200\n2 0\n4 1.5\n", "bend angle", NULL );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20 80\nvein 0 4 50\n2 30\n3 31\n", "vein 1: a vein starts farther",
						 NULL );
	expect_bad_skeleton( GOOD_CURVES "vein -1 20 80\nvein 0 4 50\n2 0\n2 0\n", "vein 1: two consecutive points", NULL );
}
