/* The collide tests' sheet: a jittered grid in the plane, its shapes (flat, U-fold, crumpled)
 * and the brute-force checks its contacts are held to (test_collide*.c). */
#pragma once

#include "solve/bvh.h"
#include "solve/collide.h"

#include <stdbool.h>
#include <stdint.h>

/* A jittered grid sheet of width 1 (the shared plane fixture; jitter ±0.1 cell keeps every
 * triangle taller than the 0.3-cell thickness the tests use, so the flat sheet has no contact)
 * with velocities and unit inverse masses, plus one Voronoi particle per triangle after the triangle layer (the
 * sere_model layout); u, v keep the plane coordinates so every shape is made from rest. */
typedef struct collide_sheet
{
	int32_t n, triangles;
	float *x, *y, *z, *vx, *vy, *vz, *inv_m;
	double *u, *v;
	int32_t* tri;
	float cell;
	sere_bvh* bvh; /* the tree and collide workspace on the sheet, NULL until collide_sheet_tree */
	sere_collide* c;
} collide_sheet;

/* Makes the sheet of nx × ny cells; returns the cell width. */
float collide_sheet_make( collide_sheet* s, int32_t nx, int32_t ny, uint64_t seed );
void collide_sheet_free( collide_sheet* s );

/* The tree over the sheet's triangles and a collide workspace of the given capacity on it. */
void collide_sheet_tree( collide_sheet* s, int32_t capacity );
/* collide_sheet_make and collide_sheet_tree on the flat sheet; returns the thickness the tests
 * use, 0.3 cell. */
float collide_sheet_open( collide_sheet* s, int32_t nx, int32_t ny, uint64_t seed, int32_t capacity );
/* Destroys the sheet's tree and workspace (if any) and frees the sheet. */
void collide_sheet_release( collide_sheet* s );

void collide_sheet_flat( collide_sheet* s );

/* U-fold across x: the half u < a stays at z = 0, a half circle of radius gap / 2 follows, and
 * the rest comes back above at z = gap, so the two halves face each other at distance gap. */
void collide_sheet_fold( collide_sheet* s, double gap );

/* Crumpled: a smooth random displacement field (eight plane waves of wavelength 0.2 to 0.5 in
 * all three axes) of the given amplitude, plus per-vertex noise, from a fixed seed. Large
 * amplitudes fold the sheet through itself. */
void collide_sheet_crumple( collide_sheet* s, double amplitude, double noise, uint64_t seed );

/* The two shapes of the thread and refusal tests: the U-fold at 0.8 of the 0.3-cell thickness,
 * and a crumple of amplitude 0.3. */
void collide_shape_fold( collide_sheet* s );
void collide_shape_crumple( collide_sheet* s );

/* qsort orders: (vertex, triangle) pairs and edge–edge quads (a0, a1, b0, b1), lexicographic. */
int collide_cmp_pair( const void* a, const void* b );
int collide_cmp_quad( const void* a, const void* b );

/* Asserts that the edge–edge contacts of the last detection are the brute-force pair set
 * (sere_collide_ref_edge_pairs) exactly, each with the parameters and distance of the scalar
 * sere_closest_points_segments bit for bit (the detection tests pairs eight at a time with
 * selects built to give the same bits); returns the pair count. */
int32_t collide_check_edge_pairs( const float* x, const float* y, const float* z, const int32_t* tri, int32_t triangles,
								  sere_collide* c, float h, const char* what );

/* Detects with the BVH (already built or refit for the current positions) and asserts the
 * contact set equals the brute-force pair set exactly, for both kinds; returns the
 * vertex–triangle pair count and writes the edge–edge one to *edge_count (may be NULL). */
int32_t collide_check_pairs( collide_sheet* s, sere_bvh* bvh, sere_collide* c, float h, const char* what,
							 int32_t* edge_count );

/* Pairs of one kind closer than (1 − tolerance) × h by brute force. */
int64_t collide_violations_of( const collide_sheet* s, float h, float tolerance, bool edges );
/* Pairs of either kind closer than (1 − tolerance) × h by brute force. */
int64_t collide_violations( const collide_sheet* s, float h, float tolerance );
