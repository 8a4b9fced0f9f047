/* _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/collide.h"
#include "core/internal/simd.h"
#include "core/internal/team.h"

#include <math.h>
#include <omp.h>
#include <string.h>

/* Vertices are queried in fixed blocks, each thread taking one contiguous run of them: it then
 * queries the part of the mesh whose BVH subtrees it refit (sere_bvh orders its parallel refit by
 * vertex index), reading nodes from its own cache; handing blocks out dynamically measured 40%
 * slower on two cores for that traffic. The runs are cut at equal time as the previous detection
 * measured it per block (crumpled parts of a leaf cost several times flat ones: on the dried
 * maple an even cut gave one thread 60% of the work, and counts of triangles and pairs missed
 * the traversal's share), which moves the cut only where the leaf changed. A block's contacts land in the list by block
 * index, whichever thread ran it. */
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
 * radius: it is on the list. The list keeps the order of the search (the tree is walked in a
 * fixed order, and a larger query box only adds visits between the same ones), so the exact test
 * meets the same pairs in the same order and finds the same contacts in the same order as a
 * search would: the same bits. On the Table 1 maple a vertex moves by about 0.1 thickness a
 * frame; half a thickness lists pairs up to two thicknesses apart, and rebuilds every few frames. */
#define SKIN 0.25f

/* The skin adapts to how long lists last (the list never changes what a detection finds, only
 * what it costs): a list the motion outgrew within SKIN_SHORT detections is replaced by one
 * with a 1.25 times wider skin, one that served over SKIN_LONG by one 0.8 times as wide, within
 * [SKIN_MIN, SKIN_MAX]. Listed pairs grow steeply with the radius (on the Table 1 maple 500 at
 * 0.1, 5000 at 0.25, 22000 at 0.35: the sheet's own neighbours sit about two thicknesses apart),
 * so the skin stays well below one thickness. */
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

struct sere_collide
{
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t edge_count;
	int32_t capacity; /* of each kind of contact */
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
	/* Per block: the time its last detection took (ns), and the running sum of those
	 * (block_count + 1) the runs are cut from. Timing decides only which thread runs a block,
	 * never what the block finds or where its contacts go. */
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
	 * generation it was built for, and per block the pairs the exact test must see while no
	 * vertex has moved by more than the skin, in the order the search met them: per thread
	 * cache_capacity pairs (the vertex or edge, the triangle or other edge, and the vertex's
	 * neighbour flag), and per block the thread, first pair and count. */
	bool cache_valid;
	float skin;			/* the next list's skin, a fraction of the thickness (SKIN) */
	float cache_delta;	/* the list's skin δ */
	int32_t cache_uses; /* detections the list has served */
	float* edge_across; /* per edge, 3 rows pad(edge_count) apart: edge_across_at at the listing */
	float cache_thickness;
	uint64_t cache_generation;
	int32_t cache_capacity;
	float *cache_x, *cache_y, *cache_z;
	int32_t *cache_item, *cache_target;
	uint8_t* cache_near;
	int32_t *cache_block_thread, *cache_block_start, *cache_block_count;
	int32_t* cache_used; /* per thread, FAR_STRIDE apart: pairs listed, or −1 after an overflow */
};

sere_collide_params sere_collide_params_default( void )
{
	sere_collide_params params = {
		/* A third of an edge of a ~4700-vertex leaf of unit width. It must stay below the mesh's
		 * smallest triangle height: past it a vertex already touches the triangle across the
		 * opposite edge of its own triangle. */
		.thickness = 0.005f,
		/* Table 2: Δt = 0.002 for every preset */
		.dt = 0.002f,
		.iterations = 8,
		/* one detection per frame, as the paper's Algorithm 1; more rounds re-query to catch
		 * contacts the push-out itself makes */
		.rounds = 1,
		.relaxation = 1.0f,
		.rebuild_ratio = SERE_BVH_REBUILD_RATIO,
	};
	return params;
}

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

float sere_closest_point_triangle( const float p[3], const float a[3], const float b[3], const float c[3],
								   float weights[3] )
{
	float q[3];
	return closest_point( p, a, b, c, weights, q );
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

float sere_closest_points_segments( const float p0[3], const float p1[3], const float q0[3], const float q1[3],
									float weights[2] )
{
	float d[3];
	return closest_segments( p0, p1, q0, q1, weights, d );
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
static sere_contact* thread_buffer( const sere_collide* c, int tid )
{
	return tid == 0 ? c->contacts : c->thread_contacts + (size_t) ( tid - 1 ) * (size_t) c->capacity;
}

/* Thread tid's edge–edge detection buffer (see thread_edge_contacts). */
static sere_edge_contact* thread_edge_buffer( const sere_collide* c, int tid )
{
	return c->thread_edge_contacts + (size_t) tid * (size_t) c->capacity;
}

/* The arrays sized by the contact capacity, in one table for allocation and release: each holds
 * size[i] bytes per unit of capacity (the per-contact arrays of the response hold both kinds). */
#define CONTACT_ARRAYS 16

static void contact_arrays( sere_collide* c, void*** slot, size_t* size )
{
	void** slots[CONTACT_ARRAYS] = {
		(void**) &c->contacts,		(void**) &c->thread_contacts,
		(void**) &c->edge_contacts, (void**) &c->thread_edge_contacts,
		(void**) &c->entries,		(void**) &c->entry_coef,
		(void**) &c->member[0],		(void**) &c->member[1],
		(void**) &c->member[2],		(void**) &c->member[3],
		(void**) &c->contact_side,	(void**) &c->weight[0],
		(void**) &c->weight[1],		(void**) &c->weight[2],
		(void**) &c->inv_weight,	(void**) &c->corr,
	};
	size_t sizes[CONTACT_ARRAYS] = {
		sizeof( sere_contact ),		 sizeof( sere_contact ) * (size_t) ( c->slots > 1 ? c->slots - 1 : 1 ),
		sizeof( sere_edge_contact ), sizeof( sere_edge_contact ) * (size_t) c->slots,
		2 * 4 * sizeof( int32_t ),	 2 * 4 * sizeof( float ),
		2 * sizeof( int32_t ),		 2 * sizeof( int32_t ),
		2 * sizeof( int32_t ),		 2 * sizeof( int32_t ),
		2 * sizeof( float ),		 2 * sizeof( float ),
		2 * sizeof( float ),		 2 * sizeof( float ),
		2 * sizeof( float ),		 2 * 4 * sizeof( float ),
	};
	memcpy( slot, slots, sizeof( slots ) );
	memcpy( size, sizes, sizeof( sizes ) );
}

static void collide_free( sere_collide* c )
{
	void** slot[CONTACT_ARRAYS];
	size_t size[CONTACT_ARRAYS];
	contact_arrays( c, slot, size );
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		sere_free( *slot[i] );
	}
	void* arrays[] = { c->block_thread,		 c->block_start,	   c->block_found,	c->block_work,
					   c->work_prefix,		 c->entry_offset,	   c->entry_cursor, c->run_total,
					   c->touched,			 c->position,		   c->acc,			c->far_count,
					   c->lane_mark,		 c->mark_offset,	   c->mark_vertex,	c->mark_bits,
					   c->edge_end,			 c->lower_edge,		   c->owned,		c->edge_triangle,
					   c->push_count,		 c->cache_x,		   c->cache_y,		c->cache_z,
					   c->cache_item,		 c->cache_target,	   c->cache_near,	c->cache_block_thread,
					   c->cache_block_start, c->cache_block_count, c->cache_used,	c->edge_across };
	for ( size_t i = 0; i < sizeof( arrays ) / sizeof( arrays[0] ); ++i )
	{
		sere_free( arrays[i] );
	}
}

/* (Re)allocates the arrays sized by the contact capacity; the old ones are kept on failure. */
static sere_status alloc_contacts( sere_collide* c, int32_t capacity )
{
	void** slot[CONTACT_ARRAYS];
	size_t size[CONTACT_ARRAYS];
	contact_arrays( c, slot, size );
	void* fresh[CONTACT_ARRAYS] = { NULL };
	bool ok = true;
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		fresh[i] = sere_alloc( size[i] * (size_t) sere_pad( capacity ) );
		ok = ok && fresh[i] != NULL;
	}
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		sere_free( ok ? *slot[i] : fresh[i] );
		*slot[i] = ok ? fresh[i] : *slot[i];
	}
	if ( !ok )
	{
		return SERE_ERR_MEMORY;
	}
	c->capacity = capacity;
	c->contact_count = 0;
	c->edge_contact_count = 0;
	c->touched_count = 0;
	return SERE_OK;
}

/* Builds the sorted neighbour lists of the mesh's edges (each edge appears in two triangles at
 * most, so a vertex has at most 2 × its triangle count neighbours before duplicates go). */
static void build_neighbors( sere_collide* c, const int32_t* tri, int32_t triangles, int32_t* offset,
							 int32_t* neighbor )
{
	int32_t n = c->vertex_count;
	memset( offset, 0, sizeof( int32_t ) * ( (size_t) n + 1 ) );
	for ( int32_t t = 0; t < triangles; ++t )
	{
		for ( int r = 0; r < 3; ++r )
		{
			offset[tri[3 * t + r] + 1] += 2;
		}
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		offset[i + 1] += offset[i];
	}
	/* fill each list, then sort it and drop repeats in place */
	int32_t* cursor = c->entry_cursor;
	for ( int32_t i = 0; i < n; ++i )
	{
		cursor[i] = offset[i];
	}
	for ( int32_t t = 0; t < triangles; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		for ( int r = 0; r < 3; ++r )
		{
			int32_t a = v[r];
			neighbor[cursor[a]++] = v[( r + 1 ) % 3];
			neighbor[cursor[a]++] = v[( r + 2 ) % 3];
		}
	}
	int32_t write = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t begin = offset[i], end = offset[i + 1];
		offset[i] = write;
		/* insertion sort: lists are a dozen entries long */
		for ( int32_t k = begin + 1; k < end; ++k )
		{
			int32_t value = neighbor[k], j = k;
			while ( j > begin && neighbor[j - 1] > value )
			{
				neighbor[j] = neighbor[j - 1];
				--j;
			}
			neighbor[j] = value;
		}
		for ( int32_t k = begin; k < end; ++k )
		{
			if ( write == offset[i] || neighbor[write - 1] != neighbor[k] )
			{
				neighbor[write++] = neighbor[k];
			}
		}
	}
	offset[n] = write;
}

/* Adds bits to vertex j's scratch marks, listing j at its first bit; returns the list's length. */
static int32_t list_mark( sere_collide* c, lane_bits* scratch, int32_t j, uint32_t bits, int32_t used )
{
	if ( scratch[j] == 0 )
	{
		c->mark_vertex[used++] = j;
	}
	scratch[j] = (lane_bits) ( scratch[j] | bits );
	return used;
}

/* The lane marks of every query group, from the neighbour lists (lane_bits). Listed once per
 * group, merged, the marks cost one plain store per vertex to set and one to clear; set from the
 * neighbour lists at every query, a vertex shared by several lanes took a read-modify-write per
 * lane, each waiting on the last. */
