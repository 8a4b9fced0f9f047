/* sere harness — private to the leafimage_*.c files (the leaf from an auxiliary image, see
 * leafimage.h): the reader every stage works on, the traced points, the outline and the vein
 * skeleton, and the stages' entry points. Not part of the harness API. */
#pragma once

#include "read/leafimage.h"

#include <png.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>

#define MAX_SIDE		 8192
#define MIN_BLADE_PIXELS 64
/* Douglas-Peucker tolerances, px. A chord cuts about 2/3 of its sag off a convex rim, so 0.25 px
 * keeps the outline's area within 0.2%; veins only need their course. */
#define OUTLINE_TOLERANCE 0.25
#define VEIN_TOLERANCE	  0.5
/* Taubin lambda|mu passes: enough to remove the staircase of an unantialiased rim. */
#define SMOOTH_PASSES 8
/* Veins stop this fraction of the leaf length (and at least this many pixels) inside the outline. */
#define MARGIN_FRACTION	  0.01
#define MARGIN_MIN_PIXELS 2.0
/* Skeleton pieces smaller than this are specks, not strokes. */
#define DUST_PIXELS 4

enum
{
	KIND_BACKGROUND,
	KIND_BLADE,
	KIND_VEIN,
	KIND_BASE,
};

typedef struct png_failure
{
	jmp_buf jump;
	char message[200];
} png_failure;

/* Everything one read needs; the per-pixel arrays are n = width x height long. */
typedef struct reader
{
	const char* path;
	char* err;
	size_t err_size;
	int w, h;
	int32_t n;
	uint8_t* kind;
	uint8_t* ink;	  /* how far from white (and how opaque) a pixel is, 0..255 */
	uint8_t* ink_max; /* the largest ink in the 5 x 5 window (full coverage nearby); then the dot mask */
	uint8_t* region;  /* the leaf silhouette; then the vein strokes, thinned to their skeleton */
	int32_t* queue;	  /* flood fills; then the pixels being thinned; then pixel -> skeleton index */
	/* libpng state lives here, not in locals, so nothing is clobbered by its longjmp */
	png_failure failure;
	FILE* file;
	png_structp png;
	png_infop info;
	uint8_t* rgba;
	png_bytep* rows;
} reader;

typedef struct points
{
	double* xy;
	int32_t count, capacity;
} points;

/* The outline in leaf coordinates, the base as vertex 0, and the pixel mapping. */
typedef struct outline
{
	double* xy;
	int32_t count;
	double base_px, base_py, scale; /* scale: pixels per leaf unit */
	double dot_distance;			/* from the base dot's centre to the traced outline, px */
} outline;

/* A vein while it is built: nodes [first, first + count) of the node arrays. Node 0 is the base
 * (skeleton index -1) or the pixel on the parent it branches from, at the parent's node attach. */
typedef struct vein_build
{
	int32_t first, count, parent, attach, order;
} vein_build;

typedef struct tip
{
	double length;
	int32_t index;
} tip;

/* The skeleton graph and the veins read from it. Skeleton pixels are numbered in raster order;
 * the pixel -> number map is the reader's queue. */
typedef struct veins_work
{
	int32_t count;
	int32_t* pixel;
	int32_t* component;
	int32_t* bfs_parent;
	int32_t* order_queue;
	double* dist;
	uint8_t* children;
	int32_t* on_vein;
	int32_t* node_pos;
	tip* tips;
	int32_t* path;
	int32_t* node_skeleton;
	double* node_xy;
	uint8_t* node_keep;
	int32_t* node_final;
	vein_build* veins;
	int32_t vein_count, node_count;
	double* scratch;
	int32_t* stack;
} veins_work;

/* One line "PATH: problem" into the caller's buffer; returns status. */
sere_status leafimage_fail( reader* r, sere_status status, const char* format, ... )
	__attribute__( ( format( printf, 3, 4 ) ) );

