/* sere — venation skeleton-based leaf wilting (seed 003: Lu, Zhao, Guo 2009). A leaf skeleton
 * (two boundary curves and a midvein, Sec. 4.1) gives the blade mesh; a venation skeleton (a
 * midvein and secondary veins cut into segments, Sec. 4.2) drives it: every mesh vertex is
 * banded to its nearest joint (Sec. 5.2), each joint turns its segment toward the downward
 * vector (Sec. 6, Lu Eq. 1) with children following, and the mesh follows its joints. A plant
 * holds several leaves that start wilting from the lowest to the highest (Sec. 7). */
#pragma once

#include "core/base.h"
#include "mesh/subdivide.h"
#include "solve/bvh.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Why a leaf or venation skeleton is not usable, with the offending vein and point. */
typedef enum sere_skeleton_problem
{
	SERE_SKELETON_OK = 0,
	SERE_SKELETON_FEW_POINTS,		 /* a curve with fewer than 2 points (or more than a million), a leaf with
									  * fewer than 3 */
	SERE_SKELETON_NONFINITE,		 /* NaN or infinity in a coordinate or parameter */
	SERE_SKELETON_REPEATED_POINT,	 /* two consecutive feature points coincide */
	SERE_SKELETON_ENDS_APART,		 /* the boundary curves and the midvein do not meet at base and tip */
	SERE_SKELETON_SELF_INTERSECTING, /* the outline crosses itself */
	SERE_SKELETON_MIDVEIN_OUTSIDE,	 /* a midvein point lies outside the outline */
	SERE_SKELETON_NO_VEINS,			 /* a venation skeleton needs at least the midvein */
	SERE_SKELETON_BAD_PARENT,		 /* vein 0 has parent -1; every other vein names an earlier vein */
	SERE_SKELETON_BAD_SEGMENTS,		 /* a vein cut into fewer than 1 or more than SERE_MAX_SEGMENTS segments */
	SERE_SKELETON_DETACHED,			 /* a vein starts farther than its length from the nearest joint of its parent
									  * vein, the joint it would hang from (a long parent segment can leave
									  * a short vein that starts on it detached: cut the parent finer) */
	SERE_SKELETON_BAD_BEND,			 /* a bend angle outside [0, π] */
	SERE_SKELETON_BAD_SPACING,		 /* sampling interval not positive or too fine for the leaf */
	SERE_SKELETON_PROBLEM_COUNT
} sere_skeleton_problem;

#define SERE_MAX_SEGMENTS 4096

typedef struct sere_skeleton_check
{
	sere_skeleton_problem problem;
	int32_t vein;  /* the vein (or curve: 0 left, 1 right, 2 midvein) at fault, or -1 */
	int32_t point; /* the feature or vein point within it as given, or -1 (problems of the sampled
					* curves, such as a crossing outline, name no point) */
} sere_skeleton_check;

const char* sere_skeleton_problem_text( sere_skeleton_problem problem );

/* Sec. 4.1: the leaf skeleton in the blade's plane. Leaf coordinates: the base (petiole) at
 * the origin by convention, the midvein running toward +x, z up. Each curve goes from base to
 * tip through its feature points; the three curves meet at the base and at the tip (ends
 * within 1% of the leaf size are snapped together). Which boundary is left or right only
 * decides orientation, which is fixed up. */
typedef struct sere_leaf_skeleton
{
	int32_t left_count, right_count, mid_count;
	const double* left_xy; /* x0 y0 x1 y1 ... */
	const double* right_xy;
	const double* mid_xy;
} sere_leaf_skeleton;

/* Sec. 4.1, the parametric form: a straight midvein of the given length along +x and two
 * symmetric boundary curves of the given total width, each with feature_count points (>= 3)
 * written to left_xy, right_xy and mid_xy (2 * feature_count doubles each). The half-width
 * profile is ovate: widest at a third of the length, rounded at the base, pointed at the tip. */
sere_status sere_leaf_skeleton_generate( double length, double width, int32_t feature_count, double* left_xy,
										 double* right_xy, double* mid_xy );

/* Checks a leaf skeleton and reports the first problem; SERE_ERR_GEOMETRY or
 * SERE_ERR_NONFINITE when it is not usable. spacing is the sampling interval of
 * sere_leaf_skeleton_mesh. */
sere_status sere_leaf_skeleton_validate( const sere_leaf_skeleton* leaf, double spacing, sere_skeleton_check* check );

