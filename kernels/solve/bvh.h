/* sere — bounding volume hierarchy over the triangles of a deforming mesh (Sec. 5.3): built
 * once with a binned surface-area heuristic, refit every frame in parallel level by level,
 * rebuilt when refitting has degraded it. Usable for any triangle mesh given as SoA positions
 * and index triples. */
#pragma once

#include "core/base.h"

#include <stdbool.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* Eight children per node: one 256-bit compare tests every child box of a node at once, and a
 * sheet of ~9000 triangles is five levels deep. Leaves hold one triangle each, stored directly
 * in the parent's child slot, so the bottom level tests eight triangle boxes per node. */
#define SERE_BVH_WIDTH 8

/* The child slot value of an unused lane; its box is empty (min = +inf, max = −inf). */
#define SERE_BVH_EMPTY INT32_MIN

/* Refit quality ratio above which sere_bvh_update rebuilds. Sheets deform continuously, so a
 * refit tree stays close to a fresh one for point queries: on a 9000-triangle sheet, bumps,
 * twists and crumples up to ratio 2 left query times within 5% of a rebuilt tree's, and a
 * rolled-up sheet at ratio 6.7 gained 25% from a rebuild. */
#define SERE_BVH_REBUILD_RATIO 2.0

/* Child boxes side by side (SoA) so a query tests all eight lanes with one compare per face.
 * child[k] >= 0 is a node index; SERE_BVH_EMPTY marks an unused lane; any other negative value
 * is the triangle ~child[k]. */
typedef struct sere_bvh_node
{
	float min_x[SERE_BVH_WIDTH], min_y[SERE_BVH_WIDTH], min_z[SERE_BVH_WIDTH];
	float max_x[SERE_BVH_WIDTH], max_y[SERE_BVH_WIDTH], max_z[SERE_BVH_WIDTH];
	int32_t child[SERE_BVH_WIDTH];
} sere_bvh_node;

typedef struct sere_bvh sere_bvh;

/* Copies the triangle_count index triples (each index in [0, vertex_count)), allocates every
 * buffer the BVH will ever need and builds it from the positions x, y, z (vertex_count
 * entries each). SERE_ERR_ARGUMENT for bad sizes or indices, SERE_ERR_NONFINITE for NaN or
 * infinite positions. On success the caller frees with sere_bvh_destroy. */
sere_status sere_bvh_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count, const float* x,
							 const float* y, const float* z, sere_bvh** out );
void sere_bvh_destroy( sere_bvh* bvh );

/* The threads build, refit and update run with (core/base.h: 0, the initial count, is OpenMP's
 * count at each call; at most SERE_MAX_THREADS, else SERE_ERR_ARGUMENT). */
sere_status sere_bvh_set_threads( sere_bvh* bvh, int32_t threads );

/* A fresh tree for the current positions (sequential and deterministic); resets the quality
 * ratio to 1. No allocation. */
sere_status sere_bvh_build( sere_bvh* bvh, const float* x, const float* y, const float* z );

/* Recomputes every box bottom-up for the current positions, in parallel within each level; the
 * boxes are exact min/max of the vertices, so they stay conservative however far the mesh has
 * moved. SERE_ERR_NONFINITE (and the boxes untouched) for NaN or infinite positions. */
sere_status sere_bvh_refit( sere_bvh* bvh, const float* x, const float* y, const float* z );

/* Quality of the refit tree against the tree as last built: the surface area heuristic cost
 * Σ area(node box) / area(root box) over the internal nodes below the root, now over at build.
 * Normalizing by the root makes it blind to uniform scaling (a drying leaf shrinks without
 * degrading its tree) and nearly so to rigid rotation; it grows when node boxes swell relative
 * to the whole, as when the sheet bends, curls or crumples. 1 right after a build, and always for
 * a tree of one node (8 triangles or fewer), which has nothing below its root to swell. */
double sere_bvh_quality_ratio( const sere_bvh* bvh );

/* True when the quality ratio exceeds threshold. */
bool sere_bvh_needs_rebuild( const sere_bvh* bvh, double threshold );

/* Refit, then rebuild when the ratio exceeds threshold; *rebuilt (may be NULL) says which. */
sere_status sere_bvh_update( sere_bvh* bvh, const float* x, const float* y, const float* z, double threshold,
							 bool* rebuilt );

/* Called once per triangle whose box overlaps the query box. */
typedef void sere_bvh_visit_fn( void* context, int32_t triangle );

/* Visits every triangle whose box overlaps the closed box [lo, hi], in a fixed order that
 * depends only on the tree. A non-finite query box visits nothing. */
void sere_bvh_query_box( const sere_bvh* bvh, const float lo[3], const float hi[3], sere_bvh_visit_fn* visit,
						 void* context );

/* Up to SERE_BVH_WIDTH query boxes answered in one traversal (SoA; lanes from count on, and
 * lanes with a non-finite bound, are ignored). Nearby boxes, e.g. the cubes around eight
 * consecutive vertices of a spatially ordered mesh, then share the walk down the tree. */
typedef struct sere_bvh_group
{
	float lo_x[SERE_BVH_WIDTH], lo_y[SERE_BVH_WIDTH], lo_z[SERE_BVH_WIDTH];
	float hi_x[SERE_BVH_WIDTH], hi_y[SERE_BVH_WIDTH], hi_z[SERE_BVH_WIDTH];
	int32_t count;
} sere_bvh_group;

/* Called once per triangle whose box overlaps at least one box of the group; bit k of lanes is
 * set when it overlaps box k. */
typedef void sere_bvh_visit_group_fn( void* context, int32_t triangle, uint32_t lanes );

/* Visits every triangle overlapping a box of the group, in a fixed order that depends only on
 * the tree and the group. */
void sere_bvh_query_group( const sere_bvh* bvh, const sere_bvh_group* group, sere_bvh_visit_group_fn* visit,
						   void* context );

/* sere_bvh_query_group restricted to the triangles with a corner index above floor, visited in
 * the same order: a subtree whose triangles' corners all lie at or below floor is not entered. A
 * search for pairs counted once (the other member's index above the query's) skips the part of
 * the tree that can only hold the pairs counted from the other side. */
void sere_bvh_query_group_above( const sere_bvh* bvh, const sere_bvh_group* group, int32_t floor,
								 sere_bvh_visit_group_fn* visit, void* context );

/* Triangles whose box overlaps the cube of half-width r around (x, y, z), i.e. whose box padded
 * by r contains the point. Writes the first min(count, capacity) into out and returns count. As
 * for sere_bvh_query_box, a cube that is not finite (a NaN or infinite point or r, or x ± r past
 * FLT_MAX) finds nothing: to list every triangle, pass a finite r larger than the mesh. */
int32_t sere_bvh_query( const sere_bvh* bvh, float x, float y, float z, float r, int32_t* out, int32_t capacity );

/* Inspection: node 0 is the root; children always have larger indices than their parent. */
const sere_bvh_node* sere_bvh_nodes( const sere_bvh* bvh, int32_t* node_count );
int32_t sere_bvh_depth( const sere_bvh* bvh );
const int32_t* sere_bvh_triangles( const sere_bvh* bvh, int32_t* triangle_count );
int32_t sere_bvh_vertex_count( const sere_bvh* bvh );

/* A number unique to the tree's last build among all builds of all BVHs in the process, never 0:
 * two queries see the same tree (the same nodes, visited in the same order, refit or not) exactly
 * when their BVH has the same generation. */
uint64_t sere_bvh_generation( const sere_bvh* bvh );

#ifdef __cplusplus
}
#endif
