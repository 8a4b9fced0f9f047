/* The drying physics as a user looks at it (docs/DESIGN.md, "Checking the physics"): every preset
 * dried to the end on its own leaf at a small size, frame by frame converged, without
 * crossings, drift or flying, shrunk as real leaves shrink. */
#include "common/params.h"
#include "common/watch.h"
#include "drying/leaf.h"
#include "fixture.h"
#include "mesh/measure.h"
#include "read/build.h"
#include "read/leafload.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Drying all five presets to the end, or relaxing six blades for 1200 frames, takes a minute
 * optimized and ten under AddressSanitizer; the sanitized suite runs the same code paths in the
 * shorter tests. */
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
	double contact_slide;	   /* Σ over frames of the horizontal motion of particles resting on the ground */
	int onset_tip, onset_base; /* first frames whose tip / base section rolled by 0.5 rad (0: never) */
	sere_shape fresh, dry;
	int64_t sweeps; /* PBD sweeps over all frames */
	float* x;		/* final triangle-layer positions, 3 per vertex */
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
	if ( params.face_down )
	{
		sere_model_mirror_z( &model );
	}
	sere_model_rest_on( &model, params.leaf.ground );
	double rest = 0.0;
	for ( int32_t k = 0; k < model.t_springs; ++k )
	{
		rest += model.s.rest0[k];
	}
	run->spacing = rest / model.t_springs;
	sere_leaf_sim* sim;
	cr_assert_eq( sere_leaf_create( &model, &sim ), SERE_OK );
	const sere_leaf_params* leaf_params = &params.leaf;
	sere_leaf_source veins; /* for the measures along and across the main veins */
	cr_assert_eq( sere_leaf_source_load( path, &veins, err, sizeof( err ) ), 0, "%s", err );
	sere_shape_input in = sere_leaf_shape_input( &model, sere_params_decimal( params.leaf.ground ) );
	in.veins = &veins.file.shape;
	cr_assert_eq( sere_shape_measure( &in, &run->fresh ), SERE_OK );
	sere_watch* watch;
	cr_assert_eq( sere_watch_create( &model, sere_params_decimal( params.leaf.ground ), 0, &watch ), SERE_OK );
	run->length = sere_watch_length( watch );
	run->normal_z_min = 1.0;
	run->gap_max = -INFINITY;
	const int32_t count = model.p.count;
	float* before = malloc( sizeof( float ) * 3 * (size_t) count );
	cr_assert_not_null( before );
	for ( int frame = 1; frame <= max_frames; ++frame )
	{
		for ( int32_t i = 0; i < count; ++i )
		{
			before[3 * i] = model.p.x[i], before[3 * i + 1] = model.p.y[i], before[3 * i + 2] = model.p.z[i];
		}
		sere_leaf_stats stats;
		cr_assert_eq( sere_leaf_step( sim, leaf_params, &stats ), SERE_OK, "%s frame %d", preset, frame );
		/* resting: on the ground (to float rounding of the clamp) before and after the frame */
		for ( int32_t i = 0; isfinite( params.leaf.ground ) && i < count; ++i )
		{
			if ( before[3 * i + 2] - params.leaf.ground < 1e-6 && model.p.z[i] - params.leaf.ground < 1e-6 )
			{
				run->contact_slide += hypot( model.p.x[i] - before[3 * i], model.p.y[i] - before[3 * i + 1] );
			}
		}
		sere_watch_frame seen;
		cr_assert_eq( sere_watch_step( watch, &model, &seen ), SERE_OK );
		run->frames = frame;
		run->converged += stats.pbd_converged;
		run->sweeps += stats.pbd_iterations;
		run->crossings_max = seen.crossings > run->crossings_max ? seen.crossings : run->crossings_max;
		run->mass_drift_max = fmax( run->mass_drift_max, seen.mass_drift );
		run->tilt_max = fmax( run->tilt_max, seen.tilt_degrees );
		run->gap_max = fmax( run->gap_max, seen.ground_gap );
		run->normal_z_min = fmin( run->normal_z_min, seen.normal_z );
		run->onset_tip = run->onset_tip == 0 && fabs( seen.roll_tip ) >= 0.5 ? frame : run->onset_tip;
		run->onset_base = run->onset_base == 0 && fabs( seen.roll_base ) >= 0.5 ? frame : run->onset_base;
		if ( stats.desiccated )
		{
			break;
		}
	}
	free( before );
	in = sere_leaf_shape_input( &model, sere_params_decimal( params.leaf.ground ) );
	in.veins = &veins.file.shape;
	cr_assert_eq( sere_shape_measure( &in, &run->dry ), SERE_OK );
	sere_leaf_source_destroy( &veins );
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

