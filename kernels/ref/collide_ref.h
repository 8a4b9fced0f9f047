/* sere — reference twins of the self-collision kernels (Sec. 5.3, Jeong Eq. 14): plain scalar loops
 * that tests and benches compare the optimized kernels with. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Brute force over all vertex_count × triangle_count pairs: every (vertex, triangle) with the
 * vertex not a corner of the triangle and squared distance (sere_closest_point_triangle, the same
 * float test the BVH search applies) below thickness², where a vertex joined by an edge to a corner
 * counts only when its closest point lies inside the face (all three weights positive). Pairs
 * come vertex-major, triangles ascending; the first min(count, capacity) are written and the
 * count is returned. */
int64_t sere_collide_ref_pairs( const float* x, const float* y, const float* z, int32_t vertex_count,
								const int32_t* tri, int32_t triangle_count, float thickness, int32_t* vertex,
								int32_t* triangle, int64_t capacity );

/* Brute force over all pairs of the triangles' distinct edges: every two edges sharing no vertex
 * whose closest points (sere_closest_points_segments, the same float test the BVH search applies)
 * lie strictly inside both and are closer than thickness, but for pairs closer than thickness at
 * the rest positions rx, ry, rz when given (NULL: none; sere_collide_set_rest). Edges are taken
 * with their lower vertex first and ordered by it, then by the higher; pair (e, f) has e before f.
 * For each pair ends gets e's and f's ends (4 entries) and weights (may be NULL) the closest
 * points' parameters s, t (2 entries), for the first min(count, capacity) pairs, in order of e,
 * then f; returns the count. */
int64_t sere_collide_ref_edge_pairs( const float* x, const float* y, const float* z, const float* rx, const float* ry,
									 const float* rz, const int32_t* tri, int32_t triangle_count, float thickness,
									 int32_t* ends, float* weights, int64_t capacity );

/* Squared distance between the segments p0 p1 and q0 q1 in double by a different route than the
 * kernel's: the closest points of the two lines when both fall inside the segments, else the
 * nearest of the four end-to-segment distances. */
double sere_collide_ref_segment_distance2( const double p0[3], const double p1[3], const double q0[3],
										   const double q1[3] );

/* Squared distance from p to triangle abc in double by a different route than the kernel's:
 * the plane projection when it falls inside the triangle, else the nearest of the three edges. */
double sere_collide_ref_distance2( const double p[3], const double a[3], const double b[3], const double c[3] );

/* Algorithm 1 line 14 and Jeong Eq. 14 transcribed in double: ĥ_t = (x_t^V − x_a)·n and
 * x_t^V = (x_a + x_b + x_c)/3 + h_t n, v_t^V = (v_a + v_b + v_c)/3, for Voronoi particle
 * voronoi_first + t. */
void sere_collide_ref_measure_h( const float* x, const float* y, const float* z, const int32_t* tri,
								 int32_t triangle_count, int32_t voronoi_first, double* h_hat );
void sere_collide_ref_restore_voronoi( double* x, double* y, double* z, double* vx, double* vy, double* vz,
									   const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
									   const double* h );

#ifdef __cplusplus
}
#endif
