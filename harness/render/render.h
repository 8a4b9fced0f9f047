/* sere harness — pictures with cairo: shaded triangle meshes seen by an orthographic camera,
 * the paper's fresh-to-dry leaf color (Sec. 6, Fig. 1, 16, 17), a perceptual colormap for
 * scalar fields, contact sheets of panels, line plots and the plane triangulation picture.
 *
 * Every function that can fail returns SERE_OK, or a sere_status (SERE_ERR_ARGUMENT,
 * SERE_ERR_NONFINITE, SERE_ERR_MEMORY, SERE_ERR_IO) with one line in err (never NULL err unless
 * err_size is 0). PNG files are written to "<path>.tmp" and renamed, so an
 * interrupted run never leaves a half-written picture. Nothing here keeps global state. */
#pragma once

#include "core/base.h"

#include <cairo.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* A triangle mesh in SoA with per-vertex colors. Colors come from rgb (3 floats per vertex,
 * interleaved, 0..1), else rgb8 (3 bytes per vertex, the PLY writer's layout), else the
 * uniform color. z may be NULL for a plane mesh (z = 0). */
typedef struct sere_render_mesh
{
	const float* x;
	const float* y;
	const float* z;
	int32_t vertex_count;
	const int32_t* triangles; /* 3 vertex indices per triangle */
	int32_t triangle_count;
	const float* rgb;
	const uint8_t* rgb8;
	float color[3];
} sere_render_mesh;

/* Orthographic camera looking at center. The camera turns azimuth degrees about +z (0: on the
 * -y side looking along +y, +x to the right; 90: on the +x side) and rises elevation degrees
 * above the xy plane (90: the top view, +x right and +y up; negative: from below).
 * scale is pixels per model unit; scale <= 0 (or not finite) asks the draw call to fit the
 * mesh into its region (center = bounding-box center) and to write the fitted center and
 * scale back, so the later frames of a sequence drawn with the same view share frame 0's
 * scale and the shrinking shows. To follow a drifting leaf at that scale, refit a copy and
 * take only its center. */
typedef struct sere_render_view
{
	double azimuth;
	double elevation;
	double center[3];
	double scale;
	double margin; /* pixels kept free around the fitted mesh */
} sere_render_view;

/* Segments between mesh vertices drawn over the whole mesh, without occlusion (veins and the
 * outline of a plane mesh). */
typedef struct sere_render_lines
{
	const int32_t* pairs; /* 2 vertex indices per segment */
	int32_t count;
	float rgb[3];
	double width; /* pixels */
} sere_render_lines;

typedef struct sere_render_style
{
	int edges;		/* outline every triangle in a darker shade of its fill */
	int unlit;		/* fill with the colors as given (scalar maps), no Lambert shading */
	double ambient; /* shade = ambient + (1 - ambient) |n.l|; <= 0 means the default 0.45 */
	const sere_render_lines* lines;
	int32_t line_set_count;
} sere_render_style;

/* Fills view->center and view->scale so the mesh fits a w x h region with view->margin
 * pixels free on every side. Non-finite coordinates give -1. */
sere_status sere_render_fit_view( const sere_render_mesh* mesh, double w, double h, sere_render_view* view, char* err,
								  size_t err_size );

/* Draws the mesh into the region (x0, y0, w, h) of cr, clipped to it: painter's algorithm
 * (triangles sorted far to near by centroid depth, ties by index, so the picture is
 * deterministic), flat Lambert shading, two-sided, a light from the upper left of the screen.
 * style may be NULL (shaded, no edges, no lines). */
sere_status sere_render_mesh_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_mesh* mesh,
								   sere_render_view* view, const sere_render_style* style, char* err, size_t err_size );

