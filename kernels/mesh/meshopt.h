/* sere — mesh optimization toward even-sized triangles (seed 002, Sec. 3, Fig. 1b–2).
 *
 * The Delaunay triangulation of the sampled outline alone is full of long, narrow triangles.
 * The seed refines it "by repeating the following two steps: relocate the vertex position;
 * modify the connection properties of triangles", 160 iterations by default, the subdivision
 * level growing with the iterations (Fig. 2). One iteration here:
 *   1. subdivide: every interior edge longer than split_ratio · h gets a new vertex at its
 *      midpoint (the two triangles become four);
 *   2. connect: Lawson edge flips until every interior edge is locally Delaunay, which
 *      maximizes the smallest angle for the current vertices;
 *   3. relocate: every interior vertex moves the fraction `relax` of the way to the
 *      area-weighted centroid of its incident triangles (which evens out triangle sizes), a
 *      move that would fold or flatten a triangle being held back.
 * The outline vertices never move and outline edges are never split or flipped, so the
 * outline stays exactly the sampled B-spline. Everything is sequential: same input, same mesh. */
#pragma once

#include "mesh/triangulate.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_meshopt_params
{
	int32_t iterations; /* the seed's 160 by default */
	double edge_length; /* h: the target edge length (> 0) */
	double split_ratio; /* split interior edges longer than split_ratio · h (default 4/3, > 1) */
	double relax;		/* fraction of the way to the centroid per iteration, in (0, 1] (default 0.5) */
} sere_meshopt_params;

sere_meshopt_params sere_meshopt_params_default( double edge_length );

typedef struct sere_meshopt_report
{
	int32_t iterations;
	int32_t splits, flips;
	int32_t vertex_count, triangle_count;
	sere_mesh_quality before, after; /* of the input and the output (outline vertices constrained) */
	double mean_edge;				 /* mean interior edge length of the output */
} sere_meshopt_report;

typedef struct sere_meshopt sere_meshopt;

/* Edge keys pack two vertex indices and a half-edge index into 64 bits. */
#define SERE_MESHOPT_MAX_VERTICES 1000000

/* A workspace for meshes of up to vertex_capacity ≤ SERE_MESHOPT_MAX_VERTICES vertices
 * (2 · vertex_capacity triangles). */
sere_status sere_meshopt_create( int32_t vertex_capacity, sere_meshopt** out );
void sere_meshopt_destroy( sere_meshopt* mo );

/* Optimizes a counter-clockwise triangulation of a simple polygon whose vertices
 * [0, boundary_count) are the outline in order (the edges (i, i+1 mod B) are exactly the mesh's
 * border edges; sere_triangulate gives such meshes). Interior vertices may be given or not.
 * SERE_ERR_ARGUMENT for bad sizes, indices or parameters, SERE_ERR_NONFINITE for NaN
 * coordinates, SERE_ERR_GEOMETRY for a triangle that is not counter-clockwise, an edge shared by
 * more than two triangles or by two that run it the same way (overlapping), or a border that is
 * not the outline, SERE_ERR_CAPACITY when the subdivision needs more vertices than the workspace
 * holds. report may be NULL. */
sere_status sere_meshopt_run( sere_meshopt* mo, const double* x, const double* y, int32_t vertex_count,
							  int32_t boundary_count, const int32_t* tri, int32_t triangle_count,
							  const sere_meshopt_params* params, sere_meshopt_report* report );

/* The current mesh (valid until the next run or destroy; meaningless after a failed run): vertices [0, boundary_count)
 * are the outline, unchanged; triangles counter-clockwise. */
typedef struct sere_meshopt_mesh
{
	int32_t vertex_count;
	int32_t boundary_count;
	const double* x;
	const double* y;
	int32_t triangle_count;
	const int32_t* tri;
} sere_meshopt_mesh;

sere_meshopt_mesh sere_meshopt_result( const sere_meshopt* mo );

#ifdef __cplusplus
}
#endif