/* Sec. 5.1: the blade mesh. The boundary curves and the midvein are rebuilt as centripetal
 * Catmull–Rom splines through their feature points and sampled every `spacing`; the interior
 * is filled with a hexagonal lattice of the same spacing kept half a spacing from the outline
 * and the midvein; the points are triangulated by constrained Delaunay triangulation (the
 * outline and the midvein are constrained edges, so concave and lobed outlines are meshed
 * correctly). z = 0; texture coordinates map the outline's bounding box to [0, 1]². check may
 * be NULL. On success the caller frees mesh with sere_tri_mesh_destroy. */
sere_status sere_leaf_skeleton_mesh( const sere_leaf_skeleton* leaf, double spacing, sere_tri_mesh* mesh,
									 sere_skeleton_check* check );

/* Sec. 4.2: one vein of a venation skeleton as the user draws it: a polyline from its start
 * (on or near its parent vein) to its end, cut into `segments` pieces of equal length whose
 * ends are the vein's joints. Its first joint hangs from the joint of the parent vein nearest
 * to the start. bend is the total angle the vein turns toward the downward vector at full
 * wilting, shared equally by its segments. */
typedef struct sere_vein_spec
{
	int32_t parent; /* -1 for the midvein, which must be vein 0; else an earlier vein */
	int32_t segments;
	float bend; /* radians, in [0, π] */
	int32_t point_count;
	const double* xy; /* leaf coordinates, x0 y0 x1 y1 ... */
} sere_vein_spec;

/* A venation skeleton: joints in depth-first order, so every parent precedes its children and
 * the subtree of joint i is the range [i, end[i]). The root is the midvein's start (the base).
 * Arrays hold sere_pad(joint_count) entries. */
typedef struct sere_skeleton
{
	int32_t joint_count;
	int32_t vein_count;
	float *x, *y, *z; /* rest positions */
	int32_t* parent;  /* -1 for the root */
	int32_t* end;	  /* one past the last joint of the subtree */
	int32_t* vein;	  /* the vein of the segment parent → joint (the root: 0) */
	float* bend;	  /* rotation of that segment toward down at full wilting, radians */
	float* delay;	  /* onset rank in [0, 1]: 0 at the farthest tip, 1 at the root (Sec. 7) */
} sere_skeleton;

/* Builds a venation skeleton from vein polylines in leaf coordinates (z = 0). check may be
 * NULL. On success the caller frees with sere_skeleton_destroy. */
sere_status sere_skeleton_create( const sere_vein_spec* veins, int32_t vein_count, sere_skeleton* skeleton,
								  sere_skeleton_check* check );
void sere_skeleton_destroy( sere_skeleton* skeleton );

/* Generated venation (Sec. 4.2 done automatically): the midvein follows the leaf skeleton's
 * midvein curve; secondary_count secondary veins alternate right and left, start at evenly
 * spaced points of the midvein's lower part and run at `angle` from it toward the tip until
 * 90% of the way to the outline. */
typedef struct sere_venation_params
{
	int32_t mid_segments;		/* the seed uses 20 (cucumber) and 30 (watermelon) */
	int32_t secondary_count;	/* 2 (cucumber) or 4 (watermelon) in the seed */
	int32_t secondary_segments; /* 4 (cucumber) or 10 (watermelon) */
	float angle;				/* between a secondary vein and the midvein, radians */
	float mid_bend, secondary_bend;
	float start, stop; /* secondary veins start between these fractions of the midvein length */
} sere_venation_params;

sere_venation_params sere_venation_params_default( void );

sere_status sere_skeleton_generate( const sere_leaf_skeleton* leaf, const sere_venation_params* params,
									sere_skeleton* skeleton, sere_skeleton_check* check );

/* Sec. 5.2, banding: a uniform grid over the joints answers "which joint is nearest" exactly
 * (ties go to the lower joint index, as a brute-force scan would), visiting only the cells
 * around the query. */
typedef struct sere_joint_grid sere_joint_grid;

sere_status sere_joint_grid_create( const float* x, const float* y, const float* z, int32_t joint_count,
									sere_joint_grid** grid );
void sere_joint_grid_destroy( sere_joint_grid* grid );
int32_t sere_joint_grid_nearest( const sere_joint_grid* grid, float x, float y, float z );

