/* sere harness — the leaf of seed 002 (Tang, Wu, Fan 2013): key points on the edge → closed
 * B-spline → sampled outline → Delaunay → mesh optimization (Sec. 3), masses from a grayscale
 * mask map (Tang Eq. 3), and a sequence of deformation states by the mass-spring model (Sec. 4), one
 * per deformation level of the seasonal Markov chain (Sec. 5). */
#pragma once

#include "core/base.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_season_leaf_options
{
	const char* keys_path;		 /* key points file (data/seasons/maple.keys), or NULL ... */
	const char* silhouette_path; /* ... a PNG silhouette the key points are taken from */
	const char* mask_path;		 /* grayscale mask map in the key points' pixel frame (PGM or PNG) */
	int32_t outline_samples;	 /* points the B-spline is sampled at */
	int32_t meshopt_iterations;	 /* the seed's 160 */
	int32_t levels;				 /* deformation states D ≥ 1: level 0 fresh and flat, D − 1 the most withered */
	int32_t steps_per_level;	 /* mass-spring steps between consecutive levels */
	int32_t threads;			 /* the mass-spring's threads (kernels/core/base.h; 0: OpenMP's count) */
} sere_season_leaf_options;

/* Defaults: data/seasons/maple.keys, data/masks/maple.pgm, 120 samples, 160 iterations,
 * 4 levels, 400 steps per level. Paths are relative to the data directory the harness finds. */
sere_season_leaf_options sere_season_leaf_options_default( void );

typedef struct sere_season_leaf
{
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t level_count;
	int32_t* tri; /* 3 per triangle, counter-clockwise seen from +z at level 0 */
	float* u;	  /* texture coordinates in [0, 1]² from the pixel frame of the key points */
	float* v;
	float* mass; /* per vertex, from the mask (Tang Eq. 3) */
	/* level_count × vertex_count × 3 floats: leaf units, the petiole at the origin, the tip
	 * towards +y, level 0 flat in z = 0. */
	float* xyz;
} sere_season_leaf;

/* Builds the leaf and its deformation levels. On failure returns the error, writes one line
 * "PATH: problem" (or "option: problem") into err and leaves nothing to free. */
sere_status sere_season_leaf_build( const sere_season_leaf_options* options, sere_season_leaf* leaf, char* err,
									size_t err_size );
void sere_season_leaf_destroy( sere_season_leaf* leaf );

#ifdef __cplusplus
}
#endif
