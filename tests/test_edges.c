/* Edges a user can trip over (issue 19): output paths that cannot be written, names and lines
 * the readers must not mangle, and limits that must be either gone or stated. Every failure is
 * one line on stderr naming the file or argument and the reason, with a non-zero exit.
 * SERE_BIN names the binary under test. */
#define _DEFAULT_SOURCE
#include "fixture.h"

#include <criterion/criterion.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* ---- helpers -------------------------------------------------------------------------------- */

static char* read_text( const char* path )
{
	FILE* f = fopen( path, "rb" );
	if ( f == NULL )
	{
		return NULL;
	}
	size_t capacity = 1 << 16, used = 0;
	char* text = malloc( capacity );
	size_t got;
	while ( ( got = fread( text + used, 1, capacity - used - 1, f ) ) > 0 )
	{
		used += got;
		if ( used + 1 == capacity )
		{
			capacity *= 2;
			text = realloc( text, capacity );
		}
	}
	fclose( f );
	text[used] = '\0';
	return text;
}

static void write_text( const char* path, const char* text )
{
	FILE* f = fopen( path, "wb" );
	cr_assert_not_null( f, "%s", path );
	fputs( text, f );
	fclose( f );
}

/* A strict JSON checker (RFC 8259): whole document, one value, UTF-8 left to the producer but
 * no raw control characters in strings and only the defined escapes. */
static const char* json_value( const char* p );

