/* _POSIX_C_SOURCE: setenv. */
#define _POSIX_C_SOURCE 200809L

#include "drying/leaf.h"
#include "drying/model.h"
#include "read/leafload.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void small_leaf_layers( sere_model* model, const char* name, int32_t points, float h_vein, float h_surf );

static void small_leaf( sere_model* model, const char* name, int32_t points )
{
	small_leaf_layers( model, name, points, -0.02f, 0.005f );
}

static void small_leaf_layers( sere_model* model, const char* name, int32_t points, float h_vein, float h_surf )
{
	char path[256], err[1024];
	snprintf( path, sizeof( path ), "data/leaves/%s.leaf", name );
	sere_leaf_source leaf;
	cr_assert_eq( sere_leaf_source_load( path, &leaf, err, sizeof( err ) ), 0, "%s", err );
	sere_build_params params = sere_build_params_default();
	params.point_count = points;
	params.boundary_count = sere_boundary_for_points( sere_shape_area( &leaf.file.shape ),
													  sere_shape_perimeter( &leaf.file.shape ), points );
	params.layer.h_vein = h_vein;
	params.layer.h_surf = h_surf;
	params.layer.mu0 = 0.5;
	cr_assert_eq( sere_model_build( &leaf.file.shape, &params, model, NULL ), SERE_OK );
	sere_leaf_source_destroy( &leaf );
}

/* The drying simulation of a model built by small_leaf or small_leaf_layers. */
static sere_leaf_sim* small_sim( sere_model* model )
{
	sere_leaf_sim* sim;
	cr_assert_eq( sere_leaf_create( model, &sim ), SERE_OK );
	return sim;
}

static void small_sim_free( sere_leaf_sim* sim, sere_model* model )
{
	sere_leaf_destroy( sim );
	sere_model_destroy( model );
}

/* The default drying parameters with the water loss rates of both layers (Table 2 w_loss^T and
 * w_loss^V) and the surface shrink σ of Jeong Eq. 12 set. */
static sere_leaf_params drying_params( double rate_t, double rate_v, double sigma_surf )
{
	sere_leaf_params params = sere_leaf_params_default();
	params.water_rate_t = rate_t;
	params.water_rate_v = rate_v;
	params.shrink.sigma_surf = sigma_surf;
	return params;
}

/* x, then y, then z of every particle, in one allocation the caller frees. */
static float* positions_of( const sere_model* model )
{
	const size_t count = (size_t) model->p.count;
	float* xyz = malloc( sizeof( float ) * 3 * count );
	cr_assert_not_null( xyz );
	memcpy( xyz, model->p.x, sizeof( float ) * count );
	memcpy( xyz + count, model->p.y, sizeof( float ) * count );
	memcpy( xyz + 2 * count, model->p.z, sizeof( float ) * count );
	return xyz;
}

static double t_area( const sere_model* model )
{
	const float* p[3] = { model->p.x, model->p.y, model->p.z };
	double area = 0.0;
	for ( int32_t t = 0; t < model->triangle_count; ++t )
	{
		const int32_t* v = model->tri + 3 * t;
		double a[3], b[3];
		for ( int k = 0; k < 3; ++k )
		{
			a[k] = p[k][v[1]] - p[k][v[0]];
			b[k] = p[k][v[2]] - p[k][v[0]];
		}
		double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2], cz = a[0] * b[1] - a[1] * b[0];
		area += 0.5 * sqrt( cx * cx + cy * cy + cz * cz );
	}
	return area;
}

Test( leaf, end_to_end_dry )
{
	sere_model model;
	small_leaf( &model, "wisteria", 400 );
	sere_leaf_sim* sim = small_sim( &model );
	sere_leaf_params params = drying_params( -0.2, -0.2, 0.5 );
	params.shrink.sigma_vein = 0.2;
	params.pbd.max_iterations = 60;
	double area0 = t_area( &model );
	double water = INFINITY;
	sere_leaf_stats stats;
	for ( int frame = 0; frame < 300; ++frame )
	{
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "frame %d", frame );
		double total = stats.water_t + stats.water_v;
		/* w_loss < 0 removes water every frame and flow only moves it: the total never rises */
		cr_assert_leq( total, water, "frame %d: water rose from %.17g to %.17g", frame, water, total );
		water = total;
	}
	for ( int32_t i = 0; i < model.p.count; ++i )
	{
		cr_assert( isfinite( model.p.x[i] ) && isfinite( model.p.y[i] ) && isfinite( model.p.z[i] ), "particle %d", i );
		cr_assert( isfinite( model.p.w[i] ) && model.p.w[i] >= 0.0 );
	}
	cr_expect_lt( stats.relative_water, 0.9 );
	/* Shrinking springs pull the blade in: the triangle layer's area falls. */
	cr_expect_lt( t_area( &model ), 0.97 * area0, "area %g of %g", t_area( &model ), area0 );
	small_sim_free( sim, &model );
}