static bool build_marks( sere_collide* c, const int32_t* neighbor_offset, const int32_t* neighbor )
{
	int32_t n = c->vertex_count;
	int32_t groups = ( n + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
	c->mark_offset = sere_alloc( sizeof( int32_t ) * ( (size_t) groups + 1 ) );
	/* a group lists each of its vertices and their neighbours once at most: over all groups,
	 * n vertices and neighbor_offset[n] neighbour entries */
	size_t most = (size_t) n + (size_t) neighbor_offset[n] + 1;
	c->mark_vertex = sere_alloc( sizeof( int32_t ) * most );
	c->mark_bits = sere_alloc( sizeof( lane_bits ) * most );
	if ( c->mark_offset == NULL || c->mark_vertex == NULL || c->mark_bits == NULL )
	{
		return false;
	}
	/* thread 0's lane marks, zero, as scratch: zero again on return */
	lane_bits* scratch = c->lane_mark;
	int32_t used = 0;
	for ( int32_t g = 0; g < groups; ++g )
	{
		int32_t first = g * SERE_BVH_WIDTH, begin = used;
		int32_t count = n - first < SERE_BVH_WIDTH ? n - first : SERE_BVH_WIDTH;
		c->mark_offset[g] = begin;
		for ( int32_t k = 0; k < count; ++k )
		{
			int32_t i = first + k;
			uint32_t near = 1u << k;
			used = list_mark( c, scratch, i, near | near << 8, used );
			for ( int32_t e = neighbor_offset[i]; e < neighbor_offset[i + 1]; ++e )
			{
				used = list_mark( c, scratch, neighbor[e], near, used );
			}
		}
		for ( int32_t e = begin; e < used; ++e )
		{
			c->mark_bits[e] = scratch[c->mark_vertex[e]];
			scratch[c->mark_vertex[e]] = 0;
		}
	}
	c->mark_offset[groups] = used;
	return true;
}

/* The edge list and each triangle's owned edges (see sere_collide.edge_end) from the sorted
 * neighbour lists: vertex a's neighbours above a are the edges it is the lower end of, in order.
 * A triangle with a repeated corner owns no edge between the two (it has no length). */
static bool build_edges( sere_collide* c, const int32_t* tri, const int32_t* neighbor_offset, const int32_t* neighbor )
{
	int32_t n = c->vertex_count, triangles = c->triangle_count;
	int32_t* first = c->lower_edge = sere_alloc( sizeof( int32_t ) * ( (size_t) n + 1 ) );
	if ( first == NULL )
	{
		return false;
	}
	int32_t edges = 0;
	for ( int32_t a = 0; a < n; ++a )
	{
		first[a] = edges;
		for ( int32_t e = neighbor_offset[a]; e < neighbor_offset[a + 1]; ++e )
		{
			edges += neighbor[e] > a;
		}
	}
	first[n] = edges;
	c->edge_count = edges;
	c->edge_end = sere_alloc( sizeof( int32_t ) * ( 2 * (size_t) edges + 1 ) );
	c->owned = sere_alloc( sizeof( int32_t ) * ( 3 * (size_t) triangles + 1 ) );
	c->edge_triangle = sere_alloc( sizeof( int32_t ) * ( (size_t) edges + 1 ) );
	uint8_t* seen = sere_alloc( (size_t) edges + 1 );
	bool ok = c->edge_end != NULL && c->owned != NULL && c->edge_triangle != NULL && seen != NULL;
	for ( int32_t a = 0; ok && a < n; ++a )
	{
		int32_t e = first[a];
		for ( int32_t k = neighbor_offset[a]; k < neighbor_offset[a + 1]; ++k )
		{
			if ( neighbor[k] > a )
			{
				c->edge_end[2 * e] = a, c->edge_end[2 * e + 1] = neighbor[k];
				e += 1;
			}
		}
	}
	for ( int32_t t = 0; ok && t < triangles; ++t )
	{
		for ( int r = 0; r < 3; ++r )
		{
			int32_t i = tri[3 * t + r], j = tri[3 * t + ( r + 1 ) % 3];
			int32_t a = i < j ? i : j, b = i < j ? j : i;
			int32_t edge = -1;
			/* the neighbours above a are sorted: find b among them */
			for ( int32_t e = first[a]; a != b && e < first[a + 1] && edge < 0; ++e )
			{
				edge = c->edge_end[2 * e + 1] == b ? e : -1;
			}
			c->owned[3 * t + r] = edge >= 0 && !seen[edge] ? edge : -1;
			if ( edge >= 0 && !seen[edge] )
			{
				seen[edge] = 1;
				c->edge_triangle[edge] = t;
			}
		}
	}
	sere_free( seen );
	return ok;
}

/* Contacts of each kind stay below this: the gather lists index 4 entries per contact of both
 * kinds with int32_t. */
#define CAPACITY_LIMIT ( 1 << 28 )

sere_status sere_collide_create( const sere_bvh* bvh, int32_t contact_capacity, sere_collide** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( bvh == NULL || contact_capacity < 0 || contact_capacity >= CAPACITY_LIMIT )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t n = sere_bvh_vertex_count( bvh );
	int32_t triangles;
	const int32_t* tri = sere_bvh_triangles( bvh, &triangles );
	int64_t capacity = contact_capacity > 0 ? contact_capacity : 8 * (int64_t) n;
	capacity = capacity < CAPACITY_LIMIT - 1 ? capacity : CAPACITY_LIMIT - 1;
	sere_collide* c = sere_alloc( sizeof( sere_collide ) );
	if ( c == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	c->vertex_count = n;
	c->triangle_count = triangles;
	c->slots = omp_get_max_threads();
	size_t vn = (size_t) sere_pad( n );
	c->entry_offset = sere_alloc( sizeof( int32_t ) * ( vn + 1 ) );
	c->entry_cursor = sere_alloc( sizeof( int32_t ) * vn * (size_t) c->slots );
	c->run_total = sere_alloc( sizeof( int32_t ) * 2 * FAR_STRIDE * (size_t) c->slots );
	c->touched = sere_alloc( sizeof( int32_t ) * vn );
	c->position = sere_alloc( 4 * sizeof( float ) * vn );
	c->acc = sere_alloc( 4 * sizeof( float ) * vn );
	c->push_count = sere_alloc( sizeof( float ) * vn );
	c->far_count = sere_alloc( sizeof( int32_t ) * FAR_STRIDE * (size_t) c->slots );
	c->lane_mark = sere_alloc( sizeof( lane_bits ) * vn * (size_t) c->slots );
	bool ok = c->entry_offset && c->entry_cursor && c->run_total && c->touched && c->position && c->acc &&
			  c->push_count && c->far_count && c->lane_mark;
	/* the mesh's edges as sorted neighbour lists, needed only to list the edges and build the
	 * mark lists (thread 0's lane marks serve as scratch) */
	int32_t* neighbor_offset = sere_alloc( sizeof( int32_t ) * ( vn + 1 ) );
	int32_t* neighbor = sere_alloc( sizeof( int32_t ) * ( 6 * (size_t) triangles + 1 ) );
	ok = ok && neighbor_offset && neighbor;
	if ( ok )
	{
		build_neighbors( c, tri, triangles, neighbor_offset, neighbor );
		ok = build_edges( c, tri, neighbor_offset, neighbor ) && build_marks( c, neighbor_offset, neighbor );
	}
	sere_free( neighbor_offset );
	sere_free( neighbor );
	c->vertex_blocks = ( n + DETECT_BLOCK - 1 ) / DETECT_BLOCK;
	c->block_count = 2 * c->vertex_blocks;
	size_t blocks = (size_t) c->block_count + 1;
	c->block_thread = sere_alloc( sizeof( int32_t ) * blocks );
	c->block_start = sere_alloc( sizeof( int32_t ) * blocks );
	c->block_found = sere_alloc( sizeof( int64_t ) * blocks );
	c->block_work = sere_alloc( sizeof( int64_t ) * blocks );
	c->work_prefix = sere_alloc( sizeof( int64_t ) * blocks );
	ok = ok && c->block_thread && c->block_start && c->block_found && c->block_work && c->work_prefix;
	c->cache_valid = false;
	c->skin = SKIN;
	c->edge_across = sere_alloc( 3 * sizeof( float ) * (size_t) sere_pad( c->edge_count > 0 ? c->edge_count : 1 ) );
	c->cache_capacity = CACHE_PAIRS * n + DETECT_BLOCK;
	size_t listed = (size_t) c->cache_capacity * (size_t) c->slots;
	c->cache_x = sere_alloc( sizeof( float ) * vn );
	c->cache_y = sere_alloc( sizeof( float ) * vn );
	c->cache_z = sere_alloc( sizeof( float ) * vn );
	c->cache_item = sere_alloc( sizeof( int32_t ) * listed );
	c->cache_target = sere_alloc( sizeof( int32_t ) * listed );
	c->cache_near = sere_alloc( listed );
	c->cache_block_thread = sere_alloc( sizeof( int32_t ) * blocks );
	c->cache_block_start = sere_alloc( sizeof( int32_t ) * blocks );
	c->cache_block_count = sere_alloc( sizeof( int32_t ) * blocks );
	c->cache_used = sere_alloc( sizeof( int32_t ) * FAR_STRIDE * (size_t) c->slots );
	ok = ok && c->cache_x && c->cache_y && c->cache_z && c->cache_item && c->cache_target && c->cache_near &&
		 c->cache_block_thread && c->cache_block_start && c->cache_block_count && c->cache_used && c->edge_across;
	if ( !ok || alloc_contacts( c, (int32_t) capacity ) != SERE_OK )
	{
		collide_free( c );
		sere_free( c );
		return SERE_ERR_MEMORY;
	}
	*out = c;
	return SERE_OK;
}

void sere_collide_destroy( sere_collide* collide )
{
	if ( collide == NULL )
	{
		return;
	}
	collide_free( collide );
	sere_free( collide );
}

sere_status sere_collide_reserve( sere_collide* collide, int32_t contact_capacity )
{
	if ( collide == NULL || contact_capacity < 1 || contact_capacity >= CAPACITY_LIMIT )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( contact_capacity <= collide->capacity )
	{
		return SERE_OK;
	}
	return alloc_contacts( collide, contact_capacity );
}

int32_t sere_collide_list_uses( const sere_collide* collide )
{
	return collide->cache_uses;
}

void sere_collide_drop_list( sere_collide* collide )
{
	collide->cache_valid = false;
	collide->cache_uses = 0;
}

const sere_contact* sere_collide_contacts( const sere_collide* collide, int32_t* count )
{
	*count = collide->contact_count;
	return collide->contacts;
}

const sere_edge_contact* sere_collide_edge_contacts( const sere_collide* collide, int32_t* count )
{
	*count = collide->edge_contact_count;
	return collide->edge_contacts;
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
	const int32_t *mark_offset, *mark_vertex;					  /* sere_collide's group mark lists */
	const lane_bits* mark_bits;
	lane_bits* mark; /* the calling thread's lane marks (sere_collide.lane_mark) */
	int32_t first;	 /* the vertex of lane 0 */
	/* An edge group's table: its lanes' edges, side by side for vector tests: their boxes grown
	 * by the lane's cull radius, their lower end's position and a unit vector across them (in the
	 * plane of their first triangle; zero when that is degenerate), the lane's cull radius, their
	 * ends and index. Lane k's rows start at table_lane[k]. */
	int32_t table_count;
	int32_t table_lane[SERE_BVH_WIDTH + 1];
	float table_lo[3][GROUP_EDGES], table_hi[3][GROUP_EDGES];
	float table_at[3][GROUP_EDGES], table_across[3][GROUP_EDGES], table_margin[GROUP_EDGES];
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
	int32_t list_used, list_capacity;
	const float* across[3]; /* sere_collide.edge_across's rows */
} detect_context;

/* closest_point for CLOSEST_LANES point–triangle pairs at once, as selects instead of branches:
 * every region's result is formed by the same operations as in closest_point and the first
 * region whose test holds is kept, so each lane gets closest_point's bits. A lane that reaches
 * the degenerate fallback is flagged in slow (its outputs are not meaningful) for the caller to
 * redo with closest_point. Rows are x, y, z; columns are lanes. (The inputs are read only; they
 * are not const because C17 does not convert float[3][8] to const float[3][8].) */
static void closest_lanes( float p[3][CLOSEST_LANES], float a[3][CLOSEST_LANES], float b[3][CLOSEST_LANES],
						   float c[3][CLOSEST_LANES], float w[3][CLOSEST_LANES], float q[3][CLOSEST_LANES],
						   float d2[CLOSEST_LANES], int32_t slow[CLOSEST_LANES] )
{
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float ab[3], ac[3], bc[3], ap[3], bp[3], cp[3];
		for ( int r = 0; r < 3; ++r )
		{
			ab[r] = b[r][l] - a[r][l], ac[r] = c[r][l] - a[r][l], bc[r] = c[r][l] - b[r][l];
			ap[r] = p[r][l] - a[r][l], bp[r] = p[r][l] - b[r][l], cp[r] = p[r][l] - c[r][l];
		}
		float d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2];
		float d2a = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
		float d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2];
		float d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
		float d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2];
		float d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
		float vc = d1 * d4 - d3 * d2a;
		float vb = d5 * d2a - d1 * d6;
		float va = d3 * d6 - d5 * d4;
		float sum = va + vb + vc;

		/* the regions in closest_point's order, each only if none before it holds (& and |, not
		 * && and ||: no branches, so the loop vectorizes) */
		int at_a = ( d1 <= 0.0f ) & ( d2a <= 0.0f );
		int at_b = !at_a & ( d3 >= 0.0f ) & ( d4 <= d3 );
		int at_c = !at_a & !at_b & ( d6 >= 0.0f ) & ( d5 <= d6 );
		int vertex = at_a | at_b | at_c;
		int on_ab = !vertex & ( vc <= 0.0f ) & ( d1 >= 0.0f ) & ( d3 <= 0.0f ) & ( d1 - d3 > 0.0f );
		int on_ac = !vertex & !on_ab & ( vb <= 0.0f ) & ( d2a >= 0.0f ) & ( d6 <= 0.0f ) & ( d2a - d6 > 0.0f );
		int on_bc = !vertex & !on_ab & !on_ac & ( va <= 0.0f ) & ( d4 - d3 >= 0.0f ) & ( d5 - d6 >= 0.0f ) &
					( ( d4 - d3 ) + ( d5 - d6 ) > 0.0f );
		int edge = on_ab | on_ac | on_bc;
		float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
		float ac2 = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
		int face =
			!vertex & !edge & ( vb >= 0.0f ) & ( vc >= 0.0f ) & ( vb + vc <= sum ) & ( sum > 0x1p-20f * ab2 * ac2 );

		float s_ab = d1 / ( d1 - d3 );
		float s_ac = d2a / ( d2a - d6 );
		float s_bc = ( d4 - d3 ) / ( ( d4 - d3 ) + ( d5 - d6 ) );
		float v_face = vb / sum, t_face = vc / sum;
		float u = at_a ? 1.0f : ( on_ab ? 1.0f - s_ab : ( on_ac ? 1.0f - s_ac : 0.0f ) );
		float v = at_b ? 1.0f : ( on_ab ? s_ab : ( on_bc ? 1.0f - s_bc : 0.0f ) );
		float t = at_c ? 1.0f : ( on_ac ? s_ac : ( on_bc ? s_bc : 0.0f ) );
		u = face ? 1.0f - v_face - t_face : u;
		v = face ? v_face : v;
		t = face ? t_face : t;
		float dist2 = 0.0f;
		for ( int r = 0; r < 3; ++r )
		{
			float point = at_a ? a[r][l] : ( at_b ? b[r][l] : c[r][l] );
			point = on_ab ? a[r][l] + s_ab * ab[r] : point;
			point = on_ac ? a[r][l] + s_ac * ac[r] : point;
			point = on_bc ? b[r][l] + s_bc * bc[r] : point;
			point = face ? a[r][l] + v_face * ab[r] + t_face * ac[r] : point;
			q[r][l] = point;
			float d = p[r][l] - point;
			dist2 += d * d;
		}
		w[0][l] = u, w[1][l] = v, w[2][l] = t;
		d2[l] = dist2;
		slow[l] = !( vertex || edge || face );
	}
}

