/* sere harness — PNG pictures with cairo: a contact sheet of leaf meshes colored by relative
 * water content (the paper's fresh-to-dry blend, Sec. 6) and line plots. */
#pragma once

#include <stddef.h>
#include <stdint.h>

typedef struct sere_panel
{
	const float *x, *y, *z;
	const float* rwc; /* per vertex relative water content in [0, 1] */
	const int32_t* tri;
	int32_t triangle_count;
	const char* caption;
} sere_panel;

/* Panels in a grid of columns, all drawn at the scale and centre of the first, seen from above
 * at an angle. Written atomically; 0 on success, else -1 with one line in err. */
int sere_picture_sheet( const char* path, const char* title, const sere_panel* panels, int count, int columns,
						char* err, size_t err_size );

typedef struct sere_series
{
	const char* name;
	const double* x;
	const double* y;
	int32_t count;
	double r, g, b;
} sere_series;

/* Line plot with axes, ticks and a legend; written atomically. */
int sere_picture_plot( const char* path, const char* title, const char* x_label, const char* y_label,
					   const sere_series* series, int count, char* err, size_t err_size );

/* The paper's blend: fresh green at relative water 1, dry brown at 0, linear between. */
void sere_picture_dry_color( double relative_water, double rgb[3] );
