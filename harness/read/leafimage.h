/* sere harness — a leaf from the paper's auxiliary image (Sec. 3.1, Fig. 3a-b).
 *
 * Colors (8-bit values, after any PNG color type or bit depth is expanded to 8-bit RGBA):
 *   background  white (R, G and B all > 230) or transparent (alpha < 128).
 *   blade       any other color. The largest 4-connected region is the leaf, its holes are
 *               filled; veins, the base dot and anything else drawn on it count as blade (so a
 *               stroke poking out of the blade becomes a bump in the outline).
 *   veins       red strokes over the blade (R > 200, G < 80, B < 80), about 2 to 6 px wide.
 *               Every stroke must touch the network of strokes that starts at the base.
 *   base        required: a blue dot (B > 200, R < 80, G < 80) inside the blade, touching the
 *               margin at the petiole. The base is the outline point nearest the dot's centre;
 *               the veins must start within the dot's radius plus two stroke widths plus 4 px
 *               of that centre (strokes may start under the dot).
 *
 * Processing: the silhouette is traced by marching squares, each crossing placed by the
 * antialiased coverage, then lightly smoothed (Taubin) and simplified (Douglas-Peucker,
 * 0.25 px). The vein strokes are thinned to one-pixel skeletons (Zhang-Suen) and walked from
 * the skeleton pixel nearest the base: the longest path is the midvein (order 1, starting at
 * the base), every other branch a vein of order parent + 1 whose first point is a vertex of its
 * parent; a loop of strokes is opened where the walks meet. A separate stroke that also starts
 * at the base is another order-1 vein (palmate leaves). Spurs shorter than about two stroke
 * widths are dropped; veins are cut where they come within 1% of the leaf length (2 px at
 * least) of the outline, so every vein point after the base lies strictly inside.
 *
 * Coordinates: pixel (i, j) covers [i, i+1) x [j, j+1), j counting down. With the base at pixel
 * position (bx, by) and s the largest distance from it to the traced outline (the leaf's length
 * in pixels), (px, py) maps to x = (px - bx) / s, y = (by - py) / s: the base is the origin and
 * outline point 0, y points up, the leaf is 1 long and its outline counter-clockwise. */
#pragma once

#include "read/leaffile.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Where the leaf sits in its image (see the mapping above). */
typedef struct sere_leaf_image_map
{
	int32_t width, height;
	double base_px, base_py;
	double pixels_per_unit;
} sere_leaf_image_map;

/* Fills leaf (the same owning struct the .leaf reader fills; free with sere_leaf_file_destroy). On
 * failure returns the error, writes one line "PATH: problem" into err and leaves nothing to free.
 * Problems: cannot open, not a PNG file, corrupt PNG, image too large (> 8192 on a side), no
 * leaf, no veins, no base, base dot off the margin, veins not reaching the base, a vein stroke not
 * connected to the network. */
sere_status sere_leaf_from_png( const char* path, sere_leaf_file* leaf, char* err, size_t err_size );

/* The same, also reporting the pixel mapping (map may be NULL). */
sere_status sere_leaf_from_png_mapped( const char* path, sere_leaf_file* leaf, sere_leaf_image_map* map, char* err,
									   size_t err_size );

/* The silhouette alone (seed 002, Sec. 3: the key points a user would click along the edge of
 * a scanned leaf): the largest non-background region of a PNG (the blade colors above), traced,
 * smoothed and simplified as above, in pixel coordinates (x right, y down), counter-clockwise as
 * seen with y up. Point 0 is the base: the outline point nearest the centre of a blue base dot if
 * the image has one, else the outline point nearest the middle of the bottom edge of the
 * silhouette's bounding box (a leaf drawn petiole down). *xy (2 per point) is the caller's to
 * free. Errors as sere_leaf_from_png, one line "PATH: problem". */
sere_status sere_silhouette_from_png( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height,
									  char* err, size_t err_size );

/* Any PNG as 8-bit gray, row 0 at the top: the luminance (0.299 R + 0.587 G + 0.114 B) / 255
 * in [0, 1], transparent pixels black. *gray is the caller's to free. Errors: cannot open, not a
 * PNG, corrupt, too large. */
sere_status sere_png_read_gray( const char* path, float** gray, int32_t* width, int32_t* height, char* err,
								size_t err_size );

#ifdef __cplusplus
}
#endif
