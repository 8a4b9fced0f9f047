/* sere harness — pictures of a drying leaf's 3D shape: an oblique view with the ground it
 * rests on and its shadow, and the top view, for a few frames of a run side by side at one
 * scale, so the curling and the shrinking both show.
 *
 * Colors: the paper's fresh-to-dry blend of the relative water content per vertex
 * (sere_render_dry_colors) on the upper face (the side of +z at rest, triangles
 * counter-clockwise seen from +z); the lower face in sere_render_lower_tint of it (paler,
 * greyer). The ground is a light gray tile under the leaf with the leaf's vertical shadow.
 *
 * Every function returns SERE_OK, or a sere_status with one line in err that starts with the
 * output path.
 * PNGs are written to "<path>.tmp" and renamed (sere_render_canvas_write_png). */
#pragma once

#include "core/base.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* The oblique camera of the pictures, in degrees (sere_render_view's conventions). */
#define SERE_LEAFPICS_AZIMUTH	   ( -35.0 )
#define SERE_LEAFPICS_ELEVATION	   30.0
#define SERE_LEAFPICS_PANEL_WIDTH  340
#define SERE_LEAFPICS_PANEL_HEIGHT 280

/* One frame of a run: vertex positions (z may be NULL: a flat leaf at z = 0), the relative
 * water content per vertex (rwc may be NULL: the whole leaf colored by relative_water), the
 * frame number and the leaf's relative water content for the caption. */
typedef struct sere_leafpics_frame
{
	const float *x, *y, *z;
	const float* rwc;
	int32_t vertex_count;
	int frame;
	double relative_water;
} sere_leafpics_frame;

/* One PNG contact sheet: a column per frame (in the order given, e.g. fresh, middle, dry)
 * headed "frame N, RWC r", an oblique row (SERE_LEAFPICS_AZIMUTH, SERE_LEAFPICS_ELEVATION)
 * with ground and shadow above a top-view row, and a legend of the colors underneath. Every
 * panel of a row has the same scale (the largest that fits every frame) and the ground tile the
 * same size (the largest footprint grown by a fifth of its larger side each way), centred on
 * each frame's leaf, so a drifting leaf stays in view while its shrinking shows.
 * ground_z is the plane the leaf rests on (the run's ground); not finite (-INFINITY: the run
 * has none) puts the ground at each frame's lowest point, under the leaf's lowest vertex.
 * title may be NULL. frame_count is 1..16; tri holds 3 tri_count vertex indices valid for
 * every frame. Panels are SERE_LEAFPICS_PANEL_WIDTH x SERE_LEAFPICS_PANEL_HEIGHT; the sheet is
 * max(760, 34 + 352 frame_count) pixels wide and 694 high (662 without a title). */
sere_status sere_leafpics_sheet( const char* path, const char* title, int frame_count,
								 const sere_leafpics_frame* frames, const int32_t* tri, int32_t tri_count,
								 float ground_z, char* err, size_t err_size );

/* The oblique view of one frame alone as a size x size PNG (size <= 0: 900), with ground,
 * shadow, title (may be NULL) and the caption "frame N, RWC r": a gallery picture. */
sere_status sere_leafpics_view( const char* path, const char* title, const sere_leafpics_frame* frame,
								const int32_t* tri, int32_t tri_count, float ground_z, int size, char* err,
								size_t err_size );

#ifdef __cplusplus
}
#endif
