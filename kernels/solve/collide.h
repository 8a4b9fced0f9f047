/* sere — self-collision of the triangle layer (Sec. 5.3): vertex–triangle and edge–edge
 * proximity found with a BVH (Bridson, Fedkiw, Anderson 2002), push-out along the triangle's or
 * the two edges' normal shared by inverse mass, and the Voronoi restore of Jeong Eq. 14. Usable for
 * any triangle mesh given as SoA positions and index triples. */
#pragma once

#include "solve/bvh.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* A contact: vertex closer than the thickness to a triangle it is not a corner of. A vertex
 * joined by an edge to a corner sits in the sheet beside the triangle, as close as the mesh is
 * fine, and counts only when its closest point lies inside the face (u, v, w all positive),
 * which takes the sheet between them folded past a right angle. The closest point on the
 * triangle is u a + v b + w c (barycentric, u + v + w = 1). side is +1 when the vertex lies on
 * the side the triangle's counter-clockwise normal n = (b − a) × (c − a) points to, −1
 * otherwise, measured at detection as the sign of (p − closest) · n (+1 when zero); the response
 * pushes the vertex out on that side, or on the side it was on at the start of the step when the
 * state carries those positions (sere_collide_state.x0: side is then rewritten). */
typedef struct sere_contact
{
	int32_t vertex;
	int32_t triangle;
	float u, v, w;
	float distance;
	float side;
} sere_contact;

/* An edge–edge contact: two mesh edges sharing no vertex, closer than the thickness, whose
 * closest points lie strictly inside both (and not closer than the thickness at rest, when the
 * workspace has rest positions: sere_collide_set_rest). Two edges can pass through each other with every
 * vertex far from every triangle; only this pair sees it coming. (Where a closest point is an
 * end, that vertex is within the thickness of the other edge's triangles, which the
 * vertex–triangle contacts see.) The edges are (a0, a1) and (b0, b1), each with its lower index first and a0 below
 * b0; the closest points are p = a0 + s (a1 − a0) and q = b0 + t (b1 − b0), s and t in (0, 1).
 * side is +1 when p lies on the side n = (a1 − a0) × (b1 − b0) points to from q, −1 otherwise,
 * measured at detection as the sign of (p − q) · n (+1 when zero): the sign that flips when the
 * edges pass through each other. The response pushes p and q apart along ±n on that side, or on
 * the side they were on at the start of the step when the state carries those positions (side is
 * then rewritten), as for sere_contact. */
typedef struct sere_edge_contact
{
	int32_t a0, a1;
	int32_t b0, b1;
	float s, t;
	float distance;
	float side;
} sere_edge_contact;

/* The deforming layer the response moves: positions, velocities and inverse masses (0 pins a
 * vertex) of the BVH's vertices, caller-owned SoA arrays. Only the first vertex_count entries
 * are used, so a sere_particles whose triangle layer comes first can be passed as is. */
typedef struct sere_collide_state
{
	float *x, *y, *z;
	float *vx, *vy, *vz;
	const float* inv_m;
	/* Optional (all three or none): the positions at the start of the step, before the dynamics
	 * moved the mesh. When given, the response pushes each vertex out on the side of the
	 * triangle it was on there (the sign of (p₀ − q₀) · n₀ at the detection weights; the
	 * detection side where that is 0), not where detection finds it: a vertex the step carried
	 * through a triangle goes back instead of being pushed further through, which would lock the
	 * sheets into each other (the start-of-step state of Bridson et al. 2002). On the maple-green
	 * maple after 400 frames this leaves 1137 edges through a triangle instead of 1925. Edge–edge
	 * contacts take their side the same way, from the sign of (p₀ − q₀) · n₀. */
	const float *x0, *y0, *z0;
} sere_collide_state;

typedef struct sere_collide_params
{
	float thickness;	  /* contact when the vertex–triangle or edge–edge distance is below it */
	float dt;			  /* time step: velocities change by Δx / dt */
	int32_t iterations;	  /* Jacobi response iterations per round (stops early once all are resolved) */
	int32_t rounds;		  /* detect + respond rounds; later rounds catch contacts made by the push-out */
	float relaxation;	  /* ω of the shared update, in (0, 2]: see sere_collide_respond */
	double rebuild_ratio; /* BVH quality ratio that triggers a rebuild (SERE_BVH_REBUILD_RATIO) */
} sere_collide_params;

/* A contact counts as resolved once the push it still needs is below this fraction of the
 * thickness; the response stops when every contact is. */
#define SERE_COLLIDE_TOLERANCE 1e-3f

