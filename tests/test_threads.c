/* The thread count is said at the call (kernels/core/base.h): every object's set_threads and
 * every `threads` argument take 0 (OpenMP's count) to SERE_MAX_THREADS and refuse the rest. */
#include "drying/leaf.h"
#include "drying/model.h"
#include "drying/osmosis.h"
#include "drying/shrink.h"
#include "fixture.h"
#include "mesh/measure.h"
#include "read/leafload.h"
#include "season/markov.h"
#include "season/massspring.h"
#include "solve/cg.h"
#include "solve/collide.h"
#include "solve/pbd.h"
#include "solve/vbd.h"
#include "wilt/skeleton.h"

#include <criterion/criterion.h>
#include <stdio.h>

static void maple( sere_model* model )
{
	char err[1024];
	sere_leaf_source leaf;
	cr_assert_eq( sere_leaf_source_load( "data/leaves/maple.leaf", &leaf, err, sizeof( err ) ), 0, "%s", err );
	sere_build_params params = sere_build_params_default();
	params.point_count = 800;
	params.boundary_count =
		sere_boundary_for_points( sere_shape_area( &leaf.file.shape ), sere_shape_perimeter( &leaf.file.shape ), 800 );
	cr_assert_eq( sere_model_build( &leaf.file.shape, &params, model, NULL ), SERE_OK );
	sere_leaf_source_destroy( &leaf );
}

/* The setters, each through the one signature sere_test_expect_thread_range calls. */
#define SETTER( type, fn )                                                                                             \
	static sere_status set_##fn( void* object, int32_t threads )                                                       \
	{                                                                                                                  \
		return fn( (type*) object, threads );                                                                          \
	}
SETTER( sere_pbd, sere_pbd_set_threads )
SETTER( sere_bvh, sere_bvh_set_threads )
SETTER( sere_collide, sere_collide_set_threads )
SETTER( sere_cg_workspace, sere_cg_set_threads )
SETTER( sere_sell, sere_sell_set_threads )
SETTER( sere_sgs, sere_sgs_set_threads )
SETTER( sere_osmosis, sere_osmosis_set_threads )
SETTER( sere_crossings, sere_crossings_set_threads )
SETTER( sere_massspring, sere_massspring_set_threads )
SETTER( sere_leaf_sim, sere_leaf_set_threads )
SETTER( sere_joint_grid, sere_joint_grid_set_threads )
SETTER( sere_pierce, sere_pierce_set_threads )
SETTER( sere_vbd, sere_vbd_set_threads )

Test( threads, every_object_takes_zero_to_the_limit )
{
	sere_model model;
	maple( &model );
	const int32_t n = model.triangle_particles, f = model.triangle_count;
	const sere_particles* p = &model.p;
	sere_pbd* pbd;
	sere_bvh* bvh;
	sere_collide* collide;
	sere_cg_workspace* cg;
	sere_sell* sell;
	sere_sgs* sgs;
	sere_osmosis* osmosis;
	sere_crossings* crossings;
	sere_massspring* ms;
	sere_leaf_sim* sim;
	sere_joint_grid* grid;
	sere_pierce* pierce;
	sere_vbd* vbd;
	cr_assert_eq( sere_pbd_create( model.s.a, model.s.b, model.s.count, p->count, &pbd ), SERE_OK );
	cr_assert_eq( sere_bvh_create( model.tri, f, n, p->x, p->y, p->z, &bvh ), SERE_OK );
	cr_assert_eq( sere_vbd_create( model.s.a, model.s.b, model.s.count, p->count, &vbd ), SERE_OK );
	cr_assert_eq( sere_collide_create( bvh, 0, &collide ), SERE_OK );
	cr_assert_eq( sere_osmosis_create( 0, n, model.s.a, model.s.b, model.t_springs, &osmosis ), SERE_OK );
	const sere_csr* a = sere_osmosis_matrix( osmosis );
	cr_assert_eq( sere_cg_create( n, &cg ), SERE_OK );
	cr_assert_eq( sere_sell_create( a, SERE_SELL_SIGMA, &sell ), SERE_OK );
	cr_assert_eq( sere_sgs_create( a, &sgs ), SERE_OK );
	cr_assert_eq( sere_crossings_create( model.tri, f, n, &crossings ), SERE_OK );
	cr_assert_eq( sere_massspring_create( p->x, p->y, p->z, n, model.tri, f, &ms ), SERE_OK );
	cr_assert_eq( sere_leaf_create( &model, &sim ), SERE_OK );
	cr_assert_eq( sere_joint_grid_create( p->x, p->y, p->z, n, &grid ), SERE_OK );
	cr_assert_eq( sere_pierce_create( model.tri, f, n, p->x, p->y, p->z, NULL, &pierce ), SERE_OK );

	const struct
	{
		const char* name;
		void* object;
		sere_test_set_fn* set;
	} setters[] = { { "pbd", pbd, set_sere_pbd_set_threads },
					{ "bvh", bvh, set_sere_bvh_set_threads },
					{ "collide", collide, set_sere_collide_set_threads },
					{ "cg", cg, set_sere_cg_set_threads },
					{ "sell", sell, set_sere_sell_set_threads },
					{ "sgs", sgs, set_sere_sgs_set_threads },
					{ "osmosis", osmosis, set_sere_osmosis_set_threads },
					{ "crossings", crossings, set_sere_crossings_set_threads },
					{ "massspring", ms, set_sere_massspring_set_threads },
					{ "leaf", sim, set_sere_leaf_set_threads },
					{ "joint grid", grid, set_sere_joint_grid_set_threads },
					{ "pierce", pierce, set_sere_pierce_set_threads },
					{ "descent", vbd, set_sere_vbd_set_threads } };
	for ( size_t k = 0; k < sizeof( setters ) / sizeof( setters[0] ); ++k )
	{
		sere_test_expect_thread_range( setters[k].name, setters[k].object, setters[k].set );
	}

	sere_pierce_destroy( pierce );
	sere_vbd_destroy( vbd );
	sere_joint_grid_destroy( grid );
	sere_leaf_destroy( sim );
	sere_massspring_destroy( ms );
	sere_crossings_destroy( crossings );
	sere_sgs_destroy( sgs );
	sere_sell_destroy( sell );
	sere_cg_destroy( cg );
	sere_osmosis_destroy( osmosis );
	sere_collide_destroy( collide );
	sere_bvh_destroy( bvh );
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
}

