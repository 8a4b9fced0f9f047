#include "build.h"

#include "leafload.h"

#include <stdio.h>

int sere_harness_build( const char* path, long long particles, long long springs, long long points,
						const sere_sim_params* params, sere_model* model, sere_build_report* report, char* name,
						size_t name_size, char* err, size_t err_size )
{
	sere_leaf leaf;
	if ( sere_leaf_load( path, &leaf, err, err_size ) != 0 )
	{
		return -1;
	}
	const sere_leaf_shape* shape = &leaf.file.shape;
	snprintf( name, name_size, "%s", leaf.file.name );
	sere_build_params build = sere_build_params_default();
	build.layer = params->layer;
	build.seed = (uint64_t) params->seed;
	if ( particles >= 0 && springs >= 0 )
	{
		if ( sere_counts_solve( particles, springs, &build.point_count, &build.boundary_count ) != SERE_OK )
		{
			snprintf( err, err_size,
					  "no triangulation has %lld particles and %lld springs (need particles = 3N - B - 2, springs = "
					  "12N - 6B - 12 with 3 <= B <= N)",
					  particles, springs );
			sere_leaf_free( &leaf );
			return -1;
		}
	}
	else
	{
		build.point_count = (int32_t) points;
		build.boundary_count =
			sere_boundary_for_points( sere_shape_area( shape ), sere_shape_perimeter( shape ), build.point_count );
	}
	sere_status status = sere_model_build( shape, &build, model, report );
	sere_leaf_free( &leaf );
	if ( status != SERE_OK )
	{
		snprintf( err, err_size, "%s: cannot build N=%d B=%d: %s", path, build.point_count, build.boundary_count,
				  sere_status_text( status ) );
		return -1;
	}
	return 0;
}
