/* The skeleton tests' leaves (test_skeleton*.c): the parametric blade of
 * sere_leaf_skeleton_generate, a grid mesh cut to its outline, and the venation skeleton
 * generated on it. */
#pragma once

#include "mesh/subdivide.h"
#include "wilt/skeleton.h"

/* Half-width of the parametric blade (sere_leaf_skeleton_generate) at x, with optional lobes
 * that make the outline concave. */
double skeleton_half_width( double x, double length, double width, double lobes );

/* A planar leaf mesh without the triangulator: a grid over the blade's box, cut into triangles,
 * keeping those whose centroid is inside the blade (all of them when lobes < 0: a rectangle);
 * unused vertices are dropped. */
void skeleton_grid_leaf( sere_tri_mesh* mesh, double length, double width, double lobes, int32_t nx, int32_t ny );

/* The parametric leaf skeleton of a 10 x 6 blade, 9 points a side, in the caller's arrays
 * l, r, m (18 doubles each). */
void skeleton_parametric_leaf( double* l, double* r, double* m, sere_leaf_skeleton* leaf );

/* The venation skeleton generated on the parametric leaf with params (NULL: the defaults). */
void skeleton_generated( sere_skeleton* s, const sere_venation_params* params );
