/* Seed 002 beyond its kernels: the L-system tree, the leaf built from key points and a mask map
 * with its deformation levels, and `sere season` as a user meets it (outputs, determinism across
 * thread counts, the sampled distribution against the exact one, bad input). */
#define _DEFAULT_SOURCE
#include "read/seasonleaf.h"
#include "season/lsystem.h"

#include "fixture.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

/* ------------------------------------------------------------------------------------------- */
/* L-system */

Test( lsystem, rewriting_follows_the_rules )
{
	const sere_lsystem_rule rules[] = { { 'A', "F[+A]-A" }, { 'F', "FF" } };
	sere_lsystem_params p = sere_lsystem_params_default();
	p.axiom = "A";
	p.rules = rules;
	p.rule_count = 2;
	p.iterations = 2;
	char* s = NULL;
	int64_t n = 0;
	cr_assert_eq( sere_lsystem_rewrite( &p, &s, &n ), SERE_OK );
	/* A → F[+A]-A → FF[+F[+A]-A]-F[+A]-A */
	cr_expect_str_eq( s, "FF[+F[+A]-A]-F[+A]-A" );
	cr_expect_eq( n, (int64_t) strlen( s ) );
	free( s );
	p.max_symbols = 10;
	cr_expect_eq( sere_lsystem_rewrite( &p, &s, &n ), SERE_ERR_CAPACITY );
	const sere_lsystem_rule twice[] = { { 'A', "F" }, { 'A', "FF" } };
	p.rules = twice;
	p.max_symbols = 1000;
	cr_expect_eq( sere_lsystem_rewrite( &p, &s, &n ), SERE_ERR_ARGUMENT );
}

Test( lsystem, default_tree_is_connected_and_deterministic )
{
	sere_lsystem_params p = sere_lsystem_params_default();
	sere_tree a, b;
	cr_assert_eq( sere_tree_grow( &p, &a ), SERE_OK );
	cr_assert_eq( sere_tree_grow( &p, &b ), SERE_OK );
	/* A → ![&FLA]/[&FLA]/[&FLA]: 3 + 9 + ... + 3^6 branches, each one segment and one leaf,
	 * plus the three trunk segments */
	int32_t branches = 0;
	for ( int32_t k = 1, w = 3; k <= p.iterations; ++k, w *= 3 )
	{
		branches += w;
	}
	cr_expect_eq( a.leaf_count, branches );
	cr_expect_eq( a.segment_count, branches + 3 );
	cr_expect_eq( a.max_depth, p.iterations );
	cr_expect_eq( memcmp( a.x0, b.x0, sizeof( float ) * 8 * (size_t) a.segment_count ), 0, "same seed, other tree" );
	cr_expect_eq( memcmp( a.leaf_x, b.leaf_x, sizeof( float ) * 9 * (size_t) a.leaf_count ), 0 );
	/* every segment starts at the origin or where an earlier segment ends (exactly: the turtle
	 * copies the end point) */
	for ( int32_t k = 0; k < a.segment_count; ++k )
	{
		int found = a.x0[k] == 0.0f && a.y0[k] == 0.0f && a.z0[k] == 0.0f;
		for ( int32_t j = 0; j < k && !found; ++j )
		{
			found = a.x1[j] == a.x0[k] && a.y1[j] == a.y0[k] && a.z1[j] == a.z0[k];
		}
		cr_assert( found, "segment %d floats free", k );
		cr_expect( a.r1[k] <= a.r0[k] && a.r1[k] > 0.0f, "segment %d radius %g -> %g", k, a.r0[k], a.r1[k] );
	}
	/* leaf frames: unit direction and normal, orthogonal (float rounding of unit vectors: 1e-5),
	 * the face turned to the sky, the blade drooping by the default 20 degrees */
	for ( int32_t k = 0; k < a.leaf_count; ++k )
	{
		double d[3] = { a.leaf_dirx[k], a.leaf_diry[k], a.leaf_dirz[k] },
			   n[3] = { a.leaf_nx[k], a.leaf_ny[k], a.leaf_nz[k] };
		cr_expect( fabs( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0 ) < 1e-5 );
		cr_expect( fabs( n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0 ) < 1e-5 );
		cr_expect( fabs( d[0] * n[0] + d[1] * n[1] + d[2] * n[2] ) < 1e-5 );
		cr_expect( n[2] > 0.9 && fabs( d[2] + sin( 20.0 * 3.14159265358979 / 180.0 ) ) < 1e-5 );
	}
	p.seed += 1;
	sere_tree c;
	cr_assert_eq( sere_tree_grow( &p, &c ), SERE_OK );
	cr_expect_neq( memcmp( a.x1, c.x1, sizeof( float ) * (size_t) a.segment_count ), 0, "the seed changes nothing" );
	sere_tree_destroy( &a ), sere_tree_destroy( &b ), sere_tree_destroy( &c );
}