/* A NaN in a Voronoi particle fails the frame it appears in, whether the restore measures ĥ or
 * uses the rest thickness: ĥ is measured only where the collision pass moved a corner, so this
 * rests on the rest of the step. While the leaf has water, osmosis meets it first, as a spring of
 * no finite length (SERE_ERR_GEOMETRY, its documented code); once a layer is dry and osmosis
 * stops (Sec. 6), the projection's confirming measure, which reads every spring, reports
 * SERE_ERR_NONFINITE. */
Test( leaf, a_nonfinite_voronoi_particle_fails_the_frame )
{
	for ( int measured = 0; measured < 2; ++measured )
	{
		for ( int dry = 0; dry < 2; ++dry )
		{
			sere_model model;
			small_leaf( &model, "wisteria", 300 );
			sere_leaf_sim* sim = small_sim( &model );
			/* a fast loss dries a layer within a few hundred frames */
			sere_leaf_params params = dry ? drying_params( -20.0, -20.0, 0.5 ) : drying_params( -0.2, -0.2, 0.5 );
			params.restore_measured = measured;
			sere_leaf_stats stats = { 0 };
			for ( int frame = 0; frame < 3 || ( dry && !stats.desiccated && frame < 2000 ); ++frame )
			{
				cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "frame %d", frame );
			}
			cr_assert_eq( stats.desiccated, dry, "the leaf must be %s", dry ? "dry" : "wet" );
			model.p.y[model.triangle_particles + model.triangle_count / 2] = NAN;
			sere_status got = sere_leaf_step( sim, &params, &stats );
			cr_expect_eq( got, dry ? SERE_ERR_NONFINITE : SERE_ERR_GEOMETRY, "restore_measured %d, dry %d: status %d",
						  measured, dry, got );
			small_sim_free( sim, &model );
		}
	}
}

/* The collision thickness follows the triangle layer: Σ l / Σ l⁰ over the T springs, 1 exactly
 * at rest (equal sums), the pass using the rest thickness times it, and fixed when turned off.
 * The scale is recomputed here from the model in the same order, so the comparison is exact. */
Test( leaf, collision_thickness_shrinks_with_the_triangle_layer )
{
	for ( int scale = 0; scale < 2; ++scale )
	{
		sere_model model;
		small_leaf( &model, "maple", 400 );
		cr_assert_eq( sere_leaf_thickness_scale( &model ), 1.0f );
		sere_leaf_sim* sim = small_sim( &model );
		sere_leaf_params params = drying_params( -0.5, -0.5, 1.0 );
		params.pbd.max_iterations = 20;
		params.scale_thickness = scale;
		sere_leaf_stats stats;
		for ( int frame = 0; frame < 60; ++frame )
		{
			cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "frame %d", frame );
		}
		double rest = 0.0, rest0 = 0.0;
		for ( int32_t k = 0; k < model.t_springs; ++k )
		{
			rest += model.s.rest[k];
			rest0 += model.s.rest0[k];
		}
		float shrink = (float) ( rest / rest0 );
		cr_assert_eq( sere_leaf_thickness_scale( &model ), shrink );
		cr_assert_lt( shrink, 0.98f, "the T layer should have shrunk: %g", shrink );
		float expected = scale ? params.collide.thickness * shrink : params.collide.thickness;
		cr_assert_eq( stats.collision_thickness, expected, "scale %d: %g, expected %g", scale,
					  stats.collision_thickness, expected );
		small_sim_free( sim, &model );
	}
}

