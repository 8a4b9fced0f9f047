/* sere — private to the collide_*.c kernels, not installed and not part of the API: the
 * collision state, the detection context, the scalar closest-point tests (Ericson, Real-Time
 * Collision Detection 5.1.5 and 5.1.9) and the functions the detection files share. */
#pragma once

#include "core/internal/simd.h"
#include "core/internal/team.h"
#include "solve/collide.h"
#include "solve/internal/bvh_shared.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* Vertices are queried in fixed blocks, each thread taking one contiguous run of them: it then
 * queries the part of the mesh whose BVH subtrees it refit (sere_bvh orders its parallel refit by
 * vertex index), reading nodes from its own cache; handing blocks out dynamically measured 40%
 * slower on two cores for that traffic. A search's runs are cut at equal time as the last search
 * measured it per block (crumpled parts of a leaf cost several times flat ones: on the dried
 * maple an even cut gave one thread 60% of the work, and counts of triangles and pairs missed
 * the traversal's share), which moves the cut only where the leaf changed; a served detection
 * walks no tree, and its runs are cut at equal counts of listed pairs. A block's contacts land
 * in the list by block index, whichever thread ran it. */
#define DETECT_BLOCK 64

/* The skin of the candidate list, as a fraction of the thickness. A detection that searches the
 * tree looks with the thickness plus twice the skin δ and lists, per block in the order it
 * meets them, every pair that could then be a contact (each vertex–triangle pair whose distance
 * a separating plane does not already put beyond that radius, bound_lanes; each edge pair the
 * edge table passes, table_hits). While every vertex stays within δ of where it was at the
 * listing (and the tree is the same build, for the same thickness), the next detections run the
 * exact test on the list alone instead of searching: a point of a triangle or edge is a convex
 * combination of its corners, so it moves by at most δ when they do, and a distance between two
 * of them changes by at most 2δ; a pair the exact test would accept now was closer than the
 * thickness (plus cull_radius's rounding margin), so closer than that plus 2δ at the listing,
 * where its boxes overlapped the grown query boxes and no separating plane put it beyond that
 * radius: it is on the list. (list_serves takes a common translation and a uniform scale off the
 * motion first: distances do not see the one and shrink with the other.) The list keeps the order
 * of the search (the tree is walked in a fixed order, and a larger query box only adds visits
 * between the same ones), so the exact test meets the same pairs in the same order and finds the
 * same contacts in the same order as a search would: the same bits. On the Table 1 maple a vertex moves by about 0.1
 * thickness a frame; half a thickness lists pairs up to two thicknesses apart, and rebuilds every few frames. */
#define SKIN 0.25f

/* The skin adapts to how long lists last (the list never changes what a detection finds, only
 * what it costs): a list the motion outgrew within SKIN_SHORT detections is replaced by one
 * with a 1.25 times wider skin, one that served over SKIN_LONG by one 0.8 times as wide, within
 * [SKIN_MIN, SKIN_MAX]. Listed pairs grow steeply with the radius (on the Table 1 maple 500 at
 * 0.1, 5000 at 0.25, 22000 at 0.35: the sheet's own neighbours sit about two thicknesses apart),
 * so the skin stays well below one thickness. The cap is where the cost is flat: the Table 1 maple
 * dried to the end (4660 points) spends within 10% of the same on collisions a frame with the cap
 * at 0.125, 0.18, 0.25 or 0.35, and 15-30% more at 0.5 (measured again once served detections
 * tested only what the motion can bring close, list_reach2). With 0.35 a searching frame costs
 * 7-10 ms at 1 thread and a served one 0.3 ms, a list lasting about 4 frames while the leaf curls
 * and 8 once it is dry: the searches, not the lists, set a frame's collision time. */
#define SKIN_MIN   0.125f
#define SKIN_MAX   0.35f
#define SKIN_SHORT 4
#define SKIN_LONG  16

/* The list's room per vertex per thread; a detection that would list more keeps no list (the next
 * one searches again). */
#define CACHE_PAIRS 48

/* Below this many contacts the response runs on the calling thread alone. */
#define RESPOND_PARALLEL 512

/* Contacts evaluated per work item of the response (a static share of whole blocks per thread). */
#define EVALUATE_BLOCK 256

/* A recorded evaluation block's push flags (collide_record.pushes): a byte for eight contacts. */
#define PUSH_BYTES ( EVALUATE_BLOCK / 8 )

/* Per-thread counters one cache line apart, so that two threads' writes never share a line. */
#define FAR_STRIDE 16

/* A vertex's lane marks: bit k (low byte) when query lane k's vertex is it or a neighbour of it,
 * bit 8 + k (high byte) when lane k's vertex is it. */
typedef uint16_t lane_bits;

static inline uint32_t near_lanes( lane_bits m )
{
	return m & 0xffu;
}

static inline uint32_t self_lanes( lane_bits m )
{
	return (uint32_t) m >> 8;
}

/* One thread's run of blocks in a recorded search (sere_collide_record_search): its walks and
 * decisions, and what it counted, a cache line apart from the next run's. */
typedef struct collide_run
{
	sere_bvh_trace trace;
	int64_t bound_pairs; /* pairs handed to bound_lanes and edge_bound_lanes */
	int64_t exact_pairs; /* pairs handed to the exact tests */
	float sink;			 /* replaying: the sum of the records gathered (keeps the loads) */
} collide_run;

/* The recorded detection the floor replays: its runs of blocks (run r is thread r's, blocks
 * run_first[r] .. run_first[r + 1]), the tree build and workspace state it was made in; for a
 * served pass (sere_collide_record_served), also what its response decided. */
typedef struct collide_record
{
	collide_run run[SERE_MAX_THREADS];
	int32_t run_first[SERE_MAX_THREADS + 1];
	int32_t runs;
	bool valid;
	bool served;		 /* a detection the candidate list served, then its response; else a search */
	uint64_t generation; /* sere_bvh_generation at the recording */
	uint64_t state;		 /* sere_collide.state at the recording */
	float thickness;	 /* the recorded detection's */
	bool listed;		 /* a search whose candidate list was whole: it kept the positions (keep_list) */
	float one;			 /* 1.0f, opaque to the compiler so the floor keeps its stores */
	float sink;			 /* the sums of the passes outside the runs */
	/* The served pass's response: its parameters, the evaluations it ran (0 without a response)
	 * and each evaluation's push flags, a bit a contact, PUSH_BYTES a block of contacts. */
	sere_collide_params params;
	int32_t evaluations;
	uint8_t* pushes;
	size_t push_capacity;
} collide_record;

struct sere_collide
{
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t edge_count;
	int32_t capacity; /* of each kind of contact */
	int32_t threads;  /* sere_collide_set_threads (0: OpenMP's count at the call, at most slots) */
	int32_t slots;	  /* threads with their own detection buffer */
	/* Detection blocks: vertex_blocks blocks of DETECT_BLOCK vertices querying for vertex–triangle
	 * contacts, then as many for edge–edge contacts (lanes are the same vertices, each standing for
	 * the edges it is the lower end of), block_count in all, cut into runs of about equal work
	 * together. */
	int32_t vertex_blocks;
	int32_t block_count;
	int32_t contact_count;		/* vertex–triangle contacts listed */
	int32_t edge_contact_count; /* edge–edge contacts listed */
	int64_t edge_found;			/* edge–edge contacts the last detection found, listed or not */
	sere_contact* contacts;		/* capacity, in block order */
	sere_edge_contact* edge_contacts;
	/* Detection buffers of threads 1 .. slots − 1, capacity apart. Thread 0 writes straight into
	 * contacts: its run of blocks starts at the first, so its contacts are already in place and
	 * only the other threads' are copied (none on one thread). */
	sere_contact* thread_contacts;
	/* Edge–edge detection buffers of threads 0 .. slots − 1, capacity apart: the edge blocks need
	 * not start thread 0's run, and their contacts are few, so all are copied. */
	sere_edge_contact* thread_edge_contacts;
	int32_t* block_thread;
	int32_t* block_start; /* in the buffer of the block's thread and kind */
	int64_t* block_found; /* count, then the offset of the block's contacts (edge–edge ones after all others) */
	/* Per block: the time its last search took (ns), and the running sum (block_count + 1) the
	 * runs are cut from: of those times for a search, of the listed pairs for a served detection.
	 * The cut decides only which thread runs a block, never what the block finds or where its
	 * contacts go. */
	int64_t* block_work;
	int64_t* work_prefix;

	/* The mesh's edges, each once: ends (lower, higher) at edge_end[2e ..], ordered by the lower
	 * end, then the higher; vertex a is the lower end of edges lower_edge[a] .. lower_edge[a + 1].
	 * owned[3t + r] is the edge from corner r to corner r + 1 of triangle t when t is the first
	 * triangle holding it, else −1: the search visits triangles, and visits each edge through
	 * one of them only; edge_triangle[e] is that triangle. */
	int32_t* edge_end;
	int32_t* lower_edge;
	int32_t* owned;
	int32_t* edge_triangle;

	/* The rest positions of sere_collide_set_rest, NULL until given. */
	float *rest_x, *rest_y, *rest_z;

	/* Gather lists: for each vertex, the contacts it takes part in (as vertex, corner or edge end),
	 * in contact order: entry e = entry_offset[i] .. names contact entries[e], whose correction
	 * λ n̂ moves the vertex by entry_coef[e] λ n̂ / m (−u, −v, −w for corners a, b, c, +1 for
	 * the vertex; 1 − s, s, −(1 − t), −t for the edge ends a0, a1, b0, b1). The coefficient sits
	 * beside the index so a gather reads one list in order and one correction per entry. */
	int32_t* entry_offset; /* vertex_count + 1 */
	/* Per thread, pad(vertex_count) apart: its contacts' entries per vertex, then where it
	 * writes the next one (list_contacts). */
	int32_t* entry_cursor;
	/* Per thread, FAR_STRIDE apart: entries and touched vertices in its run of vertices. */
	int32_t* run_total;
	int32_t* entries;  /* 4 × 2 × capacity */
	float* entry_coef; /* 4 × 2 × capacity */
	int32_t* touched;  /* vertices with at least one entry, ascending */
	int32_t touched_count;

	/* Per contact, structure of arrays for the response, 2 × capacity: the vertex–triangle
	 * contacts, then the edge–edge ones from contact_count on. Fixed at detection: the members
	 * (the vertex and the triangle's corners a, b, c; or the edge ends a0, a1, b0, b1), the side
	 * (or taken from the start-of-step positions when the response gets them) and the weights
	 * (barycentric u, v, w; or s, t). Per response: 1 / W.
	 * Per iteration: corr[4k ..] = (λ n̂, 1) when contact k pushes, else zero: one 16-byte read
	 * per gather entry gives the correction and the count. */
	int32_t* member[4];
	float* weight[3];
	float* contact_side;
	float* inv_weight;
	float* corr;

	/* Per thread of the response, FAR_STRIDE apart: its count of contacts beyond the tolerance. */
	int32_t* far_count;

	/* The response's positions of the touched vertices, interleaved (x, y, z, 0) so that the
	 * evaluation gathers a point with one 16-byte load; the response moves them here and writes
	 * them back once at its end. */
	float* position;

	/* Per touched vertex: displacement (x, y, z, 0) summed over the iterations, for the
	 * velocity update. */
	float* acc;

	/* Per vertex, each iteration: how many pushing contacts it takes part in. */
	float* push_count;

	/* Per query group g (vertices 8g .. 8g + 7): the lane marks it sets, as the vertices
	 * mark_vertex[mark_offset[g] .. mark_offset[g + 1]) (each once) and their marks mark_bits. */
	int32_t* mark_offset; /* group count + 1 */
	int32_t* mark_vertex;
	lane_bits* mark_bits;

	/* Per thread of the detection, vertex_count marks apart (zero between groups): vertex j's
	 * lane_bits while the group's lanes are queried, so the lanes a triangle is near are the OR
	 * of its corners' marks. */
	lane_bits* lane_mark;

	/* The candidate list (see SKIN): the positions it was built at, the thickness and tree
	 * generation it was built for, and per block the pairs the exact test must see while the
	 * motion stays within the skin (list_serves), in the order the search met them: per thread
	 * cache_capacity pairs (the vertex or edge, the triangle or other edge, the vertex's
	 * neighbour flag and their squared distance at the listing, see list_reach2), and per block the
	 * thread, first pair and count. */
	bool cache_valid;
	float skin;			/* the next list's skin, a fraction of the thickness (SKIN) */
	float cache_delta;	/* the list's skin δ */
	int32_t cache_uses; /* detections the list has served */
	float* edge_across; /* per edge, 3 rows pad(edge_count) apart: sere_coll_edge_across_at at the listing */
	float cache_thickness;
	uint64_t cache_generation;
	int32_t cache_capacity;
	float *cache_x, *cache_y, *cache_z;
	int32_t *cache_item, *cache_target;
	uint8_t* cache_near;
	float* cache_gap;
	float cache_reach2; /* list_reach2: the served detection's bound on a contact's squared listed distance */
	/* The listing positions' mean r̄, Σ |r − r̄|² and largest |x| + |y| + |z| (keep_shape), for
	 * list_serves' scale; and per vertex block, 4 apart, the partial sums of keep_shape and
	 * list_shrink, added in block order so that neither depends on the thread count. */
	float cache_mean[3];
	double cache_spread;
	float cache_far;
	double* cache_sum;
	int32_t *cache_block_thread, *cache_block_start, *cache_block_count;
	int32_t* cache_used; /* per thread, FAR_STRIDE apart: pairs listed, or −1 after an overflow */

	/* The last recorded search (sere_collide_record_search), NULL before the first. state changes
	 * with every detection and every change of what a detection lists (threads, capacity, rest
	 * positions): a record replays only the state it was made in. */
	collide_record* record;
	uint64_t state;
};

/* Closest point q on the segment ab to p; t is its parameter (q = a + t (b − a)). */
static inline float closest_on_segment( const float p[3], const float a[3], const float b[3], float* t )
{
	float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	float ap[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
	float len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
	float s = len2 > 0.0f ? ( ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2] ) / len2 : 0.0f;
	s = s < 0.0f ? 0.0f : ( s > 1.0f ? 1.0f : s );
	float d[3] = { ap[0] - s * ab[0], ap[1] - s * ab[1], ap[2] - s * ab[2] };
	*t = s;
	return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

/* Ericson, Real-Time Collision Detection 5.1.5: test the vertex regions, then the edge regions
 * by the signs of the barycentric areas, else the point projects inside the face. q gets the
 * closest point, w its weights; returns |p − q|². */
static inline float closest_point( const float p[3], const float a[3], const float b[3], const float c[3], float w[3],
								   float q[3] )
{
	float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	float ac[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	float ap[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
	float d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2];
	float d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
	float bp[3] = { p[0] - b[0], p[1] - b[1], p[2] - b[2] };
	float d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2];
	float d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
	float cp[3] = { p[0] - c[0], p[1] - c[1], p[2] - c[2] };
	float d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2];
	float d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
	float vc = d1 * d4 - d3 * d2;
	float vb = d5 * d2 - d1 * d6;
	float va = d3 * d6 - d5 * d4;
	float sum = va + vb + vc;
	float u, v, t;

	if ( d1 <= 0.0f && d2 <= 0.0f )
	{
		u = 1.0f, v = 0.0f, t = 0.0f;
		q[0] = a[0], q[1] = a[1], q[2] = a[2];
	}
	else if ( d3 >= 0.0f && d4 <= d3 )
	{
		u = 0.0f, v = 1.0f, t = 0.0f;
		q[0] = b[0], q[1] = b[1], q[2] = b[2];
	}
	else if ( d6 >= 0.0f && d5 <= d6 )
	{
		u = 0.0f, v = 0.0f, t = 1.0f;
		q[0] = c[0], q[1] = c[1], q[2] = c[2];
	}
	else if ( vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f && d1 - d3 > 0.0f )
	{
		float s = d1 / ( d1 - d3 );
		u = 1.0f - s, v = s, t = 0.0f;
		q[0] = a[0] + s * ab[0], q[1] = a[1] + s * ab[1], q[2] = a[2] + s * ab[2];
	}
	else if ( vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f && d2 - d6 > 0.0f )
	{
		float s = d2 / ( d2 - d6 );
		u = 1.0f - s, v = 0.0f, t = s;
		q[0] = a[0] + s * ac[0], q[1] = a[1] + s * ac[1], q[2] = a[2] + s * ac[2];
	}
	else if ( va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f && ( d4 - d3 ) + ( d5 - d6 ) > 0.0f )
	{
		float s = ( d4 - d3 ) / ( ( d4 - d3 ) + ( d5 - d6 ) );
		u = 0.0f, v = 1.0f - s, t = s;
		q[0] = b[0] + s * ( c[0] - b[0] ), q[1] = b[1] + s * ( c[1] - b[1] ), q[2] = b[2] + s * ( c[2] - b[2] );
	}
	else if ( vb >= 0.0f && vc >= 0.0f && vb + vc <= sum &&
			  sum > 0x1p-20f * ( ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2] ) *
						( ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2] ) )
	{
		/* sum = |ab|² |ac|² sin² of the angle at a, formed from products of dot products: below
		 * a millionth of |ab|² |ac|² rounding swamps it and the weights are noise */
		v = vb / sum, t = vc / sum;
		u = 1.0f - v - t;
		q[0] = a[0] + v * ab[0] + t * ac[0];
		q[1] = a[1] + v * ab[1] + t * ac[1];
		q[2] = a[2] + v * ab[2] + t * ac[2];
	}
	else
	{
		/* A degenerate triangle or a sliver thinner than a thousandth of its edges: its nearest
		 * edge, off by at most that width. (The edge tests above skip zero-length edges, which
		 * have no region.) */
		float sab, sbc, sca;
		float dab = closest_on_segment( p, a, b, &sab );
		float dbc = closest_on_segment( p, b, c, &sbc );
		float dca = closest_on_segment( p, c, a, &sca );
		if ( dab <= dbc && dab <= dca )
		{
			u = 1.0f - sab, v = sab, t = 0.0f;
			q[0] = a[0] + sab * ab[0], q[1] = a[1] + sab * ab[1], q[2] = a[2] + sab * ab[2];
		}
		else if ( dbc <= dca )
		{
			u = 0.0f, v = 1.0f - sbc, t = sbc;
			q[0] = b[0] + sbc * ( c[0] - b[0] ), q[1] = b[1] + sbc * ( c[1] - b[1] ),
			q[2] = b[2] + sbc * ( c[2] - b[2] );
		}
		else
		{
			u = sca, v = 0.0f, t = 1.0f - sca;
			q[0] = c[0] - sca * ac[0], q[1] = c[1] - sca * ac[1], q[2] = c[2] - sca * ac[2];
		}
	}
	w[0] = u, w[1] = v, w[2] = t;
	float d[3] = { p[0] - q[0], p[1] - q[1], p[2] - q[2] };
	return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

