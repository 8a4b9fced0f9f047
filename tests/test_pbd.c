#include "fixture.h"
#include "layers.h"
#include "pbd.h"
#include "ref/pbd_ref.h"
#include "shrink.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static void grid_model( sere_model* model, int32_t nx, int32_t ny, double h )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, 0.1 * nx, 0.1 * ny, 0.3, 1, 9 );
	sere_layer_params params = sere_layer_params_default();
	params.h_vein = params.h_surf = h;
	cr_assert_eq( sere_model_from_triangles( &plane.mesh, &params, model ), SERE_OK );
	sere_test_plane_free( &plane );
}

static float max_strain( const sere_model* model, int32_t count, const float* rest )
{
	float worst = 0.0f;
	for ( int32_t s = 0; s < count; ++s )
	{
		int32_t a = model->s.a[s], b = model->s.b[s];
		float dx = model->p.px[b] - model->p.px[a], dy = model->p.py[b] - model->p.py[a];
		float dz = model->p.pz[b] - model->p.pz[a];
		worst = fmaxf( worst, fabsf( sqrtf( dx * dx + dy * dy + dz * dz ) - rest[s] ) / rest[s] );
	}
	return worst;
}

Test( pbd, single_spring_reaches_rest_length )
{
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 1.0f, 3.0f };
	float x[2] = { 0.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( &a, &b, 1, 2, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, &rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_OK );
	/* One projection solves a lone constraint exactly (float rounding: 1e-6). */
	cr_expect_float_eq( x[1] - x[0], 1.0f, 1e-6f );
	/* The correction splits by inverse mass: the heavy end moves a third as far. */
	cr_expect_float_eq( x[0], 0.25f, 1e-6f );
	cr_expect_float_eq( x[1], 1.25f, 1e-6f );
	sere_pbd_destroy( pbd );
}

static void patch_converges( float scale )
{
	sere_model model;
	grid_model( &model, 16, 10, 0.01 );
	int32_t count = model.t_springs; /* the cloth: triangle layer only */
	for ( int32_t i = 0; i < model.triangle_particles; ++i )
	{
		model.p.px[i] = model.p.x[i] * scale;
		model.p.py[i] = model.p.y[i] * scale;
		model.p.pz[i] = 0.02f * sinf( 3.0f * model.p.x[i] ); /* off-plane so compression can buckle */
	}
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, count, model.triangle_particles, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, model.s.rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 20000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, model.p.px, model.p.py, model.p.pz, model.p.inv_m, &params, &report ),
				  SERE_OK );
	cr_expect( !report.hit_cap, "scale %g: %d iterations, strain %g", scale, report.iterations, report.max_strain );
	float after = max_strain( &model, count, model.s.rest );
	cr_expect_lt( after, params.tolerance, "scale %g: strain after %g, reported %g after %d", scale, after,
				  report.max_strain, report.iterations );
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
}

Test( pbd, stretched_patch_converges )
{
	patch_converges( 1.2f );
}

Test( pbd, compressed_patch_converges )
{
	patch_converges( 0.9f );
}

Test( pbd, colors_are_independent_sets )
{
	sere_model model;
	grid_model( &model, 60, 40, 0.01 );
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, model.s.count, model.p.count, &pbd ), SERE_OK );
	const sere_coloring* coloring = sere_pbd_coloring( pbd );
	int32_t* seen = malloc( sizeof( int32_t ) * model.p.count );
	int32_t total = 0;
	for ( int32_t c = 0; c < coloring->color_count; ++c )
	{
		for ( int32_t i = 0; i < model.p.count; ++i )
		{
			seen[i] = 0;
		}
		for ( int32_t k = coloring->offsets[c]; k < coloring->offsets[c + 1]; ++k )
		{
			int32_t s = coloring->order[k];
			cr_assert_eq( coloring->color[s], c );
			cr_assert_eq( seen[model.s.a[s]]++, 0, "color %d shares particle %d", c, model.s.a[s] );
			cr_assert_eq( seen[model.s.b[s]]++, 0, "color %d shares particle %d", c, model.s.b[s] );
			total += 1;
		}
	}
	cr_expect_eq( total, model.s.count );
	/* Vizing's bound for edge coloring: at most 2 x (max degree) - 1 colors with greedy. */
	int32_t* degree = calloc( model.p.count, sizeof( int32_t ) );
	int32_t max_degree = 0;
	for ( int32_t s = 0; s < model.s.count; ++s )
	{
		max_degree = ++degree[model.s.a[s]] > max_degree ? degree[model.s.a[s]] : max_degree;
		max_degree = ++degree[model.s.b[s]] > max_degree ? degree[model.s.b[s]] : max_degree;
	}
	cr_expect_leq( coloring->color_count, 2 * max_degree - 1 );
	free( seen ), free( degree );
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
}