Test( leaf, desiccated_layer_stops )
{
	sere_model model;
	small_leaf( &model, "hickory", 300 );
	sere_leaf_sim* sim = small_sim( &model );
	sere_leaf_params params = sere_leaf_params_default();
	params.water_rate_v = -50.0; /* the Voronoi layer dries in a few frames */
	params.water_rate_t = -0.1;
	params.pbd.max_iterations = 20;
	sere_leaf_stats stats = { 0 };
	int frame = 0;
	for ( ; frame < 200 && !stats.desiccated; ++frame )
	{
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
	}
	cr_assert( stats.desiccated, "the V layer never ran dry" );
	cr_expect_eq( stats.water_v, 0.0 );
	/* Sec. 6: from then on neither flow nor shrinkage change anything. */
	double water_t = stats.water_t;
	float* rest = malloc( sizeof( float ) * model.s.count );
	memcpy( rest, model.s.rest, sizeof( float ) * model.s.count );
	for ( int k = 0; k < 5; ++k )
	{
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
	}
	cr_expect_eq( stats.water_t, water_t );
	cr_expect_eq( memcmp( rest, model.s.rest, sizeof( float ) * model.s.count ), 0 );
	free( rest );
	small_sim_free( sim, &model );
}

Test( leaf, deterministic_across_threads )
{
	float* final[2];
	int32_t count = 0;
	for ( int t = 0; t < 2; ++t )
	{
		omp_set_num_threads( t + 1 );
		sere_model model;
		small_leaf( &model, "maple", 1200 );
		sere_leaf_sim* sim = small_sim( &model );
		sere_leaf_params params = drying_params( -0.5, -1.0, 1.5 );
		params.pbd.max_iterations = 40;
		sere_leaf_stats stats;
		for ( int frame = 0; frame < 40; ++frame )
		{
			cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
		}
		count = model.p.count;
		final[t] = malloc( sizeof( float ) * 6 * count );
		memcpy( final[t], model.p.x, sizeof( float ) * count );
		memcpy( final[t] + count, model.p.y, sizeof( float ) * count );
		memcpy( final[t] + 2 * count, model.p.z, sizeof( float ) * count );
		memcpy( final[t] + 3 * count, model.p.vx, sizeof( float ) * count );
		memcpy( final[t] + 4 * count, model.p.vy, sizeof( float ) * count );
		memcpy( final[t] + 5 * count, model.p.vz, sizeof( float ) * count );
		small_sim_free( sim, &model );
	}
	cr_expect_eq( memcmp( final[0], final[1], sizeof( float ) * 6 * count ), 0 );
	free( final[0] ), free( final[1] );
	omp_set_num_threads( 2 );
}

/* The step residual (sere_leaf_params.step_residual) is a measure beside the frame: with it off
 * the frames are bitwise the same and step_primal is NaN. With it on, under XPBD (descent = 0) the
 * share of the multipliers' forces left unbalanced starts near 0 from the flat leaf and grows as
 * the layers' shrinkage frustrates them (docs/DESIGN.md §8: 0.01 → 0.54 → 0.99 on the green maple
 * at 800 points); the descent, the default, ends every frame at a rest state of the same energy,
 * where the gradient is a small share of the springs' forces (0.002 here at frame 120). Returns
 * step_primal at the first and last of 120 frames. */
static void measure_beside_the_frame( int descent, float* first, float* last )
{
	float* final[2];
	int32_t count = 0;
	for ( int measure = 0; measure < 2; ++measure )
	{
		sere_model model;
		small_leaf( &model, "maple", 600 );
		sere_leaf_sim* sim = small_sim( &model );
		sere_leaf_params params = drying_params( -0.5, -1.0, 1.5 );
		params.step_residual = measure;
		params.descent = descent;
		sere_leaf_stats stats;
		for ( int frame = 0; frame < 120; ++frame )
		{
			cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
			cr_assert( measure ? stats.step_primal >= 0.0f && stats.step_primal < 2.0f : isnan( stats.step_primal ),
					   "descent %d, frame %d: %g", descent, frame, stats.step_primal );
			*first = frame == 0 && measure ? stats.step_primal : *first;
		}
		*last = stats.step_primal;
		count = model.p.count;
		final[measure] = positions_of( &model );
		small_sim_free( sim, &model );
	}
	cr_expect_eq( memcmp( final[0], final[1], sizeof( float ) * 3 * count ), 0, "descent %d", descent );
	free( final[0] ), free( final[1] );
}

