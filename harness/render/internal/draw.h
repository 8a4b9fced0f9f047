/* sere harness — private to harness/render: what render.c and render_plot.c share. */
#pragma once

#include <cairo.h>
#include <stddef.h>

/* 0 while cr draws without error, else -1 with cairo's message in err. */
int sere_render_cairo_failed( cairo_t* cr, char* err, size_t err_size );
