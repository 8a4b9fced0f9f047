/* sere — triangle meshes with texture coordinates and their 1→4 subdivision (seed 003,
 * Sec. 5.1): the rough Delaunay mesh of a blade is refined before it is bound to a skeleton. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* A triangle mesh in structure-of-arrays form. Vertex arrays hold sere_pad(vertex_count)
 * entries (the padding is zero); tri holds 3 * triangle_count indices, counter-clockwise seen
 * from +z when the mesh is planar. u, v are texture coordinates: they are fixed before any
 * deformation and never remapped (Sec. 6). */
typedef struct sere_tri_mesh
{
	int32_t vertex_count;
	int32_t triangle_count;
	float *x, *y, *z;
	float *u, *v;
	int32_t* tri;
} sere_tri_mesh;

/* Allocates zeroed arrays for the given counts. On failure every pointer is NULL. */
sere_status sere_tri_mesh_create( sere_tri_mesh* mesh, int32_t vertex_count, int32_t triangle_count );
void sere_tri_mesh_destroy( sere_tri_mesh* mesh );

/* Sec. 5.1: `iterations` passes of 1→4 subdivision. An edge is cut at its midpoint only when
 * both halves are at least min_edge long (the paper's "minimal distance of an edge", which
 * keeps refinement from making too short edges); a triangle with all three edges cut becomes
 * four, one with one or two cut edges becomes two or three (cut along the shorter diagonal),
 * so the mesh stays conforming with no hanging vertices. Midpoints take the mean of both
 * endpoints' position and texture coordinates. Input vertices keep their indices; new
 * vertices follow in edge order, so the output is deterministic. Passes stop early once no
 * edge is long enough. min_edge <= 0 cuts every edge. On success the caller frees out with
 * sere_tri_mesh_destroy. SERE_ERR_NONFINITE for NaN/inf positions, SERE_ERR_ARGUMENT for bad
 * indices or iterations outside [0, 8], SERE_ERR_CAPACITY when the result would exceed
 * INT32_MAX / 4 triangles. */
sere_status sere_subdivide( const sere_tri_mesh* in, int32_t iterations, float min_edge, sere_tri_mesh* out );

#ifdef __cplusplus
}
#endif