Test( leaf, step_residual_is_measured_beside_the_frame )
{
	cr_assert_eq( sere_leaf_params_default().descent, 1, "the default step is the descent" );
	float first, last;
	measure_beside_the_frame( 0, &first, &last );
	cr_expect_lt( first, 0.05f, "XPBD, frame 1: %g", first );
	cr_expect_gt( last, 0.2f, "XPBD, frame 120: %g", last );
	measure_beside_the_frame( 1, &first, &last );
	cr_expect_lt( last, 0.05f, "descent, frame 120: %g", last );
}

/* Threads in this process (libgomp keeps a team's threads alive between regions). */
static int process_threads( void )
{
	char line[256];
	int threads = 0;
	FILE* status = fopen( "/proc/self/status", "r" );
	cr_assert_not_null( status );
	while ( fgets( line, sizeof( line ), status ) != NULL )
	{
		sscanf( line, "Threads: %d", &threads );
	}
	fclose( status );
	return threads;
}

/* The count set on the simulation is the one its kernels run with, not OpenMP's: with OpenMP
 * at 1 thread, a leaf set to 3 makes libgomp start a team of 3 (the collision workspace, made for
 * OpenMP's 1, grows its buffers for them); and its frames are the bits of a leaf set to 1 while
 * OpenMP says 3 (the determinism contract, with the count said at the call). */
Test( leaf, explicit_threads_override_openmp )
{
	setenv( "SERE_ADAPTIVE_THREADS", "0", 1 ); /* no cap from a busy machine: the team is the count */
	const int32_t explicit_threads[2] = { 3, 1 };
	float* final[2];
	int32_t count = 0;
	for ( int t = 0; t < 2; ++t )
	{
		omp_set_num_threads( t == 0 ? 1 : 3 );
		sere_model model;
		small_leaf( &model, "maple", 1200 );
		sere_leaf_sim* sim = small_sim( &model );
		int before = process_threads();
		cr_assert_eq( sere_leaf_set_threads( sim, explicit_threads[t] ), SERE_OK );
		sere_leaf_params params = drying_params( -0.5, -1.0, 1.5 );
		params.pbd.max_iterations = 40;
		sere_leaf_stats stats;
		for ( int frame = 0; frame < 40; ++frame )
		{
			cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
		}
		if ( t == 0 )
		{
			cr_expect_geq( process_threads(), before + 2, "3 threads asked, %d in the process (%d before)",
						   process_threads(), before );
		}
		count = model.p.count;
		final[t] = positions_of( &model );
		small_sim_free( sim, &model );
	}
	cr_expect_eq( memcmp( final[0], final[1], sizeof( float ) * 3 * count ), 0 );
	free( final[0] ), free( final[1] );
	omp_set_num_threads( 2 );
}

Test( leaf, initial_shaping_creases_along_veins )
{
	sere_model model;
	small_leaf( &model, "hickory", 500 );
	sere_leaf_sim* sim = small_sim( &model );
	sere_pbd_params pbd = sere_pbd_params_default();
	pbd.max_iterations = 500;
	/* h_vein = -0.02: the vein's Voronoi particles lie below; shortening their springs
	 * creases the blade along the midvein (Fig. 3g, Fig. 4). */
	cr_assert_eq( sere_leaf_shape_initial( sim, 0.3f, 0.05f, &pbd ), SERE_OK );
	float lo = INFINITY, hi = -INFINITY;
	for ( int32_t i = 0; i < model.triangle_particles; ++i )
	{
		lo = fminf( lo, model.p.z[i] ), hi = fmaxf( hi, model.p.z[i] );
	}
	/* The triangle layer starts exactly flat (z = 0); a crease lifts it by a fair part of the
	 * layer thickness |h_vein| = 0.02. */
	cr_expect_gt( hi - lo, 0.25f * 0.02f, "the flat blade did not bend: z range %g", hi - lo );
	/* The shaped leaf is the new rest state: l0 equals the current lengths (float rounding). */
	for ( int32_t s = 0; s < model.s.count; ++s )
	{
		int32_t a = model.s.a[s], b = model.s.b[s];
		float dx = model.p.x[b] - model.p.x[a], dy = model.p.y[b] - model.p.y[a], dz = model.p.z[b] - model.p.z[a];
		cr_assert_float_eq( model.s.rest0[s], sqrtf( dx * dx + dy * dy + dz * dz ), 1e-6f );
		cr_assert_eq( model.s.rest[s], model.s.rest0[s] );
	}
	small_sim_free( sim, &model );
}

