/* sere harness — private to harness/render: what render.c and render_plot.c share. */
#pragma once

#include "core/base.h"

#include <cairo.h>
#include <stddef.h>

/* SERE_OK while cr draws without error, else SERE_ERR_MEMORY or SERE_ERR_ARGUMENT with cairo's
 * message in err. */
sere_status sere_render_cairo_failed( cairo_t* cr, char* err, size_t err_size );
