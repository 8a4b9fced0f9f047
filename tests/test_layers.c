#include "drying/layers.h"
#include "fixture.h"

#include <criterion/criterion.h>
#include <math.h>

Test( layers, counts_solve_table1 )
{
	/* Table 1's three leaves: docs/DESIGN.md gives their N and B. */
	const int64_t cases[3][4] = { { 13197, 51102, 4680, 841 },
								  { 15069, 59550, 5144, 361 },
								  { 12750, 50436, 4344, 280 } };
	for ( int k = 0; k < 3; ++k )
	{
		int32_t n = 0, b = 0;
		cr_assert_eq( sere_counts_solve( cases[k][0], cases[k][1], &n, &b ), SERE_OK );
		cr_expect_eq( n, cases[k][2] );
		cr_expect_eq( b, cases[k][3] );
	}
}

Test( layers, counts_solve_rejects_impossible )
{
	int32_t n, b;
	cr_expect_eq( sere_counts_solve( 13197, 51103, &n, &b ), SERE_ERR_COUNTS ); /* springs + 12 not a multiple of 6 */
	cr_expect_eq( sere_counts_solve( 100, 30000, &n, &b ), SERE_ERR_COUNTS );	/* N < B */
	cr_expect_eq( sere_counts_solve( 0, 0, &n, &b ), SERE_ERR_COUNTS );
	cr_expect_eq( sere_counts_solve( -5, 51102, &n, &b ), SERE_ERR_COUNTS );
}

/* The double layer (sere_model_from_triangles) on a jittered grid with a vein row. */
static void layers_build( sere_test_plane* plane, int32_t nx, int32_t ny, double width, double height, double jitter,
						  uint64_t seed, const sere_layer_params* params, sere_model* model )
{
	sere_test_plane_grid( plane, nx, ny, width, height, jitter, 1, seed );
	cr_assert_eq( sere_model_from_triangles( &plane->mesh, params, model ), SERE_OK );
}

static void layers_free( sere_test_plane* plane, sere_model* model )
{
	sere_model_destroy( model );
	sere_test_plane_free( plane );
}

Test( layers, double_layer_counts_and_springs )
{
	sere_layer_params params = sere_layer_params_default();
	params.h_vein = -0.02;
	params.h_surf = 0.005;
	sere_test_plane plane;
	sere_model model;
	layers_build( &plane, 12, 8, 1.2, 0.8, 0.3, 7, &params, &model );
	int32_t n = plane.mesh.point_count, b = plane.mesh.boundary_count;
	cr_expect_eq( model.triangle_count, 2 * n - b - 2 );
	cr_expect_eq( model.p.count, 3 * n - b - 2 );
	cr_expect_eq( model.s.count, 12 * n - 6 * b - 12 );
	cr_expect_eq( model.t_springs, 3 * n - b - 3 );
	cr_expect_eq( model.v_springs, 3 * n - 2 * b - 3 );
	cr_expect_eq( model.l_springs, 3 * model.triangle_count );
	cr_expect_eq( model.p.capacity % SERE_PAD, 0 );

	int32_t boundary_flags = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		boundary_flags += model.boundary[i];
	}
	cr_expect_eq( boundary_flags, b );

	/* Spring kinds in blocks T, V, L; endpoints in the right layers; a < b. */
	int32_t vein_t = 0, vein_v = 0;
	for ( int32_t s = 0; s < model.s.count; ++s )
	{
		int layer = model.s.kind[s] & SERE_SPRING_LAYER_MASK;
		int expected = s < model.t_springs ? SERE_SPRING_T
										   : ( s < model.t_springs + model.v_springs ? SERE_SPRING_V : SERE_SPRING_L );
		cr_assert_eq( layer, expected, "spring %d", s );
		cr_assert_lt( model.s.a[s], model.s.b[s] );
		if ( layer == SERE_SPRING_T )
		{
			cr_assert_lt( model.s.b[s], n );
			vein_t += ( model.s.kind[s] & SERE_SPRING_VEIN ) != 0;
		}
		else if ( layer == SERE_SPRING_V )
		{
			cr_assert_geq( model.s.a[s], n );
			vein_v += ( model.s.kind[s] & SERE_SPRING_VEIN ) != 0;
		}
		else
		{
			cr_assert_lt( model.s.a[s], n );
			cr_assert_geq( model.s.b[s], n );
		}
		cr_assert_gt( model.s.rest0[s], 0.0f );
	}
	/* The middle row has 12 vein edges, all interior, so 12 vein T and 12 vein V springs. */
	cr_expect_eq( vein_t, 12 );
	cr_expect_eq( vein_v, 12 );
	cr_expect_eq( model.vein_springs, 24 );

	/* Voronoi particles at centroid + h n with n = +z (Fig. 5e); tolerance: float centroid of
	 * values ≤ 1.2 rounds within a few ulps. */
	for ( int32_t t = 0; t < model.triangle_count; ++t )
	{
		const int32_t* v = model.tri + 3 * t;
		float cx = ( model.p.x[v[0]] + model.p.x[v[1]] + model.p.x[v[2]] ) / 3.0f;
		cr_expect_float_eq( model.p.x[n + t], cx, 1e-6f );
		float h = model.tri_vein[t] ? -0.02f : 0.005f;
		cr_expect_float_eq( model.p.z[n + t], h, 1e-9f );
		float normal[3];
		sere_model_triangle_normal( &model, t, normal );
		cr_expect_float_eq( normal[2], 1.0f, 1e-6f, "triangle %d must be counter-clockwise", t );
	}
	layers_free( &plane, &model );
}