typedef struct sere_collide_stats
{
	int32_t contacts;	   /* vertex–triangle contacts found by the first detection */
	int32_t edge_contacts; /* edge–edge contacts found by the first detection */
	int32_t unresolved;	   /* contacts (both kinds) of the last round short of the thickness by over the tolerance */
	int32_t iterations;	   /* response iterations run, summed over rounds */
	int32_t rounds;		   /* rounds run (a round finding no contact ends the loop) */
	bool rebuilt;		   /* the BVH was rebuilt rather than only refit */
} sere_collide_stats;

sere_collide_params sere_collide_params_default( void );

typedef struct sere_collide sere_collide;

/* A workspace for the BVH's mesh holding up to contact_capacity contacts of each kind, vertex–
 * triangle and edge–edge (0 picks 8 per vertex). The mesh's edges are listed here, once, from
 * its triangles. Per-thread buffers are made for omp_get_max_threads() threads at this call, and
 * for more by sere_collide_set_threads. On success the caller frees with sere_collide_destroy. */
sere_status sere_collide_create( const sere_bvh* bvh, int32_t contact_capacity, sere_collide** out );
void sere_collide_destroy( sere_collide* collide );

/* The threads detection and response run with (core/base.h: 0, the initial count, is OpenMP's
 * count at each call, then at most the threads this workspace has buffers for). A count above
 * those makes buffers for it (allocates; the contact and candidate lists are dropped).
 * SERE_ERR_ARGUMENT above SERE_MAX_THREADS, SERE_ERR_MEMORY (nothing changed) when the buffers
 * cannot be made. */
sere_status sere_collide_set_threads( sere_collide* collide, int32_t threads );

/* Grows the contact capacity of each kind (allocates: call it between frames after
 * SERE_ERR_CAPACITY). */
sere_status sere_collide_reserve( sere_collide* collide, int32_t contact_capacity );

/* Every (vertex, triangle) pair with the vertex not a corner of the triangle and their distance
 * (sere_closest_point_triangle) below thickness, where a vertex joined by a mesh edge to a corner
 * counts only with its closest point inside the face (see sere_contact); and every pair of mesh
 * edges sharing no vertex whose closest points (sere_closest_points_segments) lie strictly inside
 * both and are closer than thickness, but for pairs closer than thickness at rest when
 * sere_collide_set_rest gave rest positions. The BVH must be refit to these positions. Eight
 * consecutive vertices query it together (sere_bvh_query_group), once for their contacts with
 * triangles and once for the edges they are the lower end of, so number the vertices in a
 * spatially coherent order (sere_model uses Morton order); blocks of vertices run in parallel and
 * each list keeps block order, then the tree's order within a group: it is the same for every
 * thread count. *contact_count gets the number of vertex–triangle contacts found
 * (sere_collide_contacts lists them, sere_collide_edge_contacts the edge–edge ones);
 * SERE_ERR_CAPACITY when either kind exceeds the capacity (all contacts are then dropped;
 * sere_collide_resolve's stats count both kinds), SERE_ERR_NONFINITE for NaN or infinite
 * positions. */
sere_status sere_collide_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
								 const float* z, float thickness, int32_t* contact_count );

/* The sheet's rest positions (the first vertex_count entries of each array, copied; all three
 * NULL forgets them). With them, two edges whose segments lie closer than the detection's
 * thickness at rest are neighbours in the sheet and never an edge–edge contact: a strip narrower
 * than the thickness (a petiole at fine sampling) has its two sides that close at rest, and
 * pushing them apart along e × f shoved one side up and the other down every frame while the
 * springs pulled them back (the Table 1 maple's petiole tip buzzed by up to 0.0018 a frame, 40
 * times the blade's motion, and the candidate list broke in one frame of five). Folded shut, such
 * a strip is held by the vertex–triangle contacts (a neighbour over the face). Without rest
 * positions every pair of edges sharing no vertex counts. SERE_ERR_ARGUMENT for a NULL collide
 * or some but not all of x, y, z NULL; SERE_ERR_NONFINITE (nothing changed) for NaN or infinity;
 * SERE_ERR_MEMORY (the rest positions forgotten). */
sere_status sere_collide_set_rest( sere_collide* collide, const float* x, const float* y, const float* z );

/* Detections served by the current candidate list without searching the tree, since the
 * detection that searched and made it (0 right after that one; see SKIN in collide.c). A
 * detection finds the same contacts, bit for bit and in the same order, either way; this only
 * says which way it went, for tests and benchmarks. */
int32_t sere_collide_list_uses( const sere_collide* collide );

