/* The version a user can trust: sere_version() is the VERSION file the library was built from,
 * sere_simd_path() names the path the compiler flags chose, and `sere --version` prints both
 * (with the commit) and exits 0. Run from the repository root, as make test does. */
#define _DEFAULT_SOURCE
#include "core/base.h"
#include "core/internal/simd.h"
#include "fixture.h"

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The first line of VERSION, without its newline. */
static void read_version_file( char* version, size_t size )
{
	FILE* f = fopen( "VERSION", "r" );
	cr_assert_not_null( f, "VERSION not found: run the tests from the repository root" );
	cr_assert_not_null( fgets( version, (int) size, f ) );
	fclose( f );
	version[strcspn( version, "\r\n" )] = '\0';
}

Test( version, library_reports_the_version_file )
{
	char expected[64];
	read_version_file( expected, sizeof( expected ) );
	const char* version = sere_version();
	cr_assert_not_null( version );
	cr_expect_str_eq( version, expected );
	/* MAJOR.MINOR.PATCH, each a whole number */
	int major = -1, minor = -1, patch = -1, used = 0;
	cr_expect_eq( sscanf( version, "%d.%d.%d%n", &major, &minor, &patch, &used ), 3, "'%s'", version );
	cr_expect_eq( (size_t) used, strlen( version ), "'%s' has a tail", version );
	cr_expect( major >= 0 && minor >= 0 && patch >= 0 );
}

Test( version, simd_path_names_the_kernels_lane_width )
{
	const char* path = sere_simd_path();
	cr_assert_not_null( path );
	/* the name of the lane width the kernels' lane layer picked, not of the flags alone: an AVX
	 * build, or AVX2 without FMA, runs the portable 4-lane body */
	const char* expected = SERE_LANES == 16 ? "AVX-512" : SERE_LANES == 8 ? "AVX2" : "portable";
	/* the tests are compiled with the library's ARCH, so they must agree */
	cr_expect_str_eq( path, expected );
}

Test( version, command_prints_version_commit_and_simd_path )
{
	char out[4096];
	int status = sere_test_stdout( "--version", out, sizeof( out ) );
	cr_assert_eq( status, 0, "sere --version exited with %d", status );

	char version[64], line[128];
	read_version_file( version, sizeof( version ) );
	snprintf( line, sizeof( line ), "sere %s\n", version );
	cr_expect_eq( strncmp( out, line, strlen( line ) ), 0, "first line should be '%s', output: %s", version, out );
	cr_expect_not_null( strstr( out, "\ncommit: " ), "%s", out );
	snprintf( line, sizeof( line ), "\nsimd: %s\n", sere_simd_path() );
	cr_expect_not_null( strstr( out, line ), "expected '%s' in: %s", sere_simd_path(), out );
}

Test( version, help_documents_version_and_sere_data )
{
	char out[8192];
	cr_assert_eq( sere_test_stdout( "--help", out, sizeof( out ) ), 0 );
	cr_expect_not_null( strstr( out, "--version" ), "%s", out );
	cr_expect_not_null( strstr( out, "SERE_DATA" ), "%s", out );
}