static inline float clamp_unit( float s )
{
	return s < 0.0f ? 0.0f : ( s > 1.0f ? 1.0f : s );
}

/* Ericson, Real-Time Collision Detection 5.1.9: the closest points of the two lines, s clamped to
 * the first segment, t then found for it and, when it leaves the second segment, clamped and s
 * found again. Parallel lines (sin² of their angle at most 2⁻²⁰: a e − b² is then rounding of
 * the products) and a first segment of zero length take s = 0; a second of zero length, t = 0.
 * w gets (s, t), d the vector from the second closest point to the first; returns |d|².
 * closest_segments_lanes repeats every operation. */
static inline float closest_segments( const float p0[3], const float p1[3], const float q0[3], const float q1[3],
									  float w[2], float d[3] )
{
	float d1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
	float d2[3] = { q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2] };
	float r[3] = { p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2] };
	float a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
	float e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2];
	float b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2];
	float c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2];
	float f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2];
	float denom = a * e - b * b;
	float s = denom > 0x1p-20f * a * e ? clamp_unit( ( b * f - c * e ) / denom ) : 0.0f;
	float t = ( b * s + f ) / e;
	if ( !( e > 0.0f ) || t < 0.0f )
	{
		/* the second segment is a point, or the first's point is beyond its start */
		t = 0.0f;
		s = a > 0.0f ? clamp_unit( -c / a ) : 0.0f;
	}
	else if ( t > 1.0f )
	{
		t = 1.0f;
		s = a > 0.0f ? clamp_unit( ( b - c ) / a ) : 0.0f;
	}
	for ( int k = 0; k < 3; ++k )
	{
		d[k] = r[k] + s * d1[k] - t * d2[k];
	}
	w[0] = s, w[1] = t;
	return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

