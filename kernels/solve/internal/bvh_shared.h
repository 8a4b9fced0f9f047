/* sere — private to bvh.c and bvh_query.c, not installed and not part of the API: the tree's
 * state (nodes of SERE_BVH_WIDTH lanes, per-triangle boxes, the levels and cut of the parallel
 * refit), the build's limits, and the recorded walks the collision search's floor replays. */
#pragma once

#include "core/internal/simd.h"
#include "core/internal/team.h"
#include "solve/bvh.h"

#include <stdatomic.h>

/* Binned SAH down to this binary depth, object-median splits below it: the tree is then at
 * most 32 + 31 levels deep whatever the input, which bounds the traversal stack. */
#define SAH_DEPTH_LIMIT 32

/* A traversal keeps at most 7 pending siblings per level plus the node being opened. */
#define STACK_SIZE ( ( SERE_BVH_WIDTH - 1 ) * ( SAH_DEPTH_LIMIT + 31 ) + 1 )

/* Sixteen bins per axis find splits within a few percent of a full sweep at a fraction of the
 * cost; the build only runs when quality has degraded. */
#define BIN_COUNT 16

typedef struct build_item
{
	int32_t node, begin, end, depth;
} build_item;

typedef struct box3
{
	float lo[3], hi[3];
} box3;

struct sere_bvh
{
	int32_t threads; /* sere_bvh_set_threads (0: OpenMP's count at the call) */
	int32_t triangle_count;
	int32_t vertex_count;
	int32_t node_count;
	int32_t node_capacity;
	int32_t level_count;
	int32_t* tri;
	sere_bvh_node* nodes;
	int32_t* node_level;  /* per node: depth below the root */
	int32_t* level_nodes; /* node indices grouped by level, root first */
	int32_t* level_start; /* level_count + 1 offsets into level_nodes */
	/* The descendants of node n are exactly the nodes subtree_begin[n] .. subtree_end[n] − 1:
	 * build_node allocates a node's children together and then its first child's whole
	 * subtree, then the second's, ... */
	int32_t* subtree_begin;
	int32_t* subtree_end;
	/* The roots of the subtrees refit in parallel (two levels down), in the order of the mean
	 * index of their triangles' vertices: a static share of them then gives each thread the
	 * part of the mesh a static share of vertex-ordered work (the collision queries) gives it,
	 * so the nodes a thread refits are the ones it reads next, from its own cache. */
	int32_t cut_level;
	int32_t cut_count;
	int32_t* cut_roots;
	double* cut_key;
	float* node_area; /* per node: surface area of the node's own box */
	/* Per node, SERE_BVH_WIDTH apart: the highest corner index of the triangles below child k
	 * (−1 for an empty child), for sere_bvh_query_group_above. Set by the build: a refit moves
	 * boxes, never triangles between subtrees. */
	int32_t* child_top;
	double quality;		  /* SAH cost of the internal nodes after the last refit */
	double quality_built; /* the same right after the last build */
	uint64_t generation;  /* sere_bvh_generation: unique to the last build */

	/* Build scratch: per-triangle box and box centre, the triangle permutation being split,
	 * and the pending nodes. */
	float *lo_x, *lo_y, *lo_z, *hi_x, *hi_y, *hi_z;
	float *c_x, *c_y, *c_z;
	int32_t* order;
	build_item* stack;
};

/* The boxes' bounds take sere_min_x86 and sere_max_x86 (one instruction each, where fminf and
 * fmaxf are library calls): no NaN gets this far, positions are checked first. */

/* A recorded sequence of group walks (sere_bvh_query_group and _above), for the floor of the
 * collision search (collide.h, sere_collide_touch_search): one byte per decision, appended while
 * recording and read back in the same order while replaying. Per walk: 1 when it descends (some
 * lane usable), else 0; then per node it opens, the children any lane hit, and per triangle among
 * them the lanes it hit, before its visit. The visit callbacks append their own decisions to the
 * same stream in between. A replayed walk opens the same nodes in the same order and visits the
 * same triangles with the same lanes, loading every box and child of each node it opens (what the
 * box tests load) and adding them up in place of the tests. */
typedef struct sere_bvh_trace
{
	_Alignas( 64 ) uint8_t* data; /* a cache line per trace: each thread has its own */
	int64_t size, capacity;
	int64_t at;		/* replaying: the next byte */
	int64_t nodes;	/* nodes opened, recording or replaying */
	int64_t leaves; /* triangles visited */
	float sink;		/* replaying: the sum of the boxes loaded (keeps the loads) */
	int32_t isink;	/* replaying: the sum of the child_top entries loaded (_above walks) */
	bool replay;
	bool failed; /* recording: an allocation failed, the record is incomplete */
} sere_bvh_trace;

/* Doubles the trace's room; false (nothing changed) when that cannot be allocated. */
bool sere_bvh_trace_grow( sere_bvh_trace* trace );

static inline void sere_bvh_trace_put( sere_bvh_trace* trace, uint32_t byte )
{
	if ( trace->failed || ( trace->size == trace->capacity && !sere_bvh_trace_grow( trace ) ) )
	{
		trace->failed = true;
		return;
	}
	trace->data[trace->size++] = (uint8_t) byte;
}

/* The next recorded byte (0 past the end: a replay never reads beyond what was recorded unless the
 * stream and the replay disagree, which the tests' counts would show). */
static inline uint32_t sere_bvh_trace_take( sere_bvh_trace* trace )
{
	return trace->at < trace->size ? trace->data[trace->at++] : 0u;
}

/* sere_bvh_query_group (above false) or sere_bvh_query_group_above (above true), recording its
 * walk into trace, or, when trace->replay, replaying the walk recorded there instead of testing
 * boxes: the same visits in the same order. */
void sere_bvh_query_group_traced( const sere_bvh* bvh, const sere_bvh_group* group, bool above, int32_t floor,
								  sere_bvh_trace* trace, sere_bvh_visit_group_fn* visit, void* context );
