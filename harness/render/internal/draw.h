/* sere harness — private to harness/render: what render.c and render_plot.c share. */
#pragma once

#include "core/base.h"

#include <cairo.h>
#include <stddef.h>

/* SERE_OK while cr draws without error, else SERE_ERR_MEMORY or SERE_ERR_ARGUMENT with cairo's
 * message in err. */
sere_status sere_render_cairo_failed( cairo_t* cr, char* err, size_t err_size );

/* Fills the box (x, y, w, h) with gradient, which it then destroys, and outlines it one pixel wide
 * in the given grey: the color bars of the legends. */
void sere_render_gradient_box( cairo_t* cr, cairo_pattern_t* gradient, double x, double y, double w, double h,
							   double grey );