Test( lsystem, bad_grammars_are_refused )
{
	sere_lsystem_params p = sere_lsystem_params_default();
	sere_tree t;
	p.axiom = "F[A";
	cr_expect_eq( sere_tree_grow( &p, &t ), SERE_ERR_GEOMETRY );
	p.axiom = "F]A[";
	cr_expect_eq( sere_tree_grow( &p, &t ), SERE_ERR_GEOMETRY );
	p = sere_lsystem_params_default();
	p.length_ratio = 1.5;
	cr_expect_eq( sere_tree_grow( &p, &t ), SERE_ERR_ARGUMENT );
	p = sere_lsystem_params_default();
	p.radius = NAN;
	cr_expect_eq( sere_tree_grow( &p, &t ), SERE_ERR_ARGUMENT );
	p = sere_lsystem_params_default();
	p.iterations = -1;
	cr_expect_eq( sere_tree_grow( &p, &t ), SERE_ERR_ARGUMENT );
}

/* ------------------------------------------------------------------------------------------- */
/* The leaf */

static double signed_area( const float* xyz, const int32_t* q )
{
	const float *a = xyz + 3 * q[0], *b = xyz + 3 * q[1], *c = xyz + 3 * q[2];
	return 0.5 * ( ( b[0] - a[0] ) * ( c[1] - a[1] ) - ( c[0] - a[0] ) * ( b[1] - a[1] ) );
}