_Static_assert( SERE_BVH_WIDTH <= 8, "a group's lane marks are two bytes per vertex" );

_Static_assert( DETECT_BLOCK % SERE_BVH_WIDTH == 0, "query groups start at multiples of the width" );

/* Sets (set) or clears the lane marks of the group whose lane 0 is vertex c->first (lane_bits):
 * a triangle with a lane's vertex as a corner is not a contact candidate for the lane, one with a
 * neighbour of it only with the closest point inside its face. */
static void mark_lanes( detect_context* c, bool set )
{
	int32_t g = c->first / SERE_BVH_WIDTH;
	for ( int32_t e = c->mark_offset[g]; e < c->mark_offset[g + 1]; ++e )
	{
		c->mark[c->mark_vertex[e]] = set ? c->mark_bits[e] : 0;
	}
}

/* Appends the contact of a vertex–triangle pair found within the thickness. */
static void detect_emit( detect_context* c, int32_t vertex, int32_t t, const float p[3], const float a[3],
						 const float b[3], const float cc[3], const float w[3], const float q[3], float d2 )
{
	c->found += 1;
	if ( c->used < c->capacity )
	{
		float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		float ac[3] = { cc[0] - a[0], cc[1] - a[1], cc[2] - a[2] };
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float s = ( p[0] - q[0] ) * n[0] + ( p[1] - q[1] ) * n[1] + ( p[2] - q[2] ) * n[2];
		c->buffer[c->used++] = ( sere_contact ){ vertex, t, w[0], w[1], w[2], sqrtf( d2 ), s < 0.0f ? -1.0f : 1.0f };
	}
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

/* For CLOSEST_LANES point–triangle pairs: bit l set unless separating directions put the point
 * farther than list_radius from the triangle. With n̂ the unit normal, |p − x|² = ((p − x) · n̂)²
 * + |p' − x|² for x in the triangle and p' the projection of p onto its plane; the first term is
 * ((p − a) · n̂)² exactly, and the in-plane distance is bounded by the gaps (interval_gap) on the
 * in-plane directions: each edge's outward normal (edge × n̂) and each edge's direction, the
 * latter bounding the corner regions within cos 30° on a triangle of 60° angles. A triangle whose
 * sin² of the corner angle is below 2⁻²⁰ (closest_lanes' degenerate case) is always kept. */
static uint32_t bound_lanes( const detect_context* c, float p[3][CLOSEST_LANES], float a[3][CLOSEST_LANES],
							 float b[3][CLOSEST_LANES], float cc[3][CLOSEST_LANES] )
{
	int32_t keep[CLOSEST_LANES];
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float ab[3], ac[3], bc[3], ap[3];
		for ( int r = 0; r < 3; ++r )
		{
			ab[r] = b[r][l] - a[r][l], ac[r] = cc[r][l] - a[r][l], bc[r] = cc[r][l] - b[r][l];
			ap[r] = p[r][l] - a[r][l];
		}
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
		float ac2 = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
		int degenerate = !( nn > 0x1p-20f * ab2 * ac2 );
		float inv = 1.0f / sqrtf( degenerate ? 1.0f : nn );
		float u[3] = { n[0] * inv, n[1] * inv, n[2] * inv };
		float plane = ap[0] * u[0] + ap[1] * u[1] + ap[2] * u[2];
		/* in-plane directions: edges ab, bc, ca, and their outward normals edge × n̂; corners
		 * relative to a */
		float d[6][3];
		const float* edge[3] = { ab, bc, ac };
		for ( int k = 0; k < 3; ++k )
		{
			const float* e = edge[k];
			float m[3] = { e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0] };
			float ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2], mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
			float ie = 1.0f / sqrtf( ee > 0.0f ? ee : 1.0f ), im = 1.0f / sqrtf( mm > 0.0f ? mm : 1.0f );
			for ( int r = 0; r < 3; ++r )
			{
				d[k][r] = e[r] * ie, d[3 + k][r] = m[r] * im;
			}
		}
		float inplane = 0.0f;
		for ( int k = 0; k < 6; ++k )
		{
			float pb = ab[0] * d[k][0] + ab[1] * d[k][1] + ab[2] * d[k][2];
			float pc = ac[0] * d[k][0] + ac[1] * d[k][1] + ac[2] * d[k][2];
			float pp = ap[0] * d[k][0] + ap[1] * d[k][1] + ap[2] * d[k][2];
			float lo = pb < pc ? pb : pc, hi = pb < pc ? pc : pb;
			lo = lo < 0.0f ? lo : 0.0f, hi = hi > 0.0f ? hi : 0.0f;
			float gap = interval_gap( pp, pp, lo, hi );
			inplane = gap > inplane ? gap : inplane;
		}
		float far[3] = { fabsf( p[0][l] ), fabsf( p[1][l] ), fabsf( p[2][l] ) };
		for ( int r = 0; r < 3; ++r )
		{
			float m = fabsf( a[r][l] ) > fabsf( b[r][l] ) ? fabsf( a[r][l] ) : fabsf( b[r][l] );
			m = m > fabsf( cc[r][l] ) ? m : fabsf( cc[r][l] );
			far[r] = far[r] > m ? far[r] : m;
		}
		float radius = list_radius( c, far );
		keep[l] = degenerate | !( plane * plane + inplane * inplane >= radius * radius );
	}
	uint32_t mask = 0;
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		mask |= (uint32_t) ( keep[l] != 0 ) << l;
	}
	return mask;
}

/* For CLOSEST_LANES segment pairs: bit l set unless separating directions put the segments
 * farther apart than list_radius: their common normal (e × f normalized, where they are not
 * parallel to within sin² 2⁻²⁰), each one's direction and the unit vector across each one in the
 * plane of its first triangle (the table's across for e, recomputed for f). */
static uint32_t edge_bound_lanes( const detect_context* c, const int32_t* item, const int32_t* target,
								  float a0[3][CLOSEST_LANES], float a1[3][CLOSEST_LANES], float b0[3][CLOSEST_LANES],
								  float b1[3][CLOSEST_LANES] )
{
	float across[2][3][CLOSEST_LANES];
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		for ( int r = 0; r < 3; ++r )
		{
			across[0][r][l] = c->across[r][item[l]], across[1][r][l] = c->across[r][target[l]];
		}
	}
	int32_t keep[CLOSEST_LANES];
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float u[3], v[3], w1[3], w0[3], w2[3];
		for ( int r = 0; r < 3; ++r )
		{
			u[r] = a1[r][l] - a0[r][l], v[r] = b1[r][l] - b0[r][l];
			w0[r] = b0[r][l] - a0[r][l], w1[r] = b1[r][l] - a0[r][l], w2[r] = u[r];
		}
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
		int skew = nn > 0x1p-20f * uu * vv;
		float in = skew ? 1.0f / sqrtf( nn ) : 0.0f;
		float iu = uu > 0.0f ? 1.0f / sqrtf( uu ) : 0.0f, iv = vv > 0.0f ? 1.0f / sqrtf( vv ) : 0.0f;
		float d[5][3];
		for ( int r = 0; r < 3; ++r )
		{
			d[0][r] = n[r] * in, d[1][r] = u[r] * iu, d[2][r] = v[r] * iv;
			d[3][r] = across[0][r][l], d[4][r] = across[1][r][l];
		}
		float bound = 0.0f;
		for ( int k = 0; k < 5; ++k )
		{
			/* e's ends a0, a1 and f's b0, b1, relative to a0 */
			float pa = w2[0] * d[k][0] + w2[1] * d[k][1] + w2[2] * d[k][2];
			float q0 = w0[0] * d[k][0] + w0[1] * d[k][1] + w0[2] * d[k][2];
			float q1 = w1[0] * d[k][0] + w1[1] * d[k][1] + w1[2] * d[k][2];
			float gap =
				interval_gap( pa < 0.0f ? pa : 0.0f, pa > 0.0f ? pa : 0.0f, q0 < q1 ? q0 : q1, q0 < q1 ? q1 : q0 );
			bound = gap > bound ? gap : bound;
		}
		float far[3];
		for ( int r = 0; r < 3; ++r )
		{
			float m0 = fabsf( a0[r][l] ) > fabsf( a1[r][l] ) ? fabsf( a0[r][l] ) : fabsf( a1[r][l] );
			float m1 = fabsf( b0[r][l] ) > fabsf( b1[r][l] ) ? fabsf( b0[r][l] ) : fabsf( b1[r][l] );
			far[r] = m0 > m1 ? m0 : m1;
		}
		keep[l] = !( bound >= list_radius( c, far ) );
	}
	uint32_t mask = 0;
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		mask |= (uint32_t) ( keep[l] != 0 ) << l;
	}
	return mask;
}

/* Gathers the points of buffered vertex–triangle pairs start .. start + CLOSEST_LANES − 1 (lanes
 * past the end repeat the last pair). */
static void gather_pairs( const detect_context* c, int32_t start, int32_t count, float p[3][CLOSEST_LANES],
						  float a[3][CLOSEST_LANES], float b[3][CLOSEST_LANES], float cc[3][CLOSEST_LANES] )
{
	for ( int32_t l = 0; l < CLOSEST_LANES; ++l )
	{
		int32_t k = start + ( l < count ? l : count - 1 );
		int32_t vertex = c->pair_item[k];
		const int32_t* v = c->tri + 3 * (size_t) c->pair_target[k];
		p[0][l] = c->x[vertex], p[1][l] = c->y[vertex], p[2][l] = c->z[vertex];
		a[0][l] = c->x[v[0]], a[1][l] = c->y[v[0]], a[2][l] = c->z[v[0]];
		b[0][l] = c->x[v[1]], b[1][l] = c->y[v[1]], b[2][l] = c->z[v[1]];
		cc[0][l] = c->x[v[2]], cc[1][l] = c->y[v[2]], cc[2][l] = c->z[v[2]];
	}
}

/* Listing: keeps in the pair buffer (in order) only the pairs bound_lanes keeps and lists them;
 * the others cannot be contacts now either (the bound is below the distance, the radius above
 * the thickness). */
static void list_vertex_pairs( detect_context* c )
{
	int32_t kept = 0;
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float p[3][CLOSEST_LANES], a[3][CLOSEST_LANES], b[3][CLOSEST_LANES], cc[3][CLOSEST_LANES];
		gather_pairs( c, start, count, p, a, b, cc );
		uint32_t keep = bound_lanes( c, p, a, b, cc ) & ( ( 1u << count ) - 1u );
		while ( keep != 0 )
		{
			int32_t k = start + __builtin_ctz( keep );
			keep &= keep - 1;
			c->pair_item[kept] = c->pair_item[k];
			c->pair_target[kept] = c->pair_target[k];
			c->pair_near[kept] = c->pair_near[k];
			list_pair( c, kept );
			kept += 1;
		}
	}
	c->pair_count = kept;
}

/* The exact test of the buffered pairs, CLOSEST_LANES at a time, in the order they were
 * buffered (the tree's, then the lanes'), so the contact list does not depend on the batching. */
static void detect_flush( detect_context* c )
{
	if ( c->listing )
	{
		list_vertex_pairs( c );
	}
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float p[3][CLOSEST_LANES], a[3][CLOSEST_LANES], b[3][CLOSEST_LANES], cc[3][CLOSEST_LANES];
		float w[3][CLOSEST_LANES], q[3][CLOSEST_LANES], d2[CLOSEST_LANES];
		int32_t slow[CLOSEST_LANES];
		/* lanes past the end repeat the last pair and are ignored */
		gather_pairs( c, start, count, p, a, b, cc );
		closest_lanes( p, a, b, cc, w, q, d2, slow );
		uint32_t candidates = 0;
		for ( int32_t l = 0; l < count; ++l )
		{
			candidates |= (uint32_t) ( slow[l] | ( d2[l] < c->h2 ) ) << l;
		}
		while ( candidates != 0 )
		{
			int32_t l = __builtin_ctz( candidates );
			candidates &= candidates - 1;
			float pl[3] = { p[0][l], p[1][l], p[2][l] }, al[3] = { a[0][l], a[1][l], a[2][l] };
			float bl[3] = { b[0][l], b[1][l], b[2][l] }, cl[3] = { cc[0][l], cc[1][l], cc[2][l] };
			float wl[3] = { w[0][l], w[1][l], w[2][l] }, ql[3] = { q[0][l], q[1][l], q[2][l] };
			float dl = slow[l] ? closest_point( pl, al, bl, cl, wl, ql ) : d2[l];
			bool face = wl[0] > 0.0f && wl[1] > 0.0f && wl[2] > 0.0f;
			if ( dl < c->h2 && ( face || !c->pair_near[start + l] ) )
			{
				detect_emit( c, c->pair_item[start + l], c->pair_target[start + l], pl, al, bl, cl, wl, ql, dl );
			}
		}
	}
	c->pair_count = 0;
}

/* Buffers the pairs of one triangle with every group vertex whose cube overlaps its box but the
 * triangle's own corners (the lane marks), flagging the vertices joined by a mesh edge to a
 * corner: such a vertex lies in the sheet right beside the triangle, and where edges are shorter
 * than the thickness (fine outline and vein sampling, a shrunk blade) it is closer than the
 * thickness without any collision, its closest point on an edge or corner, and a push along the
 * normal would only buckle the sheet. It is a contact only when its closest point lies inside
 * the face, which takes a fold of the sheet past a right angle within one ring: the two
 * triangles of an edge closing on each other like a book, which unchecked let the vertex pass
 * through (on the maple at 800 points, at its base). */
