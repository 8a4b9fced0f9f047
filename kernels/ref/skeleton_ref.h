/* sere — reference twins of the skeleton kernels (seed 003): plain scalar loops that tests and
 * benches compare the optimized kernels with. */
#pragma once

#include "wilt/skeleton.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Sec. 5.2 literally: every vertex scans every joint for the nearest (squared distance in float,
 * the lower index on ties). */
void sere_skeleton_ref_band( const float* jx, const float* jy, const float* jz, int32_t joint_count, const float* x,
							 const float* y, const float* z, int32_t vertex_count, int32_t* joint );

/* The mesh follows its joints, one vertex at a time: x = p_j + R_j o. */
void sere_skeleton_ref_skin( const sere_joint_frames* frames, const int32_t* joint, const float* ox, const float* oy,
							 const float* oz, int32_t vertex_count, float* x, float* y, float* z );

/* Sec. 6 as the seed tells it, without limits: for each joint in turn (parents first), its
 * current segment u from the parent is turned toward d = −z about n = u × d by
 * min(bend · progress, angle(u, d)) with Lu Eq. 1, and the rotation is passed to every descendant
 * by rotating its current position about the parent joint (found by walking parent links, not
 * by subtree ranges). O(joints²); positions in double, written to x, y, z (joint_count each). */
void sere_skeleton_ref_pose( const sere_skeleton* skeleton, float t, float spread, double* x, double* y, double* z );

#ifdef __cplusplus
}
#endif