static inline void load3( const float* x, const float* y, const float* z, int32_t i, float out[3] )
{
	out[0] = x[i], out[1] = y[i], out[2] = z[i];
}

/* The unit normal of triangle t and its three corners; zero normal when degenerate. */
static inline void triangle_frame( const float* x, const float* y, const float* z, const int32_t* v, float a[3],
								   float b[3], float c[3], float n[3] )
{
	load3( x, y, z, v[0], a );
	load3( x, y, z, v[1], b );
	load3( x, y, z, v[2], c );
	float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	float ac[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	n[0] = ab[1] * ac[2] - ab[2] * ac[1];
	n[1] = ab[2] * ac[0] - ab[0] * ac[2];
	n[2] = ab[0] * ac[1] - ab[1] * ac[0];
	float length = sqrtf( n[0] * n[0] + n[1] * n[1] + n[2] * n[2] );
	float inv = length > 0.0f ? 1.0f / length : 0.0f;
	n[0] *= inv, n[1] *= inv, n[2] *= inv;
}

/* Points gathered for vector tests, GATHER_LANES at a time: sere_v8_gather_records writes the
 * points index[0 .. GATHER_LANES) of the interleaved position array into consecutive floats of
 * x, y and z (only loads, shuffles and stores: the values a scalar copy would write). A point is
 * one 16-byte load and eight are transposed in registers, where a scalar copy spends a load and
 * a store per coordinate; the vectorizer's hardware gathers (vgatherdps, three per point) from
 * the x, y, z arrays measured slower still: on the dried maple the response took 2.1 ms with
 * them, 1.55 ms with this (one thread). sere_v8_scatter_records is its inverse. */
#define GATHER_LANES 8

/* Thread tid's detection buffer (see thread_contacts). */
static inline sere_contact* thread_buffer( const sere_collide* c, int tid )
{
	return tid == 0 ? c->contacts : c->thread_contacts + (size_t) ( tid - 1 ) * (size_t) c->capacity;
}

/* Thread tid's edge–edge detection buffer (see thread_edge_contacts). */
static inline sere_edge_contact* thread_edge_buffer( const sere_collide* c, int tid )
{
	return c->thread_edge_contacts + (size_t) tid * (size_t) c->capacity;
}

/* Candidate pairs are tested CLOSEST_LANES at a time by one straight-line pass (closest_lanes). */
#define CLOSEST_LANES 8

/* Candidate (triangle, group lane) pairs gathered from the tree walk before the exact test:
 * a triangle overlaps 1.6 of a group's eight cubes on average (maple after drying), so testing
 * the pairs in full vectors keeps every lane busy where testing a triangle against its group
 * would leave most of them idle. */
#define PAIR_BUFFER 256

/* Edges of one lane of an edge group at most: a lane stands for the edges one vertex is the lower
 * end of (3 on average), LANE_EDGES at a time; a vertex with more takes several lanes. The table
 * of a group's edges is tested in vectors of 8. */
#define LANE_EDGES	8
#define GROUP_EDGES ( SERE_BVH_WIDTH * LANE_EDGES )

/* Edges reached by an edge group's walk, buffered before their tests against the table: in one
 * tight loop after the walk, their tests cost a third of what they did in the walk's callback. */
#define CANDIDATES 256

/* One group of up to eight consecutive vertices querying the BVH together, the
 * candidate pairs of its block (tested when the buffer fills and at the block's end, so that
 * only a block's last batch runs part empty, not every group's), and the calling thread's
 * contact buffers. */
typedef struct detect_context
{
	const float *x, *y, *z;
	const int32_t* tri;
	const int32_t *edge_end, *lower_edge, *owned, *edge_triangle; /* sere_collide's edges */
	const float *rest_x, *rest_y, *rest_z;						  /* its rest positions, or NULL */
	const int32_t *mark_offset, *mark_vertex;					  /* sere_collide's group mark lists */
	const lane_bits* mark_bits;
	lane_bits* mark; /* the calling thread's lane marks (sere_collide.lane_mark) */
	int32_t first;	 /* the vertex of lane 0 */
	/* An edge group's table: its lanes' edges, side by side for vector tests: their boxes grown
	 * by the lane's cull radius, their lower end's position, a unit vector across them (in the
	 * plane of their first triangle; zero when that is degenerate), their unit direction and
	 * their length along it (zero for a zero-length edge), the lane's cull radius, their ends and
	 * index. Lane k's rows start at table_lane[k]. */
	int32_t table_count;
	int32_t table_lane[SERE_BVH_WIDTH + 1];
	float table_lo[3][GROUP_EDGES], table_hi[3][GROUP_EDGES];
	float table_at[3][GROUP_EDGES], table_across[3][GROUP_EDGES], table_margin[GROUP_EDGES];
	float table_along[3][GROUP_EDGES], table_length[GROUP_EDGES];
	int32_t table_lower[GROUP_EDGES], table_upper[GROUP_EDGES], table_edge[GROUP_EDGES];
	/* edges the group's walk reached, with the lanes whose box overlaps their triangle's */
	int32_t candidate_edge[CANDIDATES];
	uint8_t candidate_lanes[CANDIDATES];
	int32_t candidate_count;
	float h2;
	int32_t pair_item[PAIR_BUFFER];	  /* the group lane's vertex, or one of its edges */
	int32_t pair_target[PAIR_BUFFER]; /* the triangle, or the other edge */
	uint8_t pair_near[PAIR_BUFFER];	  /* the vertex is joined by a mesh edge to a corner */
	int32_t pair_count;
	sere_contact* buffer;
	int32_t used;
	int64_t found;
	sere_edge_contact* edge_buffer;
	int32_t edge_used;
	int64_t edge_found;
	int32_t capacity;
	/* Listing (a searching detection, see SKIN): the query radii grow by grow = 2δ (with room
	 * for rounding), and the pairs that could be contacts within it go to the calling thread's
	 * list (list_used = −1 once it is full). */
	bool listing;
	float thickness;
	float grow;
	int32_t *list_item, *list_target;
	uint8_t* list_near;
	float* list_gap; /* the pairs' squared distances at the listing, see list_reach2 */
	int32_t list_used, list_capacity;
	const float* across[3]; /* sere_collide.edge_across's rows */
	/* Recording or replaying a search (see sere_collide_touch_search): this run's record, NULL
	 * for a plain detection, and 1.0f opaque to the compiler for the replay's stores. */
	collide_run* run;
	float one;
} detect_context;

/* The floor (sere_collide_touch_search) replays the run's walks and decisions: each test's
 * outcome is taken from the record in place of its arithmetic. */
static inline bool replaying( const detect_context* c )
{
	return c->run != NULL && c->run->trace.replay;
}

/* A test's outcome: the mask the test gave (appended to the record when recording), or the
 * recorded one when replaying. */
static inline uint32_t traced_mask( detect_context* c, uint32_t mask )
{
	if ( c->run != NULL )
	{
		sere_bvh_trace_put( &c->run->trace, mask );
	}
	return mask;
}

static inline uint32_t recorded_mask( detect_context* c )
{
	return sere_bvh_trace_take( &c->run->trace );
}

/* The sum of `count` rows of CLOSEST_LANES gathered values, the floor's use of its loads: one
 * vector add a row, then the lanes. */
static inline float sum_rows( float rows[][CLOSEST_LANES], int count )
{
	float lanes[CLOSEST_LANES] = { 0.0f };
	for ( int r = 0; r < count; ++r )
	{
		for ( int l = 0; l < CLOSEST_LANES; ++l )
		{
			lanes[l] += rows[r][l];
		}
	}
	float sum = 0.0f;
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		sum += lanes[l];
	}
	return sum;
}

