/* The drying physics as a user looks at it (DESIGN.md, "Checking the physics"): every preset
 * dried to the end on its own leaf at a small size, frame by frame converged, without
 * crossings, drift or flying, shrunk as real leaves shrink. */
#include "build.h"
#include "leaf.h"
#include "measure.h"
#include "params.h"
#include "watch.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Drying all five presets to the end takes a minute optimized and ten under AddressSanitizer;
 * the sanitized suite runs the same code paths in the shorter tests above it. */
#if defined( __SANITIZE_ADDRESS__ )
#define SERE_LONG_TEST_DISABLED 1
#else
#define SERE_LONG_TEST_DISABLED 0
#endif

typedef struct dry_run
{
	int frames, converged;
	int64_t crossings_max;
	double mass_drift_max, tilt_max, gap_max, normal_z_min, length, spacing;
	sere_shape fresh, dry;
	float* x; /* final triangle-layer positions, 3 per vertex */
	int32_t vertices;
} dry_run;

static void dry_free( dry_run* run )
{
	free( run->x );
}

/* Builds preset's leaf at points triangle-layer points with the given --set overrides and dries
 * it until a layer runs dry (Sec. 6) or max_frames, watching every frame. */
static void dry( const char* preset, const char* leaf, int points, int max_frames, const char* const* sets,
				 int set_count, dry_run* run )
{
	memset( run, 0, sizeof( *run ) );
	char err[1024], name[256], path[256];
	sere_sim_params params = sere_sim_params_default();
	cr_assert_eq( sere_params_apply( &params, preset, sets, set_count, err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "data/leaves/%s.leaf", leaf );
	sere_model model;
	sere_build_report report;
	cr_assert_eq(
		sere_harness_build( path, -1, -1, points, &params, &model, &report, name, sizeof( name ), err, sizeof( err ) ),
		0, "%s", err );
	if ( params.face_down != 0.0 )
	{
		sere_model_mirror_z( &model );
	}
	sere_model_rest_on( &model, (float) params.ground );
	double rest = 0.0;
	for ( int32_t k = 0; k < model.t_springs; ++k )
	{
		rest += model.s.rest0[k];
	}
	run->spacing = rest / model.t_springs;
	sere_leaf_sim* sim;
	cr_assert_eq( sere_leaf_create( &model, &sim ), SERE_OK );
	sere_leaf_params leaf_params = sere_run_leaf_params( &params );
	sere_shape_input in = sere_leaf_shape_input( &model, params.ground );
	cr_assert_eq( sere_shape_measure( &in, &run->fresh ), SERE_OK );
	sere_watch* watch;
	cr_assert_eq( sere_watch_create( &model, params.ground, &watch ), SERE_OK );
	run->length = sere_watch_length( watch );
	run->normal_z_min = 1.0;
	run->gap_max = -INFINITY;
	for ( int frame = 1; frame <= max_frames; ++frame )
	{
		sere_leaf_stats stats;
		cr_assert_eq( sere_leaf_step( sim, &leaf_params, &stats ), SERE_OK, "%s frame %d", preset, frame );
		sere_watch_frame seen;
		cr_assert_eq( sere_watch_step( watch, &model, &seen ), SERE_OK );
		run->frames = frame;
		run->converged += stats.pbd_converged;
		run->crossings_max = seen.crossings > run->crossings_max ? seen.crossings : run->crossings_max;
		run->mass_drift_max = fmax( run->mass_drift_max, seen.mass_drift );
		run->tilt_max = fmax( run->tilt_max, seen.tilt_degrees );
		run->gap_max = fmax( run->gap_max, seen.ground_gap );
		run->normal_z_min = fmin( run->normal_z_min, seen.normal_z );
		if ( stats.desiccated )
		{
			break;
		}
	}
	in = sere_leaf_shape_input( &model, params.ground );
	cr_assert_eq( sere_shape_measure( &in, &run->dry ), SERE_OK );
	run->vertices = model.triangle_particles;
	run->x = malloc( sizeof( float ) * 3 * (size_t) run->vertices );
	for ( int32_t i = 0; i < run->vertices; ++i )
	{
		run->x[3 * i] = model.p.x[i], run->x[3 * i + 1] = model.p.y[i], run->x[3 * i + 2] = model.p.z[i];
	}
	sere_watch_destroy( watch );
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
}

static double largest_distance( const dry_run* a, const dry_run* b )
{
	cr_assert_eq( a->vertices, b->vertices );
	double worst = 0.0;
	for ( int32_t i = 0; i < a->vertices; ++i )
	{
		double dx = a->x[3 * i] - b->x[3 * i], dy = a->x[3 * i + 1] - b->x[3 * i + 1],
			   dz = a->x[3 * i + 2] - b->x[3 * i + 2];
		worst = fmax( worst, sqrt( dx * dx + dy * dy + dz * dz ) );
	}
	return worst;
}

/* Item 1: every frame has an answer, and the answer does not depend on the budget. */
Test( drying, frames_converge_and_the_budget_does_not_change_them )
{
	dry_run normal, budget, tight;
	dry( "maple-green", "maple", 300, 100, NULL, 0, &normal );
	cr_expect_geq( normal.converged, 95, "%d of 100 frames reached the residual", normal.converged );
	const char* more[] = { "max_iterations=800" };
	dry( "maple-green", "maple", 300, 100, more, 1, &budget );
	/* Tolerance: 0.1 particle spacing, the criterion for "the same shape". */
	double moved = largest_distance( &normal, &budget );
	cr_expect_leq( moved, 0.1 * normal.spacing, "4x the sweeps moved a vertex by %g (spacing %g)", moved,
				   normal.spacing );
	/* a tighter residual is a different stop, not a different budget: the shape still agrees */
	const char* tighter[] = { "strain_tolerance=1e-4", "max_iterations=2000" };
	dry( "maple-green", "maple", 300, 100, tighter, 2, &tight );
	moved = largest_distance( &normal, &tight );
	cr_expect_leq( moved, 0.1 * normal.spacing, "a 10x tighter residual moved a vertex by %g (spacing %g)", moved,
				   normal.spacing );
	dry_free( &normal ), dry_free( &budget ), dry_free( &tight );
}

/* Item 2: with g = 0 a drying leaf stays where it is. The centre of mass, each frame's motion
 * taken with that frame's masses, moves only by float rounding; the orientation stays. */
Test( drying, no_momentum_from_nowhere )
{
	dry_run run;
	dry( "wisteria", "wisteria", 300, 8000, NULL, 0, &run );
	cr_expect_lt( run.mass_drift_max, 0.01, "the centre of mass moved %g leaf lengths", run.mass_drift_max );
	cr_expect_lt( run.tilt_max, 10.0, "the mean normal turned by %g degrees", run.tilt_max );
	dry_free( &run );
}

/* Item 2: with gravity the leaf lies on the ground in every frame and never turns over. */
Test( drying, lies_on_the_ground )
{
	dry_run run;
	dry( "plane-tree", "plane", 300, 8000, NULL, 0, &run );
	/* one collision thickness at rest (collision_thickness, 0.004) */
	cr_expect_leq( run.gap_max, 0.004, "the leaf rose %g above the ground", run.gap_max );
	cr_expect_gt( run.normal_z_min, 0.0, "the leaf turned over (mean normal z %g)", run.normal_z_min );
	dry_free( &run );
}

/* Item 3 and 4: no crossings in any frame; the final area, size and the mean area loss like
 * real leaves' (Blonder et al. 2012: 22% on average). */
Test( drying, every_preset_shrinks_like_a_leaf_without_crossings, .disabled = SERE_LONG_TEST_DISABLED )
{
	static const char* const presets[5][2] = {
		{ "maple-red", "maple" },	{ "maple-green", "maple" }, { "plane-tree", "plane" },
		{ "wisteria", "wisteria" }, { "grass", "grass" },
	};
	double loss = 0.0;
	for ( int k = 0; k < 5; ++k )
	{
		dry_run run;
		dry( presets[k][0], presets[k][1], 400, 8000, NULL, 0, &run );
		double area = run.dry.area / run.fresh.area, extent = run.dry.extent / run.length;
		cr_expect_eq( run.crossings_max, 0, "%s: %lld crossings", presets[k][0], (long long) run.crossings_max );
		cr_expect( area >= 0.35 && area <= 0.97, "%s: final area %.3f of fresh", presets[k][0], area );
		cr_expect_geq( extent, 0.5, "%s: a ball, %.3f of its length", presets[k][0], extent );
		cr_expect_geq( run.converged, 0.9 * run.frames, "%s: %d of %d frames converged", presets[k][0], run.converged,
					   run.frames );
		loss += ( 1.0 - area ) / 5.0;
		dry_free( &run );
	}
	cr_expect( loss >= 0.10 && loss <= 0.40, "mean area loss %.3f", loss );
}
