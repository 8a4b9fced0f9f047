/* sere — the whole model-building pipeline of Sec. 3: shape → samples → constrained Delaunay
 * triangulation → relaxation → double layer with masses. */
#pragma once

#include "drying/layers.h"
#include "mesh/shape.h"
#include "mesh/triangulate.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_build_params
{
	int32_t point_count;	/* N */
	int32_t boundary_count; /* B */
	uint64_t seed;
	int32_t relax_iterations; /* centroidal relaxation passes of the interior points (default 4) */
	sere_layer_params layer;
} sere_build_params;

sere_build_params sere_build_params_default( void );

typedef struct sere_build_report
{
	sere_mesh_quality quality; /* of the final triangulation; "free" = no vertex on the outline or a vein */
	int32_t vein_points;
	int32_t interior_points;
	double spacing;
	double area, perimeter;
} sere_build_report;

/* The outline point count B that makes the outline spacing match the interior spacing for N
 * points in total, from the outline's area and perimeter (at least 3, at most N; N itself when
 * N < 3, which no triangulation can use). */
int32_t sere_boundary_for_points( double area, double perimeter, int32_t point_count );

/* Builds a model with exactly N triangle particles, B of them on the outline, so the double
 * layer has 3N − B − 2 particles and 12N − 6B − 12 springs. report may be NULL. The model is
 * made by sere_model_from_triangles and freed, as every model, by sere_model_destroy: the
 * model's type, its maker and its destroy are in layers.h, this header adds the leaf-shaped
 * builder on top. */
sere_status sere_model_build( const sere_leaf_shape* shape, const sere_build_params* params, sere_model* model,
							  sere_build_report* report );

#ifdef __cplusplus
}
#endif
