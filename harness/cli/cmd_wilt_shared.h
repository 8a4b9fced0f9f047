/* sere wilt — private to the cmd_wilt*.c files: the skeleton file reader and the pictures that
 * `sere wilt` draws with harness/render (seed 003: Lu, Zhao, Guo 2009). */
#pragma once

#include "render/render.h"
#include "wilt/skeleton.h"

#include <stddef.h>
#include <stdint.h>

#define PI		  3.14159265358979323846
#define MAX_VEINS 256

typedef struct point_list
{
	int32_t count, capacity;
	double* xy;
	int32_t* line; /* file line of each point, for messages */
} point_list;

typedef struct skeleton_file
{
	char path[4096];
	char name[64];
	point_list curve[3]; /* left, right, midvein */
	int32_t curve_line[3];
	int32_t vein_count;
	point_list vein[MAX_VEINS];
	int32_t vein_line[MAX_VEINS];
	int32_t vein_parent[MAX_VEINS];
	int32_t vein_segments[MAX_VEINS];
	double vein_bend[MAX_VEINS];
} skeleton_file;

/* What every picture of a run shares: the view fitted once to the rest plant, so the later
 * frames keep frame 0's scale and the drooping shows, and the per-vertex colors' scratch. */
typedef struct wilt_picture
{
	sere_render_view view;
	int width, height;
	float* rgb; /* 3 per plant vertex */
} wilt_picture;

/* Frees the point lists of a loaded skeleton file. */
void wilt_skeleton_free( skeleton_file* s );

/* Reads NAME (a path, or data/skeletons/NAME.skel); on failure one line into err, -1 and nothing
 * to free. */
int wilt_skeleton_load( const char* name, skeleton_file* s, char* err, size_t err_size );

/* "FILE:LINE: " for a problem the kernels found, located by curve or vein and point. */
void wilt_skeleton_where( const skeleton_file* s, const sere_skeleton_check* check, int veins, char* out, size_t size );

/* Fits the view (azimuth and elevation in degrees: the eye's direction from +x toward +y, and
 * above the ground) to the rest plant and to its mirror image below each leaf's base, the room
 * that drooping leaves reach. SERE_OK, or a status with one line in err. */
sere_status wilt_picture_fit( wilt_picture* pic, double azimuth, double elevation, int width, int height,
							  const sere_plant* plant, char* err, size_t err_size );
void wilt_picture_free( wilt_picture* pic );

/* The plant as a PNG at path, written atomically through harness/render: sky, stem and
 * petioles, the leaves (far to near) and a progress bar. SERE_OK, or a status with one line in
 * err. */
sere_status wilt_picture_png( const char* path, wilt_picture* pic, const sere_plant* plant, const float* stem_top,
							  double progress, char* err, size_t err_size );