/* The leaf of preset at 300 points dried to the end with the preset's own parameters. */
static dry_run dried( const char* preset, const char* leaf )
{
	dry_run run;
	dry( preset, leaf, 300, 8000, NULL, 0, &run );
	return run;
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
	dry_run run = dried( "wisteria", "wisteria" );
	cr_expect_lt( run.mass_drift_max, 0.01, "the centre of mass moved %g leaf lengths", run.mass_drift_max );
	cr_expect_lt( run.tilt_max, 10.0, "the mean normal turned by %g degrees", run.tilt_max );
	dry_free( &run );
}

/* Item 2: with gravity the leaf lies on the ground in every frame and never turns over. */
Test( drying, lies_on_the_ground )
{
	dry_run run = dried( "plane-tree", "plane" );
	/* one collision thickness at rest (collision_thickness, 0.004) */
	cr_expect_leq( run.gap_max, 0.004, "the leaf rose %g above the ground", run.gap_max );
	cr_expect_gt( run.normal_z_min, 0.0, "the leaf turned over (mean normal z %g)", run.normal_z_min );
	dry_free( &run );
}

/* Items 3, 4 and 5: no crossings in any frame; the final area, size and the mean area loss like
 * real leaves' (Blonder et al. 2012: 22% on average); the red maple's margin curled up, the
 * plane tree and wisteria wrinkled. */
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
		dry( presets[k][0], presets[k][1], 800, 8000, NULL, 0, &run );
		double area = run.dry.area / run.fresh.area, extent = run.dry.extent / run.length;
		cr_expect_eq( run.crossings_max, 0, "%s: %lld crossings", presets[k][0], (long long) run.crossings_max );
		cr_expect( area >= 0.35 && area <= 0.97, "%s: final area %.3f of fresh", presets[k][0], area );
		cr_expect_geq( extent, 0.5, "%s: a ball, %.3f of its length", presets[k][0], extent );
		cr_expect_geq( run.converged, 0.9 * run.frames, "%s: %d of %d frames converged", presets[k][0], run.converged,
					   run.frames );
		/* Item 2 for the presets without gravity or ground (their gap is never measured): the
		 * collision response and Jeong Eq. 14 move no centre of mass. The issue allows 0.01 L; the runs
		 * move 3e-5 (maple-green) to 5e-3 (grass), and restoring every Voronoi particle whose
		 * triangle a contact touched moved the green maple's by 9e-3: 6e-3 tells them apart. */
		if ( run.gap_max == -INFINITY )
		{
			cr_expect_lt( run.mass_drift_max, 6e-3, "%s: the centre of mass moved %g leaf lengths", presets[k][0],
						  run.mass_drift_max );
		}
		/* Item 5, the morphologies of Fig. 17 measured (kernels/mesh/measure.h) */
		if ( strcmp( presets[k][0], "maple-red" ) == 0 )
		{
			cr_expect_gt( run.dry.margin_lift, 0.0, "maple-red: the margin must curl up, lift %g",
						  run.dry.margin_lift );
		}
		if ( strcmp( presets[k][0], "plane-tree" ) == 0 || strcmp( presets[k][0], "wisteria" ) == 0 )
		{
			cr_expect_gt( run.dry.wrinkle_sign_changes, run.fresh.wrinkle_sign_changes + 100,
						  "%s: wrinkles (curvature sign changes) %lld, fresh %lld", presets[k][0],
						  (long long) run.dry.wrinkle_sign_changes, (long long) run.fresh.wrinkle_sign_changes );
		}
		loss += ( 1.0 - area ) / 5.0;
		dry_free( &run );
	}
	cr_expect( loss >= 0.10 && loss <= 0.40, "mean area loss %.3f", loss );
}

/* Item 5 of the faithful-drying work, the two morphologies that need more than the shape
 * measures above: a green maple's lobes are four or five triangles wide at 800 points, too few to
 * tell a crease along a vein from the blade beside it, so its creases along the main veins and
 * rolled lobe tips are measured at 1500 points; the grass at 800. */
