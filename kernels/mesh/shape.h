/* sere — a leaf described in the plane: outline, veins and the base (petiole). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* One vein polyline: points [first, first + count) of sere_leaf_shape::vein_xy. Order 1 is the
 * midvein; parent is the index of the vein it branches from (-1 for veins that start at the
 * base). Its first point lies on the parent vein (or is the base). */
typedef struct sere_vein
{
	int32_t first;
	int32_t count;
	int32_t order;
	int32_t parent;
} sere_vein;

/* The plane description every model starts from (Sec. 3.1, Fig. 3a-b). The outline is a simple
 * polygon given counter-clockwise without repeating its first point; the base lies on it. The
 * caller owns every array. */
typedef struct sere_leaf_shape
{
	double base_x, base_y;
	int32_t outline_count;
	const double* outline_xy; /* x0 y0 x1 y1 ... */
	int32_t vein_count;
	const sere_vein* veins;
	int32_t vein_point_count;
	const double* vein_xy;
} sere_leaf_shape;

/* Why a shape is not usable, with the offending outline or vein point. */
typedef enum sere_shape_problem
{
	SERE_SHAPE_OK = 0,
	SERE_SHAPE_FEW_OUTLINE_POINTS,
	SERE_SHAPE_NONFINITE,
	SERE_SHAPE_SELF_INTERSECTING,
	SERE_SHAPE_VEIN_OUTSIDE,
	SERE_SHAPE_VEIN_DISCONNECTED,
	SERE_SHAPE_BAD_VEIN,
	SERE_SHAPE_BASE_OFF_OUTLINE,
	SERE_SHAPE_CLOCKWISE,
	SERE_SHAPE_REPEATED_POINT,
	SERE_SHAPE_VEIN_CROSSES_OUTLINE,
	SERE_SHAPE_VEINS_CROSS,
} sere_shape_problem;

/* Where a problem is. For two crossing pieces, point is the end of the segment that comes later
 * in the arrays (outline edges before vein segments) and other the end of the segment it meets;
 * both index the outline for SELF_INTERSECTING, the vein points for VEINS_CROSS, and for
 * VEIN_CROSSES_OUTLINE point is a vein point and other an outline point. */
typedef struct sere_shape_check
{
	sere_shape_problem problem;
	int32_t vein;  /* the vein at fault, or -1 */
	int32_t point; /* the outline point (outline problems) or vein point index, or -1 */
	int32_t other; /* the second point of a crossing, or -1 */
} sere_shape_check;

/* Points count as "on" a curve (the base on the outline, a branch on its parent vein, a vein
 * touching another at its first point) within this fraction of the outline's larger
 * bounding-box side: loose enough for coordinates written with 6 significant digits. */
#define SERE_SHAPE_TOLERANCE 1e-4

/* Validates a shape without changing it; fills check and returns SERE_ERR_GEOMETRY (or
 * SERE_ERR_NONFINITE) when it is not usable. The outline must be simple and counter-clockwise
 * (orientation is reported, not fixed), the base on it, every vein point after the first
 * strictly inside, and no two vein segments may meet except where a vein starts (on its parent,
 * at the base, or beside a sibling starting at the same point). Segment pairs are found with a
 * uniform grid, so the cost is about linear in the number of points for leaf-like shapes. */
sere_status sere_shape_validate( const sere_leaf_shape* shape, sere_shape_check* check );
const char* sere_shape_problem_text( sere_shape_problem problem );

/* Signed area of the outline (positive when counter-clockwise) and its perimeter. */
double sere_shape_area( const sere_leaf_shape* shape );
double sere_shape_perimeter( const sere_leaf_shape* shape );

#ifdef __cplusplus
}
#endif