/* Half-width of the query cube around a vertex: the thickness plus what rounding can add. The
 * float distance test may accept a pair up to a few ulps of the thickness too far, and the
 * closest point (and p ± r) carry a few ulps of the coordinates; both margins are far below
 * any geometric scale, and the exact test decides anyway. */
static inline float cull_radius( float h, const float p[3] )
{
	return h + h * 0x1p-10f + ( fabsf( p[0] ) + fabsf( p[1] ) + fabsf( p[2] ) ) * 0x1p-18f;
}

/* Appends pair k of the pair buffer to the calling thread's list (see SKIN). */
static inline void list_pair( detect_context* c, int32_t k )
{
	if ( c->list_used >= 0 && c->list_used < c->list_capacity )
	{
		c->list_item[c->list_used] = c->pair_item[k];
		c->list_target[c->list_used] = c->pair_target[k];
		c->list_near[c->list_used] = c->pair_near[k];
		c->list_used += 1;
	}
	else
	{
		c->list_used = -1;
	}
}

/* Listing: moves the pairs start + l of the buffer for each set bit l of keep (in lane order)
 * down to kept, kept + 1, ..., lists each and returns the next kept; edge pairs (vertex_pairs
 * false) carry near = 0. */
static inline int32_t keep_pairs( detect_context* c, int32_t start, uint32_t keep, int32_t kept, bool vertex_pairs )
{
	while ( keep != 0 )
	{
		int32_t k = start + __builtin_ctz( keep );
		keep &= keep - 1;
		c->pair_item[kept] = c->pair_item[k];
		c->pair_target[kept] = c->pair_target[k];
		c->pair_near[kept] = vertex_pairs ? c->pair_near[k] : 0;
		list_pair( c, kept );
		kept += 1;
	}
	return kept;
}