/* Drops the candidate list: the next detection searches the tree (and makes a new list). It
 * finds the same contacts as it would have from the list; benchmarks use this to time the
 * search. */
void sere_collide_drop_list( sere_collide* collide );

/* What a searching detection or a served pass moved, as sere_collide_record_search or
 * sere_collide_record_served recorded it and sere_collide_touch_search or sere_collide_touch_served
 * replayed it. */
typedef struct sere_collide_traffic
{
	int64_t nodes;		 /* tree nodes opened, by both kinds of query (none when served) */
	int64_t leaves;		 /* triangles the walks visited */
	int64_t bound_pairs; /* pairs gathered for the separating-plane bounds, both kinds */
	int64_t exact_pairs; /* pairs gathered for the exact tests: the candidate list's */
	int64_t contacts;	 /* contacts listed, both kinds */
	int64_t evaluated;	 /* a served pass: contacts its response evaluated, summed over its iterations */
	int64_t gathered;	 /* a served pass: gather-list entries its response's iterations read */
} sere_collide_traffic;

/* A searching detection (sere_collide_detect after sere_collide_drop_list: the same contacts, bits
 * and candidate list) that also records, for sere_collide_touch_search, which nodes its walks
 * opened, which triangles they visited with which lanes, and what each bound and exact test
 * decided. traffic (may be NULL) gets what it moved. Errors as sere_collide_detect's, plus
 * SERE_ERR_MEMORY when the record cannot be kept (no record then). */
sere_status sere_collide_record_search( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
										const float* z, float thickness, sere_collide_traffic* traffic );

/* The memory floor of the recorded search (benchmarks): the search's passes on its runs of blocks
 * (on the threads a detection would run with now, at most the recorded ones), with its loops and
 * their branches, but each test's outcome read from the record in place of its arithmetic, and
 * adds in place of the rest, so that it moves the same memory in the same order: the across
 * vectors' inputs (each edge's first triangle and ends, and their positions); per query group its
 * lanes' vertices, and the lane marks set and cleared; every box and child of each node the walks
 * open (and the subtree corner bounds the edge walks read); per visited triangle its corners'
 * indices and marks, or the edges it owns and their ends; the positions, edge ends, across vectors
 * and rest positions every bound and exact test gathers; and it stores the candidate list, the
 * contacts, the positions the list keeps and the response's gather lists (built as the search
 * builds them), each with the value already there (a float times a 1 the compiler cannot see).
 * Reading the record (a byte per walk, node, visited triangle, 8 table rows and batch of 8 pairs)
 * is traffic the search does not have; the search's per-thread scratch work (query boxes, the edge
 * table's rows, the tests' own arithmetic) and its timing of the blocks are left out. Leaves the
 * positions, contacts and candidate list bitwise as the recorded search left them. traffic (may be
 * NULL) gets what it moved: the record's counts when the replay is faithful. SERE_ERR_ARGUMENT for
 * a NULL argument, or when the workspace has no record of a search (none, or a served pass's), or
 * has detected (or changed threads, capacity or rest positions) since, or the tree was rebuilt. */
sere_status sere_collide_touch_search( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									   const float* z, sere_collide_traffic* traffic );

/* One pass of sere_collide_resolve whose detection the candidate list serves (params->rounds 1:
 * the same contacts, pushes and state as that pass), that also records, for
 * sere_collide_touch_served, what each exact test decided and which contacts each iteration of
 * the response pushed. A pair of its own beside the search's rather than a mode of it: a served
 * pass is a resolve, which takes the caller's state and parameters and responds, and what it
 * replays has no walks. traffic (may be NULL) gets what it moved. SERE_ERR_ARGUMENT (nothing
 * changed) for what sere_collide_resolve refuses, params->rounds other than 1, or a list that does
 * not serve these positions (the pass would search); other errors as sere_collide_resolve's, plus
 * SERE_ERR_MEMORY when the record cannot be kept (no record then). The record replaces the
 * search's, if any. */
sere_status sere_collide_record_served( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
										const sere_collide_params* params, sere_collide_traffic* traffic );