/* The threads sere_joint_grid_band runs with (core/base.h: 0, the count at create, is OpenMP's
 * count at each call; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_joint_grid_set_threads( sere_joint_grid* grid, int32_t threads );

/* Bands every vertex to its nearest joint (in parallel) and, when ox is not NULL, stores the
 * vertex's offset from that joint at rest: the rigid binding of Sec. 6, in which a vertex keeps
 * its offset in the joint's frame. jx, jy, jz are the joint positions the grid was made from. */
sere_status sere_joint_grid_band( const sere_joint_grid* grid, const float* jx, const float* jy, const float* jz,
								  const float* x, const float* y, const float* z, int32_t vertex_count, int32_t* joint,
								  float* ox, float* oy, float* oz );

/* What a banding moved, as sere_joint_grid_record_band recorded it and sere_joint_grid_touch_band
 * replayed it. */
typedef struct sere_joint_grid_traffic
{
	int64_t listed; /* queries their cell's candidate list answered (the others searched rings) */
	int64_t cells;	/* cells the ring searches opened */
	int64_t joints; /* joint records read: candidates scanned and the opened cells' joints */
} sere_joint_grid_traffic;

/* A banding without offsets (sere_joint_grid_band with ox NULL: the same joints, bits and
 * threads) that also records, for sere_joint_grid_touch_band, how many rings each query's search
 * opened (a byte a query, kept in the grid). traffic (may be NULL) gets what it read. Errors as
 * sere_joint_grid_band's, plus SERE_ERR_MEMORY when the record cannot be kept (no record then). */
sere_status sere_joint_grid_record_band( sere_joint_grid* grid, const float* x, const float* y, const float* z,
										 int32_t vertex_count, int32_t* joint, sere_joint_grid_traffic* traffic );

/* The memory floor of the recorded banding (benchmarks): the banding's finiteness pass and its
 * loop on the same threads and schedule, each query addressed as the search addresses it (its cell
 * from its coordinates), opening the cells of the rings its search opened, with sums of the
 * records' bits in place of the distances and the recorded ring count in place of the test of
 * when to stop. It reads the same candidate lists and cells and, from them, the same joint
 * records (positions, and in the ring search the joint indices), and stores each query's joint
 * times a 1 the compiler cannot see. Reading the record (a byte a query) is traffic the banding
 * does not have; the joint index a candidate scan loads on each improvement is left out. Leaves
 * joint bitwise as it was. x, y, z are the positions the record was made from. traffic (may be
 * NULL) gets what it read: the record's counts when the replay is faithful. SERE_ERR_ARGUMENT for
 * a NULL argument or a vertex count other than the record's (or no record); SERE_ERR_NONFINITE as
 * sere_joint_grid_band. */
sere_status sere_joint_grid_touch_band( sere_joint_grid* grid, const float* x, const float* y, const float* z,
										int32_t vertex_count, int32_t* joint, sere_joint_grid_traffic* traffic );

/* Sec. 6 limits and Sec. 7 timing of the wilt. */
typedef struct sere_wilt_params
{
	float droop_max;	 /* maximal drooped distance: no joint sinks more than this below its rest
						  * height; INFINITY for none */
	float min_angle;	 /* minimal included angle between adjacent segments of one vein, radians
						  * (π = straight); 0 for none */
	float spread;		 /* in [0, 1): joints start turning when t passes spread · delay, so the
						  * tips wilt first and the base last (Sec. 7) */
	float pierce_margin; /* a shortened move stops this far before the surface */
	int32_t pierce;		 /* nonzero: check every vertex move for piercing the mesh (Sec. 6) */
} sere_wilt_params;

sere_wilt_params sere_wilt_params_default( void );

/* The posed skeleton: each joint's position and its rotation from rest (row-major 3 × 3), so a
 * vertex bound to joint j with rest offset o sits at p_j + R_j o. work is double scratch for the
 * forward kinematics. */
typedef struct sere_joint_frames
{
	int32_t capacity;
	float *x, *y, *z;
	float* m[9];
	double* work;
} sere_joint_frames;

sere_status sere_joint_frames_create( sere_joint_frames* frames, int32_t joint_count );
void sere_joint_frames_destroy( sere_joint_frames* frames );

typedef struct sere_pose_stats
{
	int32_t turning;	   /* joints with a nonzero target rotation */
	int32_t droop_limited; /* joints whose rotation the maximal droop shortened */
	int32_t angle_limited; /* joints whose rotation the minimal angle shortened */
	int32_t down_limited;  /* segments that reached straight down */
} sere_pose_stats;

