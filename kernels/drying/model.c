#include "drying/model.h"

#include "mesh/sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

sere_build_params sere_build_params_default( void )
{
	sere_build_params params = {
		.point_count = 0,
		.boundary_count = 0,
		.seed = 1,
		.relax_iterations = 4,
		.layer = sere_layer_params_default(),
	};
	return params;
}

int32_t sere_boundary_for_points( double area, double perimeter, int32_t point_count )
{
	/* Fixed point of B = P / s with s² = A / ((2N − B − 2) √3/4); converges in a few steps
	 * because B ≪ 2N for any leaf worth triangulating. */
	double b = 0.0;
	for ( int k = 0; k < 32; ++k )
	{
		double triangles = fmax( 1.0, 2.0 * point_count - b - 2.0 );
		double spacing = sqrt( area / ( triangles * sqrt( 3.0 ) / 4.0 ) );
		b = fmin( (double) point_count, fmax( 3.0, round( perimeter / spacing ) ) );
	}
	return (int32_t) b;
}

static double orient( const double* x, const double* y, int32_t a, int32_t b, int32_t c, double px, double py,
					  int32_t moved )
{
	double ax = a == moved ? px : x[a], ay = a == moved ? py : y[a];
	double bx = b == moved ? px : x[b], by = b == moved ? py : y[b];
	double cx = c == moved ? px : x[c], cy = c == moved ? py : y[c];
	return ( bx - ax ) * ( cy - ay ) - ( cx - ax ) * ( by - ay );
}

/* One centroidal relaxation pass: every free point moves to the area-weighted centroid of its
 * incident triangles, but only if every incident triangle keeps at least a quarter of its area
 * (Jacobi order, so the result does not depend on traversal order). Points on the outline or
 * a vein never move, and since a point stays inside its star no constrained edge is crossed;
 * the caller retriangulates afterwards to restore the Delaunay property. */
static void relax( double* x, double* y, int32_t point_count, int32_t first_free, const sere_triangulation* tri,
				   double* sx, double* sy, double* weight )
{
	memset( sx, 0, sizeof( double ) * (size_t) point_count );
	memset( sy, 0, sizeof( double ) * (size_t) point_count );
	memset( weight, 0, sizeof( double ) * (size_t) point_count );
	for ( int32_t t = 0; t < tri->triangle_count; ++t )
	{
		const int32_t* v = tri->tri + 3 * t;
		double area = 0.5 * orient( x, y, v[0], v[1], v[2], 0.0, 0.0, -1 );
		double cx = ( x[v[0]] + x[v[1]] + x[v[2]] ) / 3.0, cy = ( y[v[0]] + y[v[1]] + y[v[2]] ) / 3.0;
		for ( int k = 0; k < 3; ++k )
		{
			sx[v[k]] += area * cx;
			sy[v[k]] += area * cy;
			weight[v[k]] += area;
		}
	}
	for ( int32_t i = first_free; i < point_count; ++i )
	{
		if ( weight[i] > 0.0 )
		{
			sx[i] /= weight[i];
			sy[i] /= weight[i];
		}
		else
		{
			sx[i] = x[i], sy[i] = y[i];
		}
	}
	/* weight now marks rejected moves. */
	memset( weight, 0, sizeof( double ) * (size_t) point_count );
	for ( int32_t t = 0; t < tri->triangle_count; ++t )
	{
		const int32_t* v = tri->tri + 3 * t;
		double area = orient( x, y, v[0], v[1], v[2], 0.0, 0.0, -1 );
		for ( int k = 0; k < 3; ++k )
		{
			if ( v[k] >= first_free && orient( x, y, v[0], v[1], v[2], sx[v[k]], sy[v[k]], v[k] ) < 0.25 * area )
			{
				weight[v[k]] = 1.0;
			}
		}
	}
	for ( int32_t i = first_free; i < point_count; ++i )
	{
		if ( weight[i] == 0.0 )
		{
			x[i] = sx[i];
			y[i] = sy[i];
		}
	}
}

sere_status sere_model_build( const sere_leaf_shape* shape, const sere_build_params* params, sere_model* model,
							  sere_build_report* report )
{
	if ( model == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( model, 0, sizeof( *model ) );
	if ( shape == NULL || params == NULL || params->relax_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_shape_check check;
	sere_status status = sere_shape_validate( shape, &check );
	if ( status != SERE_OK )
	{
		return status;
	}
	sere_sample_params sample_params = {
		.point_count = params->point_count,
		.boundary_count = params->boundary_count,
		.seed = params->seed,
		.candidates = 0,
	};
	sere_samples samples;
	status = sere_sample_leaf( shape, &sample_params, &samples );
	if ( status != SERE_OK )
	{
		return status;
	}
	const int32_t n = samples.point_count;
	const int32_t first_free = samples.boundary_count + samples.vein_point_count;
	double* scratch = malloc( sizeof( double ) * 3 * (size_t) n );
	uint8_t* constrained = malloc( (size_t) n );
	sere_triangulation tri = { 0 };
	if ( scratch == NULL || constrained == NULL )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	sere_cdt_input input = {
		.x = samples.x,
		.y = samples.y,
		.point_count = n,
		.boundary_count = samples.boundary_count,
		.segments = samples.segments,
		.segment_count = samples.segment_count,
	};
	for ( int32_t pass = 0;; ++pass )
	{
		status = sere_triangulate( &input, &tri );
		if ( status != SERE_OK )
		{
			goto done;
		}
		if ( tri.merged_count != 0 )
		{
			status = SERE_ERR_GEOMETRY; /* two samples fell on one point */
			goto done;
		}
		if ( pass == params->relax_iterations )
		{
			break;
		}
		relax( samples.x, samples.y, n, first_free, &tri, scratch, scratch + n, scratch + 2 * n );
		sere_triangulation_destroy( &tri );
	}
	if ( tri.triangle_count != 2 * n - samples.boundary_count - 2 )
	{
		status = SERE_ERR_GEOMETRY; /* a point outside the outline or on it: not a disk */
		goto done;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		constrained[i] = i < first_free;
	}
	if ( report != NULL )
	{
		memset( report, 0, sizeof( *report ) );
		sere_mesh_quality_measure( samples.x, samples.y, tri.tri, tri.triangle_count, constrained, &report->quality );
		report->vein_points = samples.vein_point_count;
		report->interior_points = n - first_free;
		report->spacing = samples.spacing;
		report->area = fabs( sere_shape_area( shape ) );
		report->perimeter = sere_shape_perimeter( shape );
	}
	sere_plane_mesh mesh = {
		.x = samples.x,
		.y = samples.y,
		.point_count = n,
		.boundary_count = samples.boundary_count,
		.tri = tri.tri,
		.triangle_count = tri.triangle_count,
		.vein_segments = samples.segments,
		.vein_segment_count = samples.segment_count,
		.base = 0,
	};
	status = sere_model_from_triangles( &mesh, &params->layer, model );

done:
	free( scratch );
	free( constrained );
	sere_triangulation_destroy( &tri );
	sere_samples_destroy( &samples );
	return status;
}