Test( drying, green_maple_creases_along_main_veins_and_rolls_its_lobe_tips, .disabled = SERE_LONG_TEST_DISABLED )
{
	dry_run run;
	dry( "maple-green", "maple", 1500, 8000, NULL, 0, &run );
	cr_log_info( "maple-green: crease along main veins %.3f, between %.3f; lobe roll tip %.3f, base %.3f",
				 run.dry.crease_main, run.dry.crease_blade, run.dry.vein_roll_tip, run.dry.vein_roll_base );
	cr_expect_eq( run.crossings_max, 0 );
	/* sharp creases along the main veins: the edges beside them bend more than the blade's */
	cr_expect_gt( run.dry.crease_main, 1.2 * run.dry.crease_blade );
	/* rolled at the tips: the lobes' sections near their tips roll more than near their bases,
	 * by a quarter turn or more */
	cr_expect_gt( run.dry.vein_roll_tip, 1.5 * run.dry.vein_roll_base );
	cr_expect_gt( run.dry.vein_roll_tip, 0.5 * 3.14159265358979323846 );
	dry_free( &run );
}

Test( drying, grass_rolls_from_the_tip, .disabled = SERE_LONG_TEST_DISABLED )
{
	dry_run run;
	dry( "grass", "grass", 800, 8000, NULL, 0, &run );
	cr_log_info( "grass: rolled by 0.5 rad at frame %d (tip) and %d (base); curl tip %.3f, base %.3f", run.onset_tip,
				 run.onset_base, run.dry.curl_tip, run.dry.curl_base );
	cr_expect_eq( run.crossings_max, 0 );
	/* the section near the tip rolls first, then the rolling reaches the base */
	cr_expect_gt( run.onset_tip, 0 );
	cr_expect_gt( run.onset_base, run.onset_tip );
	/* and at the end the tip half has curled over like a scroll, the base half much less */
	cr_expect_gt( run.dry.curl_tip, 0.5 * 3.14159265358979323846 );
	cr_expect_gt( run.dry.curl_tip, 2.0 * run.dry.curl_base );
	dry_free( &run );
}

/* Item 3 where the leaf folds hardest: the maple-green maple shrunk to l_min = 0.7 (0.75 as well
 * at 1500 points), dried to the end at 600, 800 and 1500 points, as `sere run maple.leaf --preset
 * maple-green --points P --until-dry --set min_length_ratio=0.7` does. Its tip and margin fold
 * over: with vertex–triangle contacts alone an outline edge passed through an edge of the fold
 * (3 crossings at 800 points, 2 at 1500, every vertex farther than the thickness from the other
 * sheet); the edge–edge contacts keep every frame free of crossings. */
Test( drying, folding_maple_has_no_edge_crossings, .disabled = SERE_LONG_TEST_DISABLED )
{
	static const struct
	{
		int points;
		const char* ratio;
	} runs[] = { { 600, "min_length_ratio=0.7" },
				 { 800, "min_length_ratio=0.7" },
				 { 1500, "min_length_ratio=0.7" },
				 { 1500, "min_length_ratio=0.75" } };
	for ( size_t k = 0; k < sizeof( runs ) / sizeof( runs[0] ); ++k )
	{
		dry_run run;
		const char* sets[] = { runs[k].ratio };
		dry( "maple-green", "maple", runs[k].points, 8000, sets, 1, &run );
		cr_log_info( "%d points, %s: %d frames, %lld crossings at most", runs[k].points, runs[k].ratio, run.frames,
					 (long long) run.crossings_max );
		cr_expect_gt( run.frames, 500, "%d points: dried in %d frames", runs[k].points, run.frames );
		cr_expect_eq( run.crossings_max, 0, "%d points, %s: %lld crossings", runs[k].points, runs[k].ratio,
					  (long long) run.crossings_max );
		dry_free( &run );
	}
}

/* Under XPBD (descent = 0), the plane tree's, the red maple's and the wisteria's presets run their
 * sweeps with Chebyshev semi-iteration (ρ = 0.9, Wang 2015; the wisteria after 90 plain sweeps a
 * frame). That is allowed
 * only because these leaves dry to the shape the plain sweeps converge
 * to: a solve's shape is the one its iteration tends to as the residual goes to zero, which for the
 * plain sweeps the residual 1e-5 reaches (at 800 points 0.064 spacings from 1e-6 on the green
 * maple). Dried to the end, each preset must land within 0.1 spacing of that converged plain solve
 * and take fewer sweeps than the plain sweeps at the preset's own residual (a ratio under 0.85, so
 * the test fails if the preset loses its acceleration). Measured at 300 points: see the log lines;
 * at 800 points the plane tree ends 0.076 spacings from the converged solve in 43.3 against 64.6
 * sweeps a frame and the red maple 0.048 in 71.2 against 114.4; the plane tree at the Table 1 size
 * 0.017, in 59.1 against 85.4. The wisteria is checked at 800 points, where its frames need more
 * than its 90 plain sweeps (at 300 points few do): 0.065 spacings in 90.2 against 108.2; at the
 * Table 1 size 0.023 from the plain sweeps at 1e-3, in 104.4 against 132.6. The green maple and the
 * grass keep the plain sweeps: there the two iterations converge to different buckled shapes
 * (docs/DESIGN.md, "Accelerated sweeps only where they keep the shape"). */