/* Sec. 6, Lu Eq. 1: poses the joints [first, first + count) of one leaf (a root and its subtree)
 * for wilting parameter t ∈ [0, 1], from rest, sequentially from the root. Joint i's target
 * angle is bend_i · clamp((t − spread · delay_i) / (1 − spread), 0, 1); its segment turns by
 * that angle about n = u × d (u the segment as its ancestors left it, d = −z), its subtree
 * following, limited so that the segment does not pass straight down, no joint of the subtree
 * sinks more than droop_max below its rest height, and the included angle with the previous
 * segment of the same vein stays at least min_angle. Rotations are rigid, so segment lengths
 * are kept. The result depends only on the rest skeleton and t. stats may be NULL. */
sere_status sere_skeleton_pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
								const sere_wilt_params* params, sere_joint_frames* frames, sere_pose_stats* stats );

/* sere_skeleton_pose (the same frames, bits and stats) that also records, for
 * sere_skeleton_touch_pose, whether each joint's segment turned: turned[i] for i in [first,
 * first + count) is 1 when it did (and the pose ran its limits), else 0. */
sere_status sere_skeleton_record_pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
									   const sere_wilt_params* params, sere_joint_frames* frames, uint8_t* turned,
									   sere_pose_stats* stats );

/* The memory floor of a recorded pose (benchmarks): the pose's two passes over the joints in the
 * same order, with sums in place of the rotations, the limits and the trigonometry. Per joint it
 * reads the parent index, the rest positions of the joint and its parent, the onset rank and bend
 * and the parent's posed frame (12 doubles of work), and stores the joint's 12 doubles of work;
 * for a segment turned reads, as the limits do, the grandparent's posed position (when the minimal
 * angle applies: same vein, min_angle > 0) and the rest positions of the joint's subtree (when
 * droop_max is finite); then rounds work to the frames as the pose does. Each store keeps the value
 * already there (times a 1 the compiler cannot see), which reads the joint's work first, a read the
 * pose does not make. Leaves frames (work included) bitwise as they were. Errors as
 * sere_skeleton_pose's (but t's, which it does not take), SERE_ERR_ARGUMENT for a NULL turned. */
sere_status sere_skeleton_touch_pose( const sere_skeleton* skeleton, int32_t first, int32_t count,
									  const sere_wilt_params* params, const uint8_t* turned,
									  sere_joint_frames* frames );

/* The mesh follows its joints (Sec. 6): x = p_j + R_j o for every vertex, on `threads` threads
 * (core/base.h). Fastest when vertices of one joint are adjacent (runs share one transform);
 * correct in any order. */
void sere_joint_frames_skin( const sere_joint_frames* frames, const int32_t* joint, const float* ox, const float* oy,
							 const float* oz, int32_t vertex_count, float* x, float* y, float* z, int32_t threads );

/* Sec. 6, piercing. A workspace over one triangle mesh: its BVH and per-vertex flags, made once.
 * rigid_group (copied; may be NULL) names, per vertex, a group the caller moves rigidly, such as
 * the joint a skinned vertex is banded to: a pair of triangles whose six corners share a group
 * and reached their targets in this step and the one before moved as one body and cannot have
 * come to intersect, so the search skips it. */
typedef struct sere_pierce sere_pierce;

sere_status sere_pierce_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count, const float* x,
								const float* y, const float* z, const int32_t* rigid_group, sere_pierce** pierce );
void sere_pierce_destroy( sere_pierce* pierce );

/* The threads sere_pierce_step and its BVH run with (core/base.h: 0, the initial count, is
 * OpenMP's count at each step; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_pierce_set_threads( sere_pierce* pierce, int32_t threads );

typedef struct sere_pierce_stats
{
	int32_t shortened;	 /* moves that would have passed through a triangle, shortened */
	int32_t pulled_back; /* vertices pulled back toward their previous position to undo an intersection */
	int32_t rounds;		 /* detect-and-pull-back rounds */
	int32_t reverted;	 /* 1 when the round cap was reached and every move was undone */
	int32_t rebuilt;	 /* 1 when the BVH was rebuilt rather than refit */
} sere_pierce_stats;

/* Moves every vertex from its previous position (px, py, pz), where the mesh does not intersect
 * itself, toward its target (x, y, z, changed in place) as the seed's piercing check does: a move
 * that would pass through a triangle not incident to the vertex (at the previous positions) is
 * shortened to stop `margin` before it. Moving vertices independently can still fold triangles
 * through each other, so the result is then searched for intersecting triangle pairs (as
 * sere_mesh_count_intersections counts them) and the vertices of each pair are pulled halfway back to
 * their previous positions, four times at most and then all the way, round after round until
 * none remain; after 32 rounds every move is undone. The mesh therefore never intersects itself
 * when it did not before. Deterministic for any thread count: every decision is a per-vertex
 * gather over previous positions or a flag set, never a scatter in thread order. On return the
 * workspace BVH is refit to the result. stats may be NULL. */