static void detect_visit( void* context, int32_t t, uint32_t lanes )
{
	detect_context* c = context;
	const int32_t* v = c->tri + 3 * (size_t) t;
	lane_bits m = (lane_bits) ( c->mark[v[0]] | c->mark[v[1]] | c->mark[v[2]] );
	lanes &= ~self_lanes( m );
	uint32_t near = near_lanes( m );

	while ( lanes != 0 )
	{
		if ( c->pair_count == PAIR_BUFFER )
		{
			detect_flush( c );
		}
		int32_t k = __builtin_ctz( lanes );
		c->pair_target[c->pair_count] = t;
		c->pair_item[c->pair_count] = c->first + k;
		c->pair_near[c->pair_count] = (uint8_t) ( near >> k & 1u );
		c->pair_count += 1;
		lanes &= lanes - 1;
	}
}

/* closest_segments for CLOSEST_LANES segment pairs at once, as selects instead of branches: each
 * lane's result is formed by the same operations as in closest_segments, so it gets the same
 * bits (a zero-length or parallel lane computes quotients it then does not select). Rows are x,
 * y, z; columns are lanes. */
static void closest_segments_lanes( float p0[3][CLOSEST_LANES], float p1[3][CLOSEST_LANES], float q0[3][CLOSEST_LANES],
									float q1[3][CLOSEST_LANES], float w[2][CLOSEST_LANES], float d2[CLOSEST_LANES] )
{
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float d1[3], dd[3], r[3];
		for ( int k = 0; k < 3; ++k )
		{
			d1[k] = p1[k][l] - p0[k][l], dd[k] = q1[k][l] - q0[k][l], r[k] = p0[k][l] - q0[k][l];
		}
		float a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
		float e = dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2];
		float b = d1[0] * dd[0] + d1[1] * dd[1] + d1[2] * dd[2];
		float c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2];
		float f = dd[0] * r[0] + dd[1] * r[1] + dd[2] * r[2];
		float denom = a * e - b * b;
		float s = denom > 0x1p-20f * a * e ? clamp_unit( ( b * f - c * e ) / denom ) : 0.0f;
		float t = ( b * s + f ) / e;
		int low = !( e > 0.0f ) | ( t < 0.0f ), high = !low & ( t > 1.0f );
		float s_low = a > 0.0f ? clamp_unit( -c / a ) : 0.0f;
		float s_high = a > 0.0f ? clamp_unit( ( b - c ) / a ) : 0.0f;
		s = low ? s_low : ( high ? s_high : s );
		t = low ? 0.0f : ( high ? 1.0f : t );
		float dist2 = 0.0f;
		for ( int k = 0; k < 3; ++k )
		{
			float d = r[k] + s * d1[k] - t * dd[k];
			dist2 += d * d;
		}
		w[0][l] = s, w[1][l] = t;
		d2[l] = dist2;
	}
}

/* Appends the contact of edges e and f (e < f), closer than the thickness with both closest
 * points inside. */
static void detect_edge_emit( detect_context* c, int32_t e, int32_t f, const float a0[3], const float a1[3],
							  const float b0[3], const float b1[3] )
{
	c->edge_found += 1;
	if ( c->edge_used < c->capacity )
	{
		float w[2], d[3];
		float d2 = closest_segments( a0, a1, b0, b1, w, d );
		float u[3] = { a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2] };
		float v[3] = { b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2] };
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float side = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
		c->edge_buffer[c->edge_used++] = ( sere_edge_contact ){
			c->edge_end[2 * e], c->edge_end[2 * e + 1],		c->edge_end[2 * f], c->edge_end[2 * f + 1], w[0], w[1],
			sqrtf( d2 ),		side < 0.0f ? -1.0f : 1.0f,
		};
	}
}

/* Gathers the ends of buffered edge pairs start .. start + CLOSEST_LANES − 1 (lanes past the end
 * repeat the last pair). */
static void gather_edge_pairs( const detect_context* c, int32_t start, int32_t count, float a0[3][CLOSEST_LANES],
							   float a1[3][CLOSEST_LANES], float b0[3][CLOSEST_LANES], float b1[3][CLOSEST_LANES] )
{
	for ( int32_t l = 0; l < CLOSEST_LANES; ++l )
	{
		int32_t k = start + ( l < count ? l : count - 1 );
		const int32_t* e = c->edge_end + 2 * (size_t) c->pair_item[k];
		const int32_t* f = c->edge_end + 2 * (size_t) c->pair_target[k];
		a0[0][l] = c->x[e[0]], a0[1][l] = c->y[e[0]], a0[2][l] = c->z[e[0]];
		a1[0][l] = c->x[e[1]], a1[1][l] = c->y[e[1]], a1[2][l] = c->z[e[1]];
		b0[0][l] = c->x[f[0]], b0[1][l] = c->y[f[0]], b0[2][l] = c->z[f[0]];
		b1[0][l] = c->x[f[1]], b1[1][l] = c->y[f[1]], b1[2][l] = c->z[f[1]];
	}
}

/* Listing: keeps in the pair buffer (in order) only the edge pairs edge_bound_lanes keeps and
 * lists them, as list_vertex_pairs. */
static void list_edge_pairs( detect_context* c )
{
	int32_t kept = 0;
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float a0[3][CLOSEST_LANES], a1[3][CLOSEST_LANES], b0[3][CLOSEST_LANES], b1[3][CLOSEST_LANES];
		gather_edge_pairs( c, start, count, a0, a1, b0, b1 );
		int32_t item[CLOSEST_LANES], target[CLOSEST_LANES];
		for ( int32_t l = 0; l < CLOSEST_LANES; ++l )
		{
			int32_t k = start + ( l < count ? l : count - 1 );
			item[l] = c->pair_item[k], target[l] = c->pair_target[k];
		}
		uint32_t keep = edge_bound_lanes( c, item, target, a0, a1, b0, b1 ) & ( ( 1u << count ) - 1u );
		while ( keep != 0 )
		{
			int32_t k = start + __builtin_ctz( keep );
			keep &= keep - 1;
			c->pair_item[kept] = c->pair_item[k];
			c->pair_target[kept] = c->pair_target[k];
			c->pair_near[kept] = 0;
			list_pair( c, kept );
			kept += 1;
		}
	}
	c->pair_count = kept;
}

/* The exact test of the buffered edge pairs, CLOSEST_LANES at a time, in the order they were
 * buffered. A pair is a contact when it is closer than the thickness and both closest points
 * lie strictly inside their edges: where one is an end, that vertex is within the thickness of
 * the other edge's triangles, a vertex–triangle pair. */
static void detect_edge_flush( detect_context* c )
{
	if ( c->listing )
	{
		list_edge_pairs( c );
	}
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float a0[3][CLOSEST_LANES], a1[3][CLOSEST_LANES], b0[3][CLOSEST_LANES], b1[3][CLOSEST_LANES];
		float w[2][CLOSEST_LANES], d2[CLOSEST_LANES];
		/* lanes past the end repeat the last pair and are ignored */
		gather_edge_pairs( c, start, count, a0, a1, b0, b1 );
		closest_segments_lanes( a0, a1, b0, b1, w, d2 );
		uint32_t hits = 0;
		for ( int32_t l = 0; l < count; ++l )
		{
			int inside = ( w[0][l] > 0.0f ) & ( w[0][l] < 1.0f ) & ( w[1][l] > 0.0f ) & ( w[1][l] < 1.0f );
			hits |= (uint32_t) ( inside & ( d2[l] < c->h2 ) ) << l;
		}
		while ( hits != 0 )
		{
			int32_t l = __builtin_ctz( hits );
			hits &= hits - 1;
			float p0[3] = { a0[0][l], a0[1][l], a0[2][l] }, p1[3] = { a1[0][l], a1[1][l], a1[2][l] };
			float q0[3] = { b0[0][l], b0[1][l], b0[2][l] }, q1[3] = { b1[0][l], b1[1][l], b1[2][l] };
			detect_edge_emit( c, c->pair_item[start + l], c->pair_target[start + l], p0, p1, q0, q1 );
		}
	}
	c->pair_count = 0;
}

/* Bit l set when row j = from + l of the table (8 rows) is a candidate for edge f = (f0, f1) with
 * ends p, q and box lo, hi: the row's edge comes before f (its lower end is below f0: each pair is
 * tested once), shares no end with it, has its grown box overlapping f's, and f does not lie
 * beyond the row's margin on one side of the plane through the row's edge across it: where a
 * flat sheet puts the edges beside it, which boxes alone let through (on the flat Table 1 maple
 * this plane takes the pairs left by the boxes from 23 thousand to 10). */
static inline uint32_t table_hits( const detect_context* c, int32_t from, const float lo[3], const float hi[3],
								   const float p[3], const float q[3], int32_t f0, int32_t f1 )
{
	sere_m8 hit = sere_m8_all();
	sere_v8 sp = sere_v8_zero(), sq = sere_v8_zero();
	for ( int a = 0; a < 3; ++a )
	{
		hit = sere_m8_and( hit, sere_v8_le( sere_v8_splat( lo[a] ), sere_v8_load( c->table_hi[a] + from ) ) );
		hit = sere_m8_and( hit, sere_v8_ge( sere_v8_splat( hi[a] ), sere_v8_load( c->table_lo[a] + from ) ) );
		sere_v8 at = sere_v8_load( c->table_at[a] + from ), across = sere_v8_load( c->table_across[a] + from );
		sp = sere_v8_add( sp, sere_v8_mul( sere_v8_sub( sere_v8_splat( p[a] ), at ), across ) );
		sq = sere_v8_add( sq, sere_v8_mul( sere_v8_sub( sere_v8_splat( q[a] ), at ), across ) );
	}
	sere_v8 margin = sere_v8_load( c->table_margin + from );
	sere_v8 low = sere_v8_sub( sere_v8_zero(), margin );
	sere_m8 beyond = sere_m8_or( sere_m8_and( sere_v8_gt( sp, margin ), sere_v8_gt( sq, margin ) ),
								 sere_m8_and( sere_v8_lt( sp, low ), sere_v8_lt( sq, low ) ) );
	sere_m8 skip = sere_m8_or( sere_i8_eq( c->table_upper + from, f0 ), sere_i8_eq( c->table_upper + from, f1 ) );
	skip = sere_m8_or( skip, sere_i8_gt( c->table_lower + from, f0 - 1 ) );
	return sere_m8_bits( sere_m8_and_not( hit, sere_m8_or( beyond, skip ) ) );
}

/* Tests the buffered candidate edges f against the rows of the lanes whose box overlaps their
 * triangle's (table_hits) and buffers the pairs that pass for the exact test. */
static void detect_edge_candidates( detect_context* c )
{
	for ( int32_t k = 0; k < c->candidate_count; ++k )
	{
		int32_t f = c->candidate_edge[k];
		uint32_t lanes = c->candidate_lanes[k];
		int32_t f0 = c->edge_end[2 * f], f1 = c->edge_end[2 * f + 1];
		float p[3], q[3], lo[3], hi[3];
		load3( c->x, c->y, c->z, f0, p );
		load3( c->x, c->y, c->z, f1, q );
		for ( int a = 0; a < 3; ++a )
		{
			lo[a] = p[a] < q[a] ? p[a] : q[a];
			hi[a] = p[a] < q[a] ? q[a] : p[a];
		}
		int32_t rows = c->table_lane[32 - __builtin_clz( lanes )];
		for ( int32_t from = c->table_lane[__builtin_ctz( lanes )]; from < rows; from += 8 )
		{
			uint32_t hits = table_hits( c, from, lo, hi, p, q, f0, f1 );
			hits &= rows - from >= 8 ? 0xffu : ( 1u << ( rows - from ) ) - 1;
			while ( hits != 0 )
			{
				int32_t j = from + __builtin_ctz( hits );
				hits &= hits - 1;
				if ( c->pair_count == PAIR_BUFFER )
				{
					detect_edge_flush( c );
				}
				c->pair_item[c->pair_count] = c->table_edge[j];
				c->pair_target[c->pair_count] = f;
				c->pair_count += 1;
			}
		}
	}
	c->candidate_count = 0;
}

/* Buffers the edges f triangle t owns that may pair with an edge of the group (their lower end is
 * above the group's lowest lane vertex), with the group's lanes whose box overlaps t's, for
 * detect_edge_candidates. A pair is any two edges sharing no end: unlike a vertex and the
 * triangles beside it (detect_visit), edges a ring or two apart are not excluded. Two edges of a
 * smooth sheet have their closest points at an end, and only where the sheet folds back on
 * itself do both fall inside, closer than the thickness; there the fold must be held open. On
 * the maple at 1500 points a folding tip let two edges joined through one mesh edge pass through
 * each other, and no rule excluding neighbours' edges kept the six drying runs of the tests free
 * of crossings. */
static void detect_edge_visit( void* context, int32_t t, uint32_t lanes )
{
	detect_context* c = context;
	if ( c->candidate_count > CANDIDATES - 3 )
	{
		detect_edge_candidates( c );
	}
	const int32_t* owned = c->owned + 3 * (size_t) t;
	/* without branches: which owned edges pass is as good as random */
	for ( int r = 0; r < 3; ++r )
	{
		int32_t f = owned[r];
		int32_t f0 = c->edge_end[2 * ( f < 0 ? 0 : f )];
		c->candidate_edge[c->candidate_count] = f;
		c->candidate_lanes[c->candidate_count] = (uint8_t) lanes;
		c->candidate_count += ( f >= 0 ) & ( f0 > c->first );
	}
}

