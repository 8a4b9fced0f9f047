#include "core/geometry.h"
#include "drying/model.h"
#include "mesh/sample.h"
#include "read/leafload.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char* const shipped[] = { "maple", "plane",   "wisteria", "hibiscus",	"ginkgo",
									   "grass", "hickory", "cucumber", "watermelon" };

static void load( const char* name, sere_leaf_source* leaf )
{
	char path[256], err[1024];
	snprintf( path, sizeof( path ), "data/leaves/%s.leaf", name );
	cr_assert_eq( sere_leaf_source_load( path, leaf, err, sizeof( err ) ), 0, "%s", err );
}

Test( model, table1_counts_exact )
{
	/* Table 1 of the paper: particle and spring counts of the three timed leaves. */
	const struct
	{
		const char* name;
		int64_t particles, springs;
	} cases[] = { { "maple", 13197, 51102 }, { "plane", 15069, 59550 }, { "wisteria", 12750, 50436 } };
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		sere_leaf_source leaf;
		load( cases[k].name, &leaf );
		sere_build_params params = sere_build_params_default();
		cr_assert_eq(
			sere_counts_solve( cases[k].particles, cases[k].springs, &params.point_count, &params.boundary_count ),
			SERE_OK );
		sere_model model;
		sere_build_report report;
		sere_status status = sere_model_build( &leaf.file.shape, &params, &model, &report );
		cr_assert_eq( status, SERE_OK, "%s: %s", cases[k].name, sere_status_text( status ) );
		cr_expect_eq( model.p.count, cases[k].particles, "%s", cases[k].name );
		cr_expect_eq( model.s.count, cases[k].springs, "%s", cases[k].name );
		cr_expect_eq( report.quality.inverted, 0 );
		/* The quality bar: away from constrained segments at least 20 degrees. */
		cr_expect_geq( report.quality.min_angle_free_deg, 20.0, "%s: %.2f", cases[k].name,
					   report.quality.min_angle_free_deg );
		sere_model_destroy( &model );
		sere_leaf_source_destroy( &leaf );
	}
}

Test( model, every_shipped_leaf_builds_with_quality )
{
	for ( size_t k = 0; k < sizeof( shipped ) / sizeof( shipped[0] ); ++k )
	{
		sere_leaf_source leaf;
		load( shipped[k], &leaf );
		const sere_leaf_shape* shape = &leaf.file.shape;
		sere_build_params params = sere_build_params_default();
		params.point_count = 1500;
		params.boundary_count =
			sere_boundary_for_points( sere_shape_area( shape ), sere_shape_perimeter( shape ), 1500 );
		sere_model model;
		sere_build_report report;
		sere_status status = sere_model_build( shape, &params, &model, &report );
		cr_assert_eq( status, SERE_OK, "%s: %s", shipped[k], sere_status_text( status ) );
		int32_t n = params.point_count, b = params.boundary_count;
		cr_expect_eq( model.p.count, 3 * n - b - 2, "%s", shipped[k] );
		cr_expect_eq( model.s.count, 12 * n - 6 * b - 12, "%s", shipped[k] );
		cr_expect_geq( report.quality.min_angle_free_deg, 20.0, "%s: %.2f", shipped[k],
					   report.quality.min_angle_free_deg );
		cr_expect_gt( report.quality.min_angle_deg, 1.0, "%s: %.2f", shipped[k], report.quality.min_angle_deg );
		/* Every vein segment became a T spring flagged as a vein. */
		cr_expect_gt( model.vein_springs, 0, "%s", shipped[k] );
		sere_model_destroy( &model );
		sere_leaf_source_destroy( &leaf );
	}
}

Test( model, sampling_is_deterministic_and_spread )
{
	sere_leaf_source leaf;
	load( "hickory", &leaf );
	sere_sample_params params = { .point_count = 1200, .boundary_count = 150, .seed = 3, .candidates = 0 };
	sere_samples a, b;
	cr_assert_eq( sere_sample_leaf( &leaf.file.shape, &params, &a ), SERE_OK );
	cr_assert_eq( sere_sample_leaf( &leaf.file.shape, &params, &b ), SERE_OK );
	cr_assert_eq( a.point_count, 1200 );
	cr_assert_eq( memcmp( a.x, b.x, sizeof( double ) * 1200 ), 0 );
	cr_assert_eq( memcmp( a.y, b.y, sizeof( double ) * 1200 ), 0 );
	/* Best-candidate sampling keeps points apart: no two closer than a quarter spacing, and
	 * every interior point inside the outline polygon. */
	double* polygon = malloc( sizeof( double ) * 2 * 150 );
	for ( int32_t k = 0; k < 150; ++k )
	{
		polygon[2 * k] = a.x[k];
		polygon[2 * k + 1] = a.y[k];
	}
	for ( int32_t i = a.boundary_count; i < a.point_count; ++i )
	{
		cr_assert( sere_point_in_polygon( polygon, 150, a.x[i], a.y[i] ) );
		for ( int32_t j = 0; j < i; ++j )
		{
			cr_assert_gt( hypot( a.x[i] - a.x[j], a.y[i] - a.y[j] ), 0.25 * a.spacing, "points %d and %d", i, j );
		}
	}
	free( polygon );
	params.seed = 4;
	sere_samples c;
	cr_assert_eq( sere_sample_leaf( &leaf.file.shape, &params, &c ), SERE_OK );
	/* Vein points follow the veins; only the interior fill depends on the seed. */
	int32_t first_free = a.boundary_count + a.vein_point_count;
	cr_expect_neq( memcmp( a.x + first_free, c.x + first_free, sizeof( double ) * 100 ), 0 );
	sere_samples_destroy( &a );
	sere_samples_destroy( &b );
	sere_samples_destroy( &c );
	sere_leaf_source_destroy( &leaf );
}

Test( model, too_few_points_for_the_veins )
{
	sere_leaf_source leaf;
	load( "maple", &leaf );
	sere_build_params params = sere_build_params_default();
	params.point_count = 60;
	params.boundary_count = 50;
	sere_model model;
	cr_expect_eq( sere_model_build( &leaf.file.shape, &params, &model, NULL ), SERE_ERR_COUNTS );
	sere_leaf_source_destroy( &leaf );
}