typedef struct accelerated_case
{
	const char *preset, *leaf;
	int points;
} accelerated_case;

/* Dries each case three times, with `accelerated` (the preset's own acceleration), `plain` (none)
 * and `converged` (none, to a tighter stop; NULL: the plain sets again, when their stop is as tight
 * as it gets), and expects the accelerated shape within 0.1 spacing of the converged one in under
 * 0.85 of the plain sweeps, every frame converged. */
static void expect_acceleration_keeps_the_shape( const accelerated_case* cases, size_t case_count,
												 const char* const* accelerated, int accelerated_count,
												 const char* const* plain_sets, int plain_count,
												 const char* const* converged_sets, int converged_count )
{
	for ( size_t k = 0; k < case_count; ++k )
	{
		dry_run preset, plain, converged;
		const char *name = cases[k].preset, *leaf = cases[k].leaf;
		dry( name, leaf, cases[k].points, 8000, accelerated, accelerated_count, &preset );
		dry( name, leaf, cases[k].points, 8000, plain_sets, plain_count, &plain );
		dry( name, leaf, cases[k].points, 8000, converged_sets ? converged_sets : plain_sets,
			 converged_sets ? converged_count : plain_count, &converged );
		cr_assert_eq( preset.frames, converged.frames, "%s", name );
		double apart = largest_distance( &preset, &converged ) / converged.spacing;
		double plain_apart = largest_distance( &plain, &converged ) / converged.spacing;
		double ratio = (double) preset.sweeps / (double) plain.sweeps;
		cr_log_info( "%s, %d points, %d frames: Chebyshev %.1f sweeps a frame, %.3f spacings from the converged "
					 "plain solve; plain %.1f, %.3f",
					 name, cases[k].points, preset.frames, (double) preset.sweeps / preset.frames, apart,
					 (double) plain.sweeps / plain.frames, plain_apart );
		cr_expect_lt( apart, 0.1, "%s: Chebyshev ends %.3f spacings from the converged plain solve", name, apart );
		cr_expect_lt( ratio, 0.85, "%s: Chebyshev takes %.2f of the plain sweeps", name, ratio );
		cr_expect_eq( preset.converged, preset.frames, "%s", name );
		dry_free( &preset );
		dry_free( &plain );
		dry_free( &converged );
	}
}

Test( drying, chebyshev_presets_land_on_the_converged_plain_shape, .disabled = SERE_LONG_TEST_DISABLED )
{
	static const accelerated_case presets[] = { { "plane-tree", "plane", 300 },
												{ "maple-red", "maple", 300 },
												{ "wisteria", "wisteria", 800 } };
	const char* preset_sets[] = { "descent=0" };
	const char* plain_sets[] = { "descent=0", "chebyshev_rho=0" };
	const char* converged_sets[] = { "descent=0", "chebyshev_rho=0", "strain_tolerance=1e-5", "max_iterations=100000" };
	expect_acceleration_keeps_the_shape( presets, 3, preset_sets, 1, plain_sets, 2, converged_sets, 4 );
}

/* The descent (the default step) runs its sweeps with Chebyshev semi-iteration, ρ = 0.8 after 2
 * plain sweeps, from a warm start (the prediction plus the last frame's correction), on every
 * preset, each frame to the rounding of the coordinates. A descent has one answer near each
 * prediction, so plain sweeps from the prediction and accelerated ones from the warm start,
 * converged that far, land on one shape. At 800 points the presets end 0.041 (red maple), 0.036
 * (green maple), 0.006 (plane tree) and 0.069 (wisteria) spacings from the plain sweeps, in
 * 0.12–0.42 of their sweeps (docs/DESIGN.md §8). The grass is left out: its nearly unstressed
 * blade's shape is set at the rounding of its coordinates (plain and accelerated sweeps, each
 * converged to it, end 2.4–3.8 spacings apart), as under XPBD. */