static const char* json_space( const char* p )
{
	while ( *p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' )
	{
		++p;
	}
	return p;
}

static const char* json_string( const char* p )
{
	if ( *p != '"' )
	{
		return NULL;
	}
	for ( ++p; *p != '"'; ++p )
	{
		if ( (unsigned char) *p < 0x20 )
		{
			return NULL;
		}
		if ( *p == '\\' )
		{
			++p;
			if ( *p == 'u' )
			{
				for ( int k = 1; k <= 4; ++k )
				{
					if ( !strchr( "0123456789abcdefABCDEF", p[k] ) || p[k] == '\0' )
					{
						return NULL;
					}
				}
				p += 4;
			}
			else if ( *p == '\0' || !strchr( "\"\\/bfnrt", *p ) )
			{
				return NULL;
			}
		}
	}
	return p + 1;
}

static const char* json_value( const char* p )
{
	p = json_space( p );
	if ( *p == '{' || *p == '[' )
	{
		char close = *p == '{' ? '}' : ']';
		p = json_space( p + 1 );
		if ( *p == close )
		{
			return p + 1;
		}
		for ( ;; )
		{
			if ( close == '}' )
			{
				p = json_string( json_space( p ) );
				if ( p == NULL || *( p = json_space( p ) ) != ':' )
				{
					return NULL;
				}
				++p;
			}
			p = json_value( p );
			if ( p == NULL )
			{
				return NULL;
			}
			p = json_space( p );
			if ( *p == close )
			{
				return p + 1;
			}
			if ( *p != ',' )
			{
				return NULL;
			}
			++p;
		}
	}
	if ( *p == '"' )
	{
		return json_string( p );
	}
	const char* words[] = { "true", "false", "null" };
	for ( int k = 0; k < 3; ++k )
	{
		if ( strncmp( p, words[k], strlen( words[k] ) ) == 0 )
		{
			return p + strlen( words[k] );
		}
	}
	char* end;
	strtod( p, &end );
	return end > p && ( *p == '-' || ( *p >= '0' && *p <= '9' ) ) ? end : NULL;
}

static int json_valid( const char* text )
{
	const char* end = json_value( text );
	return end != NULL && *json_space( end ) == '\0';
}

/* ---- input parsing --------------------------------------------------------------------------- */

Test( edges, json_escaper_keeps_documents_valid )
{
	cr_expect( json_valid( "{\"a\": [1, -2.5e3, \"x\\\"y\\u0001\", true, null], \"b\": {}}" ) );
	cr_expect( !json_valid( "{\"a\": \"x\"y\"}" ), "the checker must reject a raw quote" );
	cr_expect( !json_valid( "{\"a\": \"x\001\"}" ), "the checker must reject a raw control character" );
}

/* A copy of wisteria.leaf whose name line holds a quote, a backslash and control characters. */
static void weird_leaf( const char* dir, char* path, size_t size )
{
	char* text = read_text( "data/leaves/wisteria.leaf" );
	cr_assert_not_null( text );
	char* name = strstr( text, "\nname wisteria\n" );
	cr_assert_not_null( name );
	snprintf( path, size, "%s/weird.leaf", dir );
	FILE* f = fopen( path, "wb" );
	cr_assert_not_null( f );
	fwrite( text, 1, (size_t) ( name - text ), f );
	fputs( "\nname we\"ird\\ \001leaf\t\x7f end\xc3\xa9\n", f );
	fputs( name + strlen( "\nname wisteria\n" ), f );
	fclose( f );
	free( text );
}

Test( edges, leaf_name_with_quote_and_control_characters_gives_valid_json )
{
	char* dir = sere_test_scratch( "edges-json" );
	char leaf[512], args[2048], out[16384], path[512];
	weird_leaf( dir, leaf, sizeof( leaf ) );
	snprintf( args, sizeof( args ), "model %s --points 300 --json", leaf );
	cr_assert_eq( sere_test_stdout( args, out, sizeof( out ) ), 0, "sere %s failed", args );
	cr_expect( json_valid( out ), "sere model --json is not JSON: %s", out );
	cr_expect_not_null( strstr( out, "\"leaf\": \"we\\\"ird\\\\ \\u0001leaf\\t\\u007f end\xc3\xa9\"" ), "%s", out );

	char err[4096];
	snprintf( args, sizeof( args ), "run %s --points 300 --frames 2 --out %s/run", leaf, dir );
	cr_assert_eq( sere_test_run( args, err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "%s/run/summary.json", dir );
	char* summary = read_text( path );
	cr_assert_not_null( summary );
	cr_expect( json_valid( summary ), "summary.json is not JSON:\n%s", summary );
	cr_expect_not_null( strstr( summary, "\"status\": \"complete\"" ), "%s", summary );
	free( summary );
	sere_test_scratch_remove( dir );
}

Test( edges, leaf_name_not_utf8_is_refused )
{
	char* dir = sere_test_scratch( "edges-utf8" );
	char path[512], args[1024], err[4096], where[600];
	snprintf( path, sizeof( path ), "%s/latin1.leaf", dir );
	write_text( path, "name caf\xe9\nbase 0 0\noutline 3\n0 0\n1 0\n0 1\n" );
	snprintf( args, sizeof( args ), "model %s", path );
	cr_expect_neq( sere_test_run( args, err, sizeof( err ) ), 0 );
	snprintf( where, sizeof( where ), "%s:1: name is not UTF-8 text (byte 0xE9 at character 4)", path );
	cr_expect_not_null( strstr( err, where ), "expected '%s' in: %s", where, err );
	sere_test_expect_one_line( "latin1", err );
	sere_test_scratch_remove( dir );
}

static void expect_seed( const char* dir, const char* preset, const char* expected )
{
	char args[2048], err[4096], path[512];
	snprintf( args, sizeof( args ), "run data/leaves/wisteria.leaf --points 300 --frames 1 --preset %s --out %s/run",
			  preset, dir );
	cr_assert_eq( sere_test_run( args, err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "%s/run/summary.json", dir );
	char* summary = read_text( path );
	cr_assert_not_null( summary );
	cr_expect_not_null( strstr( summary, expected ), "expected %s in %s", expected, summary );
	free( summary );
}

Test( edges, long_preset_comment_stays_a_comment )
{
	char* dir = sere_test_scratch( "edges-preset" );
	/* 1023 characters of comment, then "seed=7": a 1024-byte line buffer used to cut it there
	 * and apply the tail */
	static char text[8192];
	char* p = text;
	p += sprintf( p, "dt = 0.002\n#" );
	memset( p, 'x', 1022 );
	p += 1022;
	p += sprintf( p, "seed=7\n" );
	char preset[512];
	snprintf( preset, sizeof( preset ), "%s/long.preset", dir );
	write_text( preset, text );
	expect_seed( dir, preset, "\"seed\": 1" );

	/* an error after a 5000-character line names its own line, 3 */
	p = text;
	p += sprintf( p, "dt = 0.002\n# " );
	memset( p, 'y', 5000 );
	p += 5000;
	sprintf( p, "\nstiffness = 2\n" );
	write_text( preset, text );
	char args[2048], err[4096], where[600];
	snprintf( args, sizeof( args ), "run data/leaves/wisteria.leaf --frames 1 --preset %s --out %s/run", preset, dir );
	cr_expect_neq( sere_test_run( args, err, sizeof( err ) ), 0 );
	snprintf( where, sizeof( where ), "%s:3: stiffness = 2 is out of range", preset );
	cr_expect_not_null( strstr( err, where ), "expected '%s' in: %s", where, err );
	sere_test_expect_one_line( "preset", err );
	sere_test_scratch_remove( dir );
}

Test( edges, long_chain_line_keeps_line_numbers )
{
	char* dir = sere_test_scratch( "edges-chain" );
	char* chain = read_text( "data/seasons/maple.chain" );
	cr_assert_not_null( chain );
	/* line 1: a 3000-character comment; line 2: a mistake */
	size_t length = strlen( chain );
	char* text = malloc( length + 4096 );
	text[0] = '#';
	memset( text + 1, 'z', 3000 );
	sprintf( text + 3001, "\nbogus 1 2\n%s", chain );
	char path[512], args[2048], err[4096], where[600];
	snprintf( path, sizeof( path ), "%s/long.chain", dir );
	write_text( path, text );
	snprintf( args, sizeof( args ), "season --chain %s --days 2 --temperature 10 --humidity 0.5 --out %s/season", path,
			  dir );
	cr_expect_neq( sere_test_run( args, err, sizeof( err ) ), 0 );
	snprintf( where, sizeof( where ), "%s:2: unknown keyword 'bogus'", path );
	cr_expect_not_null( strstr( err, where ), "expected '%s' in: %s", where, err );
	sere_test_expect_one_line( "chain", err );

	/* the tail of a long comment is not read as a keyword */
	text[0] = '#';
	memset( text + 1, 'z', 1100 );
	sprintf( text + 1101, "bogus\n%s", chain );
	write_text( path, text );
	snprintf( args, sizeof( args ), "season --chain %s --schedule %s/missing.schedule --out %s/season", path, dir,
			  dir );
	cr_expect_neq( sere_test_run( args, err, sizeof( err ) ), 0 );
	cr_expect_null( strstr( err, "bogus" ), "a comment's tail was read: %s", err );
	cr_expect_not_null( strstr( err, "missing.schedule" ), "the chain was not accepted: %s", err );
	free( text );
	free( chain );
	sere_test_scratch_remove( dir );
}

/* ---- silent limits --------------------------------------------------------------------------- */

Test( edges, more_than_1023_mesh_frames_are_all_written, .timeout = 240 )
{
	char* dir = sere_test_scratch( "edges-frames" );
	char args[1024], err[4096], path[512];
	snprintf( args, sizeof( args ), "run data/leaves/wisteria.leaf --points 100 --every 1 --frames 1100 --out %s",
			  dir );
	cr_assert_eq( sere_test_run( args, err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "%s/frames/frame_01100.vtp", dir );
	struct stat info;
	cr_expect_eq( stat( path, &info ), 0, "the last frame is missing" );
	snprintf( path, sizeof( path ), "%s/leaf.pvd", dir );
	char* pvd = read_text( path );
	cr_assert_not_null( pvd );
	int listed = 0;
	for ( const char* p = pvd; ( p = strstr( p, "<DataSet" ) ) != NULL; ++p )
	{
		listed += 1;
	}
	cr_expect_eq( listed, 1101, "leaf.pvd lists %d frames", listed );
	free( pvd );
	sere_test_scratch_remove( dir );
}

Test( edges, too_few_points_names_a_count_that_builds )
{
	char err[4096], args[1024];
	/* the count that used to fail for the outline-matched B now builds */
	cr_expect_eq( sere_test_run( "model data/leaves/wisteria.leaf --points 100", err, sizeof( err ) ), 0, "%s", err );
	const char* commands[] = { "model data/leaves/maple.leaf --points 10",
							   "run data/leaves/maple.leaf --points 10 --frames 1 --out /tmp/sere-edges-never" };
	for ( int k = 0; k < 2; ++k )
	{
		cr_expect_neq( sere_test_run( commands[k], err, sizeof( err ) ), 0, "%s", commands[k] );
		sere_test_expect_one_line( commands[k], err );
		const char* hint = strstr( err, "; --points " );
		cr_assert_not_null( strstr( err, "data/leaves/maple.leaf: --points 10 is too few" ), "%s", err );
		cr_assert_not_null( hint, "%s", err );
		int points = atoi( hint + strlen( "; --points " ) );
		cr_expect_gt( points, 10 );
		snprintf( args, sizeof( args ), "model data/leaves/maple.leaf --points %d", points );
		cr_expect_eq( sere_test_run( args, err, sizeof( err ) ), 0, "the named count does not build: %s", err );
	}
}

/* ---- output paths ---------------------------------------------------------------------------- */

Test( edges, empty_out_is_refused )
{
	struct stat info;
	int had_summary = stat( "/summary.json", &info ) == 0;
	const char* commands[] = { "run data/leaves/wisteria.leaf --points 300 --frames 1 --out ''",
							   "wilt --frames 2 --out ''", "season --out ''" };
	for ( int k = 0; k < 3; ++k )
	{
		char err[4096];
		cr_expect_neq( sere_test_run( commands[k], err, sizeof( err ) ), 0, "%s", commands[k] );
		cr_expect_not_null( strstr( err, "--out needs a directory name" ), "%s: %s", commands[k], err );
		cr_expect_null( strstr( err, "Success" ), "%s", err );
		sere_test_expect_one_line( commands[k], err );
	}
	cr_expect( had_summary || stat( "/summary.json", &info ) != 0, "sere run wrote into /" );
}

Test( edges, summary_json_directory_is_refused )
{
	char* dir = sere_test_scratch( "edges-dir" );
	char path[512], err[4096];
	snprintf( path, sizeof( path ), "%s/summary.json", dir );
	cr_assert_eq( mkdir( path, 0755 ), 0 );
	cr_expect_neq(
		sere_test_run_in( "run data/leaves/wisteria.leaf --points 300 --frames 2 --out %s", dir, err, sizeof( err ) ),
		0 );
	cr_expect_not_null( strstr( err, path ), "the message does not name %s: %s", path, err );
	sere_test_expect_one_line( "summary.json", err );
	sere_test_scratch_remove( dir );
}

Test( edges, wilt_out_that_is_a_file )
{
	char* dir = sere_test_scratch( "edges-wilt" );
	char path[512], args[1024], err[4096];
	snprintf( path, sizeof( path ), "%s/file", dir );
	write_text( path, "x\n" );
	snprintf( args, sizeof( args ), "wilt --frames 2 --out %s", path );
	cr_expect_neq( sere_test_run( args, err, sizeof( err ) ), 0 );
	cr_expect_not_null( strstr( err, "Not a directory" ), "%s", err );
	cr_expect_null( strstr( err, "Success" ), "%s", err );
	sere_test_expect_one_line( "wilt", err );
	sere_test_scratch_remove( dir );
}

/* PLY files whose size matches their header: vertices of as many floats as the header lists
 * (x, y, z and the per-vertex properties), faces of a count byte and three indices. */
static void expect_whole_ply( const char* path )
{
	char* text = read_text( path );
	cr_assert_not_null( text, "%s", path );
	struct stat info;
	cr_assert_eq( stat( path, &info ), 0 );
	int vertices = -1, faces = -1;
	const char* v = strstr( text, "element vertex " );
	const char* f = strstr( text, "element face " );
	const char* end = strstr( text, "end_header\n" );
	cr_assert( v && f && end, "%s: no PLY header", path );
	sscanf( v, "element vertex %d", &vertices );
	sscanf( f, "element face %d", &faces );
	long header = (long) ( end - text ) + (long) strlen( "end_header\n" );
	long floats = 0;
	for ( const char* p = strstr( text, "property float " ); p != NULL && p < end;
		  p = strstr( p + 1, "property float " ) )
	{
		floats += 1;
	}
	cr_expect_geq( floats, 3, "%s: no x, y, z", path );
	cr_expect_eq( (long) info.st_size, header + 4L * floats * vertices + 13L * faces, "%s is cut short", path );
	free( text );
}

Test( edges, full_disk_stops_with_one_line_and_a_summary, .timeout = 120 )
{
	char* dir = sere_test_scratch( "edges-full" );
	/* A 256 KiB tmpfs holds frame 0 and a few more (root, as here and in CI); where mounting is
	 * not allowed, a file-size limit makes the first VTP fail with EFBIG instead. */
	int mounted = mount( "tmpfs", dir, "tmpfs", 0, "size=256k" ) == 0;
	char err[4096];
	int pipe_fd[2];
	cr_assert_eq( pipe( pipe_fd ), 0 );
	pid_t pid = fork();
	cr_assert_geq( pid, 0 );
	if ( pid == 0 )
	{
		if ( !mounted )
		{
			struct rlimit limit = { 20000, 20000 };
			setrlimit( RLIMIT_FSIZE, &limit );
		}
		dup2( pipe_fd[1], 2 );
		close( pipe_fd[0] );
		freopen( "/dev/null", "w", stdout );
		execl( sere_test_bin(), sere_test_bin(), "run", "data/leaves/wisteria.leaf", "--points", "300", "--frames",
			   "200", "--every", "1", "--out", dir, (char*) NULL );
		_exit( 127 );
	}
	close( pipe_fd[1] );
	size_t used = 0;
	ssize_t got;
	while ( used + 1 < sizeof( err ) && ( got = read( pipe_fd[0], err + used, sizeof( err ) - 1 - used ) ) > 0 )
	{
		used += (size_t) got;
	}
	err[used] = '\0';
	close( pipe_fd[0] );
	int status;
	waitpid( pid, &status, 0 );
	cr_expect( WIFEXITED( status ) && WEXITSTATUS( status ) != 0, "exit status %d", status );
	const char* reason = strerror( mounted ? ENOSPC : EFBIG );
	cr_expect_not_null( strstr( err, "sere run: cannot write " ), "%s", err );
	cr_expect_not_null( strstr( err, "/frames/frame_" ), "the message does not name the file: %s", err );
	cr_expect_not_null( strstr( err, reason ), "expected '%s' in: %s", reason, err );
	sere_test_expect_one_line( "full disk", err );

	char path[512];
	snprintf( path, sizeof( path ), "%s/summary.json", dir );
	char* summary = read_text( path );
	cr_assert_not_null( summary, "no summary.json" );
	cr_expect( json_valid( summary ), "summary.json is not JSON:\n%s", summary );
	cr_expect_not_null( strstr( summary, "\"status\": \"error: cannot write " ), "%s", summary );
	cr_expect_not_null( strstr( summary, "\"frames_completed\": " ), "%s", summary );
	free( summary );

	/* every frame leaf.pvd lists is whole; no temporary file is left */
	snprintf( path, sizeof( path ), "%s/leaf.pvd", dir );
	char* pvd = read_text( path );
	int listed = 0;
	for ( const char* p = pvd; p != NULL && ( p = strstr( p, "file=\"" ) ) != NULL; ++p )
	{
		int frame = -1;
		sscanf( p, "file=\"frames/frame_%d.vtp\"", &frame );
		cr_assert_geq( frame, 0 );
		snprintf( path, sizeof( path ), "%s/frames/frame_%05d.ply", dir, frame );
		expect_whole_ply( path );
		listed += 1;
	}
	free( pvd );
	if ( mounted )
	{
		cr_expect_gt( listed, 1, "the disk should have held a few frames" );
	}
	char command[1024];
	snprintf( command, sizeof( command ), "ls %s %s/frames | grep -c '\\.tmp$'", dir, dir );
	FILE* pipe = popen( command, "r" );
	int tmp_count = -1;
	cr_expect_eq( fscanf( pipe, "%d", &tmp_count ), 1 );
	pclose( pipe );
	cr_expect_eq( tmp_count, 0, "temporary files left behind" );
	if ( mounted )
	{
		cr_expect_eq( umount( dir ), 0 );
	}
	sere_test_scratch_remove( dir );
}
