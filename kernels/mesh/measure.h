/* sere — measures of the shape of a leaf's triangle layer, for testing that a drying leaf still
 * looks like a leaf: how often the sheet passes through itself (edge–triangle crossings), and
 * area, size, creases along and between the veins, wrinkling, margin curl, rolling and midvein
 * bending. A C API on plain arrays: a sere_model is measured by passing its first
 * triangle_particles positions, its triangles, its T springs and its flags. */
#pragma once

#include "core/base.h"
#include "mesh/shape.h"

#include <stdbool.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* The crossing predicate both counters share, so that the fast count equals the brute-force
 * count bit for bit: whether segment pq passes through the interior of triangle abc.
 *
 * It is a crossing when the boxes of the segment and of the triangle overlap (closed boxes; a
 * true crossing always passes, and the grid of the fast counter culls by exactly this test), p
 * and q lie strictly on opposite sides of the triangle's plane, and the
 * line pq passes strictly inside all three edges: the five signed volumes
 *   n · (p − a), n · (q − a) with n = (b − a) × (c − a), and
 *   (q − p) · ((a − p) × (b − p)), (q − p) · ((b − p) × (c − p)), (q − p) · ((c − p) × (a − p))
 * have opposite signs for the first two and one common sign for the last three. Any volume
 * that comes out exactly zero means "not a crossing": an end touching the triangle, the segment
 * lying in its plane, or passing through one of its edges or corners. A triangle with two
 * coincident corners has n = 0 exactly and a segment with p = q has zero edge volumes exactly, so
 * neither ever crosses. The ends are taken in lexicographic order of their coordinates, so
 * swapping p and q never changes the answer. The volumes are evaluated in double (not exact arithmetic), so
 * configurations within rounding of touching may fall either way; they fall the same way in
 * both counters because both call this function on the same doubles. */
bool sere_segment_crosses_triangle( const double p[3], const double q[3], const double a[3], const double b[3],
									const double c[3] );

/* sere_segment_crosses_triangle for the mesh edge ea–eb with ends p, q and the mesh triangle
 * with corners v, at the float positions x, y, z converted to double. False when the two share
 * a vertex: a triangle's own edges and the edges meeting it at a corner never cross it. */
bool sere_edge_crosses_triangle( const double p[3], const double q[3], int32_t ea, int32_t eb, const int32_t v[3],
								 const float* x, const float* y, const float* z );

/* Workspace of the fast crossing counter: the unique undirected edges of the triangles and a
 * uniform grid over the triangles' boxes, all allocated once. */
typedef struct sere_crossings sere_crossings;

/* Copies the triangle_count index triples (each index in [0, vertex_count)) and extracts their
 * unique undirected edges (an edge whose two ends are the same index is dropped: a point crosses
 * nothing). SERE_ERR_ARGUMENT for bad sizes or indices. On success free with
 * sere_crossings_destroy. */
sere_status sere_crossings_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count,
								   sere_crossings** out );
void sere_crossings_destroy( sere_crossings* crossings );

/* Number of (edge, triangle) pairs, over every unique edge and every triangle sharing no vertex
 * index with it, for which sere_segment_crosses_triangle holds at the positions x, y, z
 * (vertex_count entries each). A surface passing through itself along a curve gives one pair
 * for every edge of either sheet the curve cuts. Exactly sere_crossings_ref_count, for any
 * thread count: each pair is tested in one grid cell only and the total is an integer sum. No
 * allocation; the grid is re-sized to the current positions on every call (coarser when the
 * sheet is spread out so thinly that the fixed buffers would not hold it).
 * SERE_ERR_NONFINITE (and *count = 0) for NaN or infinite positions of a used vertex. */
sere_status sere_crossings_count( sere_crossings* crossings, const float* x, const float* y, const float* z,
								  int64_t* count );

/* The threads sere_crossings_count runs with (core/base.h: 0, the initial count, is OpenMP's
 * count at each call; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_crossings_set_threads( sere_crossings* crossings, int32_t threads );

/* One call on `threads` threads: create, count, destroy (allocates; use the workspace to count
 * many frames). */
sere_status sere_crossings_count_once( const float* x, const float* y, const float* z, int32_t vertex_count,
									   const int32_t* tri, int32_t triangle_count, int64_t* count, int32_t threads );

