/* sere — private to kernels/mesh's shape measures (measure.c, measure_roll.c) and crossings
 * (crossings.c): small 3-vectors of doubles and the steps the measures share. */
#pragma once

#include "mesh/measure.h"

#include <stdbool.h>
#include <stdint.h>

static inline void sub3( const double u[3], const double v[3], double out[3] )
{
	out[0] = u[0] - v[0], out[1] = u[1] - v[1], out[2] = u[2] - v[2];
}

static inline void cross3( const double u[3], const double v[3], double out[3] )
{
	out[0] = u[1] * v[2] - u[2] * v[1];
	out[1] = u[2] * v[0] - u[0] * v[2];
	out[2] = u[0] * v[1] - u[1] * v[0];
}

static inline double dot3( const double u[3], const double v[3] )
{
	return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static inline void sere_measure_position( const sere_shape_input* in, int32_t i, double p[3] )
{
	p[0] = in->x[i], p[1] = in->y[i], p[2] = in->z[i];
}

/* The input's arrays and counts are usable (measure.c). */
sere_status sere_measure_validate( const sere_shape_input* in );

/* Triangle t's unit normal, zero for a degenerate triangle (measure.c). */
void sere_measure_unit_normal( const sere_shape_input* in, int32_t t, double n[3] );

/* The roll of the band of triangles at v_fraction of the leaf's length, tris and lateral its
 * scratch of triangle_count items each (measure_roll.c). */
double sere_measure_band_roll( const sere_shape_input* in, double v_fraction, int32_t* tris, double* lateral );

/* The angle the leaf's axis turns through between the bands at fractions from and to
 * (measure_roll.c). */
double sere_measure_axis_curl( const sere_shape_input* in, double from, double to );

/* Creases along and between the main veins, and the roll of the sections across them near their
 * tips and their bases; false when out of memory (measure_roll.c). */
bool sere_measure_main_veins( const sere_shape_input* in, const int32_t* edge_tri, const double* dihedral,
							  sere_shape* out );