/* Zhang-Suen thinning of the pixels listed in live (count of them; pixels outside the image
 * count as empty). Each sub-iteration marks pixels 2 and deletes them at its end, so every test
 * in it sees its starting image; the list shrinks with the strokes, so the cost follows the
 * vein pixels, not the image. */
void leafimage_thin( uint8_t* m, int w, int h, int32_t* live, int32_t count );

/* Taubin's lambda|mu smoothing: a shrinking Laplacian step then an inflating one, which removes
 * pixel-scale wiggles without shrinking the curve. Open polylines keep their end points. */
void leafimage_smooth( double* xy, int32_t n, int closed, double* scratch );

/* Simplifies a polyline keeping every vertex already marked in keep. */
void leafimage_simplify_between_kept( const double* xy, int32_t n, double tolerance, uint8_t* keep, int32_t* stack );

/* Distance from p to the closed polygon of n points. */
double leafimage_outline_distance( const double* xy, int32_t n, const double* p );

/* Any PNG (palette, gray, 1-16 bits, with or without alpha or tRNS, interlaced) as 8-bit RGBA. */
sere_status leafimage_load_png( reader* r );

/* The color convention of leafimage.h, and each pixel's ink: max(255 - R, 255 - G, 255 - B)
 * scaled by alpha, which is linear in the coverage of an antialiased rim over white or over
 * transparency, so ink / ink_max estimates how much of a pixel the blade covers. */
void leafimage_classify( reader* r );

/* The silhouette: blade pixels, minus rim pixels less than half covered (so the region's edge
 * is the 50% coverage line), then the largest 4-connected piece with its holes filled. Holes
 * are found by flooding the background 4-connected from the border, so a pocket reached only
 * diagonally is filled too: the region then has no diagonal-only contacts (no marching-squares
 * saddles) and its boundary is one simple loop. Returns the region's pixel count. */
int32_t leafimage_silhouette( reader* r );

/* A reader for one public call: the caller's error buffer cleared, the path named in messages. */
reader leafimage_reader_start( const char* path, char* err, size_t err_size );

/* Loads the PNG, classifies its pixels, finds the silhouette and traces its outline into
 * traced; no_leaf names what was missing when the silhouette is too small. The caller frees
 * traced.xy and the reader's buffers whatever the status. */
sere_status leafimage_trace_png( reader* r, points* traced, const char* no_leaf );

/* The largest 8-connected blue blob: its centre and radius (from its area), px. */
int leafimage_base_dot( reader* r, double* x, double* y, double* radius );

/* Smooths and simplifies the traced loop (each optional), puts the base where the outline
 * passes nearest the dot, maps to leaf coordinates and orients counter-clockwise. Fails with
 * SERE_ERR_GEOMETRY if the result is not a simple polygon (a sub-pixel neck), so the caller can
 * retry with less processing. */
sere_status leafimage_make_outline( const points* traced, int do_smooth, int do_simplify, double dot_x, double dot_y,
									outline* o );

/* The veins' skeleton as trees rooted at the base: thins the strokes, checks every stroke reaches
 * the base, then splits each tree into polylines, longest first (tips in order of their path
 * length from the base; each walks back until it meets a vein already taken). */
sere_status leafimage_skeleton_veins( reader* r, veins_work* v, double dot_x, double dot_y, double dot_radius,
									  double base_px, double base_py );

/* Leaf-coordinate veins kept strictly inside the outline: each is cut where it first comes within
 * margin of it (a vein from the base first has to leave the margin band it starts in; points in
 * that band stay if they are inside by more than a quarter pixel). Veins that keep under two
 * points, get shorter than two pixels, or whose branch point was cut away are dropped with
 * their branches. Fills leaf's vein arrays. */
sere_status leafimage_place_veins( reader* r, veins_work* v, const outline* o, sere_leaf_file* leaf );

/* Frees the arrays of v (not v). */
void leafimage_veins_work_free( veins_work* v );

/* Frees the reader's buffers and closes its file. */
void leafimage_reader_free( reader* r );