/* Separating directions (see SKIN): the projections of a convex set onto a unit direction d̂
 * span the interval of its corners' projections, and |p − q| ≥ (p − q) · d̂ for any points p, q,
 * so the gap between two sets' intervals on d̂ bounds their distance from below. Rounding moves
 * the projections by a few ulps of the coordinates and the directions by a few ulps of 1 off unit
 * length, which the |p| 2⁻¹⁶ (64 times cull_radius's own allowance) and the 2⁻¹⁰ of the radius
 * added by list_radius cover. */
static inline float interval_gap( float p_lo, float p_hi, float q_lo, float q_hi )
{
	float gap = q_lo - p_hi, other = p_lo - q_hi;
	return gap > other ? gap : other;
}

/* The radius a listed pair must be within: the thickness with its rounding margin (cull_radius at
 * the pair's farthest coordinates far), the grown skin, and room for the bounds' rounding. */
static inline float list_radius( const detect_context* c, const float far[3] )
{
	float r = cull_radius( c->thickness, far ) + c->grow;
	return r + r * 0x1p-10f + ( fabsf( far[0] ) + fabsf( far[1] ) + fabsf( far[2] ) ) * 0x1p-16f;
}

/* What a served detection tests of the list (see SKIN). A listing search runs the exact test on
 * every pair it lists, and keeps each one's squared distance then where that test is well
 * conditioned: a triangle whose sin² of the corner angle is at least 2⁻⁸ (its barycentric
 * coordinates then carry 2⁻¹⁶ of relative error at most, far inside the rounding allowance below
 * for edges up to tens of thicknesses), or two edges whose sin² is at least 2⁻¹⁰ (well clear of
 * closest_segments' parallel case). Elsewhere it keeps 0, and the pair is always tested: on a
 * sliver the closest point can land off along the face, its distance farther than the true one
 * by more than any allowance (a review built one whose contact a served pass then missed: now a
 * test). With the motion since the listing a scale s and a translation T plus a residual of at
 * most D (moved) per vertex (list_serves), a point of a triangle or edge moves the same way with a
 * residual of at most D, so a distance now is at least s times the distance then less 2D: a pair
 * farther than (thickness + 2D) / s then is farther than the thickness now and cannot be a
 * contact. The served detection skips those, keeping the others in the list's order: the same
 * contacts in the same order. Well-conditioned float distances are within a few ulps of the
 * coordinates of the true ones (|p| 2⁻¹⁹ is ample), which `far` 2⁻¹⁴ covers, with far bounding |p|
 * then and now (the largest |x| + |y| + |z| of either); 2⁻¹⁰ of the reach covers its own rounding
 * and the quotient's. A list is tested least just after its search, when D is small and its pairs
 * are needed least. Returns the bound on a contact's squared distance at the listing. */
