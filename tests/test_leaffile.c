#define _DEFAULT_SOURCE
#include "leaffile.h"

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char* const square = "outline 4\n0 0\n1 0\n1 1\n0 1\n";

/* Writes text to a fresh file, reads it, and expects failure with "PATH:LINE:" and phrase. */
static void expect_bad( const char* text, int line, const char* phrase )
{
	char path[] = "/tmp/sere-leaf-XXXXXX";
	int fd = mkstemp( path );
	cr_assert_geq( fd, 0 );
	FILE* f = fdopen( fd, "w" );
	fputs( text, f );
	fclose( f );
	sere_leaf_file leaf;
	char err[1024];
	cr_expect_neq( sere_leaf_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "accepted: %s", text );
	char where[128];
	if ( line > 0 )
	{
		snprintf( where, sizeof( where ), "%s:%d: ", path, line );
	}
	else
	{
		snprintf( where, sizeof( where ), "%s: ", path );
	}
	cr_expect_eq( strncmp( err, where, strlen( where ) ), 0, "expected '%s' at the start of: %s", where, err );
	cr_expect_not_null( strstr( err, phrase ), "expected '%s' in: %s", phrase, err );
	cr_expect_null( strchr( err, '\n' ), "one line: %s", err );
	remove( path );
}

Test( leaffile, bad_inputs_name_file_line_and_problem )
{
	char text[1024];
	/* wrong count: the vein keyword arrives where the fourth point should be */
	expect_bad( "name x\nbase 0 0\noutline 4\n0 0\n1 0\n1 1\nvein 1 -1 2\n0 0\n0.5 0.5\n", 7, "non-numeric value" );
	expect_bad( "base 0 0\noutline 4\n0 0\n1 zero\n1 1\n0 1\n", 4, "non-numeric value in outline point 2" );
	expect_bad( "base 0 0\noutline 4\n0 0\n1 0\nnan 1\n0 1\n", 5, "NaN or infinite" );
	expect_bad( "base 0 0\noutline 4\n0 0\n1 0\n1 inf\n0 1\n", 5, "NaN or infinite" );
	expect_bad( "base 0 0\noutline 2\n0 0\n1 0\n", 2, "at least 3 points" );
	/* a bowtie: edges 0-1 and 2-3 cross */
	expect_bad( "base 0 0\noutline 4\n0 0\n1 1\n1 0\n0 1\n", 3, "intersects itself" );
	snprintf( text, sizeof( text ), "base 0 0\n%svein 1 -1 2\n0 0\n1.5 0.5\n", square );
	expect_bad( text, 9, "vein point outside the outline" );
	snprintf( text, sizeof( text ), "base 0 0\n%svein 1 -1 2\n0.2 0.2\n0.5 0.5\n", square );
	expect_bad( text, 8, "not connected to the base" );
	snprintf( text, sizeof( text ), "base 0 0\n%svein 1 -1 2\n0 0\n0.5 0.5\nvein 2 0 2\n0.2 0.6\n0.3 0.8\n", square );
	expect_bad( text, 11, "not connected to the base" );
	/* clockwise */
	expect_bad( "base 0 0\noutline 4\n0 0\n0 1\n1 1\n1 0\n", 3, "counter-clockwise" );
	expect_bad( "base 0 0\nstem 3\n", 2, "unknown keyword 'stem'" );
	expect_bad( "base 0 0\noutline 4\n0 0\n1 0\n", 4, "file ends after 2 of 4 outline points" );
	expect_bad( "outline 4\n0 0\n1 0\n1 1\n0 1\n", 0, "no base point" );
	expect_bad( "base 0.5 0.5\noutline 4\n0 0\n1 0\n1 1\n0 1\n", 1, "base does not lie on the outline" );

	sere_leaf_file leaf;
	char err[512];
	cr_expect_eq( sere_leaf_read( "/tmp/sere-no-such-leaf.leaf", &leaf, err, sizeof( err ) ), SERE_ERR_ARGUMENT );
	cr_expect_not_null( strstr( err, "/tmp/sere-no-such-leaf.leaf: cannot open" ), "%s", err );
}

Test( leaffile, shipped_leaves_load_and_round_trip )
{
	const char* names[] = { "maple", "plane",	"wisteria", "hibiscus",	 "ginkgo",
							"grass", "hickory", "cucumber", "watermelon" };
	for ( size_t k = 0; k < sizeof( names ) / sizeof( names[0] ); ++k )
	{
		char path[256], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", names[k] );
		sere_leaf_file leaf, again;
		cr_assert_eq( sere_leaf_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
		cr_expect_gt( leaf.shape.vein_count, 0, "%s has veins", names[k] );
		cr_expect_gt( sere_shape_area( &leaf.shape ), 0.0 );
		char copy[] = "/tmp/sere-roundtrip-XXXXXX";
		int fd = mkstemp( copy );
		cr_assert_geq( fd, 0 );
		close( fd );
		cr_assert_eq( sere_leaf_write( copy, &leaf.shape, leaf.name ), 0 );
		cr_assert_eq( sere_leaf_read( copy, &again, err, sizeof( err ) ), SERE_OK, "%s", err );
		/* %.9g keeps every double of the generator's 9-digit files exactly */
		cr_expect_eq( again.shape.outline_count, leaf.shape.outline_count );
		cr_expect_eq( memcmp( again.outline_xy, leaf.outline_xy, sizeof( double ) * 2 * leaf.shape.outline_count ), 0 );
		cr_expect_eq( memcmp( again.vein_xy, leaf.vein_xy, sizeof( double ) * 2 * leaf.shape.vein_point_count ), 0 );
		cr_expect_str_eq( again.name, leaf.name );
		sere_leaf_file_free( &leaf );
		sere_leaf_file_free( &again );
		remove( copy );
	}
}