/* Dries a small leaf for some frames with the given stall setting and returns the triangle
 * layer's final x, y, z and the frames the stall rule stopped. */
static int stall_run( float stall, int frames, float* xyz, int32_t* iterations, int* capped )
{
	sere_model model;
	small_leaf( &model, "wisteria", 300 );
	sere_leaf_sim* sim = small_sim( &model );
	sere_leaf_params params = drying_params( -0.2, -1.0, 1.0 );
	params.pbd.max_iterations = 100;
	params.pbd.compliance = 0.0f; /* the stall rule belongs to the paper's hard constraints */
	params.pbd.stall = stall;
	int stalled = 0;
	*iterations = 0;
	*capped = 0;
	for ( int frame = 0; frame < frames; ++frame )
	{
		sere_leaf_stats stats;
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "frame %d", frame );
		cr_assert( !( stats.pbd_stalled && stats.pbd_hit_cap ), "a frame is either stalled or capped" );
		cr_assert( !stats.pbd_stalled || stats.pbd_iterations < params.pbd.max_iterations );
		stalled += stats.pbd_stalled;
		*capped += stats.pbd_hit_cap;
		*iterations += stats.pbd_iterations;
	}
	for ( int32_t i = 0; i < model.triangle_particles; ++i )
	{
		xyz[3 * i] = model.p.x[i], xyz[3 * i + 1] = model.p.y[i], xyz[3 * i + 2] = model.p.z[i];
	}
	small_sim_free( sim, &model );
	return stalled;
}

Test( leaf, stall_rule )
{
	enum
	{
		frames = 12,
		max_points = 300,
	};
	static float paper[3 * max_points], stalling[3 * max_points];
	int32_t it_paper, it_stalling;
	int cap_paper, cap_stalling;
	cr_assert_eq( stall_run( 0.0f, frames, paper, &it_paper, &cap_paper ), 0 );
	cr_assert_gt( cap_paper, 0, "the setup must be frustrated: some frames reach the cap" );
	/* A real threshold stops frustrated frames early and spends fewer sweeps. */
	int stalled = stall_run( 0.05f, frames, stalling, &it_stalling, &cap_stalling );
	cr_expect_gt( stalled, 0 );
	cr_expect_lt( it_stalling, it_paper, "stall rule: %d sweeps, paper rule %d", it_stalling, it_paper );
	double worst = 0.0;
	for ( int i = 0; i < 3 * max_points; ++i )
	{
		worst = fmax( worst, fabs( (double) stalling[i] - (double) paper[i] ) );
	}
	/* The sweeps it skips only creep toward the frustrated floor: after 12 frames no particle is
	 * more than one particle spacing (about 0.03 for 300 points on this leaf of size 1) from
	 * where the paper's rule puts it (measured: 0.010, with 340 instead of 1200 sweeps). */
	cr_expect_lt( worst, 0.03, "stall rule moved a particle %g away from the paper rule's shape", worst );
}

/* The fold across the triangle-layer vein edges: for every vein edge a–b between triangles
 * (a, b, c) and (b, a, d), the heights of d above the first triangle's plane and of c above the
 * second's, along the normals (the side the Voronoi layer starts on), over the edge length,
 * averaged. Positive: the blade folds toward the Voronoi layer, which becomes the inside of the
 * crease; negative: away from it. */
