/* sere — graph coloring of distance constraints for parallel Gauss–Seidel (Sec. 5.2): springs
 * that share a particle get different colors, so each color is a batch solved in parallel. */
#pragma once

#include "base.h"

#ifdef __cplusplus
extern "C"
{
#endif

#define SERE_MAX_COLORS 64

typedef struct sere_coloring
{
	int32_t color_count;
	int32_t offsets[SERE_MAX_COLORS + 1]; /* color c owns order[offsets[c] .. offsets[c+1]) */
	int32_t* order;						  /* spring indices sorted by color, ascending within a color */
	int32_t* color;						  /* per spring */
	int32_t min_batch, max_batch;
} sere_coloring;

/* Greedy and deterministic: springs in index order take the least-used color that neither
 * endpoint has yet (opening a new color only when all are taken), which balances the batch
 * sizes. SERE_ERR_CAPACITY past SERE_MAX_COLORS. The caller frees with sere_coloring_destroy. */
sere_status sere_color_springs( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
								sere_coloring* coloring );
void sere_coloring_destroy( sere_coloring* coloring );

#ifdef __cplusplus
}
#endif
