/* What the public headers promise for bad input, kernel by kernel, for a caller who plugs one
 * kernel into another solver: each case below once came back OK with a wrong result, crashed, or
 * named the wrong cause. The statuses are core/base.h's: ARGUMENT for a null pointer or a value
 * out of range, NONFINITE for NaN or infinity in the data, GEOMETRY for a shape that cannot be
 * used. */
#include "drying/layers.h"
#include "drying/leaf.h"
#include "drying/model.h"
#include "fixture.h"
#include "mesh/measure.h"
#include "mesh/sample.h"
#include "mesh/shape.h"
#include "solve/bvh.h"
#include "wilt/skeleton.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The unit square with its centre, the centre listed first and the corners after it. */
static const double kCentreX[5] = { 0.5, 0, 1, 1, 0 }, kCentreY[5] = { 0.5, 0, 0, 1, 1 };
static const int32_t kCentreTri[12] = { 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 0 };
/* The same square with the corners first, as the header asks. */
static const double kCornerX[5] = { 0, 1, 1, 0, 0.5 }, kCornerY[5] = { 0, 0, 1, 1, 0.5 };
static const int32_t kCornerTri[12] = { 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4 };

Test( contracts, a_plane_mesh_must_list_its_outline_first )
{
	sere_layer_params params = sere_layer_params_default();
	sere_model model;
	/* the centre first: four boundary edges as the count says, but the flags would mark the centre */
	sere_plane_mesh centre_first = { kCentreX, kCentreY, 5, 4, kCentreTri, 4, NULL, 0, 1 };
	cr_expect_eq( sere_model_from_triangles( &centre_first, &params, &model ), SERE_ERR_GEOMETRY );
	sere_plane_mesh corners_first = { kCornerX, kCornerY, 5, 4, kCornerTri, 4, NULL, 0, 0 };
	cr_assert_eq( sere_model_from_triangles( &corners_first, &params, &model ), SERE_OK );
	int32_t flagged = 0;
	for ( int32_t i = 0; i < model.triangle_particles; ++i )
	{
		flagged += model.boundary[i] != 0;
		cr_expect_eq( model.boundary[i] != 0, !( model.p.x[i] == 0.5f && model.p.y[i] == 0.5f ), "particle %d", i );
	}
	cr_expect_eq( flagged, 4 );
	sere_model_destroy( &model );

	/* a vein segment naming a point that is not there (it once wrote outside the model) */
	const int32_t far_vein[2] = { 0, 100000000 }, negative_vein[2] = { 0, -7 };
	sere_plane_mesh veined = corners_first;
	veined.vein_segment_count = 1;
	veined.vein_segments = far_vein;
	cr_expect_eq( sere_model_from_triangles( &veined, &params, &model ), SERE_ERR_ARGUMENT );
	veined.vein_segments = negative_vein;
	cr_expect_eq( sere_model_from_triangles( &veined, &params, &model ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_model_from_triangles( &corners_first, &params, NULL ), SERE_ERR_ARGUMENT );
	int32_t n, b;
	cr_expect_eq( sere_counts_solve( 278, 1068, NULL, &b ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_counts_solve( 278, 1068, &n, NULL ), SERE_ERR_ARGUMENT );
}

Test( contracts, masses_refuse_a_zero_mass_and_nan )
{
	sere_layer_params params = sere_layer_params_default();
	sere_model model;
	sere_plane_mesh mesh = { kCornerX, kCornerY, 5, 4, kCornerTri, 4, NULL, 0, 0 };
	cr_assert_eq( sere_model_from_triangles( &mesh, &params, &model ), SERE_OK );
	sere_layer_params bad = params;
	bad.m_min = 0.0; /* m⁰ = 0 at the farthest particle: an infinite inverse mass */
	cr_expect_eq( sere_model_assign_masses( &model, &bad ), SERE_ERR_ARGUMENT );
	bad = params, bad.mu0 = NAN;
	cr_expect_eq( sere_model_assign_masses( &model, &bad ), SERE_ERR_ARGUMENT );
	bad = params, bad.D = NAN;
	cr_expect_eq( sere_model_assign_masses( &model, &bad ), SERE_ERR_ARGUMENT );
	bad = params, bad.omega_vein = INFINITY;
	cr_expect_eq( sere_model_assign_masses( &model, &bad ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_model_assign_masses( NULL, &params ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_model_assign_masses( &model, &params ), SERE_OK );
	for ( int32_t i = 0; i < model.p.count; ++i )
	{
		cr_expect( isfinite( model.p.inv_m[i] ) && model.p.inv_m[i] > 0.0f, "inverse mass %g", model.p.inv_m[i] );
	}
	sere_model_destroy( &model );
}

Test( contracts, a_leaf_step_refuses_what_would_poison_it )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, 6, 5, 0.6, 0.5, 0.2, 1, 3 );
	sere_layer_params layer = sere_layer_params_default();
	sere_model model;
	sere_status built = sere_model_from_triangles( &plane.mesh, &layer, &model );
	cr_assert_eq( built, SERE_OK, "%s", sere_status_text( built ) );
	sere_test_plane_free( &plane );
	sere_leaf_sim* sim;
	cr_assert_eq( sere_leaf_create( &model, &sim ), SERE_OK );
	sere_leaf_stats stats;
	const float dampings[3] = { NAN, 3.0f, -0.1f }, grounds[2] = { NAN, INFINITY };
	for ( int k = 0; k < 3; ++k )
	{
		sere_leaf_params params = sere_leaf_params_default();
		params.damping = dampings[k];
		cr_expect_eq( sere_leaf_step( sim, &params, &stats ), SERE_ERR_ARGUMENT, "damping %g", dampings[k] );
	}
	for ( int k = 0; k < 2; ++k )
	{
		sere_leaf_params params = sere_leaf_params_default();
		params.ground = grounds[k];
		cr_expect_eq( sere_leaf_step( sim, &params, &stats ), SERE_ERR_ARGUMENT, "ground %g", grounds[k] );
	}
	sere_leaf_params params = sere_leaf_params_default();
	cr_expect_eq( sere_leaf_step( sim, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_leaf_step( sim, &params, &stats ), SERE_OK, "the refusals left the leaf usable" );
	for ( int32_t i = 0; i < model.p.count; ++i )
	{
		cr_assert( isfinite( model.p.vz[i] ), "velocity %d is %g", i, model.p.vz[i] );
	}

	/* Initial shaping: refused before it changes a rest length. */
	const int32_t first_v = model.t_springs;
	const float rest_before = model.s.rest[first_v];
	sere_pbd_params pbd = sere_pbd_params_default();
	cr_expect_eq( sere_leaf_shape_initial( sim, 0.1f, 0.1f, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_leaf_shape_initial( sim, 1.0f, 0.1f, &pbd ), SERE_ERR_ARGUMENT, "crease 1: zero rest" );
	cr_expect_eq( sere_leaf_shape_initial( sim, 0.1f, -1.0f, &pbd ), SERE_ERR_ARGUMENT, "curl −1: zero rest" );
	cr_expect_eq( sere_leaf_shape_initial( sim, NAN, 0.1f, &pbd ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_leaf_shape_initial( NULL, 0.1f, 0.1f, &pbd ), SERE_ERR_ARGUMENT );
	cr_expect_eq( memcmp( &model.s.rest[first_v], &rest_before, sizeof( float ) ), 0 );
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
}

Test( contracts, a_tree_of_one_node_keeps_its_quality )
{
	const int32_t tri[6] = { 0, 1, 2, 0, 2, 3 };
	float x[4] = { 0, 1, 1, 0 }, y[4] = { 0, 0, 1, 1 }, z[4] = { 0 };
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, 2, 4, x, y, z, &bvh ), SERE_OK );
	cr_expect_eq( sere_bvh_quality_ratio( bvh ), 1.0, "right after the build (it was 0/0)" );
	z[2] = 5.0f;
	cr_assert_eq( sere_bvh_refit( bvh, x, y, z ), SERE_OK );
	cr_expect_eq( sere_bvh_quality_ratio( bvh ), 1.0, "one node has nothing below its root to swell" );
	cr_expect( !sere_bvh_needs_rebuild( bvh, 1.5 ) );
	sere_bvh_destroy( bvh );
}

/* The square as a shape input for the measures, with one vein up its middle. */
typedef struct measured_square
{
	float x[5], y[5], z[5];
	int32_t tri[12], edge_a[8], edge_b[8];
	uint8_t boundary[5];
	double vein_xy[4];
	sere_vein vein;
	sere_leaf_shape veins;
	sere_shape_input in;
} measured_square;

static void measured_square_make( measured_square* s )
{
	memset( s, 0, sizeof( *s ) );
	const int32_t ea[8] = { 0, 1, 2, 3, 0, 1, 2, 3 }, eb[8] = { 1, 2, 3, 0, 4, 4, 4, 4 };
	for ( int i = 0; i < 5; ++i )
	{
		s->x[i] = (float) kCornerX[i], s->y[i] = (float) kCornerY[i], s->boundary[i] = i < 4;
	}
	memcpy( s->tri, kCornerTri, sizeof( s->tri ) );
	memcpy( s->edge_a, ea, sizeof( ea ) ), memcpy( s->edge_b, eb, sizeof( eb ) );
	const double vein_xy[4] = { 0.5, 0.0, 0.5, 1.0 };
	memcpy( s->vein_xy, vein_xy, sizeof( vein_xy ) );
	s->vein = ( sere_vein ){ 0, 2, 1, -1 };
	s->veins.vein_count = 1, s->veins.veins = &s->vein;
	s->veins.vein_point_count = 2, s->veins.vein_xy = s->vein_xy;
	s->in = sere_shape_input_default();
	s->in.x = s->x, s->in.y = s->y, s->in.z = s->z, s->in.u = s->x, s->in.v = s->y;
	s->in.vertex_count = 5, s->in.tri = s->tri, s->in.triangle_count = 4;
	s->in.edge_a = s->edge_a, s->in.edge_b = s->edge_b, s->in.edge_count = 8;
	s->in.boundary = s->boundary, s->in.threads = 1;
	s->in.veins = &s->veins;
}

Test( contracts, the_measures_check_the_veins_they_walk )
{
	static measured_square s;
	sere_shape out;
	measured_square_make( &s );
	cr_expect_eq( sere_shape_measure( &s.in, &out ), SERE_OK );
	s.vein.first = 1000000, s.vein.count = 5; /* it once read there */
	cr_expect_eq( sere_shape_measure( &s.in, &out ), SERE_ERR_ARGUMENT );
	measured_square_make( &s );
	s.vein.count = -3;
	cr_expect_eq( sere_shape_measure( &s.in, &out ), SERE_ERR_ARGUMENT );
	measured_square_make( &s );
	s.vein_xy[1] = NAN; /* it once measured a NaN crease with SERE_OK */
	cr_expect_eq( sere_shape_measure( &s.in, &out ), SERE_ERR_NONFINITE );

	/* validation of a plane shape: no check to write into, and vein points without their array */
	const double outline[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };
	sere_leaf_shape shape = { 0.5, 0.0, 4, outline, 0, NULL, 3, NULL };
	sere_shape_check check;
	cr_expect_eq( sere_shape_validate( &shape, &check ), SERE_ERR_ARGUMENT );
	shape.vein_point_count = 0;
	cr_expect_eq( sere_shape_validate( &shape, NULL ), SERE_ERR_ARGUMENT );
}

Test( contracts, null_outputs_are_refused )
{
	const double outline[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };
	sere_leaf_shape shape = { 0.5, 0.0, 4, outline, 0, NULL, 0, NULL };
	const sere_sample_params sample = { 40, 12, 1, 0 };
	cr_expect_eq( sere_sample_leaf( &shape, &sample, NULL ), SERE_ERR_ARGUMENT );
	sere_build_params build = sere_build_params_default();
	cr_expect_eq( sere_model_build( &shape, &build, NULL, NULL ), SERE_ERR_ARGUMENT );
	const int32_t tri[3] = { 0, 1, 2 };
	const float x[3] = { 0, 1, 0 }, y[3] = { 0, 0, 1 }, z[3] = { 0 };
	cr_expect_eq( sere_pierce_create( tri, 1, 3, x, y, z, NULL, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_plant_create( NULL, 0, NULL, 0, NULL ), SERE_ERR_ARGUMENT );
	const double mid[4] = { 0, 0, 10, 0 };
	const sere_vein_spec midvein = { -1, 1, 1.0f, 2, mid };
	sere_skeleton_check check = { SERE_SKELETON_DETACHED, 7, 7 };
	cr_expect_eq( sere_skeleton_create( &midvein, 1, NULL, &check ), SERE_ERR_ARGUMENT );
	cr_expect_eq( check.problem, SERE_SKELETON_OK, "no problem of an earlier call left behind" );

	/* generated venation: a refused call clears the check (it kept an earlier call's problem) */
	enum
	{
		features = 9
	};
	double left[2 * features], right[2 * features], middle[2 * features];
	cr_assert_eq( sere_leaf_skeleton_generate( 1.0, 0.5, features, left, right, middle ), SERE_OK );
	const sere_leaf_skeleton leaf = { features, features, features, left, right, middle };
	sere_venation_params venation = sere_venation_params_default();
	venation.start = -1.0f;
	sere_skeleton skeleton;
	check = ( sere_skeleton_check ){ SERE_SKELETON_DETACHED, 7, 7 };
	cr_expect_eq( sere_skeleton_generate( &leaf, &venation, &skeleton, &check ), SERE_ERR_ARGUMENT );
	cr_expect_eq( check.problem, SERE_SKELETON_OK );
	venation = sere_venation_params_default();
	cr_expect_eq( sere_skeleton_generate( &leaf, &venation, NULL, &check ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_leaf_skeleton_mesh( &leaf, 0.05, NULL, &check ), SERE_ERR_ARGUMENT );

	/* a spacing the mesh cannot hold is refused by the validation too (it passed there) */
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 4e-4, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_BAD_SPACING );
	sere_tri_mesh mesh;
	cr_expect_eq( sere_leaf_skeleton_mesh( &leaf, 4e-4, &mesh, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.05, &check ), SERE_OK );
}