static double vein_fold( const sere_model* model )
{
	const float *x = model->p.x, *y = model->p.y, *z = model->p.z;
	double sum = 0.0;
	int edges = 0;
	for ( int32_t s = 0; s < model->s.count; ++s )
	{
		if ( model->s.kind[s] != ( SERE_SPRING_T | SERE_SPRING_VEIN ) )
		{
			continue;
		}
		int32_t a = model->s.a[s], b = model->s.b[s], side[2] = { -1, -1 }, apex[2] = { -1, -1 };
		for ( int32_t t = 0; t < model->triangle_count; ++t )
		{
			const int32_t* v = model->tri + 3 * t;
			for ( int k = 0; k < 3; ++k )
			{
				int32_t from = v[k], to = v[( k + 1 ) % 3], other = v[( k + 2 ) % 3];
				int which = from == a && to == b ? 0 : from == b && to == a ? 1 : -1;
				if ( which >= 0 )
				{
					side[which] = t, apex[which] = other;
				}
			}
		}
		if ( side[0] < 0 || side[1] < 0 )
		{
			continue; /* a vein edge on the outline */
		}
		double fold = 0.0;
		for ( int k = 0; k < 2; ++k )
		{
			const int32_t* v = model->tri + 3 * side[k];
			double ux = x[v[1]] - x[v[0]], uy = y[v[1]] - y[v[0]], uz = z[v[1]] - z[v[0]];
			double wx = x[v[2]] - x[v[0]], wy = y[v[2]] - y[v[0]], wz = z[v[2]] - z[v[0]];
			double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
			double nl = sqrt( nx * nx + ny * ny + nz * nz );
			int32_t q = apex[1 - k];
			fold += ( ( x[q] - x[v[0]] ) * nx + ( y[q] - y[v[0]] ) * ny + ( z[q] - z[v[0]] ) * nz ) / nl;
		}
		double ex = x[b] - x[a], ey = y[b] - y[a], ez = z[b] - z[a];
		sum += 0.5 * fold / sqrt( ex * ex + ey * ey + ez * ez );
		edges += 1;
	}
	cr_assert_gt( edges, 10, "the leaf has too few interior vein edges" );
	return sum / edges;
}

/* Fig. 15's setup: σ_surf = 0 and only the Voronoi layer dries (w_loss^V = −2, w_loss^T = 0),
 * here without gravity so that only the shrinkage bends the leaf; the fold after 100 frames,
 * when the layer has lost two thirds of its water. */
static double crease( float sigma_vein )
{
	sere_model model;
	small_leaf_layers( &model, "hickory", 600, 0.01f, 0.01f );
	sere_leaf_sim* sim = small_sim( &model );
	sere_leaf_params params = drying_params( 0.0, -2.0, 0.0 );
	params.shrink.sigma_vein = sigma_vein;
	params.gravity[0] = params.gravity[1] = params.gravity[2] = 0.0f;
	params.ground = -INFINITY;
	params.pbd.max_iterations = 100;
	sere_leaf_stats stats;
	for ( int frame = 0; frame < 100; ++frame )
	{
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "frame %d", frame );
	}
	double fold = vein_fold( &model );
	small_sim_free( sim, &model );
	return fold;
}

Test( leaf, fig15_crease_follows_sigma_vein )
{
	/* Measured folds (height of the far corner over the edge length): σ_vein = 1: +0.30,
	 * σ_vein = 5: +0.51, σ_vein = −5: −0.83. The bounds ask for the order and sign the paper
	 * shows, with room for the sweeps' residual. (σ_vein = −5 stretches the vein springs to
	 * 3.9 l⁰ by the end of drying; no shape meets that, and left to run for 300 frames that
	 * leaf crumples and its mean fold decays toward 0.) */
	double reversed = crease( -5.0f ), mild = crease( 1.0f ), sharp = crease( 5.0f );
	cr_expect_gt( mild, 0.1, "sigma_vein = 1: fold %g, not toward the Voronoi layer", mild );
	cr_expect_gt( sharp, mild + 0.1, "sigma_vein = 5: fold %g, not sharper than %g at 1", sharp, mild );
	cr_expect_lt( reversed, -0.1, "sigma_vein = -5: fold %g, not reversed", reversed );
}

/* Dries a 400-point maple for `frames` frames with the XPBD step (descent 0) or the descent (1),
 * Chebyshev-accelerated (rho > 0) or plain, shrinking fast and frustrated (as
 * leaf.deterministic_across_threads); the particles' final positions into xyz (3 count floats), the
 * sweeps into *sweeps. Returns the mean T rest length at rest, the particle spacing. */