static inline float list_reach2( float thickness, float moved, float scale, float far )
{
	float reach = ( thickness + 2.0f * moved ) / scale;
	reach += reach * 0x1p-10f + far * 0x1p-14f;
	return reach * reach;
}

/* Listing: where the squared distances of buffered pairs start .. start + count − 1 go in the
 * calling thread's list (list_reach2: the buffer's pairs are the list's last pair_count), NULL
 * when nothing is being listed or the list is full. */
static inline float* listed_gaps( const detect_context* c, int32_t start )
{
	return c->listing && c->list_used >= 0 ? c->list_gap + ( c->list_used - c->pair_count + start ) : NULL;
}

/* For CLOSEST_LANES lanes: whether u = u1 − u0 and v = v1 − v0 have sin² of their angle at least
 * k, as |u × v|² = u² v² − (u · v)² ≥ k u² v² (list_reach2's condition). */
static inline void sine2_at_least( float u0[3][CLOSEST_LANES], float u1[3][CLOSEST_LANES], float v0[3][CLOSEST_LANES],
								   float v1[3][CLOSEST_LANES], float k, int32_t sharp[CLOSEST_LANES] )
{
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float uu = 0.0f, vv = 0.0f, uv = 0.0f;
		for ( int r = 0; r < 3; ++r )
		{
			float u = u1[r][l] - u0[r][l], v = v1[r][l] - v0[r][l];
			uu += u * u, vv += v * v, uv += u * v;
		}
		sharp[l] = uu * vv - uv * uv >= k * uu * vv;
	}
}

