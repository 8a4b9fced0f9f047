#include "read/build.h"

#include "read/leafload.h"

#include <stdio.h>

/* N points with the outline count B matched to the interior spacing, or, when that leaves the
 * veins no room (a leaf with many veins and few points) or a vein point outside the coarse
 * outline, the largest smaller B that builds. */
static sere_status build_points( const sere_leaf_shape* shape, sere_build_params* build, int32_t n, sere_model* model,
								 sere_build_report* report )
{
	int32_t matched = sere_boundary_for_points( sere_shape_area( shape ), sere_shape_perimeter( shape ), n );
	int32_t step = matched / 16 > 1 ? matched / 16 : 1;
	sere_status status = SERE_ERR_COUNTS;
	for ( int32_t b = matched; b >= 3; b -= step )
	{
		build->point_count = n;
		build->boundary_count = b;
		status = sere_model_build( shape, build, model, report );
		if ( status != SERE_ERR_COUNTS && status != SERE_ERR_GEOMETRY )
		{
			break;
		}
	}
	return status;
}

sere_status sere_harness_build( const char* path, long long particles, long long springs, long long points,
								const sere_sim_params* params, sere_model* model, sere_build_report* report, char* name,
								size_t name_size, char* err, size_t err_size )
{
	sere_leaf_source leaf;
	sere_status status = sere_leaf_source_load( path, &leaf, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	status = sere_harness_build_leaf( &leaf, path, particles, springs, points, params, model, report, name, name_size,
									  err, err_size );
	sere_leaf_source_destroy( &leaf );
	return status;
}

sere_status sere_harness_build_leaf( const sere_leaf_source* leaf, const char* path, long long particles,
									 long long springs, long long points, const sere_sim_params* params,
									 sere_model* model, sere_build_report* report, char* name, size_t name_size,
									 char* err, size_t err_size )
{
	const sere_leaf_shape* shape = &leaf->file.shape;
	snprintf( name, name_size, "%s", leaf->file.name );
	sere_build_params build = sere_build_params_default();
	build.layer = params->layer;
	build.seed = params->seed;
	if ( particles >= 0 && springs >= 0 )
	{
		sere_status status = sere_counts_solve( particles, springs, &build.point_count, &build.boundary_count );
		if ( status != SERE_OK )
		{
			snprintf( err, err_size,
					  "no triangulation has %lld particles and %lld springs (need particles = 3N - B - 2, springs = "
					  "12N - 6B - 12 with 3 <= B <= N)",
					  particles, springs );
			return status;
		}
	}
	else
	{
		sere_status status = build_points( shape, &build, (int32_t) points, model, report );
		if ( status == SERE_ERR_COUNTS || status == SERE_ERR_GEOMETRY )
		{
			/* Too few points for this leaf: name a count that works, 25% steps up. */
			int32_t n = (int32_t) points;
			sere_status more = status;
			sere_model probe;
			for ( int k = 0; k < 40 && n < 10000000 && ( more == SERE_ERR_COUNTS || more == SERE_ERR_GEOMETRY ); ++k )
			{
				n += n / 4 > 1 ? n / 4 : 1;
				sere_build_params copy = build;
				more = build_points( shape, &copy, n, &probe, NULL );
			}
			if ( more == SERE_OK )
			{
				sere_model_destroy( &probe );
				snprintf(
					err, err_size,
					"%s: --points %lld is too few for this leaf (its outline and %d veins need more); --points %d "
					"builds",
					path, points, (int) shape->vein_count, (int) n );
				return status;
			}
		}
		if ( status != SERE_OK )
		{
			snprintf( err, err_size, "%s: cannot build %lld triangle-layer points: %s", path, points,
					  sere_status_text( status ) );
			return status;
		}
		return SERE_OK;
	}
	sere_status status = sere_model_build( shape, &build, model, report );
	if ( status != SERE_OK )
	{
		snprintf( err, err_size, "%s: cannot build N=%d B=%d: %s", path, build.point_count, build.boundary_count,
				  sere_status_text( status ) );
		return status;
	}
	return SERE_OK;
}
