/* sere fuzz — the venation skeleton reader of `sere wilt` (harness/cli/cmd_wilt_skelfile.c,
 * wilt_skeleton_load; data/skeletons/cucumber.skel describes the format).
 *
 * build_leaf and the options are static, so this file compiles cmd_wilt.c itself (the library's
 * copy is then not linked; the reader comes from the library). Every input goes the way
 * `sere wilt FILE` takes it up to the first frame: the command's default options, then
 * build_leaf (the file, the leaf skeleton's checks, the blade mesh, one subdivision, the
 * venation skeleton from the file's veins or generated). */
#define _GNU_SOURCE
#include "fuzz.h"

#include "../harness/cli/cmd_wilt.c"

int LLVMFuzzerInitialize( int* argc, char*** argv )
{
	(void) argc, (void) argv;
	fuzz_quiet();
	return 0;
}

int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size )
{
	char command[] = "wilt", path[64];
	snprintf( path, sizeof( path ), "%s", fuzz_file( data, size ) );
	char* argv[] = { command, path, NULL };
	wilt_options o;
	FUZZ_CHECK( parse_options( 2, argv, &o ) == SERE_OPTIONS_GO );
	wilt_run r;
	memset( &r, 0, sizeof( r ) );
	double leaf_length = 0.0;
	if ( build_leaf( &o, &r, &leaf_length ) == 0 )
	{
		FUZZ_CHECK( isfinite( leaf_length ) && leaf_length > 0.0 );
		FUZZ_CHECK( r.mesh.triangle_count > 0 && r.skeleton.joint_count > 0 );
	}
	wilt_run_free( &r );
	return 0;
}