Test( pbd, deterministic_across_threads )
{
	float* result[2];
	int32_t n = 0;
	for ( int t = 0; t < 2; ++t )
	{
		omp_set_num_threads( t + 1 );
		sere_model model;
		grid_model( &model, 60, 40, 0.01 );
		n = model.p.count;
		for ( int32_t s = 0; s < model.s.count; ++s )
		{
			model.s.rest[s] *= ( model.s.kind[s] & SERE_SPRING_LAYER_MASK ) == SERE_SPRING_V ? 0.9f : 1.0f;
		}
		sere_pbd* pbd;
		cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, model.s.count, model.p.count, &pbd ), SERE_OK );
		cr_assert_eq( sere_pbd_set_rest( pbd, model.s.rest ), SERE_OK );
		sere_pbd_params params = sere_pbd_params_default();
		params.max_iterations = 30;
		sere_pbd_report report;
		cr_assert_eq( sere_pbd_project( pbd, model.p.px, model.p.py, model.p.pz, model.p.inv_m, &params, &report ),
					  SERE_OK );
		result[t] = malloc( sizeof( float ) * 3 * n );
		memcpy( result[t], model.p.px, sizeof( float ) * n );
		memcpy( result[t] + n, model.p.py, sizeof( float ) * n );
		memcpy( result[t] + 2 * n, model.p.pz, sizeof( float ) * n );
		sere_pbd_destroy( pbd );
		sere_model_destroy( &model );
	}
	cr_expect_eq( memcmp( result[0], result[1], sizeof( float ) * 3 * n ), 0 );
	free( result[0] ), free( result[1] );
	omp_set_num_threads( 2 );
}

Test( pbd, colored_and_reference_reach_the_same_shape )
{
	/* In-plane perturbation of a membrane pinned at its rim: the rest shape is the unique
	 * solution, so both solvers must reach it whatever their sweep order. */
	sere_model model;
	grid_model( &model, 20, 14, 0.01 );
	int32_t n = model.triangle_particles, count = model.t_springs;
	sere_ref_particle* ref = malloc( sizeof( sere_ref_particle ) * n );
	sere_ref_spring* springs = malloc( sizeof( sere_ref_spring ) * count );
	for ( int32_t i = 0; i < n; ++i )
	{
		model.p.inv_m[i] = model.boundary[i] ? 0.0f : model.p.inv_m[i];
		float jx = model.boundary[i] ? 0.0f : 0.03f * sinf( 7.0f * i );
		float jy = model.boundary[i] ? 0.0f : 0.03f * cosf( 5.0f * i );
		model.p.px[i] = model.p.x[i] + jx;
		model.p.py[i] = model.p.y[i] + jy;
		model.p.pz[i] = 0.0f;
		ref[i] = ( sere_ref_particle ){ model.p.px[i], model.p.py[i], 0.0f, model.p.inv_m[i] };
	}
	for ( int32_t s = 0; s < count; ++s )
	{
		springs[s] = ( sere_ref_spring ){ model.s.a[s], model.s.b[s], model.s.rest[s] };
	}
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, count, n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, model.s.rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	params.tolerance = 1e-5f;
	params.max_iterations = 20000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, model.p.px, model.p.py, model.p.pz, model.p.inv_m, &params, &report ),
				  SERE_OK );
	float ref_strain;
	int32_t ref_iterations = sere_pbd_ref_project( ref, springs, count, 1.0f, 1e-5f, 20000, &ref_strain );
	cr_assert_lt( ref_strain, 1e-5f, "reference: %d sweeps", ref_iterations );
	float worst = 0.0f;
	for ( int32_t i = 0; i < n; ++i )
	{
		worst = fmaxf( worst, fabsf( model.p.px[i] - ref[i].x ) + fabsf( model.p.py[i] - ref[i].y ) );
	}
	/* Strains below 1e-6 on springs of length 0.1 bound the position error to ~1e-5 per
	 * spring over a chain of about ten springs to the rim: 1e-4 (0.1% of a spacing). */
	cr_expect_lt( worst, 1e-4f, "max difference %g", worst );
	free( ref ), free( springs );
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
}

