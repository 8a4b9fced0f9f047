/* sere harness — a leaf from the paper's auxiliary image (Sec. 3.1, Fig. 3a-b).
 *
 * Colors the reader expects in the PNG (any bit depth or color type; alpha below 128 counts
 * as background):
 *   background  white (R, G, B all above 230) or transparent
 *   blade       any other color: the silhouette is the largest connected region of it
 *   veins       red strokes drawn over the blade (R > 180, G < 90, B < 90), a few pixels wide
 *   base        a blue dot on the margin at the petiole (B > 180, R < 90, G < 90)
 * The outline is traced along the silhouette's border, the vein strokes are thinned to
 * one-pixel skeletons and followed from the pixel nearest the base: the longest path is the
 * midvein (order 1), every other branch a vein whose first point lies on the vein it leaves.
 * Coordinates: y up, the base at the origin, the leaf's height scaled to 1. */
#pragma once

#include "leaffile.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Fills leaf (the same owning struct the .leaf reader fills). On failure returns the error
 * and writes one line "PATH: problem" into err. */
sere_status sere_leaf_from_png( const char* path, sere_leaf_file* leaf, char* err, size_t err_size );

#ifdef __cplusplus
}
#endif