Test( layers, tau_and_masses )
{
	sere_layer_params params = sere_layer_params_default();
	params.D = 2.0;
	sere_test_plane plane;
	sere_model model;
	layers_build( &plane, 16, 10, 1.6, 1.0, 0.25, 11, &params, &model );
	int32_t n = model.triangle_particles;
	/* Jeong Eq. 1: τ = 1 at the base and 0 at the farthest particle; Jeong Eq. 2 maps it onto [m_min, m_max]. */
	cr_expect_float_eq( model.p.tau[model.base], 1.0f, 0.0f );
	cr_expect_eq( model.d[model.base], 0.0 );
	float tau_min = 1.0f;
	for ( int32_t i = 0; i < model.p.count; ++i )
	{
		cr_assert( model.p.tau[i] >= 0.0f && model.p.tau[i] <= 1.0f );
		cr_assert( model.p.m0[i] >= params.m_min - 1e-12 && model.p.m0[i] <= params.m_max + 1e-12 );
		/* w = μ⁰ m and M = m − w hold to rounding of one multiply and one subtract. */
		cr_assert( fabs( model.p.w[i] - params.mu0 * model.p.m0[i] ) <= 1e-15 );
		cr_assert( fabs( model.p.M[i] + model.p.w[i] - model.p.m[i] ) <= 1e-15 );
		cr_assert_float_eq( model.p.inv_m[i], (float) ( 1.0 / model.p.m0[i] ), 1e-6f );
		if ( i < n )
		{
			tau_min = fminf( tau_min, model.p.tau[i] );
		}
	}
	cr_expect_float_eq( tau_min, 0.0f, 0.0f );
	/* Vein springs are cheaper (ω_vein < ω_surf): a particle on the vein row far from the base
	 * is closer in weighted distance than one at the same plane distance off the vein. */
	double far_vein = 0.0;
	double far_corner = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( model.vein[i] )
		{
			far_vein = fmax( far_vein, model.d[i] );
		}
		far_corner = fmax( far_corner, model.d[i] );
	}
	cr_expect_lt( far_vein, 0.5 * far_corner );
	/* Voronoi masses are their triangle's mean (Sec. 4). */
	for ( int32_t t = 0; t < model.triangle_count; ++t )
	{
		const int32_t* v = model.tri + 3 * t;
		double mean = ( model.p.m0[v[0]] + model.p.m0[v[1]] + model.p.m0[v[2]] ) / 3.0;
		cr_assert( fabs( model.p.m0[n + t] - mean ) <= 1e-15 );
	}
	layers_free( &plane, &model );
}

Test( layers, rejects_bad_meshes )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, 4, 4, 1.0, 1.0, 0.0, 0, 1 );
	sere_layer_params params = sere_layer_params_default();
	sere_model model;
	/* A clockwise triangle. */
	int32_t saved = plane.tri[1];
	plane.tri[1] = plane.tri[2];
	plane.tri[2] = saved;
	cr_expect_eq( sere_model_from_triangles( &plane.mesh, &params, &model ), SERE_ERR_GEOMETRY );
	plane.tri[2] = plane.tri[1];
	plane.tri[1] = saved;
	/* A hole: drop one triangle, so boundary edges no longer match the outline. */
	plane.mesh.triangle_count -= 1;
	cr_expect_eq( sere_model_from_triangles( &plane.mesh, &params, &model ), SERE_ERR_GEOMETRY );
	plane.mesh.triangle_count += 1;
	/* NaN coordinates. */
	plane.x[3] = NAN;
	cr_expect_eq( sere_model_from_triangles( &plane.mesh, &params, &model ), SERE_ERR_NONFINITE );
	plane.x[3] = 0.75;
	/* Out-of-range parameters. */
	params.mu0 = 1.5;
	cr_expect_eq( sere_model_from_triangles( &plane.mesh, &params, &model ), SERE_ERR_ARGUMENT );
	sere_test_plane_free( &plane );
}