sere_status sere_pierce_step( sere_pierce* pierce, const float* px, const float* py, const float* pz, float* x,
							  float* y, float* z, float margin, sere_pierce_stats* stats );

/* The workspace's BVH, refit to the positions of the last step (or the creation positions). */
const sere_bvh* sere_pierce_bvh( const sere_pierce* pierce );

/* Pairs of triangles that intersect: triangles sharing an edge are skipped, triangles sharing
 * one corner are tested with their opposite edges, others with all six edges (segment against
 * triangle, in double). bvh must be refit to x, y, z. On `threads` threads (core/base.h). */
int64_t sere_mesh_count_intersections( const sere_bvh* bvh, const int32_t* tri, int32_t triangle_count, const float* x,
									   const float* y, const float* z, int32_t threads );

/* A leaf kind: its blade mesh and its venation skeleton in leaf coordinates. */
typedef struct sere_leaf_template
{
	const sere_tri_mesh* mesh;
	const sere_skeleton* skeleton;
} sere_leaf_template;

/* Where one leaf sits on the plant (Sec. 7): its base, the compass direction and the angle
 * above horizontal of its midvein, its scale, and the plant time at which it starts wilting
 * (lower leaves earlier). */
typedef struct sere_leaf_placement
{
	int32_t template_index;
	float base[3];
	float azimuth;	 /* radians from +x, counter-clockwise seen from above */
	float elevation; /* radians above horizontal */
	float scale;
	float onset;
} sere_leaf_placement;

/* Every leaf of a plant in world coordinates, concatenated: leaf k owns joints
 * [joint_first[k], joint_first[k + 1]), vertices [vertex_first[k], vertex_first[k + 1]) and
 * triangles [triangle_first[k], triangle_first[k + 1]). Triangle indices are global. A leaf's
 * vertices are its template's reordered by joint (stably), so skinning streams one joint's
 * vertices at a time; its triangles are ordered by their lowest vertex (stably). */
typedef struct sere_plant
{
	int32_t leaf_count;
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t *joint_first, *vertex_first, *triangle_first;
	float* onset;
	float* leaf_t; /* each leaf's wilting parameter at the last frame */
	sere_skeleton joints;
	sere_joint_frames frames;
	int32_t* joint;		 /* each vertex's joint (global index) */
	float *ox, *oy, *oz; /* its rest offset from that joint */
	float *x, *y, *z;	 /* current positions */
	float *rx, *ry, *rz; /* rest positions */
	float *u, *v;		 /* texture coordinates, never changed */
	int32_t* tri;
	float *tx, *ty, *tz; /* targets of the piercing check */
	sere_pose_stats* leaf_stats;
	sere_pierce* pierce;
	int32_t threads; /* sere_plant_set_threads (0 at create: OpenMP's count at each frame) */
} sere_plant;

sere_status sere_plant_create( const sere_leaf_template* templates, int32_t template_count,
							   const sere_leaf_placement* leaves, int32_t leaf_count, sere_plant** plant );
void sere_plant_destroy( sere_plant* plant );

/* Back to the rest pose. */
void sere_plant_reset( sere_plant* plant );

/* The threads sere_plant_frame runs with, posing, skinning and piercing (core/base.h;
 * SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_plant_set_threads( sere_plant* plant, int32_t threads );

typedef struct sere_wilt_stats
{
	sere_pose_stats pose;	  /* summed over leaves */
	sere_pierce_stats pierce; /* zero without the piercing check */
} sere_wilt_stats;

/* One frame at plant time `time`: leaf k wilts with t_k = clamp(time − onset_k, 0, 1) (so the
 * time step per frame sets the speed, Sec. 7); skeletons are posed in parallel across leaves,
 * the mesh skinned in parallel across vertices, then, with params->pierce, moves from the
 * previous frame are checked for piercing over the whole plant. Without the piercing check a
 * frame depends only on time; with it, on the frames before. stats may be NULL. */
sere_status sere_plant_frame( sere_plant* plant, float time, const sere_wilt_params* params, sere_wilt_stats* stats );

#ifdef __cplusplus
}
#endif