/* What sere_shape_measure reads. Lengths are in the units of the positions; angles in radians.
 * For a sere_model m: x, y, z = m.p.x, y, z; u, v = m.u, m.v; vertex_count = m.triangle_particles;
 * tri = m.tri; edge_a, edge_b = m.s.a, m.s.b with edge_count = m.t_springs and edge_vein =
 * m.s.kind (the T springs come first, and SERE_SPRING_VEIN is the only bit a T spring sets);
 * boundary = m.boundary. */
typedef struct sere_shape_input
{
	const float *x, *y, *z; /* current positions of the triangle-layer vertices */
	const float *u, *v;		/* fresh plane coordinates: the leaf at rest in z = 0, base at the origin, tip
							 * towards +v */
	int32_t vertex_count;
	const int32_t* tri; /* 3 per triangle, counter-clockwise seen from +z at rest */
	int32_t triangle_count;
	const int32_t *edge_a, *edge_b; /* every undirected edge of the triangles, once */
	const uint8_t* edge_vein;		/* per edge, nonzero on a vein; may be NULL (no veins) */
	int32_t edge_count;
	const uint8_t* boundary;  /* per vertex, nonzero on the outline */
	double ground;			  /* height of the supporting plane z = ground, or -INFINITY for none */
	double wrinkle_threshold; /* |dihedral| above which an edge counts for wrinkle_sign_changes */
	double band;			  /* half-width δ of the roll cross-sections, as a fraction of the fresh v range */
	/* Optional: the leaf's veins in the fresh plane (the u, v coordinates), for the measures
	 * along and across the main veins (crease_main ... vein_roll_base); NULL leaves them NaN. */
	const sere_leaf_shape* veins;
	int32_t main_order;		/* veins of this order or lower are the main veins (1 the midvein) */
	const int32_t* midvein; /* optional polyline of vertex indices from base to tip, or NULL */
	int32_t midvein_count;
	bool skip_extent; /* true: leave extent NaN (the exact diameter is O(N²); per-frame measures skip it) */
	/* true: measure only the pose (area, centroid, mean_normal, flip, min_z, max_z, ground_gap),
	 * roll_tip and roll_base, which need no edge adjacency, and extent unless skip_extent: every
	 * other measure is NaN, its counts −1. A per-frame watch reads no more, and this skips the
	 * adjacency (a sort of the edges, and with it its checks: no SERE_ERR_GEOMETRY, and no
	 * SERE_ERR_ARGUMENT for an edge listed twice or a triangle edge missing from the list), the
	 * dihedrals and the vein measures. The same bits for what it measures. */
	bool pose_only;
	int32_t threads; /* the measure's threads (core/base.h; 0: OpenMP's count at the call) */
} sere_shape_input;

/* Everything zero or NULL except ground = -INFINITY, wrinkle_threshold = 0.05 rad (about 3°, so
 * that rounding and the slight bending of a nearly flat blade do not count), band = 0.03 and
 * main_order = 2 (the midvein and the veins branching from it: a maple's lobes). */
sere_shape_input sere_shape_input_default( void );