Test( pbd, shrinking_voronoi_layer_becomes_concave_side )
{
	sere_model model;
	grid_model( &model, 16, 16, 0.03 ); /* Voronoi particles 0.03 above the triangle layer (+z) */
	for ( int32_t s = 0; s < model.s.count; ++s )
	{
		if ( ( model.s.kind[s] & SERE_SPRING_LAYER_MASK ) == SERE_SPRING_V )
		{
			model.s.rest[s] *= 0.9f;
		}
	}
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, model.s.count, model.p.count, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, model.s.rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 3000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, model.p.px, model.p.py, model.p.pz, model.p.inv_m, &params, &report ),
				  SERE_OK );
	/* Curling toward the shrinking layer lifts the rim above the centre (Fig. 2c). */
	double rim = 0.0, centre = 0.0;
	int32_t rim_count = 0, centre_count = 0;
	for ( int32_t i = 0; i < model.triangle_particles; ++i )
	{
		double r = hypot( model.p.x[i] - 0.8, model.p.y[i] - 0.8 );
		if ( model.boundary[i] )
		{
			rim += model.p.pz[i], rim_count += 1;
		}
		else if ( r < 0.25 )
		{
			centre += model.p.pz[i], centre_count += 1;
		}
	}
	cr_expect_gt( rim / rim_count - centre / centre_count, 0.05, "rim %g centre %g", rim / rim_count,
				  centre / centre_count );
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
}

Test( pbd, bad_input_gives_errors )
{
	int32_t a[2] = { 0, 1 }, b[2] = { 1, 2 };
	float rest[2] = { 1.0f, 1.0f }, inv_m[3] = { 1.0f, 1.0f, 1.0f };
	float x[3] = { 0.0f, 1.0f, 2.0f }, y[3] = { 0 }, z[3] = { 0 };
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( a, b, 2, 3, &pbd ), SERE_OK );
	float zero[2] = { 1.0f, 0.0f };
	cr_expect_eq( sere_pbd_set_rest( pbd, zero ), SERE_ERR_GEOMETRY );
	cr_assert_eq( sere_pbd_set_rest( pbd, rest ), SERE_OK );
	sere_pbd_params params = sere_pbd_params_default();
	sere_pbd_report report;
	x[1] = NAN;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	cr_expect( isnan( x[1] ) && x[0] == 0.0f && x[2] == 2.0f, "nothing else touched" );
	x[1] = 0.0f; /* particles 0 and 1 coincide: a zero-length spring */
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	cr_expect( isfinite( x[0] ) && isfinite( x[1] ) && isfinite( x[2] ) );
	sere_pbd_destroy( pbd );
}

Test( shrink, eq12_values_and_stop_rules )
{
	int32_t a[3] = { 0, 2, 4 }, b[3] = { 1, 3, 5 };
	uint8_t kind[3] = { SERE_SPRING_T | SERE_SPRING_VEIN, SERE_SPRING_V, SERE_SPRING_T };
	float rest0[3] = { 2.0f, 2.0f, 2.0f }, rest[3] = { 2.0f, 2.0f, 1.5f };
	double m0[6] = { 1.0, 1.0, 1.0, 1.0, 1.0, 1.0 };
	double m[6] = { 0.6, 0.6, 0.6, 0.6, 0.05, 0.6 };
	sere_shrink_params params = {
		.sigma_vein = 0.5, .sigma_surf = 1.5, .alpha = 1.3, .m_min = 0.1, .min_length_ratio = 0.2
	};
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, m, m0, &params ), SERE_OK );
	/* v_rel = 0.6 (Eq. 11); l = l0 (1 - σ 0.4^1.3) (Eq. 12), computed in double then rounded to float */
	cr_expect_float_eq( rest[0], (float) ( 2.0 * ( 1.0 - 0.5 * pow( 0.4, 1.3 ) ) ), 1e-6f );
	cr_expect_float_eq( rest[1], (float) ( 2.0 * ( 1.0 - 1.5 * pow( 0.4, 1.3 ) ) ), 1e-6f );
	cr_expect_eq( rest[2], 1.5f ); /* a particle below m_min: the spring keeps its length */
	/* Below the length ratio: σ = 10 would make l negative, so the spring stops. */
	params.sigma_surf = 10.0;
	rest[1] = 1.7f;
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 1, 1, m, m0, &params ), SERE_OK );
	cr_expect_eq( rest[1], 1.7f );
	/* Gaining water (v_rel > 1) restores at most the rest length. */
	double wet[6] = { 1.2, 1.2, 1.2, 1.2, 1.2, 1.2 };
	cr_assert_eq( sere_shrink( a, b, kind, rest0, rest, 0, 3, wet, m0, &params ), SERE_OK );
	cr_expect_eq( rest[0], 2.0f );
	cr_expect_eq( rest[1], 2.0f );
}
