/* sere — graph coloring of distance constraints for parallel Gauss–Seidel (Sec. 5.2): springs
 * that share a particle get different colors, so the springs of one color can be projected at
 * the same time (threads, SIMD lanes) without two of them writing the same particle. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* A particle's colors are kept as bits of one 64-bit word. */
#define SERE_MAX_COLORS 64

typedef struct sere_coloring
{
	int32_t color_count;
	int32_t offsets[SERE_MAX_COLORS + 1]; /* color c owns order[offsets[c] .. offsets[c+1]) */
	int32_t* order;						  /* spring indices sorted by color, ascending within a color */
	int32_t* color;						  /* per spring */
	int32_t min_batch, max_batch;		  /* smallest and largest color */
} sere_coloring;

/* Greedy and deterministic: springs in index order take the least-used color that neither
 * endpoint has yet (the lowest such color on a tie), opening a new color only when every open
 * one is taken at an endpoint; then springs move from large colors to smaller ones free at both
 * their ends while that narrows the gap. The count stays within the greedy bound 2Δ − 1 for
 * maximum particle degree Δ, and the batches come out nearly equal (Table 1 maple: 19 colors
 * of 2689–2690 springs, in about 3 ms). SERE_ERR_ARGUMENT for an index out of range or a spring
 * joining a particle to itself, SERE_ERR_CAPACITY past SERE_MAX_COLORS. The caller frees with
 * sere_coloring_destroy (also safe after a failed call). */
sere_status sere_coloring_create( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
								  sere_coloring* coloring );
void sere_coloring_destroy( sere_coloring* coloring );

/* out[k] = in[order[k]] for every spring: moves per-spring arrays (a, b, rest, rest0, kind)
 * into color order, so a caller can store its springs the way a colored sweep streams them.
 * After such a reorder, color c is the contiguous range [offsets[c], offsets[c+1]). in and out
 * must not overlap. */
void sere_coloring_gather_i32( const sere_coloring* coloring, const int32_t* in, int32_t* out );
void sere_coloring_gather_f32( const sere_coloring* coloring, const float* in, float* out );
void sere_coloring_gather_u8( const sere_coloring* coloring, const uint8_t* in, uint8_t* out );

#ifdef __cplusplus
}
#endif
