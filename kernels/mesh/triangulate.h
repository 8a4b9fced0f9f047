/* sere — constrained Delaunay triangulation of a leaf's plane points (Sec. 3.1, Fig. 3d). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Points [0, boundary_count) are the outer polygon in counter-clockwise order; its edges are
 * constrained and every triangle outside it is removed. segments holds segment_count further
 * constrained edges as index pairs (vein segments). No Steiner points are ever inserted: the
 * output vertices are exactly the input points. */
typedef struct sere_cdt_input
{
	const double* x;
	const double* y;
	int32_t point_count;
	int32_t boundary_count;
	const int32_t* segments;
	int32_t segment_count;
} sere_cdt_input;

typedef struct sere_triangulation
{
	int32_t triangle_count;
	int32_t* tri;		  /* 3 * triangle_count vertex indices, counter-clockwise */
	int32_t* vertex_map;  /* point_count entries: the vertex each input point became (duplicates merge) */
	int32_t merged_count; /* input points that merged into an earlier duplicate */
} sere_triangulation;

/* Builds the CDT with exact predicates. Collinear, cocircular and duplicate points are handled;
 * a constrained segment that passes through a point is split there. Crossing constrained
 * segments or a self-intersecting boundary give SERE_ERR_GEOMETRY. On success the caller frees
 * with sere_triangulation_destroy. */
sere_status sere_triangulate( const sere_cdt_input* input, sere_triangulation* out );
void sere_triangulation_destroy( sere_triangulation* triangulation );

typedef struct sere_mesh_quality
{
	double min_angle_deg;		 /* over all triangles */
	double min_angle_free_deg;	 /* over triangles with no vertex on a constrained segment or the boundary */
	double max_aspect;			 /* longest edge / (2 * sqrt(3) * inradius): 1 for equilateral */
	int32_t inverted;			 /* triangles with non-positive signed area */
	int32_t free_triangle_count; /* triangles counted in min_angle_free_deg */
} sere_mesh_quality;

/* constrained_vertex: point_count flags, nonzero for points on the boundary or a segment (may
 * be NULL: then every triangle is free). */
void sere_mesh_quality_measure( const double* x, const double* y, const int32_t* tri, int32_t triangle_count,
								const uint8_t* constrained_vertex, sere_mesh_quality* quality );

#ifdef __cplusplus
}
#endif