typedef struct sere_shape
{
	double area;		   /* Σ of the current 3D triangle areas (length²) */
	double extent;		   /* largest distance between any two vertices, exact (length) */
	double centroid[3];	   /* area-weighted mean of the triangle centroids (length) */
	double mean_normal[3]; /* Σ area·unit normal / Σ area (counter-clockwise normals, +z at rest): not
							* normalized, so |mean_normal| is 1 for a flat leaf and shrinks as it curls
							* or crumples (dimensionless) */
	bool flip;			   /* mean_normal points down (its z < 0): the leaf has turned over */
	double min_z, max_z;   /* lowest and highest vertex (length) */
	double ground_gap;	   /* min_z − ground, NaN without ground (length) */
	/* Signed dihedral of an interior edge (two triangles): the angle between their unit normals,
	 * positive when the surface folds towards the side the normals point to (a valley seen from
	 * above at rest, as when a leaf cups upwards), negative for a ridge; 0 when flat. */
	double crease_vein;				/* mean |dihedral| over interior vein edges, 0 when none (rad) */
	double crease_surf;				/* the same over interior non-vein edges (rad) */
	int32_t vein_edges, surf_edges; /* how many interior edges each mean is over */
	/* Pairs of interior edges of one triangle whose dihedrals both exceed wrinkle_threshold in
	 * magnitude with opposite signs: 0 for a flat, cupped or rolled leaf (one sign of bending
	 * everywhere), many for a wrinkled or crumpled one (a ridge beside a valley). */
	int64_t wrinkle_sign_changes;
	/* Mean over boundary vertices of their signed distance to the least-squares (orthogonal)
	 * plane of the interior vertices, positive on the side mean_normal points to: > 0 when the
	 * margin curls up towards the upper face, < 0 when it curls down. NaN with fewer than three
	 * interior or no boundary vertices (length). */
	double margin_lift;
	/* Cross-section rolling at the fresh-v fractions 0.85 and 0.25 (sere_shape_roll): the angle
	 * the normal turns through across the section, positive when the margins curl towards the
	 * upper face (rad: 0 flat, π a half tube, 2π a closed tube); NaN for a band too small to say. */
	double roll_tip, roll_base;
	/* Curling along the length: the angle between the current directions of the fresh axis (+v,
	 * base to tip) in the bands at fractions 0.55 and 0.93 (the tip half) and 0.07 and 0.45 (the
	 * base half), each direction the band's fresh-area weighted image of +v (rad, 0 straight, π
	 * turned back on itself; NaN for an empty band). A narrow tip relieves its mismatch by curling
	 * like a scroll rather than rolling its cross-section. */
	double curl_tip, curl_base;
	/* With veins given (NaN otherwise). A vein in the double layer is a rib two triangles wide
	 * whose Voronoi particles sit deeper than the blade's, so a crease along it bends the edges at
	 * and beside the rib rather than the vein edge itself:
	 * crease_main is the mean |dihedral| over interior edges whose fresh midpoint lies within one
	 * spacing (the mean fresh edge length) of a main vein, crease_blade the same over edges two
	 * spacings or more from every main vein (rad). */
	double crease_main, crease_blade;
	/* Each triangle belongs to its nearest main vein (its lobe on a lobed leaf); the sections
	 * across each main vein at 70–95% and at 20–45% of its length roll as roll_tip does, and these
	 * are the means of |roll| over the main veins whose section holds six triangles or more (rad). */
	double vein_roll_tip, vein_roll_base;
	/* 1 / radius of the least-squares circle through the current midvein points (best plane,
	 * then an algebraic circle fit in it); 0 for a straight midvein, and 0 without a midvein or
	 * with fewer than three points (1/length). */
	double midvein_curvature;
} sere_shape;

/* Every measure above, computed sequentially except the diameter (an exact max over all
 * vertex pairs in parallel), so the result is the same for any thread count. Allocates
 * scratch. SERE_ERR_ARGUMENT for null arrays, bad sizes or indices (a vein's points outside
 * vein_xy among them), a triangle edge missing from the edge list, a ground that is NaN or +inf;
 * SERE_ERR_NONFINITE for non-finite positions, plane coordinates or vein points; SERE_ERR_GEOMETRY when an edge has
 * more than two triangles or two triangles run along it in the same direction (not an oriented manifold). */
sere_status sere_shape_measure( const sere_shape_input* in, sere_shape* out );

/* The signed dihedral (as in sere_shape) of every edge of in->edge_a, edge_b into dihedral
 * (edge_count entries; 0 on edges with fewer than two triangles). Errors as sere_shape_measure. */
sere_status sere_shape_dihedrals( const sere_shape_input* in, double* dihedral );

/* Rolling of the cross-section at fresh v = v_min + v_fraction (v_max − v_min): the triangles
 * whose fresh centroid lies within ±band (v_max − v_min) of it. Each triangle's deformation
 * gradient maps the fresh axis (+v) and lateral (+u) directions to current ones; the band's
 * current axis and mean normal follow (fresh-area weighted), each triangle's normal angle θ
 * about that axis is fitted by least squares as a line in its centroid's fresh u, and the slope
 * times the band's fresh width (its corners' u range) is the roll: the angle the normal turns
 * through from one margin to the other, positive when the margins curl towards the side the
 * normals point to. A flat, shrunk, sheared or lengthwise-bent leaf gives 0; a sheet bent into a
 * cylinder about the v axis gives its opening angle exactly (2π closed). Uneven shrinkage or a
 * zigzag of rows does not count, unlike a chord-to-arc ratio. NaN when the band holds fewer than
 * three triangles or they all have the same u. */
sere_status sere_shape_roll( const sere_shape_input* in, double v_fraction, double* roll );

#ifdef __cplusplus
}
#endif