/* The memory floor of the recorded served pass (benchmarks), as sere_collide_touch_search is the
 * search's and with its record and emitters: the pass's loops, branches and barriers on the threads
 * a pass would run with now (the detection's runs as recorded), each test's outcome read from the
 * record and adds in place of the arithmetic, so that it moves the same memory in the same order.
 * That is the check that the list serves (its passes over the positions and the list's); the
 * replay of every listed pair (its batches copied from the list, their points gathered, each
 * contact written where the pass writes it); the contact listing and gather lists (the pass's own
 * code); then, for the evaluations the recorded response ran, the inputs it checks loaded, the
 * members' points gathered, the corrections stored with the recorded push flags, the pushes
 * shared and gathered, the sides, positions and velocities loaded and stored. The response's
 * scratch (weights, corrections, push counts, moves) takes the sums; the contacts and velocities
 * are stored with the values already there (times one) and the positions copied through the
 * response's records unmoved, so that it leaves them and the candidate list bitwise as the
 * recorded pass left them. Reading the record (a byte per batch of 8 pairs, per 8 contacts an
 * evaluation) is traffic the pass does not have; the detection's timing of its blocks is left
 * out. state: the recorded pass's (the values may differ; with start-of-step positions if it had
 * them). traffic (may be NULL) gets what it moved: the record's counts when the replay is
 * faithful. SERE_ERR_ARGUMENT for a NULL argument or an invalid state, when the last record is
 * not a served pass's, or when the workspace has detected (or changed threads, capacity or rest
 * positions) since, or the tree was rebuilt. */
sere_status sere_collide_touch_served( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
									   sere_collide_traffic* traffic );

const sere_contact* sere_collide_contacts( const sere_collide* collide, int32_t* count );
const sere_edge_contact* sere_collide_edge_contacts( const sere_collide* collide, int32_t* count );

/* Pushes the detected contacts apart. Each iteration evaluates every contact at the current
 * positions at its point of detection q = u a + v b + w c (barycentric weights fixed, as cloth
 * solvers keep them through a response): unit normal n̂ = side · n, height s = (p − q) · n̂
 * and in-plane offset l; the target height is s* = sqrt(thickness² − l²), so moving along n̂
 * makes the distance exactly the thickness. The constraint C = s − s* < 0 is solved as in
 * position-based cloth: λ = −C / W with W = w_p + Σ w_k b_k², the vertex moves by w_p λ n̂
 * and corner k by −w_k b_k λ n̂. An edge–edge contact is the same constraint between
 * p = (1 − s) a0 + s a1 and q = (1 − t) b0 + t b1 along n = (a1 − a0) × (b1 − b0), with
 * W = w_a0 (1 − s)² + w_a1 s² + w_b0 (1 − t)² + w_b1 t²: a0 moves by w_a0 (1 − s) λ n̂, b0 by
 * −w_b0 (1 − t) λ n̂, and so on. Each pushing contact's correction is divided by the largest
 * number of pushing contacts any of its four members takes part in, so that every member takes
 * the same share and the contact moves no momentum (dividing each vertex's sum by its own count,
 * Macklin et al. 2014, does); every vertex then gathers those corrections in contact order and
 * moves by ω times their sum (never scattered in thread order, so the result is bitwise the same
 * for every thread count). ω = 1 solves an isolated contact exactly; up to 2
 * converges faster where contacts crowd (a U-fold: 4 iterations instead of 16) but overshoots
 * isolated ones by ω − 1. Iterations stop once every contact is within
 * SERE_COLLIDE_TOLERANCE. Velocities change by the total Δx / dt, as the paper's PBD does
 * (Sec. 5.2). Degenerate triangles and parallel edges give no push. *unresolved (may be NULL) gets the
 * contacts of either kind still short by more than the tolerance. SERE_ERR_NONFINITE (positions and contacts untouched)
 * for NaN or infinity in a contact vertex's velocity, inverse mass or start-of-step position;
 * SERE_ERR_ARGUMENT when x0, y0, z0 are neither all given nor all NULL. */
sere_status sere_collide_respond( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, int32_t* unresolved );

/* One self-collision pass of Algorithm 1 (line 23): refit the BVH (rebuilding it past
 * params->rebuild_ratio), then params->rounds times detect and respond, refitting between rounds.
 * When the candidate list serves the first detection (sere_collide_list_uses), that detection
 * does not read the tree and the first refit is skipped: the tree then still bounds the positions
 * of the last search; refit it before querying it yourself.
 * stats may be NULL. An error in the first round leaves the state untouched; one in a later
 * round (SERE_ERR_CAPACITY) keeps the pushes of the rounds before it. */
sere_status sere_collide_resolve( sere_collide* collide, sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, sere_collide_stats* stats );

/* ĥ_t = (x_t^V − x_a) · n_t for each triangle t = (a, b, c), n_t its unit normal and x_t^V the
 * Voronoi particle voronoi_first + t (Algorithm 1 line 14: stored before collisions). A
 * degenerate triangle gives 0. On `threads` threads (core/base.h), as the two below. */
sere_status sere_collide_measure_h( const float* x, const float* y, const float* z, const int32_t* tri,
									int32_t triangle_count, int32_t voronoi_first, float* h_hat, int32_t threads );