/* A leaf seen in 3D: the ground it rests on with its shadow, and its two faces told apart.
 * Kept apart from sere_render_style so the callers that list that struct's fields in order
 * stay valid. All zero: nothing extra (sere_render_mesh_draw's picture).
 *
 * Faces: a triangle (a, b, c) shows its upper face when its normal (b - a) x (c - a) points
 * towards the camera, else its lower face; for a leaf whose triangles run counter-clockwise
 * seen from +z at rest, the upper face is the side of +z. With lower_tint the upper face keeps
 * the per-vertex colors and the lower face is drawn in sere_render_lower_tint of them (paler
 * and greyer, like the underside of a real leaf); both are Lambert shaded alike.
 *
 * Ground: a light gray quad in the plane z = ground_z under the mesh, its outline a shade
 * darker, and on it the mesh's shadow: every triangle projected vertically onto the plane,
 * the union filled once in a translucent dark gray (overlaps do not darken twice) and clipped
 * to the quad. Both are drawn before the mesh, whatever the camera (from below, the mesh is
 * still drawn over them). */
typedef struct sere_render_scene
{
	int lower_tint;
	int ground; /* draw the ground quad (and the shadow unless no_shadow) */
	int no_shadow;
	double ground_z;	  /* not finite: the mesh's lowest z, so it rests on the ground */
	double ground_box[4]; /* x_min, y_min, x_max, y_max of the quad; empty (min >= max): the
						   * mesh's xy footprint grown on every side by a fifth of its larger side */
} sere_render_scene;

/* The lower-face tint of rgb: halfway to a pale warm gray (0.88, 0.88, 0.82), so a fresh green
 * (0.30, 0.55, 0.18) becomes (0.59, 0.72, 0.50) and a dry brown turns beige. */
void sere_render_lower_tint( const float rgb[3], float out[3] );

/* sere_render_fit_view for the mesh and, when scene asks for a ground, the four corners of its
 * quad, so the whole scene fits the region; with a ground the center is then moved to the
 * middle of the scene's projection (an oblique scene fills its region evenly). scene may be
 * NULL (exactly sere_render_fit_view). */
sere_status sere_render_fit_scene( const sere_render_mesh* mesh, const sere_render_scene* scene, double w, double h,
								   sere_render_view* view, char* err, size_t err_size );

/* sere_render_mesh_draw with a scene (may be NULL: the same picture as sere_render_mesh_draw);
 * an unfitted view is fitted with sere_render_fit_scene. Deterministic: the same input gives
 * the same pixels. */
sere_status sere_render_mesh_draw_scene( cairo_t* cr, double x0, double y0, double w, double h,
										 const sere_render_mesh* mesh, sere_render_view* view,
										 const sere_render_style* style, const sere_render_scene* scene, char* err,
										 size_t err_size );

/* Screen position of a model point under view in the region (x0, y0, w, h) (view fitted). */
void sere_render_project( const sere_render_view* view, double x0, double y0, double w, double h, double x, double y,
						  double z, double* sx, double* sy );

/* Segments between points of their own (x, y, z of both ends, 6 doubles a segment), not mesh
 * vertices: a plant's stem and petioles. Drawn with the view's projection (fitted) into the
 * region (x0, y0, w, h) over what is already there, without occlusion, with round caps. */
typedef struct sere_render_segments
{
	const double* xyz;
	int32_t count;
	float rgb[3];
	double width; /* pixels */
} sere_render_segments;

void sere_render_segments_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_view* view,
								const sere_render_segments* segments );

/* The paper's blend (Sec. 6): fresh green at relative water content 1, dry brown at 0,
 * linear between, clamped to [0, 1]; NaN counts as dry. */
void sere_render_dry_color( double relative_water, float rgb[3] );
/* The same for n values into 3 n interleaved floats. */
void sere_render_dry_colors( const float* relative_water, int32_t n, float* rgb );

/* A perceptually uniform colormap (viridis-like: dark blue, teal, green, yellow) at t in
 * [0, 1], clamped; NaN maps to 0. */
void sere_render_colormap( double t, float rgb[3] );
/* values mapped linearly from [lo, hi] onto the colormap, into 3 n interleaved floats. */
void sere_render_colormap_values( const float* values, int32_t n, double lo, double hi, float* rgb );

