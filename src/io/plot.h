/* Small charts drawn into an RGB8 buffer and written as PNG: line plots with axes, ticks and
 * text labels (the stb_easy_font bitmap font, its quads rasterized here), and a log-scaled
 * heat map with a colour bar. Used by evray bench --sweep and evray plot; no plotting library. */
#ifndef EVR_IO_PLOT_H
#define EVR_IO_PLOT_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"
#include "evray_experimental.h"

/* An RGB8 image, rows top to bottom, initially white. */
typedef struct {
    int w, h;
    uint8_t *rgb;
} evr_canvas;

evr_status evr_canvas_init(evr_canvas *c, int w, int h, evr_error *err);
void evr_canvas_release(evr_canvas *c);
/* Fills [x0,x1) x [y0,y1), clipped to the image. */
void evr_canvas_rect(evr_canvas *c, int x0, int y0, int x1, int y1, const uint8_t col[3]);
/* A line of the given thickness (pixels), clipped to the image. */
void evr_canvas_line(evr_canvas *c, double x0, double y0, double x1, double y1, int thick,
                     const uint8_t col[3]);
/* Text with its top-left corner at (x, y); each font pixel is scale x scale image pixels.
 * The font is about 6 pixels wide and 7 high per character at scale 1. */
void evr_canvas_text(evr_canvas *c, int x, int y, int scale, const char *text,
                     const uint8_t col[3]);
int evr_text_width(const char *text, int scale);
/* The heat map's dark-to-bright colours (black, purple, red, orange, yellow, white), v in [0, 1]
 * (clamped). */
void evr_plot_colormap(double v, uint8_t out[3]);

/* The line plots and heat maps (evr_plot_series, evr_plot_spec, evr_plot_lines_png,
 * evr_plot_heatmap_png) are declared in evray_experimental.h. */

#endif