/* Kernels on plain arrays check their `threads` argument before anything else that would pass:
 * each call here succeeds at 0 threads and is refused one past either bound. */
Test( threads, arguments_out_of_range_are_refused )
{
	sere_model model;
	maple( &model );
	const int32_t n = model.triangle_particles, f = model.triangle_count;
	sere_particles* p = &model.p;
	const int32_t bad[] = { -1, SERE_MAX_THREADS + 1 };
	for ( int k = 0; k < 3; ++k )
	{
		const int32_t threads = k < 2 ? bad[k] : 0;
		const sere_status expected = k < 2 ? SERE_ERR_ARGUMENT : SERE_OK;
		sere_shrink_params shrink = { .sigma_vein = 0.5, .sigma_surf = 0.5, .alpha = 1.3, .m_min = 0.1 };
		cr_expect_eq( sere_shrink( model.s.a, model.s.b, model.s.kind, model.s.rest0, model.s.rest, 0, 0, p->m, p->m0,
								   &shrink, threads ),
					  expected, "shrink at %d threads", threads );
		sere_markov_day day = { .state_count = 1 };
		uint8_t state = 0;
		int64_t count = 0;
		cr_expect_eq( sere_markov_advance( &day, &state, 1, 0, 1, 0, NULL, threads ), expected, "advance at %d",
					  threads );
		cr_expect_eq( sere_markov_count( &state, 1, 1, &count, threads ), expected, "count at %d", threads );
		int64_t crossings = -1;
		cr_expect_eq( sere_crossings_count_once( p->x, p->y, p->z, n, model.tri, f, &crossings, threads ), expected,
					  "crossings at %d", threads );
		cr_expect_eq( sere_collide_measure_h( p->x, p->y, p->z, model.tri, f, n, model.h, threads ), expected,
					  "measure_h at %d", threads );
		cr_expect_eq(
			sere_collide_restore_voronoi( p->x, p->y, p->z, p->vx, p->vy, p->vz, model.tri, f, n, model.h, threads ),
			expected, "restore at %d", threads );
		uint8_t* moved = calloc( (size_t) n, 1 );
		cr_expect_eq( sere_collide_restore_voronoi_moved( p->x, p->y, p->z, p->vx, p->vy, p->vz, model.tri, f, n,
														  model.h, moved, 0.002f, threads ),
					  expected, "restore moved at %d", threads );
		cr_expect_eq( sere_collide_measure_h_moved( p->x, p->y, p->z, p->x, p->y, p->z, model.tri, f, n, moved, model.h,
													threads ),
					  expected, "measure_h moved at %d", threads );
		free( moved );
	}
	sere_model_destroy( &model );
}
