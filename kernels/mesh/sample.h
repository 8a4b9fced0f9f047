/* sere — sampling a leaf shape into the particles of the triangle layer (Sec. 3.1, Fig. 3c). */
#pragma once

#include "core/base.h"
#include "mesh/shape.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_sample_params
{
	int32_t point_count;	/* N: every point of the triangle layer */
	int32_t boundary_count; /* B: points on the outline */
	uint64_t seed;			/* interior fill is deterministic for a seed */
	int32_t candidates;		/* best-candidate tries per interior point (default 24) */
} sere_sample_params;

/* Points [0, boundary_count) are the outline resampled counter-clockwise starting at the base
 * (point 0); then the vein points; then the interior fill. */
typedef struct sere_samples
{
	int32_t point_count;
	int32_t boundary_count;
	int32_t vein_point_count; /* vein points beyond the base */
	double* x;
	double* y;
	uint8_t* vein;	   /* per point: on a vein (the base included) */
	int32_t* segments; /* vein segments as index pairs */
	int32_t segment_count;
	double spacing; /* target edge length */
} sere_samples;

/* Resamples the outline to exactly B points by arc length from the base, places vein points
 * along each vein at the target spacing (a branch point is shared by parent and child), and
 * fills the interior with N − B − (vein points) evenly spread points kept off the outline and
 * the vein segments (Mitchell's best-candidate sampling: exact count, Poisson-disk-like
 * spacing). SERE_ERR_COUNTS when the veins alone need more than N − B points. */
sere_status sere_sample_leaf( const sere_leaf_shape* shape, const sere_sample_params* params, sere_samples* out );
void sere_samples_destroy( sere_samples* samples );

#ifdef __cplusplus
}
#endif