/* Listing: keeps the squared distances d2 of `count` buffered pairs in the list where the exact
 * test is well conditioned (sharp), 0 elsewhere (list_reach2). */
static inline void keep_gaps( float* gap, int32_t count, const float d2[CLOSEST_LANES],
							  const int32_t sharp[CLOSEST_LANES] )
{
	for ( int32_t l = 0; l < count; ++l )
	{
		gap[l] = sharp[l] ? d2[l] : 0.0f;
	}
}

/* collide_search.c: vertex–triangle detection. */

/* The exact test (closest_point, Ericson 5.1.5) of the buffered vertex–triangle pairs, in the
 * order they were buffered. */
void sere_coll_detect_flush( detect_context* c );

/* Queries the groups of vertex block `block` (lanes are vertices); nonzero when a vertex is not
 * finite. */
int sere_coll_detect_vertex_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness );

/* collide_edges.c: edge–edge detection. */

/* The exact test (closest_segments, Ericson 5.1.9) of the buffered edge pairs, in the order they
 * were buffered. */
void sere_coll_detect_edge_flush( detect_context* c );

/* Queries vertex block `block` for edge–edge pairs (its edges by their lower end). */
void sere_coll_detect_edge_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness );

/* The unit vector across edge e in the plane of its first triangle, for the edge table. */
void sere_coll_edge_across_at( sere_collide* collide, const int32_t* tri, const float* x, const float* y,
							   const float* z, int32_t e );

