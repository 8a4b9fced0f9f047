/* sere wilt — private to the cmd_wilt*.c files: the skeleton file reader and the picture
 * renderer that `sere wilt` uses (seed 003: Lu, Zhao, Guo 2009). */
#pragma once

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

typedef struct camera
{
	double right[3], up[3], toward[3]; /* toward: from the scene to the eye */
	double scale, u0, v0;			   /* screen = ((p·right − u0) · scale, (v0 − p·up) · scale) */
	int width, height;
} camera;

typedef struct depth_item
{
	float depth;
	int32_t triangle;
} depth_item;

/* Frees the point lists of a loaded skeleton file. */
void wilt_skeleton_free( skeleton_file* s );

/* Reads NAME (a path, or data/skeletons/NAME.skel); on failure one line into err, -1 and nothing
 * to free. */
int wilt_skeleton_load( const char* name, skeleton_file* s, char* err, size_t err_size );

/* "FILE:LINE: " for a problem the kernels found, located by curve or vein and point. */
void wilt_skeleton_where( const skeleton_file* s, const sere_skeleton_check* check, int veins, char* out, size_t size );

/* Fits the view to the rest plant and to its mirror image below each leaf's base, the room that
 * drooping leaves reach. */
void wilt_camera_fit( camera* c, double azimuth, double elevation, int width, int height, const sere_plant* plant );

/* The plant as a PNG at path, written atomically: sky, stem and petioles, the leaves far to near
 * and a progress bar; order is scratch of triangle_count items. 0 on success. */
int wilt_render_png( const char* path, const camera* c, const sere_plant* plant, const float* stem_top,
					 depth_item* order, double progress );