/* The first block of run `part` of `parts`: runs of about equal work by the previous detection
 * (work_prefix), or of equal block counts before any. */
static int32_t run_begin( const sere_collide* c, int part, int parts )
{
	if ( part >= parts )
	{
		return c->block_count;
	}
	int64_t total = c->work_prefix[c->block_count];
	if ( total == 0 )
	{
		return (int32_t) ( (int64_t) c->block_count * part / parts );
	}
	int64_t target = total * part / parts;
	int32_t lo = 0, hi = c->block_count;
	while ( lo < hi )
	{
		int32_t mid = lo + ( hi - lo ) / 2;
		if ( c->work_prefix[mid] < target )
		{
			lo = mid + 1;
		}
		else
		{
			hi = mid;
		}
	}
	return lo;
}

/* Lists the contacts found (total vertex–triangle ones, then edge_total edge–edge ones): copies
 * each block's contacts from its thread's buffer to the block's place in its list (thread 0's
 * vertex–triangle contacts are there already), with the per-contact arrays of the response, and
 * builds the per-vertex gather lists by a stable counting sort, in one parallel region. Each
 * thread counts the entries of its own (static, contiguous) share of blocks per vertex; then,
 * over its run of vertices, turns the counts of every thread into where each thread's entries of
 * each vertex begin, thread by thread: a vertex's list is then in contact order whatever the
 * thread count. Each thread finally writes the entries of the contacts it copied. Run
 * sequentially, the gather lists alone cost a fifth of the search's time on two threads (random
 * writes into a list of 4 × contacts entries). */
static void list_contacts( sere_collide* c, const int32_t* tri, int64_t total, int64_t edge_total, int threads )
{
	int32_t n = c->vertex_count;
	size_t stride = (size_t) sere_pad( n );
	int64_t all = total + edge_total;
#pragma omp parallel num_threads( threads )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		int32_t* mine = c->entry_cursor + (size_t) tid * stride;
		memset( mine, 0, sizeof( int32_t ) * (size_t) n );
#pragma omp for schedule( static )
		for ( int32_t block = 0; block < c->block_count; ++block )
		{
			int64_t begin = c->block_found[block];
			int64_t next = block + 1 < c->block_count ? c->block_found[block + 1] : all;
			size_t count = (size_t) ( next - begin );
			if ( block < c->vertex_blocks )
			{
				const sere_contact* from = thread_buffer( c, c->block_thread[block] ) + c->block_start[block];
				if ( count > 0 && from != c->contacts + begin )
				{
					memcpy( c->contacts + begin, from, sizeof( sere_contact ) * count );
				}
				for ( int64_t k = begin; k < next; ++k )
				{
					const sere_contact* contact = c->contacts + k;
					const int32_t* v = tri + 3 * (size_t) contact->triangle;
					c->member[0][k] = contact->vertex;
					c->member[1][k] = v[0], c->member[2][k] = v[1], c->member[3][k] = v[2];
					c->contact_side[k] = contact->side;
					c->weight[0][k] = contact->u, c->weight[1][k] = contact->v, c->weight[2][k] = contact->w;
				}
			}
			else
			{
				const sere_edge_contact* from = thread_edge_buffer( c, c->block_thread[block] ) + c->block_start[block];
				if ( count > 0 )
				{
					memcpy( c->edge_contacts + ( begin - total ), from, sizeof( sere_edge_contact ) * count );
				}
				for ( int64_t k = begin; k < next; ++k )
				{
					const sere_edge_contact* contact = c->edge_contacts + ( k - total );
					c->member[0][k] = contact->a0, c->member[1][k] = contact->a1;
					c->member[2][k] = contact->b0, c->member[3][k] = contact->b1;
					c->contact_side[k] = contact->side;
					c->weight[0][k] = contact->s, c->weight[1][k] = contact->t, c->weight[2][k] = 0.0f;
				}
			}
			for ( int64_t k = begin; k < next; ++k )
			{
				for ( int r = 0; r < 4; ++r )
				{
					mine[c->member[r][k]] += 1;
				}
			}
		}
		/* this thread's run of vertices: its entries and touched vertices */
		int32_t first = (int32_t) ( (int64_t) n * tid / team ), last = (int32_t) ( (int64_t) n * ( tid + 1 ) / team );
		int32_t entries = 0, touched = 0;
		for ( int32_t i = first; i < last; ++i )
		{
			int32_t before = entries;
			for ( int t = 0; t < team; ++t )
			{
				entries += c->entry_cursor[(size_t) t * stride + (size_t) i];
			}
			touched += entries > before;
		}
		c->run_total[2 * FAR_STRIDE * tid] = entries;
		c->run_total[2 * FAR_STRIDE * tid + 1] = touched;
#pragma omp barrier
		entries = touched = 0;
		for ( int t = 0; t < tid; ++t )
		{
			entries += c->run_total[2 * FAR_STRIDE * t];
			touched += c->run_total[2 * FAR_STRIDE * t + 1];
		}
		for ( int32_t i = first; i < last; ++i )
		{
			c->entry_offset[i] = entries;
			for ( int t = 0; t < team; ++t )
			{
				int32_t* cursor = c->entry_cursor + (size_t) t * stride + (size_t) i;
				int32_t count = *cursor;
				*cursor = entries;
				entries += count;
			}
			if ( entries > c->entry_offset[i] )
			{
				c->touched[touched++] = i;
			}
		}
		if ( tid == team - 1 )
		{
			c->entry_offset[n] = entries;
			c->touched_count = touched;
		}
#pragma omp barrier
		/* the same static schedule as the copy: each thread lists the contacts it counted */
#pragma omp for schedule( static )
		for ( int32_t block = 0; block < c->block_count; ++block )
		{
			int64_t next = block + 1 < c->block_count ? c->block_found[block + 1] : all;
			for ( int64_t k = c->block_found[block]; k < next; ++k )
			{
				/* a triangle's corners move against the push by their barycentric weight, the
				 * vertex with it; the first edge's ends with it by their weights on the edge, the
				 * second edge's against it */
				bool vertex = k < total;
				float s = c->weight[0][k], t = c->weight[1][k];
				int32_t member[4] = { c->member[vertex ? 1 : 0][k], c->member[vertex ? 2 : 1][k],
									  c->member[vertex ? 3 : 2][k], c->member[vertex ? 0 : 3][k] };
				float coef[4] = { -s, -t, -c->weight[2][k], 1.0f };
				if ( !vertex )
				{
					coef[0] = 1.0f - s, coef[1] = s, coef[2] = -( 1.0f - t ), coef[3] = -t;
				}
				for ( int r = 0; r < 4; ++r )
				{
					int32_t e = mine[member[r]]++;
					c->entries[e] = (int32_t) k;
					c->entry_coef[e] = coef[r];
				}
			}
		}
	}
}

/* Queries the groups of vertex block `block` (lanes are vertices: detect_visit). */
static int detect_vertex_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness )
{
	int bad = 0;
	int32_t end = ( block + 1 ) * DETECT_BLOCK < n ? ( block + 1 ) * DETECT_BLOCK : n;
	for ( int32_t first = block * DETECT_BLOCK; first < end; first += SERE_BVH_WIDTH )
	{
		sere_bvh_group group;
		group.count = end - first < SERE_BVH_WIDTH ? end - first : SERE_BVH_WIDTH;
		c->first = first;
		for ( int32_t k = 0; k < group.count; ++k )
		{
			float p[3];
			load3( c->x, c->y, c->z, first + k, p );
			/* a NaN or infinite vertex leaves its lane non-finite: the query ignores it */
			bad |= !( isfinite( p[0] ) && isfinite( p[1] ) && isfinite( p[2] ) );
			float r = cull_radius( thickness, p ) + c->grow;
			group.lo_x[k] = p[0] - r, group.lo_y[k] = p[1] - r, group.lo_z[k] = p[2] - r;
			group.hi_x[k] = p[0] + r, group.hi_y[k] = p[1] + r, group.hi_z[k] = p[2] + r;
		}
		mark_lanes( c, true );
		sere_bvh_query_group( bvh, &group, detect_visit, c );
		mark_lanes( c, false );
	}
	detect_flush( c );
	return bad;
}

/* Adds the edges e .. end (at most LANE_EDGES) of vertex a to the table as lane k of group. The
 * lane's box is the box of those edges grown by the cull radius of its farthest corner. */
static void table_lane( detect_context* c, sere_bvh_group* group, int32_t k, int32_t a, int32_t e, int32_t end,
						float thickness )
{
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	float pa[3];
	load3( c->x, c->y, c->z, a, pa );
	int32_t from = c->table_lane[k] = c->table_count;
	for ( int32_t i = e; i < end; ++i )
	{
		int32_t j = c->table_count++, b = c->edge_end[2 * i + 1];
		float pb[3];
		load3( c->x, c->y, c->z, b, pb );
		for ( int d = 0; d < 3; ++d )
		{
			c->table_lo[d][j] = pa[d] < pb[d] ? pa[d] : pb[d];
			c->table_hi[d][j] = pa[d] < pb[d] ? pb[d] : pa[d];
			lo[d] = c->table_lo[d][j] < lo[d] ? c->table_lo[d][j] : lo[d];
			hi[d] = c->table_hi[d][j] > hi[d] ? c->table_hi[d][j] : hi[d];
		}
		for ( int d = 0; d < 3; ++d )
		{
			c->table_at[d][j] = pa[d];
			c->table_across[d][j] = c->across[d][i];
		}
		c->table_lower[j] = a, c->table_upper[j] = b, c->table_edge[j] = i;
	}
	float far[3];
	for ( int d = 0; d < 3; ++d )
	{
		far[d] = fabsf( lo[d] ) > fabsf( hi[d] ) ? fabsf( lo[d] ) : fabsf( hi[d] );
	}
	float r = cull_radius( thickness, far ) + c->grow;
	for ( int32_t j = from; j < c->table_count; ++j )
	{
		for ( int d = 0; d < 3; ++d )
		{
			c->table_lo[d][j] -= r, c->table_hi[d][j] += r;
		}
		c->table_margin[j] = r;
	}
	group->lo_x[k] = lo[0] - r, group->lo_y[k] = lo[1] - r, group->lo_z[k] = lo[2] - r;
	group->hi_x[k] = hi[0] + r, group->hi_y[k] = hi[1] + r, group->hi_z[k] = hi[2] + r;
}

/* Queries vertex block `block` for edge–edge pairs: groups of up to eight lanes, each standing
 * for up to LANE_EDGES of the edges a vertex is the lower end of, in vertex order (a vertex that is
 * no edge's lower end takes no lane). Non-finite positions are reported by the vertex–triangle
 * blocks. */
static void detect_edge_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness )
{
	int32_t a = block * DETECT_BLOCK, end = ( block + 1 ) * DETECT_BLOCK < n ? ( block + 1 ) * DETECT_BLOCK : n;
	int32_t e = c->lower_edge[a];
	for ( ;; )
	{
		sere_bvh_group group;
		group.count = 0;
		c->table_count = 0;
		while ( group.count < SERE_BVH_WIDTH && a < end )
		{
			int32_t last = c->lower_edge[a + 1];
			if ( e == last )
			{
				a += 1;
				e = c->lower_edge[a];
				continue;
			}
			int32_t stop = last - e > LANE_EDGES ? e + LANE_EDGES : last;
			if ( group.count == 0 )
			{
				c->first = a;
			}
			table_lane( c, &group, group.count++, a, e, stop, thickness );
			e = stop;
		}
		if ( group.count == 0 )
		{
			break;
		}
		c->table_lane[group.count] = c->table_count;
		/* detect_edge_visit keeps only edges whose lower end is above c->first, so whose upper
		 * end is above c->first + 1: a triangle with no corner above that owns none of them */
		sere_bvh_query_group_above( bvh, &group, c->first + 1, detect_edge_visit, c );
		detect_edge_candidates( c );
	}
	detect_edge_flush( c );
}

/* The unit vector across edge e = (a, b) in the plane of its first triangle: n × (b − a),
 * normalized (zero when that is degenerate), for table_hits and edge_bound_lanes. */
static void edge_across_at( sere_collide* collide, const int32_t* tri, const float* x, const float* y, const float* z,
							int32_t e )
{
	float corner[3][3], n[3], pa[3], pb[3];
	triangle_frame( x, y, z, tri + 3 * (size_t) collide->edge_triangle[e], corner[0], corner[1], corner[2], n );
	load3( x, y, z, collide->edge_end[2 * e], pa );
	load3( x, y, z, collide->edge_end[2 * e + 1], pb );
	float u[3] = { pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2] };
	float m[3] = { n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0] };
	float length = sqrtf( m[0] * m[0] + m[1] * m[1] + m[2] * m[2] );
	float inverse = length > 0.0f ? 1.0f / length : 0.0f;
	size_t stride = (size_t) sere_pad( collide->edge_count );
	for ( int d = 0; d < 3; ++d )
	{
		collide->edge_across[(size_t) d * stride + (size_t) e] = m[d] * inverse;
	}
}

/* Runs the exact test on block `block`'s listed pairs (see SKIN), in their order, as the search
 * would have buffered them. */