/* ĥ_t of sere_collide_measure_h, measured after the pass for the triangles it moved: only for a
 * triangle with a corner flagged in moved (per triangle-layer particle), from its corners as they
 * were before the pass (cx, cy, cz, voronoi_first entries each) and its Voronoi particle in x, y,
 * z (which the pass does not move). Every other h_hat[t] is left as it is. This is the ĥ the
 * Voronoi restore reads, without measuring every triangle before every pass (Algorithm 1 line 14
 * stores it for all). The same arithmetic as sere_collide_measure_h, so the same bits.
 * SERE_ERR_ARGUMENT for a corner outside [0, voronoi_first); SERE_ERR_NONFINITE where a measured ĥ
 * is NaN or infinite (0 written there). On either, h_hat may be partly written. */
sere_status sere_collide_measure_h_moved( const float* cx, const float* cy, const float* cz, const float* x,
										  const float* y, const float* z, const int32_t* tri, int32_t triangle_count,
										  int32_t voronoi_first, const uint8_t* moved, float* h_hat, int32_t threads );

/* Jeong Eq. 14: x_t^V = (x_a + x_b + x_c) / 3 + h_t n_t and v_t^V = (v_a + v_b + v_c) / 3, with h the
 * ĥ of sere_collide_measure_h or the rest thickness (the two modes of Sec. 5.3), for Voronoi
 * particle voronoi_first + t. Every corner must lie below voronoi_first (the triangle layer comes
 * first, docs/DESIGN.md), else SERE_ERR_ARGUMENT. A degenerate triangle puts its particle at the
 * centroid. SERE_ERR_NONFINITE (nothing written) for NaN or infinity in the triangle layer's
 * positions or velocities or in h. */
sere_status sere_collide_restore_voronoi( float* x, float* y, float* z, float* vx, float* vy, float* vz,
										  const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
										  const float* h, int32_t threads );

/* Jeong Eq. 14 where the collision response acted (Sec. 5.3: "when a particle on the triangle layer
 * passes through the Voronoi layer as a result of a displacement introduced to correct a
 * self-collision, the positions and velocities of Voronoi particles are also modified"): only
 * for triangles with a corner flagged in moved (per triangle-layer particle) whose Voronoi
 * particle the move has left on the wrong side of the triangle (its height along n_t no longer
 * has the sign of h_t, or is 0), x_t^V is set to the centroid + h_t n_t and its velocity changed
 * by the displacement over dt. Every other triangle keeps the Voronoi particle the projection
 * placed, and the next frame's link springs bring it back to its thickness with the triangle's
 * corners sharing the push. Restoring every triangle with a moved corner teleported deep
 * Voronoi particles by up to 2.5 times the push (a corner pushed by δ turns n by about
 * δ / spacing, and h_vein is 2.5 spacings), and those one-sided moves carried a green maple's
 * centre of mass 0.01 L over its run. Unlike Jeong Eq. 14 applied to
 * every triangle with the corners' mean velocity, this injects no velocity where nothing
 * collided: that version, on a curled leaf, lifted the whole leaf frame after frame. Errors as
 * sere_collide_restore_voronoi (positions and velocities of the corners are not checked), plus
 * SERE_ERR_ARGUMENT for a NULL moved or dt <= 0. */
sere_status sere_collide_restore_voronoi_moved( float* x, float* y, float* z, float* vx, float* vy, float* vz,
												const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
												const float* h, const uint8_t* moved, float dt, int32_t threads );

/* Closest point on triangle abc to p by Ericson's walk over the Voronoi regions of the
 * vertices, edges and face: returns the squared distance and writes the barycentric weights of
 * the closest point. Degenerate triangles fall back to the nearest of the three edges. */
float sere_closest_point_triangle( const float p[3], const float a[3], const float b[3], const float c[3],
								   float weights[3] );

/* Closest points of the segments p0 p1 and q0 q1 by Ericson's clamped solution of the two lines'
 * closest points: returns the squared distance of p0 + s (p1 − p0) and q0 + t (q1 − q0) and
 * writes weights = { s, t }, both in [0, 1]. Segments at an angle whose sin² is at most 2⁻²⁰
 * (parallel to 0.06°), or a first one of zero length, take s = 0, then t and s clamped in turn; a
 * second one of zero length takes t = 0 and s clamped: a closest pair at an end, never strictly
 * inside both. */
float sere_closest_points_segments( const float p0[3], const float p1[3], const float q0[3], const float q1[3],
									float weights[2] );

#ifdef __cplusplus
}
#endif