static double dry_maple( int descent, float rho, int frames, float* xyz, int32_t* count, int64_t* sweeps )
{
	sere_model model;
	small_leaf( &model, "maple", 400 );
	sere_leaf_sim* sim = small_sim( &model );
	sere_leaf_params params = drying_params( -0.5, -1.0, 1.5 );
	params.descent = descent;
	params.pbd.chebyshev_rho = descent ? 0.0f : rho;
	params.descent_rho = descent ? rho : 0.0f;
	sere_leaf_stats stats;
	*sweeps = 0;
	for ( int frame = 0; frame < frames; ++frame )
	{
		cr_assert_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK );
		cr_assert( stats.pbd_converged, "rho %g, frame %d: %d sweeps", rho, frame, stats.pbd_iterations );
		*sweeps += stats.pbd_iterations;
	}
	*count = model.p.count;
	memcpy( xyz, model.p.x, sizeof( float ) * (size_t) model.p.count );
	memcpy( xyz + model.p.count, model.p.y, sizeof( float ) * (size_t) model.p.count );
	memcpy( xyz + 2 * model.p.count, model.p.z, sizeof( float ) * (size_t) model.p.count );
	double spacing = 0.0;
	for ( int32_t k = 0; k < model.t_springs; ++k )
	{
		spacing += model.s.rest0[k];
	}
	spacing /= model.t_springs;
	small_sim_free( sim, &model );
	return spacing;
}

/* The largest distance between two position sets of n particles (x, then y, then z). */
static double largest_apart( const float* a, const float* b, int32_t n )
{
	double worst = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		double dx = a[i] - b[i], dy = a[n + i] - b[n + i], dz = a[2 * n + i] - b[2 * n + i];
		worst = fmax( worst, sqrt( dx * dx + dy * dy + dz * dz ) );
	}
	return worst;
}

Test( leaf, chebyshev_keeps_the_shape_of_the_plain_sweeps )
{
	enum
	{
		frames = 100,
		capacity = 3 * 2000
	};
	static float plain[capacity], fast[capacity];
	int32_t n = 0;
	int64_t sweeps_plain, sweeps_fast;
	cr_assert_eq( sere_leaf_params_default().pbd.chebyshev_rho, 0.0f, "XPBD's default is the plain sweeps" );
	double spacing = dry_maple( 0, 0.0f, frames, plain, &n, &sweeps_plain );
	cr_assert_leq( 3 * n, capacity );
	dry_maple( 0, 0.9f, frames, fast, &n, &sweeps_fast );
	cr_expect_lt( sweeps_fast, sweeps_plain * 3 / 4, "XPBD sweeps: Chebyshev %lld, plain %lld", (long long) sweeps_fast,
				  (long long) sweeps_plain );
	/* Each frame both paths stop at the XPBD residual 1e-3 and end a little apart (see
	 * tests/test_pbd.c, chebyshev_reaches_the_plain_step_in_fewer_sweeps); over the frames the
	 * difference is carried on by the velocities. The shapes must agree to 0.1 spacing: here
	 * 0.062 (the plain sweeps at residual 5e-4 instead: 0.022), 18 against 36 sweeps a frame
	 * over the first 50 frames, 22 against 43 over 100. Left to run to 200 frames at 800 points
	 * the two part by up to 1.1 spacings where the plain sweeps at 5e-4 stay within 0.08, which
	 * is why XPBD's default stays plain. */
	double worst = largest_apart( fast, plain, n );
	cr_expect_lt( worst, 0.1 * spacing, "XPBD: largest distance %g, spacing %g (sweeps %lld vs %lld)", worst, spacing,
				  (long long) sweeps_fast, (long long) sweeps_plain );
	/* The descent has one answer near each prediction, which both paths reach to moves of 1e-5
	 * of a spring, so the default, ρ = 0.8, keeps the plain sweeps' shape (docs/DESIGN.md §8). */
	const float rho = sere_leaf_params_default().descent_rho;
	cr_assert_gt( rho, 0.0f, "the descent's default is accelerated" );
	dry_maple( 1, 0.0f, frames, plain, &n, &sweeps_plain );
	dry_maple( 1, rho, frames, fast, &n, &sweeps_fast );
	worst = largest_apart( fast, plain, n );
	cr_log_info( "descent: Chebyshev %lld sweeps, plain %lld, %g spacings apart", (long long) sweeps_fast,
				 (long long) sweeps_plain, worst / spacing );
	cr_expect_lt( sweeps_fast, sweeps_plain * 3 / 4, "descent sweeps: Chebyshev %lld, plain %lld",
				  (long long) sweeps_fast, (long long) sweeps_plain );
	cr_expect_lt( worst, 0.1 * spacing, "descent: largest distance %g, spacing %g", worst, spacing );
}