static void replay_block( detect_context* c, const sere_collide* collide, int32_t block, bool vertices )
{
	size_t base = (size_t) collide->cache_block_thread[block] * (size_t) collide->cache_capacity +
				  (size_t) collide->cache_block_start[block];
	int32_t count = collide->cache_block_count[block];
	for ( int32_t done = 0; done < count; done += PAIR_BUFFER )
	{
		int32_t batch = count - done < PAIR_BUFFER ? count - done : PAIR_BUFFER;
		memcpy( c->pair_item, collide->cache_item + base + done, sizeof( int32_t ) * (size_t) batch );
		memcpy( c->pair_target, collide->cache_target + base + done, sizeof( int32_t ) * (size_t) batch );
		memcpy( c->pair_near, collide->cache_near + base + done, (size_t) batch );
		c->pair_count = batch;
		if ( vertices )
		{
			detect_flush( c );
		}
		else
		{
			detect_edge_flush( c );
		}
	}
}

/* True when the list (see SKIN) serves positions x, y, z and this thickness: it is whole, was made
 * for a thickness no smaller and for this build of the tree, and every vertex is within δ of
 * where it was then, up to one translation T common to all (the middle of the displacements'
 * box): distances, the only thing the list's argument uses, do not see T. The float |Δ − T|²
 * is within a few ulps of the true one, and the |T| 2⁻¹⁴ taken off δ covers what T adds to
 * cull_radius's |p| term and to the rounding of Δ − T, both far inside the 2⁻⁸ δ of room the
 * grown radius keeps; a NaN fails the test. */
static bool list_serves( const sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
						 const float* z, float thickness, int threads )
{
	if ( !collide->cache_valid || !( thickness <= collide->cache_thickness ) ||
		 sere_bvh_generation( bvh ) != collide->cache_generation )
	{
		return false;
	}
	int32_t n = collide->vertex_count;
	const float* now[3] = { x, y, z };
	const float* then[3] = { collide->cache_x, collide->cache_y, collide->cache_z };
	float lo[3], hi[3];
	for ( int a = 0; a < 3; ++a )
	{
		float l = INFINITY, h = -INFINITY;
		const float *p = now[a], *q = then[a];
#pragma omp parallel for num_threads( threads ) schedule( static ) reduction( min : l ) reduction( max : h )
		for ( int32_t i = 0; i < n; ++i )
		{
			float d = p[i] - q[i];
			l = d < l ? d : l;
			h = d > h ? d : h;
		}
		lo[a] = l, hi[a] = h;
	}
	if ( !( isfinite( lo[0] + lo[1] + lo[2] ) && isfinite( hi[0] + hi[1] + hi[2] ) ) )
	{
		return false;
	}
	float t[3] = { 0.5f * ( lo[0] + hi[0] ), 0.5f * ( lo[1] + hi[1] ), 0.5f * ( lo[2] + hi[2] ) };
	float skin = collide->cache_delta - ( fabsf( t[0] ) + fabsf( t[1] ) + fabsf( t[2] ) ) * 0x1p-14f;
	if ( !( skin > 0.0f ) )
	{
		return false;
	}
	float limit = skin * skin;
	int far = 0;
#pragma omp parallel for num_threads( threads ) schedule( static ) reduction( | : far )
	for ( int32_t i = 0; i < n; ++i )
	{
		float dx = x[i] - collide->cache_x[i] - t[0], dy = y[i] - collide->cache_y[i] - t[1];
		float dz = z[i] - collide->cache_z[i] - t[2];
		far |= !( dx * dx + dy * dy + dz * dz <= limit );
	}
	return !far;
}

sere_status sere_collide_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
								 const float* z, float thickness, int32_t* contact_count )
{
	if ( collide == NULL || bvh == NULL || x == NULL || y == NULL || z == NULL || contact_count == NULL ||
		 !( thickness > 0.0f ) || !isfinite( thickness ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t triangles;
	const int32_t* tri = sere_bvh_triangles( bvh, &triangles );
	if ( sere_bvh_vertex_count( bvh ) != collide->vertex_count || triangles != collide->triangle_count )
	{
		return SERE_ERR_ARGUMENT;
	}
	*contact_count = 0;
	collide->contact_count = 0;
	collide->edge_contact_count = 0;
	collide->edge_found = 0;
	collide->touched_count = 0;
	int32_t n = collide->vertex_count;
	int32_t threads = sere_team_default();
	threads = threads < collide->slots ? threads : collide->slots;
	float h2 = thickness * thickness;
	collide->work_prefix[0] = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		collide->work_prefix[block + 1] = collide->work_prefix[block] + collide->block_work[block];
	}
	bool replay = list_serves( collide, bvh, x, y, z, thickness, threads );
	bool listing = !replay;
	if ( replay )
	{
		collide->cache_uses += 1;
	}
	else
	{
		if ( collide->cache_valid && collide->cache_uses < SKIN_SHORT )
		{
			collide->skin = collide->skin * 1.25f < SKIN_MAX ? collide->skin * 1.25f : SKIN_MAX;
		}
		else if ( collide->cache_valid && collide->cache_uses > SKIN_LONG )
		{
			collide->skin = collide->skin * 0.8f > SKIN_MIN ? collide->skin * 0.8f : SKIN_MIN;
		}
		collide->cache_valid = false;
		collide->cache_uses = 0;
		collide->cache_delta = collide->skin * thickness;
		int32_t edges = collide->edge_count;
#pragma omp parallel for num_threads( threads ) schedule( static )
		for ( int32_t e = 0; e < edges; ++e )
		{
			edge_across_at( collide, tri, x, y, z, e );
		}
	}
	size_t across_stride = (size_t) sere_pad( collide->edge_count );
	for ( int t = 0; t < threads; ++t )
	{
		/* a thread the team turns out not to have lists nothing */
		collide->cache_used[FAR_STRIDE * t] = 0;
	}
	int bad = 0;
#pragma omp parallel num_threads( threads ) reduction( | : bad )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		detect_context c = {
			.x = x,
			.y = y,
			.z = z,
			.tri = tri,
			.edge_end = collide->edge_end,
			.lower_edge = collide->lower_edge,
			.owned = collide->owned,
			.edge_triangle = collide->edge_triangle,
			.mark_offset = collide->mark_offset,
			.mark_vertex = collide->mark_vertex,
			.mark_bits = collide->mark_bits,
			.mark = collide->lane_mark + (size_t) tid * (size_t) sere_pad( n ),
			.h2 = h2,
			.buffer = thread_buffer( collide, tid ),
			.edge_buffer = thread_edge_buffer( collide, tid ),
			.capacity = collide->capacity,
			.listing = listing,
			.thickness = thickness,
			/* 2δ, and 2⁻⁸ of it for the rounding of the displacement test and of cull_radius's
			 * |p| term at the moved positions */
			.grow = listing ? 2.0f * collide->cache_delta * ( 1.0f + 0x1p-8f ) : 0.0f,
			.list_item = collide->cache_item + (size_t) tid * (size_t) collide->cache_capacity,
			.list_target = collide->cache_target + (size_t) tid * (size_t) collide->cache_capacity,
			.list_near = collide->cache_near + (size_t) tid * (size_t) collide->cache_capacity,
			.list_capacity = collide->cache_capacity,
			.across = { collide->edge_across, collide->edge_across + across_stride,
						collide->edge_across + 2 * across_stride },
		};
		int32_t run_end = run_begin( collide, tid + 1, team );
		for ( int32_t block = run_begin( collide, tid, team ); block < run_end; ++block )
		{
			bool vertices = block < collide->vertex_blocks;
			int32_t start = vertices ? c.used : c.edge_used;
			int64_t found = vertices ? c.found : c.edge_found;
			double clock = omp_get_wtime();
			int32_t listed = c.list_used;
			if ( replay )
			{
				replay_block( &c, collide, block, vertices );
			}
			else if ( vertices )
			{
				bad |= detect_vertex_block( &c, bvh, block, n, thickness );
			}
			else
			{
				detect_edge_block( &c, bvh, block - collide->vertex_blocks, n, thickness );
			}
			if ( listing )
			{
				collide->cache_block_thread[block] = tid;
				collide->cache_block_start[block] = listed;
				collide->cache_block_count[block] = c.list_used - listed;
			}
			collide->block_thread[block] = tid;
			collide->block_start[block] = start;
			collide->block_found[block] = ( vertices ? c.found : c.edge_found ) - found;
			collide->block_work[block] = (int64_t) ( ( omp_get_wtime() - clock ) * 1e9 );
		}
		collide->cache_used[FAR_STRIDE * tid] = c.list_used;
	}
	if ( listing )
	{
		bool whole = !bad;
		for ( int t = 0; t < threads; ++t )
		{
			whole = whole && collide->cache_used[FAR_STRIDE * t] >= 0;
		}
		collide->cache_valid = whole;
		if ( !whole && !bad )
		{
			/* the list outgrew its room: the next one lists fewer pairs */
			collide->skin = SKIN_MIN;
		}
		if ( whole )
		{
			memcpy( collide->cache_x, x, sizeof( float ) * (size_t) n );
			memcpy( collide->cache_y, y, sizeof( float ) * (size_t) n );
			memcpy( collide->cache_z, z, sizeof( float ) * (size_t) n );
			collide->cache_thickness = thickness;
			collide->cache_generation = sere_bvh_generation( bvh );
		}
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	int64_t total = 0, edge_total = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		*( block < collide->vertex_blocks ? &total : &edge_total ) += collide->block_found[block];
	}
	*contact_count = total < INT32_MAX ? (int32_t) total : INT32_MAX;
	collide->edge_found = edge_total;
	if ( total > collide->capacity || edge_total > collide->capacity )
	{
		return SERE_ERR_CAPACITY;
	}
	/* block_found becomes each block's offset in the per-contact arrays: the vertex–triangle
	 * contacts, then the edge–edge ones */
	int64_t offset = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		int64_t found = collide->block_found[block];
		collide->block_found[block] = offset;
		offset += found;
	}
	list_contacts( collide, tri, total, edge_total, threads );
	collide->contact_count = (int32_t) total;
	collide->edge_contact_count = (int32_t) edge_total;
	return SERE_OK;
}

/* Gathers the four members' points of contacts [begin, begin + count) into rows 3r .. 3r + 2 of
 * point (x, y, z of member r), eight contacts at a time (sere_v8_gather_records). */
static void gather_members( const sere_collide* c, int32_t begin, int32_t count, float point[12][EVALUATE_BLOCK] )
{
	for ( int32_t m = 0; m < count; m += GATHER_LANES )
	{
		for ( int r = 0; r < 4; ++r )
		{
			const int32_t* index = c->member[r] + begin + m;
			int32_t tail[GATHER_LANES];
			if ( m + GATHER_LANES > count )
			{
				/* a short last batch repeats its last contact; the lanes past count are not used */
				for ( int l = 0; l < GATHER_LANES; ++l )
				{
					tail[l] = index[m + l < count ? l : count - 1 - m];
				}
				index = tail;
			}
			sere_v8_gather_records( c->position, index, point[3 * r] + m, point[3 * r + 1] + m, point[3 * r + 2] + m );
		}
	}
}

/* Writes the corrections of contacts [begin, begin + count), rows (λ n̂, push), to corr as
 * records. */
static void store_corrections( sere_collide* c, int32_t begin, int32_t count, float row[4][EVALUATE_BLOCK] )
{
	float* corr = c->corr + 4 * (size_t) begin;
	int32_t whole = count - count % GATHER_LANES;
	for ( int32_t m = 0; m < whole; m += GATHER_LANES )
	{
		sere_v8_scatter_records( row[0] + m, row[1] + m, row[2] + m, row[3] + m, corr + 4 * (size_t) m );
	}
	for ( int32_t k = whole; k < count; ++k )
	{
		corr[4 * k] = row[0][k], corr[4 * k + 1] = row[1][k], corr[4 * k + 2] = row[2][k], corr[4 * k + 3] = row[3][k];
	}
}

/* Evaluates vertex–triangle contacts [begin, end), at most EVALUATE_BLOCK of them, at the current
 * positions (see sere_collide_respond) at their points of detection q = u a + v b + w c: stores
 * corr[4k ..] = (λ n̂, 1) for a contact that pushes, zeros for one that does not, and returns
 * how many push by more than the tolerance. The four points are gathered first, then the
 * arithmetic runs as straight-line vector code across contacts. */