/* The floor of sere_coll_edge_across_at: the same loads, their sum returned, and the same stores
 * of the values already there (times one). */
float sere_coll_edge_across_touch( sere_collide* collide, const int32_t* tri, const float* x, const float* y,
								   const float* z, int32_t e, float one );

/* collide_detect.c: the candidate list. */

/* Whether the candidate list (see SKIN) serves a detection at these positions and thickness:
 * sere_collide_resolve asks before refitting the tree, which a served detection does not read. */
bool sere_coll_list_serves( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y, const float* z,
							float thickness );

/* sere_collide_detect, told whether the list serves (served 1 or 0, from sere_coll_list_serves at
 * the same positions, tree and thickness) or to find out (−1). */
sere_status sere_coll_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
							  const float* z, float thickness, int served, int32_t* contact_count );

/* sere_coll_detect recording into the workspace's record (made here if need be) for the floor: a search
 * (served 0: sere_collide_record_search) or a detection the list serves (served 1, which the
 * caller has checked). traffic (may be NULL) gets what it moved. */
sere_status sere_coll_record_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									 const float* z, float thickness, int served, sere_collide_traffic* traffic );

/* The floor of the recorded detection: the search's (sere_collide_touch_search), or the served
 * one's with the check that the list serves before it (served). SERE_ERR_ARGUMENT, nothing done,
 * when the record is of the other kind or does not replay the workspace as it is. */
sere_status sere_coll_touch_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									const float* z, bool served, sere_collide_traffic* traffic );