/* A categorical palette for curves (colorblind-safe, repeats after 8). */
void sere_render_palette( int index, float rgb[3] );

/* Text helpers with the sheet's font. align: 0 left, 1 centered, 2 right at x; y is the
 * baseline. */
void sere_render_text( cairo_t* cr, double x, double y, double size, int bold, int align, const char* text );
/* A vertical colorbar in (x, y, w, h) for the colormap from lo (bottom) to hi (top), labeled
 * with nice ticks on its right and the label above. */
void sere_render_colorbar( cairo_t* cr, double x, double y, double w, double h, double lo, double hi,
						   const char* label );

/* A white image canvas. */
typedef struct sere_render_canvas
{
	cairo_surface_t* surface;
	cairo_t* cr;
	int width;
	int height;
} sere_render_canvas;

sere_status sere_render_canvas_create( sere_render_canvas* canvas, int width, int height, char* err, size_t err_size );
/* Checks the drawing status, then writes the PNG atomically. */
sere_status sere_render_canvas_write_png( const sere_render_canvas* canvas, const char* path, char* err,
										  size_t err_size );
void sere_render_canvas_destroy( sere_render_canvas* canvas );

/* Draws panel `index` into the region (x, y, w, h) of cr and may write its caption
 * (e.g. "frame 120, RWC 0.63") into caption; returns SERE_OK, or a status with a message in err. */
typedef sere_status sere_render_panel_fn( void* user, int index, cairo_t* cr, double x, double y, double w, double h,
										  char* caption, size_t caption_size, char* err, size_t err_size );

typedef struct sere_render_sheet
{
	const char* title; /* may be NULL */
	int columns;
	int count;
	int panel_width;  /* pixels; <= 0 means 320 */
	int panel_height; /* pixels; <= 0 means panel_width */
	sere_render_panel_fn* draw;
	void* user;
} sere_render_sheet;

/* A grid of panels with a caption under each and a title on top, written as a PNG. */
sere_status sere_render_contact_sheet( const char* path, const sere_render_sheet* sheet, char* err, size_t err_size );

/* One curve. Points with a non-finite coordinate break the line. */
typedef struct sere_render_series
{
	const char* name;
	const double* x;
	const double* y;
	int32_t count;
	float rgb[3];
	int dashed;
} sere_render_series;

typedef struct sere_render_axes
{
	const char* title;
	const char* x_label;
	const char* y_label;
	int fixed_y; /* use y_min..y_max instead of the data's range */
	double y_min;
	double y_max;
} sere_render_axes;

/* A line plot in the region (x0, y0, w, h): title, axes with nice ticks, grid lines, labels
 * and a legend in the corner the data leaves emptiest. -1 when there is no finite point. */
sere_status sere_render_plot_draw( cairo_t* cr, double x0, double y0, double w, double h, const sere_render_axes* axes,
								   const sere_render_series* series, int series_count, char* err, size_t err_size );

/* The plot alone as a width x height PNG. */
sere_status sere_render_plot( const char* path, int width, int height, const sere_render_axes* axes,
							  const sere_render_series* series, int series_count, char* err, size_t err_size );

/* The flat triangulation of a leaf seen from above (sere model --png): triangles outlined,
 * optionally filled by a per-vertex scalar through the colormap with a colorbar, vein edges
 * in red, the outline in dark gray. */
typedef struct sere_render_plane
{
	const char* title;
	const float* x;
	const float* y;
	int32_t vertex_count;
	const int32_t* triangles;
	int32_t triangle_count;
	const float* scalar;	   /* per vertex, or NULL for a plain leaf green */
	const char* scalar_name;   /* colorbar label, e.g. "tau" */
	const int32_t* vein_pairs; /* vertex index pairs, or NULL */
	int32_t vein_count;
	const int32_t* outline_pairs; /* vertex index pairs, or NULL */
	int32_t outline_count;
} sere_render_plane;

sere_status sere_render_plane_png( const char* path, int width, int height, const sere_render_plane* plane, char* err,
								   size_t err_size );

#ifdef __cplusplus
}
#endif