static int32_t evaluate_contacts( sere_collide* c, int32_t begin, int32_t end, float h2, float tolerance )
{
	float point[12][EVALUATE_BLOCK];
	int32_t count = end - begin;
	gather_members( c, begin, count, point );
	const float* restrict bu = c->weight[0] + begin, * restrict bv = c->weight[1] + begin, * restrict bw = c->weight[2] + begin;
	const float* restrict side = c->contact_side + begin, * restrict inv_weight = c->inv_weight + begin;
	/* the corrections as rows (λ n̂, push), written to corr as records below */
	float row[4][EVALUATE_BLOCK];
	int32_t far = 0;
#pragma omp simd reduction( + : far )
	for ( int32_t k = 0; k < count; ++k )
	{
		float p[3] = { point[0][k], point[1][k], point[2][k] };
		float a[3] = { point[3][k], point[4][k], point[5][k] };
		float b[3] = { point[6][k], point[7][k], point[8][k] };
		float cc[3] = { point[9][k], point[10][k], point[11][k] };
		float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		float ac[3] = { cc[0] - a[0], cc[1] - a[1], cc[2] - a[2] };
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		/* a degenerate triangle has no normal (scale 0) and never pushes */
		/* side[k] is ±1, so side / |n| = side · (1 / |n|) exactly; written as a product used on
		 * every path, its load stays a plain vector load instead of a masked one */
		float inverse_length = length2 > 0.0f ? 1.0f / sqrtf( length2 > 0.0f ? length2 : 1.0f ) : 0.0f;
		float scale = side[k] * inverse_length;
		float inverse = inv_weight[k];
		n[0] *= scale, n[1] *= scale, n[2] *= scale;
		float d[3];
		for ( int r = 0; r < 3; ++r )
		{
			d[r] = p[r] - ( bu[k] * a[r] + bv[k] * b[r] + bw[k] * cc[r] );
		}
		float height = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
		float l[3] = { d[0] - height * n[0], d[1] - height * n[1], d[2] - height * n[2] };
		float room = h2 - ( l[0] * l[0] + l[1] * l[1] + l[2] * l[2] );
		float deficit = sqrtf( room > 0.0f ? room : 0.0f ) - height;
		/* an immovable contact (1/W = 0) never pushes either */
		int push = ( room > 0.0f ) & ( deficit > 0.0f ) & ( scale != 0.0f ) & ( inverse > 0.0f );
		float lambda = push ? deficit * inverse : 0.0f;
		row[0][k] = lambda * n[0];
		row[1][k] = lambda * n[1];
		row[2][k] = lambda * n[2];
		row[3][k] = push ? 1.0f : 0.0f;
		far += push & ( deficit > tolerance );
	}
	store_corrections( c, begin, count, row );
	return far;
}

/* evaluate_contacts for edge–edge contacts [begin, end): the same constraint between the points
 * of detection p = (1 − s) a0 + s a1 and q = (1 − t) b0 + t b1, along n = (a1 − a0) × (b1 − b0).
 * Parallel edges have no normal (scale 0) and never push. */
static int32_t evaluate_edges( sere_collide* c, int32_t begin, int32_t end, float h2, float tolerance )
{
	float point[12][EVALUATE_BLOCK];
	int32_t count = end - begin;
	gather_members( c, begin, count, point );
	const float* restrict ws = c->weight[0] + begin, * restrict wt = c->weight[1] + begin;
	const float* restrict side = c->contact_side + begin, * restrict inv_weight = c->inv_weight + begin;
	float row[4][EVALUATE_BLOCK];
	int32_t far = 0;
#pragma omp simd reduction( + : far )
	for ( int32_t k = 0; k < count; ++k )
	{
		float a0[3] = { point[0][k], point[1][k], point[2][k] };
		float a1[3] = { point[3][k], point[4][k], point[5][k] };
		float b0[3] = { point[6][k], point[7][k], point[8][k] };
		float b1[3] = { point[9][k], point[10][k], point[11][k] };
		float u[3] = { a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2] };
		float v[3] = { b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2] };
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float inverse_length = length2 > 0.0f ? 1.0f / sqrtf( length2 > 0.0f ? length2 : 1.0f ) : 0.0f;
		float scale = side[k] * inverse_length;
		float inverse = inv_weight[k];
		n[0] *= scale, n[1] *= scale, n[2] *= scale;
		float s = ws[k], t = wt[k];
		float d[3];
		for ( int r = 0; r < 3; ++r )
		{
			d[r] = ( ( 1.0f - s ) * a0[r] + s * a1[r] ) - ( ( 1.0f - t ) * b0[r] + t * b1[r] );
		}
		float height = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
		float l[3] = { d[0] - height * n[0], d[1] - height * n[1], d[2] - height * n[2] };
		float room = h2 - ( l[0] * l[0] + l[1] * l[1] + l[2] * l[2] );
		float deficit = sqrtf( room > 0.0f ? room : 0.0f ) - height;
		int push = ( room > 0.0f ) & ( deficit > 0.0f ) & ( scale != 0.0f ) & ( inverse > 0.0f );
		float lambda = push ? deficit * inverse : 0.0f;
		row[0][k] = lambda * n[0];
		row[1][k] = lambda * n[1];
		row[2][k] = lambda * n[2];
		row[3][k] = push ? 1.0f : 0.0f;
		far += push & ( deficit > tolerance );
	}
	store_corrections( c, begin, count, row );
	return far;
}

/* The coefficient of entry e as a group (coefficient, coefficient, coefficient, 1). */
static inline sere_v4 entry_coefficient( const sere_collide* c, int32_t e )
{
	return sere_v4_xyz( c->entry_coef[e], 1.0f );
}

/* The correction record of entry e. */
static inline sere_v4 entry_correction( const sere_collide* c, int32_t e )
{
	return sere_v4_load( c->corr + 4 * (size_t) c->entries[e] );
}

/* Adds the entries [e, end) to sum in order. */
static inline sere_v4 gather_sum( const sere_collide* c, int32_t e, int32_t end, sere_v4 sum )
{
	for ( ; e < end; ++e )
	{
		sum = sere_v4_add( sum, sere_v4_mul( entry_coefficient( c, e ), entry_correction( c, e ) ) );
	}
	return sum;
}

/* Moves touched vertex slot j (vertex i) by ω / count times the summed correction. */
static inline void gather_move( sere_collide* c, int32_t j, sere_v4 sum, const float* inv_m, float relaxation )
{
	int32_t i = c->touched[j];
	if ( sere_v4_w( sum ) == 0.0f )
	{
		return;
	}
	float scale = relaxation * inv_m[i];
	/* lane 3 scaled by 0: the padding stays 0 */
	sere_v4 d = sere_v4_mul( sum, sere_v4_xyz( scale, 0.0f ) );
	float* position = c->position + 4 * (size_t) i;
	float* acc = c->acc + 4 * (size_t) j;
	sere_v4_store( position, sere_v4_add( sere_v4_load( position ), d ) );
	sere_v4_store( acc, sere_v4_add( sere_v4_load( acc ), d ) );
}

/* Moves touched vertex slots j and j + 1 (gather_apply for each), their sums side by side in
 * one group of eight while both have entries left, then each on its own: every lane sees the
 * products and sums of the one-vertex form in the same order. A vertex averages 21 entries on
 * the dried maple, and two independent chains of adds keep the adder busy where one waits on
 * the last add. */
static void gather_apply_pair( sere_collide* c, int32_t j, const float* inv_m, float relaxation )
{
	int32_t i0 = c->touched[j], i1 = c->touched[j + 1];
	int32_t e0 = c->entry_offset[i0], end0 = c->entry_offset[i0 + 1];
	int32_t e1 = c->entry_offset[i1], end1 = c->entry_offset[i1 + 1];
	int32_t common = end0 - e0 < end1 - e1 ? end0 - e0 : end1 - e1;
	sere_v8 sum = sere_v8_zero();
	for ( int32_t k = 0; k < common; ++k )
	{
		sere_v8 coefficient = sere_v8_pair( entry_coefficient( c, e0 + k ), entry_coefficient( c, e1 + k ) );
		sere_v8 corr = sere_v8_pair( entry_correction( c, e0 + k ), entry_correction( c, e1 + k ) );
		sum = sere_v8_add( sum, sere_v8_mul( coefficient, corr ) );
	}
	sere_v4 sum0 = gather_sum( c, e0 + common, end0, sere_v8_low( sum ) );
	sere_v4 sum1 = gather_sum( c, e1 + common, end1, sere_v8_high( sum ) );
	gather_move( c, j, sum0, inv_m, relaxation );
	gather_move( c, j + 1, sum1, inv_m, relaxation );
}

/* Moves touched vertex slot j by ω times the mean of its pushing contacts' corrections, summed
 * in contact order (a contact that does not push has a zero correction and counts 0). The sums
 * run in the four lanes of one group, (coefficient, coefficient, coefficient, 1) times the
 * contact's (λ n̂, 1). */
static void gather_apply( sere_collide* c, int32_t j, const float* inv_m, float relaxation )
{
	int32_t i = c->touched[j];
	sere_v4 sum = gather_sum( c, c->entry_offset[i], c->entry_offset[i + 1], sere_v4_zero() );
	gather_move( c, j, sum, inv_m, relaxation );
}

/* The first touched slot of part `part` of `parts` when the touched vertices are cut into runs
 * of about equal gather work (entries): vertices differ a lot in their number of contacts (on the
 * dried maple one half of the touched vertices holds 62% of the entries), and a cut by vertex
 * count would leave one thread waiting at every iteration's barrier. */
/* Averaging without creating momentum. A vertex in n pushing contacts must not take the sum of
 * their corrections (Jacobi overshoots), but dividing each vertex's sum by its own n (Macklin
 * et al. 2014) gives the members of one contact different shares of its impulse, and the leaf's
 * centre of mass moves: 0.009 L over a green maple's run, all of it in the frames with edge
 * contacts. Instead each contact's correction is divided by the largest n among its four
 * members, so all of them take the same share and Σ m Δx = λ n̂ Σ coefficients = 0 per contact
 * (the coefficients 1, −u, −v, −w or 1 − s, s, −(1 − t), −t sum to 0). Called by every thread of
 * the response between the evaluation and the gather: counts for its touched vertices, a
 * barrier, then the shares for its contacts (the loop's own barrier ends it). */
static void share_pushes( sere_collide* c, int32_t mine_begin, int32_t mine_end, int32_t contacts )
{
	for ( int32_t j = mine_begin; j < mine_end; ++j )
	{
		int32_t i = c->touched[j];
		float n = 0.0f;
		for ( int32_t e = c->entry_offset[i]; e < c->entry_offset[i + 1]; ++e )
		{
			n += c->corr[4 * (size_t) c->entries[e] + 3];
		}
		c->push_count[i] = n;
	}
#pragma omp barrier
#pragma omp for schedule( static )
	for ( int32_t k = 0; k < contacts; ++k )
	{
		float* corr = c->corr + 4 * (size_t) k;
		if ( corr[3] == 0.0f )
		{
			continue;
		}
		float n = 1.0f;
		for ( int r = 0; r < 4; ++r )
		{
			n = fmaxf( n, c->push_count[c->member[r][k]] );
		}
		float share = 1.0f / n;
		corr[0] *= share, corr[1] *= share, corr[2] *= share;
	}
}

static int32_t touched_split( const sere_collide* c, int part, int parts )
{
	if ( part >= parts )
	{
		return c->touched_count;
	}
	int64_t target = (int64_t) c->entry_offset[c->vertex_count] * part / parts;
	int32_t lo = 0, hi = c->touched_count;
	while ( lo < hi )
	{
		int32_t mid = lo + ( hi - lo ) / 2;
		if ( c->entry_offset[c->touched[mid]] < target )
		{
			lo = mid + 1;
		}
		else
		{
			hi = mid;
		}
	}
	return lo;
}

static bool state_valid( const sere_collide_state* s )
{
	return s != NULL && s->x && s->y && s->z && s->vx && s->vy && s->vz && s->inv_m &&
		   ( s->x0 == NULL ) == ( s->y0 == NULL ) && ( s->x0 == NULL ) == ( s->z0 == NULL );
}

/* The side of contact k's triangle its vertex was on at the start of the step: the sign of
 * (p₀ − q₀) · n₀ at the detection weights, or the detection side when that is neither positive
 * nor negative (the vertex in the plane, a degenerate triangle, or NaN, which respond refuses).
 * For an edge–edge contact (vertex false), the side of its second edge the first was on: the same
 * sign with p₀, q₀ the points of detection on the two edges and n₀ = (a1 − a0) × (b1 − b0). */
static inline float history_side( const sere_collide* c, const sere_collide_state* s, int32_t k, bool vertex )
{
	float point[4][3];
	for ( int r = 0; r < 4; ++r )
	{
		load3( s->x0, s->y0, s->z0, c->member[r][k], point[r] );
	}
	float u = c->weight[0][k], v = c->weight[1][k], w = c->weight[2][k];
	float ab[3], ac[3], d[3];
	for ( int r = 0; r < 3; ++r )
	{
		if ( vertex )
		{
			ab[r] = point[2][r] - point[1][r], ac[r] = point[3][r] - point[1][r];
			d[r] = point[0][r] - ( u * point[1][r] + v * point[2][r] + w * point[3][r] );
		}
		else
		{
			ab[r] = point[1][r] - point[0][r], ac[r] = point[3][r] - point[2][r];
			d[r] = ( ( 1.0f - u ) * point[0][r] + u * point[1][r] ) - ( ( 1.0f - v ) * point[2][r] + v * point[3][r] );
		}
	}
	float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
	float height = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
	return height > 0.0f ? 1.0f : ( height < 0.0f ? -1.0f : c->contact_side[k] );
}

static bool params_valid( const sere_collide_params* p )
{
	return p != NULL && p->thickness > 0.0f && isfinite( p->thickness ) && p->dt > 0.0f && isfinite( p->dt ) &&
		   p->iterations >= 0 && p->rounds >= 1 && p->rebuild_ratio > 0.0 && p->relaxation > 0.0f &&
		   p->relaxation <= 2.0f;
}

