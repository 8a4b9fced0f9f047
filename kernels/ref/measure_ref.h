/* sere — reference twins of the shape measures: plain scalar loops that tests compare the
 * optimized kernels of measure.h with. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Brute force over every unique undirected edge of the triangles (an edge whose two ends are one
 * index is dropped) × every triangle sharing no vertex index with it: the number of pairs for
 * which sere_segment_crosses_triangle holds on the positions converted to double. Touching,
 * coplanar and degenerate configurations count as no crossing (see that predicate). Edges are
 * found by a quadratic scan of earlier triangles, a different route than the fast counter's
 * sort, so the two agree only if both find the same set. O(edges × triangles): for tests. */
int64_t sere_crossings_ref_count( const float* x, const float* y, const float* z, int32_t vertex_count,
								  const int32_t* tri, int32_t tri_count );

/* The signed dihedral of every listed edge (0 unless exactly two triangles hold it), by a
 * different route than sere_shape_dihedrals: the triangles of each edge by a scan of all of
 * them, the magnitude as atan2(|n0 × n1|, n0 · n1) and the sign that of n0 · (c1 − a), where n0
 * is the unit normal of the triangle holding a → b, and c1 the corner of the other triangle off
 * the edge (positive: the surface folds towards its normals). Also the total 3D area. */
void sere_shape_ref_dihedrals( const float* x, const float* y, const float* z, const int32_t* tri, int32_t tri_count,
							   const int32_t* edge_a, const int32_t* edge_b, int32_t edge_count, double* dihedral,
							   double* area );

#ifdef __cplusplus
}
#endif