Test( drying, descent_presets_land_on_the_converged_plain_shape, .disabled = SERE_LONG_TEST_DISABLED )
{
	static const accelerated_case presets[] = { { "plane-tree", "plane", 300 },
												{ "maple-red", "maple", 300 },
												{ "maple-green", "maple", 300 },
												{ "wisteria", "wisteria", 300 } };
	const char* plain_sets[] = { "descent_rho=0", "descent_warm=0" };
	expect_acceleration_keeps_the_shape( presets, 4, NULL, 0, plain_sets, 2, NULL, 0 );
}

static double slide( const dry_run* run )
{
	return hypot( run->dry.centroid[0] - run->fresh.centroid[0], run->dry.centroid[1] - run->fresh.centroid[1] );
}

/* Item 2: the ground contact has Coulomb friction. A leaf on the ground under gravity tilted by
 * tan θ = 0.5 (no drying): μ_s = 0.8 holds it where it lies; μ_s = 0.3, μ_k = 0.2 let it slide,
 * accelerating. And on the drying plane tree, which curls up on the ground, what rests on the
 * ground slides less with friction than without. */
Test( drying, ground_friction )
{
	dry_run held, sliding;
	const char* tilt[] = { "water_rate_t=0", "water_rate_v=0", "gravity_x=4.9", "gravity_z=-9.8" };
	dry( "plane-tree", "plane", 300, 200, tilt, 4, &held );
	const char* slippery[] = { "water_rate_t=0", "water_rate_v=0",		"gravity_x=4.9",
							   "gravity_z=-9.8", "friction_static=0.3", "friction_kinetic=0.2" };
	dry( "plane-tree", "plane", 300, 200, slippery, 6, &sliding );
	cr_log_info( "tilted gravity, 200 frames: moved %g (mu_s 0.8), %g (mu_s 0.3)", slide( &held ), slide( &sliding ) );
	/* Static: the leaf settles onto the ground (its shape, not its place, changes by about 3e-5);
	 * held means under a thousandth of its length. */
	cr_expect_lt( slide( &held ), 1e-3 * held.length, "static friction let the leaf move %g", slide( &held ) );
	/* Kinetic: (0.5 - 0.2) g = 2.94 accelerates it, and the damping of 0.1 per frame caps its speed
	 * at 2.94 dt / 0.1, 0.0235 leaf lengths over 200 frames; half of that must be reached. */
	cr_expect_gt( slide( &sliding ), 0.0118, "below tan(theta) the leaf must slide, moved %g", slide( &sliding ) );
	dry_free( &held ), dry_free( &sliding );

	dry_run curling, frictionless;
	dry( "plane-tree", "plane", 300, 8000, NULL, 0, &curling );
	const char* none[] = { "friction_static=0", "friction_kinetic=0" };
	dry( "plane-tree", "plane", 300, 8000, none, 2, &frictionless );
	cr_log_info( "resting particles slid %g with friction, %g without", curling.contact_slide,
				 frictionless.contact_slide );
	cr_expect_lt( curling.contact_slide, 0.8 * frictionless.contact_slide, "friction: %g, without: %g",
				  curling.contact_slide, frictionless.contact_slide );
	dry_free( &curling ), dry_free( &frictionless );
}

/* The determinism contract on the whole frame with every new piece in it: ground contact and
 * friction, the face-down mirror, the local Sec. 6 stop, crossings and the restore (maple-red),
 * the same bits for 1, 2 and 3 threads. */
Test( drying, same_bits_for_any_thread_count )
{
	dry_run runs[3];
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		dry( "maple-red", "maple", 300, 60, NULL, 0, runs + t );
	}
	omp_set_num_threads( 2 );
	for ( int t = 1; t < 3; ++t )
	{
		cr_expect_eq( memcmp( runs[0].x, runs[t].x, sizeof( float ) * 3 * (size_t) runs[0].vertices ), 0,
					  "1 and %d threads differ", t + 1 );
	}
	for ( int t = 0; t < 3; ++t )
	{
		dry_free( runs + t );
	}
}

/* Item 6, a law from outside the paper (Guo et al. 2025, Midveins regulate the shape formation
 * of drying leaves): a lamina shrinking uniformly by the mismatch strain around a midvein that
 * does not shrink curls, and the midvein's curvature grows linearly with the strain. A 1 x 0.4
 * blade 0.03 thick with its midvein along the long axis. The midvein is a bundle: besides the
 * paper's vein springs (the T springs along it, the V springs across it), the V springs joining
 * two of its triangles and the L springs of those triangles are its own, so that it keeps its
 * length through its thickness and resists bending along itself; none of the vein's springs
 * shrink and they are 100 times stiffer than the blade's. Every other spring is shortened by
 * eps; the default frame (no water, no gravity) relaxes the blade for 1200 frames. */