Test( seasonleaf, maple_from_key_points_and_mask, .timeout = 60 )
{
	sere_season_leaf_options o = sere_season_leaf_options_default();
	o.outline_samples = 64;
	sere_season_leaf leaf;
	char err[512];
	cr_assert_eq( sere_season_leaf_build( &o, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
	cr_expect_eq( leaf.level_count, 4 );
	cr_expect_gt( leaf.vertex_count, o.outline_samples, "meshopt added no interior vertices" );
	const int32_t n = leaf.vertex_count;
	double area = 0.0, extent = 0.0, lo = 1.0, hi = 0.0;
	for ( int32_t t = 0; t < leaf.triangle_count; ++t )
	{
		double a = signed_area( leaf.xyz, leaf.tri + 3 * t );
		cr_expect_gt( a, 0.0, "triangle %d is not counter-clockwise at level 0", t );
		area += a;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		cr_expect_eq( leaf.xyz[3 * i + 2], 0.0f, "level 0 is not flat" );
		extent = fmax( extent, hypot( leaf.xyz[3 * i], leaf.xyz[3 * i + 1] ) );
		lo = fmin( lo, leaf.mass[i] ), hi = fmax( hi, leaf.mass[i] );
		cr_expect( leaf.u[i] >= 0.0f && leaf.u[i] <= 1.0f && leaf.v[i] >= 0.0f && leaf.v[i] <= 1.0f );
	}
	/* 1 long from the petiole (the spline between key points may bulge past the farthest key
	 * point by a little: 3%) */
	cr_expect( extent > 0.97 && extent < 1.03, "extent %g", extent );
	cr_expect( area > 0.1, "area %g", area );
	/* the maple mask is dark (gray 20/255) at the lobe corners and the petiole, bright elsewhere
	 * (Fig. 3b); Tang Eq. 3's logarithm maps 20/255 to 0.59 and white to 1. No vertex samples the
	 * black outside the painted leaf (that would give 0.1). Near the petiole the blade is
	 * lighter than on average. */
	cr_expect( lo > 0.5 && lo < 0.7 && hi > 0.9, "masses %g..%g", lo, hi );
	double near = 0.0, all = 0.0;
	int32_t near_count = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		all += leaf.mass[i] / n;
		if ( hypot( leaf.xyz[3 * i], leaf.xyz[3 * i + 1] ) < 0.1 )
		{
			near += leaf.mass[i], near_count += 1;
		}
	}
	cr_assert_gt( near_count, 0 );
	cr_expect_lt( near / near_count, all - 0.05, "petiole %g, blade %g", near / near_count, all );
	/* every level keeps the petiole at the origin, and each withers more than the one before:
	 * the mean distance from the flat blade grows */
	double previous = 0.0;
	for ( int32_t level = 1; level < leaf.level_count; ++level )
	{
		const float* p = leaf.xyz + 3 * (size_t) n * (size_t) level;
		cr_expect( p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f, "level %d moved the petiole", level );
		double moved = 0.0;
		for ( int32_t i = 0; i < n; ++i )
		{
			double dx = p[3 * i] - leaf.xyz[3 * i], dy = p[3 * i + 1] - leaf.xyz[3 * i + 1], dz = p[3 * i + 2];
			cr_assert( isfinite( dx + dy + dz ) );
			moved += sqrt( dx * dx + dy * dy + dz * dz ) / n;
		}
		cr_expect_gt( moved, previous, "level %d moved %g, level %d %g", level, moved, level - 1, previous );
		previous = moved;
	}
	sere_season_leaf_destroy( &leaf );
}

Test( seasonleaf, silhouette_gives_the_same_leaf_outline, .timeout = 60 )
{
	sere_season_leaf_options o = sere_season_leaf_options_default();
	o.keys_path = NULL;
	o.silhouette_path = "masks/maple_silhouette.png";
	o.outline_samples = 64;
	o.levels = 1;
	sere_season_leaf leaf;
	char err[512];
	cr_assert_eq( sere_season_leaf_build( &o, &leaf, err, sizeof( err ) ), SERE_OK, "%s", err );
	/* the silhouette is the keys' leaf drawn in the same frame; traced and resampled it is 1 long
	 * from its base and its texture coordinates cover the same part of the frame (the key
	 * points span u in about [0.15, 0.85]) */
	double u_lo = 1.0, u_hi = 0.0;
	for ( int32_t i = 0; i < leaf.vertex_count; ++i )
	{
		u_lo = fmin( u_lo, leaf.u[i] ), u_hi = fmax( u_hi, leaf.u[i] );
	}
	cr_expect( u_lo > 0.1 && u_lo < 0.25 && u_hi > 0.75 && u_hi < 0.9, "u in [%g, %g]", u_lo, u_hi );
	sere_season_leaf_destroy( &leaf );
}

static void expect_leaf_error( sere_season_leaf_options o, const char* phrase )
{
	sere_season_leaf leaf;
	char err[512];
	cr_expect_neq( sere_season_leaf_build( &o, &leaf, err, sizeof( err ) ), SERE_OK, "expected '%s'", phrase );
	cr_expect_not_null( strstr( err, phrase ), "expected '%s' in: %s", phrase, err );
	cr_expect_null( strchr( err, '\n' ), "not one line: %s", err );
}

Test( seasonleaf, bad_input_is_named )
{
	sere_season_leaf_options o = sere_season_leaf_options_default();
	o.levels = 1;
	/* one bad key point file or mask each, the rest of the options left as o has them */
	static const struct
	{
		const char *keys, *mask, *phrase;
	} bad_files[] = {
		{ "tests/data/bad/nope.keys", NULL, "tests/data/bad/nope.keys: cannot open" },
		{ "tests/data/bad/point_outside.keys", NULL,
		  "point_outside.keys:4: point (600, 10) outside the 512 x 512 image" },
		{ "tests/data/bad/no_image.keys", NULL, "no_image.keys:2: 'image W H' must come before the points" },
		{ "tests/data/bad/two_points.keys", NULL, "two_points.keys: 2 key points; a leaf needs at least 3" },
		{ NULL, "tests/data/bad/small_mask.pgm", "the mask is 4 x 4 pixels but the key points' image is 512 x 512" },
		{ NULL, "tests/data/bad/truncated_mask.pgm", "truncated" },
		{ NULL, "tests/data/bad/two_points.keys", "not a binary PGM" },
	};
	for ( size_t k = 0; k < sizeof( bad_files ) / sizeof( bad_files[0] ); ++k )
	{
		sere_season_leaf_options b = o;
		b.keys_path = bad_files[k].keys != NULL ? bad_files[k].keys : o.keys_path;
		b.mask_path = bad_files[k].mask != NULL ? bad_files[k].mask : o.mask_path;
		expect_leaf_error( b, bad_files[k].phrase );
	}
	sere_season_leaf_options b = o;
	b.levels = 0;
	expect_leaf_error( b, "deformation levels: 0 is outside [1, 64]" );
	b = o;
	b.silhouette_path = "masks/maple_silhouette.png";
	expect_leaf_error( b, "give key points or a silhouette, exactly one" );
}

/* ------------------------------------------------------------------------------------------- */
/* sere season */

static int run_season( const char* args, char* err, size_t err_size )
{
	char command[1100];
	snprintf( command, sizeof( command ), "season %s", args );
	return sere_test_run( command, err, err_size );
}

static char* slurp( const char* path )
{
	FILE* f = fopen( path, "rb" );
	cr_assert_not_null( f, "%s missing", path );
	fseek( f, 0, SEEK_END );
	long n = ftell( f );
	fseek( f, 0, SEEK_SET );
	char* s = malloc( (size_t) n + 1 );
	cr_assert_eq( fread( s, 1, (size_t) n, f ), (size_t) n );
	s[n] = '\0';
	fclose( f );
	return s;
}

Test( season_cli, outputs_threads_and_the_exact_distribution, .timeout = 120 )
{
	char err[4096];
	const char* common =
		"--leaves 200000 --iterations 3 --samples 24 --steps 50 --days 40 --temperature 8 --humidity 0.5";
	char args[1024];
	snprintf( args, sizeof( args ), "%s --threads 1 --out /tmp/sere-season-1", common );
	cr_assert_eq( run_season( args, err, sizeof( err ) ), 0, "%s", err );
	snprintf( args, sizeof( args ), "%s --threads 2 --no-pictures --out /tmp/sere-season-2", common );
	cr_assert_eq( run_season( args, err, sizeof( err ) ), 0, "%s", err );
	char* one = slurp( "/tmp/sere-season-1/distribution.csv" );
	char* two = slurp( "/tmp/sere-season-2/distribution.csv" );
	cr_expect_str_eq( one, two, "1 and 2 threads sample different populations" );
	char* ply1 = slurp( "/tmp/sere-season-1/tree_end.ply" );
	char* ply2 = slurp( "/tmp/sere-season-2/tree_end.ply" );
	cr_expect_str_eq( ply1, ply2 );
	/* header, then days 0..40; each row's exact and sampled shares sum to 1 (printed with 8
	 * decimals: 6 states × 5e-9 rounding) and agree within 5 standard errors of a share
	 * (sqrt(0.25 / 200000) ≈ 1.1e-3) */
	int rows = 0, states = 0;
	char* save = NULL;
	for ( char* line = strtok_r( one, "\n", &save ); line != NULL; line = strtok_r( NULL, "\n", &save ) )
	{
		if ( rows++ == 0 )
		{
			for ( char* c = line; *c; ++c )
			{
				states += strncmp( c, ",exact_", 7 ) == 0;
			}
			cr_assert_eq( states, 6, "header: %s", line );
			continue;
		}
		double v[3 + 12];
		char* p = line;
		for ( int k = 0; k < 3 + 2 * states; ++k )
		{
			v[k] = strtod( p, &p );
			p += *p == ',';
		}
		cr_expect_eq( v[0], rows - 2 );
		double exact = 0.0, sampled = 0.0;
		for ( int s = 0; s < states; ++s )
		{
			exact += v[3 + s], sampled += v[3 + states + s];
			cr_expect( fabs( v[3 + s] - v[3 + states + s] ) < 5.5e-3, "day %g state %d: exact %g sampled %g", v[0], s,
					   v[3 + s], v[3 + states + s] );
		}
		cr_expect( fabs( exact - 1.0 ) < 1e-7 && fabs( sampled - 1.0 ) < 1e-7, "day %g sums %g %g", v[0], exact,
				   sampled );
	}
	cr_expect_eq( rows, 1 + 41 );
	const char* pictures[] = { "season_start.png", "season_end.png", "seasons.png",	  "leaf_levels.png",
							   "distribution.png", "summary.json",	 "tree_start.ply" };
	for ( size_t k = 0; k < sizeof( pictures ) / sizeof( pictures[0] ); ++k )
	{
		char path[256];
		snprintf( path, sizeof( path ), "/tmp/sere-season-1/%s", pictures[k] );
		FILE* f = fopen( path, "rb" );
		cr_expect_not_null( f, "%s missing", path );
		if ( f != NULL )
		{
			fclose( f );
		}
	}
	free( one ), free( two ), free( ply1 ), free( ply2 );
}

static void expect_season_error( const char* args, const char* phrase )
{
	char command[1100];
	snprintf( command, sizeof( command ), "season %s", args );
	cr_expect_neq( sere_test_expect_error( command, phrase ), 0, "'%s' should fail", command );
}

Test( season_cli, bad_input_one_clear_line )
{
	const char* out = "--out /tmp/sere-season-bad --no-pictures";
	char args[1024];
#define BAD( extra, phrase )                                                                                           \
	snprintf( args, sizeof( args ), "%s %s", extra, out );                                                             \
	expect_season_error( args, phrase )
	BAD( "--bogus 3", "unknown option '--bogus'" );
	BAD( "--days 10 --temperature 5", "constant weather needs all of --days, --temperature and --humidity" );
	BAD( "--days 10 --temperature 5 --humidity 1.5", "--humidity takes a number from 0 to 1" );
	BAD( "--leaves 10", "--leaves 10 is fewer than the tree's" );
	BAD( "--chain tests/data/bad/nope.chain", "tests/data/bad/nope.chain: cannot open" );
	BAD( "--chain tests/data/bad/unknown_state.chain", "unknown_state.chain:4: unknown state 'purple'" );
	BAD( "--chain tests/data/bad/probability.chain", "probability.chain:3: green: '1.2' is not a probability" );
	BAD( "--chain tests/data/bad/self_loop.chain", "self_loop.chain: not a usable chain" );
	BAD( "--chain tests/data/bad/no_initial.chain", "no_initial.chain: missing 'initial'" );
	BAD( "--schedule tests/data/bad/backwards.schedule", "backwards.schedule:3: day 5: days are whole numbers" );
	BAD( "--schedule tests/data/bad/humidity.schedule", "humidity.schedule:2: humidity 70 is outside [0, 1]" );
	BAD( "--mask tests/data/bad/small_mask.pgm", "the mask is 4 x 4 pixels" );
	/* found by fuzz_png: a sample above the maxval, a header not ended by one whitespace byte */
	BAD( "--mask tests/data/bad/above_maxval.pgm", "above the maxval 100" );
	BAD( "--mask tests/data/bad/pgm_separator.pgm", "not a binary PGM" );
#undef BAD
}
