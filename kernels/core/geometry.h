/* sere — plane geometry shared by the kernels and the harness: one point-in-polygon test, one
 * polygon area and one point–segment distance, so that every caller rounds the same way. */
#pragma once

#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

/* Even-odd point-in-polygon test for a polygon of count vertices (xy interleaved). A point
 * exactly on an edge may go either way. */
int sere_point_in_polygon( const double* xy, int32_t count, double px, double py );

/* Signed area of a polygon of count vertices (xy interleaved): positive when counterclockwise. */
double sere_polygon_area( const double* xy, int32_t count );

/* The vector from p to the nearest point of the segment a–b: (a + t (b − a)) − p with t clamped
 * to [0, 1] (t = 0 for a segment of zero length). All points are (x, y). */
void sere_segment_offset( const double* p, const double* a, const double* b, double* dx, double* dy );

/* |sere_segment_offset|, by hypot. */
double sere_point_segment_distance( const double* p, const double* a, const double* b );

#ifdef __cplusplus
}
#endif