static sere_status respond( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
							const sere_collide_params* params, int32_t* unresolved, int32_t* iterations )
{
	if ( collide == NULL || bvh == NULL || !state_valid( state ) || !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t triangles;
	sere_bvh_triangles( bvh, &triangles );
	if ( triangles != collide->triangle_count || sere_bvh_vertex_count( bvh ) != collide->vertex_count )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* the vertex–triangle contacts [0, vertex_contacts), then the edge–edge ones */
	int32_t vertex_contacts = collide->contact_count, touched = collide->touched_count;
	int32_t contacts = vertex_contacts + collide->edge_contact_count;
	/* A few hundred contacts take less time than the barriers of a parallel response; the result
	 * is the same either way. */
	bool parallel = contacts >= RESPOND_PARALLEL;
	const float* inv_m = state->inv_m;
	int bad = 0;
#pragma omp parallel num_threads( sere_team_default() ) if ( parallel )
	{
#pragma omp for reduction( | : bad ) schedule( static ) nowait
		for ( int32_t j = 0; j < touched; ++j )
		{
			int32_t i = collide->touched[j];
			bad |= !( isfinite( state->vx[i] ) && isfinite( state->vy[i] ) && isfinite( state->vz[i] ) &&
					  isfinite( inv_m[i] ) && inv_m[i] >= 0.0f );
			bad |= state->x0 != NULL &&
				   !( isfinite( state->x0[i] ) && isfinite( state->y0[i] ) && isfinite( state->z0[i] ) );
			float* position = collide->position + 4 * (size_t) i;
			position[0] = state->x[i], position[1] = state->y[i], position[2] = state->z[i], position[3] = 0.0f;
			float* acc = collide->acc + 4 * (size_t) j;
			acc[0] = acc[1] = acc[2] = acc[3] = 0.0f;
		}
		/* W = w_p + Σ w_k b_k² (or Σ over the edge ends of w times the squared weight on the
		 * edge) with the weights of detection, fixed for the response */
#pragma omp for schedule( static )
		for ( int32_t k = 0; k < contacts; ++k )
		{
			int32_t* const* m = collide->member;
			float u = collide->weight[0][k], v = collide->weight[1][k], w = collide->weight[2][k];
			float weight =
				k < vertex_contacts
					? inv_m[m[0][k]] + inv_m[m[1][k]] * u * u + inv_m[m[2][k]] * v * v + inv_m[m[3][k]] * w * w
					: inv_m[m[0][k]] * ( 1.0f - u ) * ( 1.0f - u ) + inv_m[m[1][k]] * u * u +
						  inv_m[m[2][k]] * ( 1.0f - v ) * ( 1.0f - v ) + inv_m[m[3][k]] * v * v;
			collide->inv_weight[k] = weight > 0.0f ? 1.0f / weight : 0.0f;
		}
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	float h = params->thickness, h2 = h * h;
	float tolerance = SERE_COLLIDE_TOLERANCE * h;
	float inv_dt = 1.0f / params->dt;
	/* evaluation blocks of each kind, the edge–edge ones after the others */
	int32_t vertex_blocks = ( vertex_contacts + EVALUATE_BLOCK - 1 ) / EVALUATE_BLOCK;
	int32_t blocks = vertex_blocks + ( contacts - vertex_contacts + EVALUATE_BLOCK - 1 ) / EVALUATE_BLOCK;
	int32_t remaining = 0, applied = 0;
	int32_t* far = collide->far_count;
	int threads = sere_team_default();
	threads = threads < collide->slots ? threads : collide->slots;
	/* Per-thread counts of contacts still short of the tolerance, summed by every thread after
	 * a barrier: two barriers per iteration (this one and the gather's), no reduction clause. */
#pragma omp parallel num_threads( threads ) if ( parallel )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		int32_t mine_begin = touched_split( collide, tid, team ), mine_end = touched_split( collide, tid + 1, team );
		/* the sides, only now that every input is known to be finite (an error leaves them) */
		if ( state->x0 != NULL )
		{
#pragma omp for schedule( static )
			for ( int32_t k = 0; k < contacts; ++k )
			{
				bool vertex = k < vertex_contacts;
				float side = history_side( collide, state, k, vertex );
				collide->contact_side[k] = side;
				*( vertex ? &collide->contacts[k].side : &collide->edge_contacts[k - vertex_contacts].side ) = side;
			}
		}
		for ( int32_t it = 0; it <= params->iterations; ++it )
		{
			int32_t mine = 0;
#pragma omp for schedule( static ) nowait
			for ( int32_t block = 0; block < blocks; ++block )
			{
				bool vertex = block < vertex_blocks;
				int32_t begin =
					vertex ? block * EVALUATE_BLOCK : vertex_contacts + ( block - vertex_blocks ) * EVALUATE_BLOCK;
				int32_t last = vertex ? vertex_contacts : contacts;
				int32_t end = begin + EVALUATE_BLOCK < last ? begin + EVALUATE_BLOCK : last;
				mine += vertex ? evaluate_contacts( collide, begin, end, h2, tolerance )
							   : evaluate_edges( collide, begin, end, h2, tolerance );
			}
			far[tid * FAR_STRIDE] = mine;
#pragma omp barrier
			int32_t total = 0;
			for ( int t = 0; t < team; ++t )
			{
				total += far[t * FAR_STRIDE];
			}
			/* every contact within the tolerance, or the iterations spent (the last evaluation
			 * only counts what is left): the same decision on every thread */
			if ( total == 0 || it == params->iterations )
			{
#pragma omp single nowait
				remaining = total;
				break;
			}
			share_pushes( collide, mine_begin, mine_end, contacts );
			int32_t j = mine_begin;
			for ( ; j + 1 < mine_end; j += 2 )
			{
				gather_apply_pair( collide, j, inv_m, params->relaxation );
			}
			if ( j < mine_end )
			{
				gather_apply( collide, j, inv_m, params->relaxation );
			}
			/* also keeps far[] from being rewritten before all have read it */
#pragma omp barrier
#pragma omp single nowait
			applied += 1;
		}
		/* the gather's share: each thread reads the sums it wrote */
		for ( int32_t j = mine_begin; j < mine_end; ++j )
		{
			int32_t i = collide->touched[j];
			const float* position = collide->position + 4 * (size_t) i;
			const float* acc = collide->acc + 4 * (size_t) j;
			state->x[i] = position[0], state->y[i] = position[1], state->z[i] = position[2];
			state->vx[i] += acc[0] * inv_dt;
			state->vy[i] += acc[1] * inv_dt;
			state->vz[i] += acc[2] * inv_dt;
		}
	}
	*unresolved = remaining;
	*iterations = applied;
	return SERE_OK;
}

sere_status sere_collide_respond( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, int32_t* unresolved )
{
	int32_t remaining, iterations;
	sere_status status = respond( collide, bvh, state, params, &remaining, &iterations );
	if ( status == SERE_OK && unresolved != NULL )
	{
		*unresolved = remaining;
	}
	return status;
}

sere_status sere_collide_resolve( sere_collide* collide, sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, sere_collide_stats* stats )
{
	if ( collide == NULL || bvh == NULL || !state_valid( state ) || !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_collide_stats local = { 0 };
	sere_status status = sere_bvh_update( bvh, state->x, state->y, state->z, params->rebuild_ratio, &local.rebuilt );
	for ( int32_t round = 0; status == SERE_OK && round < params->rounds; ++round )
	{
		if ( round > 0 )
		{
			status = sere_bvh_refit( bvh, state->x, state->y, state->z );
			if ( status != SERE_OK )
			{
				break;
			}
		}
		int32_t found = 0;
		status = sere_collide_detect( collide, bvh, state->x, state->y, state->z, params->thickness, &found );
		if ( round == 0 )
		{
			local.contacts = found;
			local.edge_contacts = collide->edge_found < INT32_MAX ? (int32_t) collide->edge_found : INT32_MAX;
		}
		if ( status != SERE_OK )
		{
			break;
		}
		local.rounds += 1;
		local.unresolved = 0;
		if ( found == 0 && collide->edge_contact_count == 0 )
		{
			break;
		}
		int32_t iterations = 0;
		status = respond( collide, bvh, state, params, &local.unresolved, &iterations );
		local.iterations += iterations;
	}
	if ( stats != NULL )
	{
		*stats = local;
	}
	return status;
}

sere_status sere_collide_measure_h( const float* x, const float* y, const float* z, const int32_t* tri,
									int32_t triangle_count, int32_t voronoi_first, float* h_hat )
{
	if ( x == NULL || y == NULL || z == NULL || tri == NULL || h_hat == NULL || triangle_count < 0 ||
		 voronoi_first < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
#pragma omp parallel for num_threads( sere_team_default() ) reduction( | : bad ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		float a[3], b[3], c[3], n[3], p[3];
		triangle_frame( x, y, z, tri + 3 * (size_t) t, a, b, c, n );
		load3( x, y, z, voronoi_first + t, p );
		/* Algorithm 1 line 14 */
		float h = ( p[0] - a[0] ) * n[0] + ( p[1] - a[1] ) * n[1] + ( p[2] - a[2] ) * n[2];
		/* a NaN or infinity in any of the four points reaches h through n or the difference */
		bad |= !isfinite( h );
		h_hat[t] = isfinite( h ) ? h : 0.0f;
	}
	return bad ? SERE_ERR_NONFINITE : SERE_OK;
}

sere_status sere_collide_restore_voronoi( float* x, float* y, float* z, float* vx, float* vy, float* vz,
										  const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
										  const float* h )
{
	if ( x == NULL || y == NULL || z == NULL || vx == NULL || vy == NULL || vz == NULL || tri == NULL || h == NULL ||
		 triangle_count < 0 || voronoi_first < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* Check everything read before writing anything: the corners (all below voronoi_first, so
	 * contiguous scans, and never a Voronoi particle being written) and the thicknesses. */
	/* Two reductions in one region need two variables: with a shared one, the first loop's
	 * combine could race with the second's. */
	int bad = 0, bad_h = 0, outside = 0;
#pragma omp parallel num_threads( sere_team_default() )
	{
#pragma omp for reduction( | : bad ) schedule( static ) nowait
		for ( int32_t i = 0; i < voronoi_first; ++i )
		{
			bad |= !( isfinite( x[i] ) && isfinite( y[i] ) && isfinite( z[i] ) && isfinite( vx[i] ) &&
					  isfinite( vy[i] ) && isfinite( vz[i] ) );
		}
#pragma omp for reduction( | : bad_h, outside ) schedule( static )
		for ( int32_t t = 0; t < triangle_count; ++t )
		{
			bad_h |= !isfinite( h[t] );
			outside |= tri[3 * t] < 0 || tri[3 * t] >= voronoi_first || tri[3 * t + 1] < 0 ||
					   tri[3 * t + 1] >= voronoi_first || tri[3 * t + 2] < 0 || tri[3 * t + 2] >= voronoi_first;
		}
	}
	if ( outside )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( bad || bad_h )
	{
		return SERE_ERR_NONFINITE;
	}
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		float a[3], b[3], c[3], n[3];
		triangle_frame( x, y, z, v, a, b, c, n );
		int32_t i = voronoi_first + t;
		/* Jeong Eq. 14 */
		x[i] = ( a[0] + b[0] + c[0] ) / 3.0f + h[t] * n[0];
		y[i] = ( a[1] + b[1] + c[1] ) / 3.0f + h[t] * n[1];
		z[i] = ( a[2] + b[2] + c[2] ) / 3.0f + h[t] * n[2];
		vx[i] = ( vx[v[0]] + vx[v[1]] + vx[v[2]] ) / 3.0f;
		vy[i] = ( vy[v[0]] + vy[v[1]] + vy[v[2]] ) / 3.0f;
		vz[i] = ( vz[v[0]] + vz[v[1]] + vz[v[2]] ) / 3.0f;
	}
	return SERE_OK;
}

sere_status sere_collide_restore_voronoi_moved( float* x, float* y, float* z, float* vx, float* vy, float* vz,
												const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
												const float* h, const uint8_t* moved, float dt )
{
	if ( x == NULL || y == NULL || z == NULL || vx == NULL || vy == NULL || vz == NULL || tri == NULL || h == NULL ||
		 moved == NULL || triangle_count < 0 || voronoi_first < 0 || !( dt > 0.0f ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0, outside = 0;
#pragma omp parallel for num_threads( sere_team_default() ) reduction( | : bad, outside ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		outside |=
			v[0] < 0 || v[0] >= voronoi_first || v[1] < 0 || v[1] >= voronoi_first || v[2] < 0 || v[2] >= voronoi_first;
		bad |= !isfinite( h[t] );
	}
	if ( outside )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	const float inv_dt = 1.0f / dt;
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		if ( !( moved[v[0]] | moved[v[1]] | moved[v[2]] ) )
		{
			continue;
		}
		float a[3], b[3], c[3], n[3];
		triangle_frame( x, y, z, v, a, b, c, n );
		int32_t i = voronoi_first + t;
		/* only a Voronoi particle the collision pushed through its triangle (Sec. 5.3) */
		float height = ( x[i] - ( a[0] + b[0] + c[0] ) / 3.0f ) * n[0] +
					   ( y[i] - ( a[1] + b[1] + c[1] ) / 3.0f ) * n[1] +
					   ( z[i] - ( a[2] + b[2] + c[2] ) / 3.0f ) * n[2];
		if ( height * h[t] > 0.0f )
		{
			continue;
		}
		/* Jeong Eq. 14 */
		float tx = ( a[0] + b[0] + c[0] ) / 3.0f + h[t] * n[0];
		float ty = ( a[1] + b[1] + c[1] ) / 3.0f + h[t] * n[1];
		float tz = ( a[2] + b[2] + c[2] ) / 3.0f + h[t] * n[2];
		/* Sec. 5.2: a position change Δx changes the velocity by Δx/Δt, as every other
		 * correction of the frame does. */
		vx[i] += ( tx - x[i] ) * inv_dt;
		vy[i] += ( ty - y[i] ) * inv_dt;
		vz[i] += ( tz - z[i] ) * inv_dt;
		x[i] = tx, y[i] = ty, z[i] = tz;
	}
	return SERE_OK;
}
