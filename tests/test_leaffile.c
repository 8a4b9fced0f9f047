#define _POSIX_C_SOURCE 200809L
#include "read/leaffile.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char* const shipped[] = { "maple", "plane",   "wisteria", "hibiscus",	"ginkgo",
									   "grass", "hickory", "cucumber", "watermelon" };
#define SHIPPED_COUNT ( sizeof( shipped ) / sizeof( shipped[0] ) )

static double distance_to_outline( const sere_leaf_shape* s, const double* p )
{
	double best = INFINITY;
	for ( int32_t i = 0; i < s->outline_count; ++i )
	{
		const double* a = s->outline_xy + 2 * i;
		const double* b = s->outline_xy + 2 * ( ( i + 1 ) % s->outline_count );
		double ex = b[0] - a[0], ey = b[1] - a[1], l2 = ex * ex + ey * ey;
		double t = l2 > 0.0 ? fmin( 1.0, fmax( 0.0, ( ( p[0] - a[0] ) * ex + ( p[1] - a[1] ) * ey ) / l2 ) ) : 0.0;
		best = fmin( best, hypot( a[0] + t * ex - p[0], a[1] + t * ey - p[1] ) );
	}
	return best;
}

Test( leaffile, shipped_leaves_load_and_validate )
{
	for ( size_t k = 0; k < SHIPPED_COUNT; ++k )
	{
		char path[256], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", shipped[k] );
		sere_leaf_file leaf;
		cr_assert_eq( sere_leaf_file_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
		const sere_leaf_shape* s = &leaf.shape;
		cr_expect_str_eq( leaf.name, shipped[k] );
		cr_expect_geq( s->outline_count, 500, "%s: a dense outline", shipped[k] );
		cr_expect_gt( s->vein_count, 0, "%s has veins", shipped[k] );
		cr_expect_gt( sere_shape_area( s ), 0.0, "%s counter-clockwise", shipped[k] );
		/* The generator makes the base the first outline point, exactly. */
		cr_expect( s->base_x == s->outline_xy[0] && s->base_y == s->outline_xy[1], "%s: base is outline point 0",
				   shipped[k] );
		sere_shape_check check;
		cr_expect_eq( sere_shape_validate( s, &check ), SERE_OK, "%s", sere_shape_problem_text( check.problem ) );
		cr_expect_eq( s->veins[0].order, 1, "%s: vein 0 is the midvein", shipped[k] );
		/* Every vein ends well inside: the generator keeps 2% of the leaf (grass, whose blade
		 * is 7% wide, 0.6%); 0.005 leaves room for the 6-decimal rounding. */
		for ( int32_t v = 0; v < s->vein_count; ++v )
		{
			const double* end = s->vein_xy + 2 * ( s->veins[v].first + s->veins[v].count - 1 );
			cr_expect_gt( distance_to_outline( s, end ), 0.005, "%s vein %d ends at the margin", shipped[k], v );
		}
		sere_leaf_file_destroy( &leaf );
	}
}

Test( leaffile, table1_leaves_suit_their_point_counts )
{
	/* perimeter^2 / area aimed at by the generator so that outline and interior spacing agree
	 * at Table 1's counts (the lead's targets, +-20%). */
	const struct
	{
		const char* name;
		double target;
	} cases[] = { { "maple", 150.0 }, { "plane", 25.0 }, { "wisteria", 18.0 } };
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		char path[256], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", cases[k].name );
		sere_leaf_file leaf;
		cr_assert_eq( sere_leaf_file_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
		double p = sere_shape_perimeter( &leaf.shape ), a = sere_shape_area( &leaf.shape );
		cr_expect_geq( p * p / a, 0.8 * cases[k].target, "%s: %.1f", cases[k].name, p * p / a );
		cr_expect_leq( p * p / a, 1.2 * cases[k].target, "%s: %.1f", cases[k].name, p * p / a );
		sere_leaf_file_destroy( &leaf );
	}
}

static void expect_same( const sere_leaf_file* a, const sere_leaf_file* b, const char* what )
{
	const sere_leaf_shape* s = &a->shape;
	const sere_leaf_shape* t = &b->shape;
	cr_expect_str_eq( a->name, b->name, "%s", what );
	cr_expect( memcmp( &s->base_x, &t->base_x, sizeof( double ) ) == 0 &&
				   memcmp( &s->base_y, &t->base_y, sizeof( double ) ) == 0,
			   "%s: base", what );
	cr_assert_eq( s->outline_count, t->outline_count, "%s", what );
	cr_assert_eq( s->vein_count, t->vein_count, "%s", what );
	cr_assert_eq( s->vein_point_count, t->vein_point_count, "%s", what );
	cr_expect_eq( memcmp( s->outline_xy, t->outline_xy, sizeof( double ) * 2 * (size_t) s->outline_count ), 0,
				  "%s: outline", what );
	cr_expect_eq( memcmp( s->vein_xy, t->vein_xy, sizeof( double ) * 2 * (size_t) s->vein_point_count ), 0,
				  "%s: vein points", what );
	cr_expect_eq( memcmp( s->veins, t->veins, sizeof( sere_vein ) * (size_t) s->vein_count ), 0, "%s: veins", what );
}

static void temporary_path( char* path, size_t size, const char* stem )
{
	snprintf( path, size, "/tmp/sere-leaffile-%s-%ld.leaf", stem, (long) getpid() );
}

Test( leaffile, write_then_read_gives_identical_arrays )
{
	for ( size_t k = 0; k < SHIPPED_COUNT; ++k )
	{
		char path[256], copy[256], err[1024];
		snprintf( path, sizeof( path ), "data/leaves/%s.leaf", shipped[k] );
		temporary_path( copy, sizeof( copy ), shipped[k] );
		sere_leaf_file leaf, again;
		cr_assert_eq( sere_leaf_file_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
		cr_assert_eq( sere_leaf_file_write( copy, &leaf.shape, leaf.name, err, sizeof( err ) ), SERE_OK, "%s", err );
		cr_assert_eq( sere_leaf_file_read( copy, &again, err, sizeof( err ) ), SERE_OK, "%s", err );
		expect_same( &leaf, &again, shipped[k] );
		sere_leaf_file_destroy( &leaf );
		sere_leaf_file_destroy( &again );
		remove( copy );
	}
}

Test( leaffile, round_trip_is_exact_for_any_double )
{
	/* Values with no short decimal form: the writer must print enough digits for each. */
	const double t = 1.0 / 3.0, r = sqrt( 2.0 ) / 7.0;
	double outline[10] = { 0.0, 0.0, 1.0 + t, 1e-17, 1.5, r, 1.0 - r * r, 0.9 + t, -0.1 / 3.0, 0.5 + 1e-13 };
	/* Vein 1 starts exactly where vein 0 ends. */
	double points[8] = { 0.0,		  0.0,	   0.4 + 1e-12,			  0.3 * t,
						 0.4 + 1e-12, 0.3 * t, 0.5 * ( 1.4 - r * r ), 0.5 * ( 0.9 + 1.3 * t ) };
	sere_vein vein[2] = { { 0, 2, 1, -1 }, { 2, 2, 2, 0 } };
	sere_leaf_shape shape = { .base_x = 0.0,
							  .base_y = 0.0,
							  .outline_count = 5,
							  .outline_xy = outline,
							  .vein_count = 2,
							  .veins = vein,
							  .vein_point_count = 4,
							  .vein_xy = points };
	sere_shape_check check;
	cr_assert_eq( sere_shape_validate( &shape, &check ), SERE_OK, "%s", sere_shape_problem_text( check.problem ) );
	char path[256], err[1024];
	temporary_path( path, sizeof( path ), "exact" );
	cr_assert_eq( sere_leaf_file_write( path, &shape, "a leaf with spaces", err, sizeof( err ) ), SERE_OK, "%s", err );
	sere_leaf_file again;
	cr_assert_eq( sere_leaf_file_read( path, &again, err, sizeof( err ) ), SERE_OK, "%s", err );
	cr_expect_str_eq( again.name, "a leaf with spaces" );
	cr_expect_eq( memcmp( again.outline_xy, outline, sizeof( outline ) ), 0 );
	cr_expect_eq( memcmp( again.vein_xy, points, sizeof( points ) ), 0 );
	cr_expect_eq( memcmp( again.veins, vein, sizeof( vein ) ), 0 );
	sere_leaf_file_destroy( &again );
	remove( path );
}

Test( leaffile, writer_refuses_what_the_reader_would_not_return )
{
	double clockwise[8] = { 0, 0, 0, 1, 1, 1, 1, 0 };
	double square[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };
	sere_leaf_shape shape = { .outline_count = 4, .outline_xy = clockwise };
	char path[256], err[1024];
	temporary_path( path, sizeof( path ), "refused" );
	remove( path );
	cr_expect_eq( sere_leaf_file_write( path, &shape, "cw", err, sizeof( err ) ), SERE_ERR_GEOMETRY );
	cr_expect_not_null( strstr( err, "counter-clockwise" ), "%s", err );
	shape.outline_xy = square;
	const char* names[] = { "a#b", "two\nlines", " padded", "padded ", "tab\tinside" };
	for ( size_t k = 0; k < sizeof( names ) / sizeof( names[0] ); ++k )
	{
		cr_expect_eq( sere_leaf_file_write( path, &shape, names[k], err, sizeof( err ) ), SERE_ERR_ARGUMENT, "'%s'",
					  names[k] );
		cr_expect_not_null( strstr( err, path ), "%s", err );
	}
	cr_expect_neq( access( path, F_OK ), 0, "nothing written" );
	/* No name: the reader falls back to the file name. */
	cr_assert_eq( sere_leaf_file_write( path, &shape, NULL, err, sizeof( err ) ), SERE_OK, "%s", err );
	char tmp[300];
	snprintf( tmp, sizeof( tmp ), "%s.tmp", path );
	cr_expect_neq( access( tmp, F_OK ), 0, "the temporary was renamed" );
	sere_leaf_file again;
	cr_assert_eq( sere_leaf_file_read( path, &again, err, sizeof( err ) ), SERE_OK, "%s", err );
	char stem[256];
	snprintf( stem, sizeof( stem ), "sere-leaffile-refused-%ld", (long) getpid() );
	cr_expect_str_eq( again.name, stem );
	sere_leaf_file_destroy( &again );
	remove( path );
}

Test( leaffile, reads_comments_blanks_tabs_crlf_and_any_order )
{
	/* A byte order mark, CRLF ends, tabs, comments after values, the vein before the outline. */
	const char* text = "\xEF\xBB\xBF# a hand-written leaf\r\n"
					   "name  oak  leaf   # trailing comment\r\n"
					   "\r\n"
					   "vein\t1 -1 2\r\n"
					   "0 0\r\n"
					   "  0.5\t0.5   # mid\r\n"
					   "base 0 0\r\n"
					   "outline 4\r\n"
					   "0 0\r\n"
					   "1e0 0\r\n"
					   "1 +1\r\n"
					   "0 1\r\n";
	char path[256], err[1024];
	temporary_path( path, sizeof( path ), "free" );
	FILE* f = fopen( path, "wb" );
	cr_assert_not_null( f );
	fputs( text, f );
	fclose( f );
	sere_leaf_file leaf;
	cr_assert_eq( sere_leaf_file_read( path, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
	cr_expect_str_eq( leaf.name, "oak  leaf" );
	const double outline[8] = { 0, 0, 1, 0, 1, 1, 0, 1 }, vein[4] = { 0, 0, 0.5, 0.5 };
	cr_expect_eq( leaf.shape.outline_count, 4 );
	cr_expect_eq( memcmp( leaf.outline_xy, outline, sizeof( outline ) ), 0 );
	cr_expect_eq( memcmp( leaf.vein_xy, vein, sizeof( vein ) ), 0 );
	cr_expect_eq( leaf.outline_line[0], 9, "source lines are kept for messages" );
	cr_expect_eq( leaf.vein_line[1], 6 );
	sere_leaf_file_destroy( &leaf );
	remove( path );
}

Test( leaffile, bad_inputs_name_the_file_the_line_and_the_problem )
{
	const struct
	{
		const char* file;
		int line; /* 0: no line in the message */
		const char* phrase;
		sere_status status;
	} cases[] = {
		{ "count_too_large", 9, "the count on line 4 is larger than the points given", SERE_ERR_ARGUMENT },
		{ "count_too_small", 7, "the outline on line 3 has more points than its count (3)", SERE_ERR_ARGUMENT },
		{ "non_numeric", 4, "non-numeric value 'zero' in outline point 2", SERE_ERR_ARGUMENT },
		{ "nan", 5, "NaN or infinite coordinate 'nan' in outline point 3", SERE_ERR_NONFINITE },
		{ "inf", 5, "NaN or infinite coordinate '-inf' in outline point 3", SERE_ERR_NONFINITE },
		{ "overflow", 4, "'1e999' in outline point 2 is too large", SERE_ERR_NONFINITE },
		{ "three_numbers", 4, "outline point 2 must be two numbers 'x y'", SERE_ERR_ARGUMENT },
		{ "few_points", 2, "outline has fewer than 3 points (2)", SERE_ERR_GEOMETRY },
		{ "self_intersecting", 7,
		  "outline intersects itself: the edge from line 6 to line 7 meets the edge from line 4 to line 5",
		  SERE_ERR_GEOMETRY },
		{ "clockwise", 2, "outline must be counter-clockwise", SERE_ERR_GEOMETRY },
		{ "repeated_point", 8, "must not repeat its first point at the end", SERE_ERR_GEOMETRY },
		{ "base_off_outline", 1, "base does not lie on the outline", SERE_ERR_GEOMETRY },
		{ "vein_outside", 10, "vein point outside the outline (vein 0, point 3)", SERE_ERR_GEOMETRY },
		{ "vein_crosses_outline", 15,
		  "vein 0 crosses the outline: its segment from line 14 to line 15 meets the outline edge from line 7 to "
		  "line 8",
		  SERE_ERR_GEOMETRY },
		{ "vein_disconnected", 8, "vein 0 not connected to the base: a vein without parent (-1) must start at the base",
		  SERE_ERR_GEOMETRY },
		{ "branch_disconnected", 11, "vein 1 not connected to the base: its first point must lie on its parent, vein 0",
		  SERE_ERR_GEOMETRY },
		{ "veins_cross", 13, "veins cross or touch", SERE_ERR_GEOMETRY },
		{ "bad_parent", 7, "vein 0: PARENT 3 must be -1", SERE_ERR_ARGUMENT },
		{ "unknown_keyword", 2, "unknown keyword 'stem'", SERE_ERR_ARGUMENT },
		{ "truncated", 5, "file ends after 2 of 4 outline points", SERE_ERR_ARGUMENT },
		{ "missing_base", 6, "file ends without a 'base X Y' line", SERE_ERR_ARGUMENT },
		{ "second_outline", 7, "a second 'outline' (the first is on line 2)", SERE_ERR_ARGUMENT },
		{ "long_line", 4, "line longer than 1022 characters", SERE_ERR_ARGUMENT },
		{ "empty", 0, "file is empty", SERE_ERR_ARGUMENT },
		{ "does_not_exist", 0, "cannot open: No such file or directory", SERE_ERR_ARGUMENT },
	};
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		char path[256], where[300], err[1024];
		snprintf( path, sizeof( path ), "tests/data/bad/%s.leaf", cases[k].file );
		if ( cases[k].line > 0 )
		{
			snprintf( where, sizeof( where ), "%s:%d: ", path, cases[k].line );
		}
		else
		{
			snprintf( where, sizeof( where ), "%s: ", path );
		}
		sere_leaf_file leaf;
		memset( err, 0, sizeof( err ) );
		sere_status status = sere_leaf_file_read( path, &leaf, err, sizeof( err ) );
		cr_expect_eq( status, cases[k].status, "%s: status %d: %s", cases[k].file, (int) status, err );
		cr_expect_eq( strncmp( err, where, strlen( where ) ), 0, "expected '%s' to start: %s", where, err );
		cr_expect_not_null( strstr( err, cases[k].phrase ), "expected '%s' in: %s", cases[k].phrase, err );
		cr_expect_null( strchr( err, '\n' ), "one line: %s", err );
		/* Nothing is left to free after a failure. */
		cr_expect( leaf.outline_xy == NULL && leaf.vein_xy == NULL && leaf.veins == NULL, "%s", cases[k].file );
	}
}

Test( leaffile, a_short_error_buffer_is_not_overrun )
{
	char err[16];
	memset( err, 'x', sizeof( err ) );
	sere_leaf_file leaf;
	cr_expect_neq( sere_leaf_file_read( "tests/data/bad/veins_cross.leaf", &leaf, err, 8 ), SERE_OK );
	cr_expect_eq( strlen( err ), 7u );
	cr_expect_eq( err[8], 'x' );
}

/* ---- the shape validator ------------------------------------------------------------------ */

static sere_shape_problem problem_of( const double* outline, int32_t n, const double* vein_xy, const sere_vein* veins,
									  int32_t vein_count, sere_shape_check* check )
{
	int32_t points = 0;
	for ( int32_t v = 0; v < vein_count; ++v )
	{
		points = veins[v].first + veins[v].count > points ? veins[v].first + veins[v].count : points;
	}
	sere_leaf_shape shape = { .base_x = outline[0],
							  .base_y = outline[1],
							  .outline_count = n,
							  .outline_xy = outline,
							  .vein_count = vein_count,
							  .veins = veins,
							  .vein_point_count = points,
							  .vein_xy = vein_xy };
	sere_shape_validate( &shape, check );
	return check->problem;
}

static const double unit_square[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };

Test( shape, branches_may_meet_their_parent_and_siblings_only_where_they_start )
{
	sere_shape_check check;
	/* Midvein up the middle; two siblings leave one midvein vertex, a third leaves the middle of
	 * a segment (not a vertex), and a vein from the base leaves beside the midvein. Binary
	 * fractions, so that touching is exact. */
	double square_with_base[10] = { 0.5, 0, 1, 0, 1, 1, 0, 1, 0, 0 };
	double xy[] = { 0.5, 0,		0.5,   0.375, 0.5, 0.75, /* vein 0 */
					0.5, 0.375, 0.75,  0.625,			 /* vein 1 */
					0.5, 0.375, 0.25,  0.625,			 /* vein 2 */
					0.5, 0.5,	0.75,  0.875,			 /* vein 3: from the middle of a segment */
					0.5, 0,		0.875, 0.25 };			 /* vein 4: from the base */
	sere_vein veins[5] = { { 0, 3, 1, -1 }, { 3, 2, 2, 0 }, { 5, 2, 2, 0 }, { 7, 2, 2, 0 }, { 9, 2, 2, -1 } };
	cr_expect_eq( problem_of( square_with_base, 5, xy, veins, 5, &check ), SERE_SHAPE_OK, "%s at point %d",
				  sere_shape_problem_text( check.problem ), check.point );

	/* Vein 4 now ends on vein 1: touching anywhere but a vein's own start is refused. */
	double touching[22];
	memcpy( touching, xy, sizeof( xy ) );
	touching[20] = 0.625, touching[21] = 0.5;
	cr_expect_eq( problem_of( square_with_base, 5, touching, veins, 5, &check ), SERE_SHAPE_VEINS_CROSS );
	cr_expect_eq( check.vein, 4 );
	cr_expect_eq( check.point, 10 );
	cr_expect_eq( check.other, 4, "the segment of vein 1 it meets ends at point 4" );

	/* A first segment running along its parent is not a branch. */
	double along[] = { 0.5, 0, 0.5, 0.8, 0.5, 0.2, 0.5, 0.5 };
	sere_vein along_veins[2] = { { 0, 2, 1, -1 }, { 2, 2, 2, 0 } };
	cr_expect_eq( problem_of( square_with_base, 5, along, along_veins, 2, &check ), SERE_SHAPE_VEINS_CROSS );

	/* A vein folding back onto itself. */
	double fold[] = { 0.5, 0, 0.5, 0.8, 0.5, 0.4 };
	sere_vein fold_vein[1] = { { 0, 3, 1, -1 } };
	cr_expect_eq( problem_of( square_with_base, 5, fold, fold_vein, 1, &check ), SERE_SHAPE_VEINS_CROSS );
	/* A repeated vein point. */
	double twice[] = { 0.5, 0, 0.5, 0.4, 0.5, 0.4, 0.5, 0.8 };
	sere_vein twice_vein[1] = { { 0, 4, 1, -1 } };
	cr_expect_eq( problem_of( square_with_base, 5, twice, twice_vein, 1, &check ), SERE_SHAPE_REPEATED_POINT );
	cr_expect_eq( check.vein, 0 );
	cr_expect_eq( check.point, 2 );
}

Test( shape, outlines_that_touch_themselves_are_not_simple )
{
	sere_shape_check check;
	/* Two squares sharing the vertex (1, 1): a figure eight through one point. */
	double eight[14] = { 0, 0, 1, 0, 1, 1, 2, 1, 2, 2, 1, 2, 1, 1 };
	cr_expect_eq( problem_of( eight, 7, NULL, NULL, 0, &check ), SERE_SHAPE_SELF_INTERSECTING );
	/* Named by their ends: the later edge (1 2)-(1 1) ends at point 6, the earlier (1 0)-(1 1) at 2. */
	cr_expect_eq( check.point, 6 );
	cr_expect_eq( check.other, 2 );
	/* Pulled apart at that point, it is simple. */
	double apart[16] = { 0, 0, 1, 0, 1, 1, 2, 1, 2, 2, 1.5, 2, 1, 2, 1, 1.5 };
	cr_expect_eq( problem_of( apart, 8, NULL, NULL, 0, &check ), SERE_SHAPE_OK, "%s",
				  sere_shape_problem_text( check.problem ) );
	/* A vertex lying on a non-adjacent edge. */
	double pinch[10] = { 0, 0, 2, 0, 2, 2, 1, 0, 0, 2 };
	cr_expect_eq( problem_of( pinch, 5, NULL, NULL, 0, &check ), SERE_SHAPE_SELF_INTERSECTING );
	/* A degenerate triangle. */
	double flat[6] = { 0, 0, 2, 0, 1, 0 };
	cr_expect_eq( problem_of( flat, 3, NULL, NULL, 0, &check ), SERE_SHAPE_SELF_INTERSECTING );
	/* Clockwise is reported as such, not as a self-intersection. */
	double cw[8] = { 0, 0, 0, 1, 1, 1, 1, 0 };
	cr_expect_eq( problem_of( cw, 4, NULL, NULL, 0, &check ), SERE_SHAPE_CLOCKWISE );
	cr_expect_eq( problem_of( unit_square, 4, NULL, NULL, 0, &check ), SERE_SHAPE_OK );
}

/* A star-like polygon with jittered angles and radii: simple for small jitter, often not for
 * large (a point stepping back past its neighbour). */
static double next_uniform( uint32_t* state )
{
	*state = *state * 1664525u + 1013904223u;
	return ( *state >> 8 ) / 16777216.0;
}

static void jittered_star( double* xy, int32_t n, double jitter, uint32_t* state )
{
	for ( int32_t i = 0; i < n; ++i )
	{
		double a = 2.0 * 3.14159265358979323846 * ( i + 3.0 * jitter * ( next_uniform( state ) - 0.5 ) ) / n;
		double r = 1.0 + 0.3 * sin( 5.0 * a ) + jitter * ( next_uniform( state ) - 0.5 );
		xy[2 * i] = r * cos( a );
		xy[2 * i + 1] = r * sin( a );
	}
}

static int brute_force_simple( const double* xy, int32_t n )
{
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t j = i + 1; j < n; ++j )
		{
			const double *a = xy + 2 * i, *b = xy + 2 * ( ( i + 1 ) % n ), *c = xy + 2 * j,
						 *d = xy + 2 * ( ( j + 1 ) % n );
			if ( j == i + 1 || ( i == 0 && j == n - 1 ) )
			{
				continue; /* the star never folds back on an adjacent edge */
			}
			double o1 = ( b[0] - a[0] ) * ( c[1] - a[1] ) - ( b[1] - a[1] ) * ( c[0] - a[0] );
			double o2 = ( b[0] - a[0] ) * ( d[1] - a[1] ) - ( b[1] - a[1] ) * ( d[0] - a[0] );
			double o3 = ( d[0] - c[0] ) * ( a[1] - c[1] ) - ( d[1] - c[1] ) * ( a[0] - c[0] );
			double o4 = ( d[0] - c[0] ) * ( b[1] - c[1] ) - ( d[1] - c[1] ) * ( b[0] - c[0] );
			if ( ( ( o1 > 0 ) != ( o2 > 0 ) ) && ( ( o3 > 0 ) != ( o4 > 0 ) ) )
			{
				return 0;
			}
		}
	}
	return 1;
}

Test( shape, grid_search_agrees_with_all_pairs )
{
	/* The uniform grid must find every crossing an all-pairs search finds, and no other. */
	uint32_t state = 12345u;
	int simple = 0, crossed = 0;
	for ( int trial = 0; trial < 60; ++trial )
	{
		int32_t n = 50 + 37 * ( trial % 7 );
		double* xy = malloc( sizeof( double ) * 2 * (size_t) n );
		jittered_star( xy, n, 0.02 + 1.0 * ( trial % 5 ) / 4.0, &state );
		sere_shape_check check;
		sere_shape_problem p = problem_of( xy, n, NULL, NULL, 0, &check );
		int expect_simple = brute_force_simple( xy, n );
		cr_expect_eq( p == SERE_SHAPE_SELF_INTERSECTING, !expect_simple, "trial %d: %s", trial,
					  sere_shape_problem_text( p ) );
		simple += expect_simple;
		crossed += !expect_simple;
		free( xy );
	}
	cr_expect( simple > 10 && crossed > 10, "both kinds tried: %d simple, %d crossed", simple, crossed );
}
