/* sere harness — one triangle mesh as glTF 2.0 binary (.glb): positions, per-vertex normals,
 * per-vertex colors (COLOR_0) and indices, in one buffer, with a two-sided material, so
 * Blender, three.js and any glTF viewer show a scene without a converter. */
#pragma once

#include "core/base.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* A mesh in SoA with sRGB colors, 3 bytes per vertex (the PLY writer's layout). */
typedef struct sere_glb_mesh
{
	const float *x, *y, *z;
	const uint8_t* rgb;
	int32_t vertex_count;
	const int32_t* tri; /* 3 vertex indices per triangle */
	int32_t triangle_count;
} sere_glb_mesh;

/* Writes the mesh to path atomically ("<path>.tmp", renamed). Normals are the area-weighted
 * means of the triangle normals around each vertex (+z where they cancel); colors become
 * linear floats, as glTF's COLOR_0 is linear. Deterministic: the same mesh gives the same bytes.
 * SERE_OK, or SERE_ERR_ARGUMENT (an empty mesh, an index out of range), SERE_ERR_MEMORY or
 * SERE_ERR_IO (a write error) with one line in err naming path. */
sere_status sere_glb_write( const char* path, const sere_glb_mesh* mesh, char* err, size_t err_size );

#ifdef __cplusplus
}
#endif