static double midvein_curvature( double eps )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, 30, 12, 1.0, 0.4, 0.2, 1, 7 );
	sere_layer_params layer = sere_layer_params_default();
	layer.h_vein = 0.03, layer.h_surf = 0.03;
	sere_model model;
	cr_assert_eq( sere_model_from_triangles( &plane.mesh, &layer, &model ), SERE_OK );
	sere_test_plane_free( &plane );
	const int32_t n = model.triangle_particles;
	for ( int32_t k = model.t_springs; k < model.s.count; ++k )
	{
		int32_t a = model.s.a[k], b = model.s.b[k];
		int layer_kind = model.s.kind[k] & SERE_SPRING_LAYER_MASK;
		if ( ( layer_kind == SERE_SPRING_V && model.tri_vein[a - n] && model.tri_vein[b - n] ) ||
			 ( layer_kind == SERE_SPRING_L && b >= n && model.tri_vein[b - n] ) )
		{
			model.s.kind[k] |= SERE_SPRING_VEIN;
		}
	}
	for ( int32_t k = 0; k < model.s.count; ++k )
	{
		if ( !( model.s.kind[k] & SERE_SPRING_VEIN ) )
		{
			model.s.rest0[k] *= (float) ( 1.0 - eps );
			model.s.rest[k] = model.s.rest0[k];
		}
	}
	sere_leaf_sim* sim;
	cr_assert_eq( sere_leaf_create( &model, &sim ), SERE_OK );
	sere_leaf_params params = sere_leaf_params_default();
	params.water_rate_t = 0.0, params.water_rate_v = 0.0;
	params.vein_compliance = 0.01f;
	params.pbd.max_iterations = 2000; /* a stiff vein needs more sweeps to reach the residual */
	for ( int frame = 0; frame < 1200; ++frame )
	{
		sere_leaf_stats stats;
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
		cr_assert( stats.pbd_converged, "eps %g frame %d did not converge", eps, frame );
	}
	/* the midvein's vertices from base to tip, ordered along the blade */
	int32_t* vein = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t count = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( model.vein[i] )
		{
			int32_t j = count++;
			while ( j > 0 && model.u[vein[j - 1]] > model.u[i] )
			{
				vein[j] = vein[j - 1], --j;
			}
			vein[j] = i;
		}
	}
	cr_assert_geq( count, 20 );
	sere_shape_input in = sere_leaf_shape_input( &model, -INFINITY );
	in.midvein = vein, in.midvein_count = count;
	sere_shape shape;
	cr_assert_eq( sere_shape_measure( &in, &shape ), SERE_OK );
	free( vein );
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
	return shape.midvein_curvature;
}

Test( drying, midvein_curvature_is_linear_in_the_mismatch, .disabled = SERE_LONG_TEST_DISABLED )
{
	const double strains[6] = { 0.01, 0.02, 0.04, 0.06, 0.08, 0.10 };
	double kappa[6], mean_e = 0.0, mean_k = 0.0;
	for ( int k = 0; k < 6; ++k )
	{
		kappa[k] = midvein_curvature( strains[k] );
		mean_e += strains[k] / 6.0, mean_k += kappa[k] / 6.0;
	}
	double see = 0.0, sek = 0.0, skk = 0.0;
	for ( int k = 0; k < 6; ++k )
	{
		see += ( strains[k] - mean_e ) * ( strains[k] - mean_e );
		sek += ( strains[k] - mean_e ) * ( kappa[k] - mean_k );
		skk += ( kappa[k] - mean_k ) * ( kappa[k] - mean_k );
	}
	double slope = sek / see, r2 = sek * sek / ( see * skk );
	cr_log_info( "midvein curvature at 1, 2, 4, 6, 8, 10%%: %g %g %g %g %g %g; slope %g, R^2 %g", kappa[0], kappa[1],
				 kappa[2], kappa[3], kappa[4], kappa[5], slope, r2 );
	cr_expect_gt( slope, 0.0, "the midvein must curl more as the lamina shrinks more" );
	/* the curl is real: at 10% the unit blade's midvein bends with a radius under its length */
	cr_expect_gt( kappa[5], 1.0, "curvature %g at 10%%", kappa[5] );
	cr_expect_geq( r2, 0.95, "curvature against strain: R^2 = %g", r2 );
}
