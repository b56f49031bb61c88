/* Label images for evray plot: an optical flow field in the colour wheel of Baker et al., "A
 * Database and Evaluation Methodology for Optical Flow" (Middlebury, IJCV 2011), the colouring
 * that flow papers and tools share, and a depth map in the heat map's colours; see
 * evray_experimental.h. */
#include "io/plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const uint8_t BLACK[3] = {0, 0, 0}, FRAME[3] = {160, 160, 160},
                     NO_SURFACE_DEPTH[3] = {0, 128, 128};

/* The wheel's 55 hues: red to yellow in 15 steps, yellow to green in 6, green to cyan in 4, cyan
 * to blue in 11, blue to magenta in 13, magenta to red in 6 (the paper's counts: more steps
 * where the eye tells hues apart less well). Hue i, each channel in [0, 1]. */
#define WHEEL_HUES 55
#define PI 3.14159265358979323846
static void wheel_hue(int i, double c[3])
{
    static const int steps[6] = {15, 6, 4, 11, 13, 6};
    /* each segment: the channel that rises (+) or falls (-), and the one held at full */
    static const int moving[6] = {1, 0, 2, 1, 0, 2}, rising[6] = {1, 0, 1, 0, 1, 0},
                     full[6] = {0, 1, 1, 2, 2, 0};
    int s = 0;
    while (i >= steps[s]) i -= steps[s++];
    c[0] = c[1] = c[2] = 0.0;
    c[full[s]] = 1.0;
    double f = floor(255.0 * i / steps[s]) / 255.0;
    c[moving[s]] = rising[s] ? f : 1.0 - f;
}

/* The colour of flow (u, v) (px/s, v down) with magnitude max at the wheel's edge. */
static void flow_colour(double u, double v, double max, uint8_t out[3])
{
    double rad = max > 0.0 ? sqrt(u * u + v * v) / max : 0.0, a = atan2(-v, -u) / PI,
           fk = (a + 1.0) / 2.0 * (WHEEL_HUES - 1), f, c0[3], c1[3];
    int k0 = (int)floor(fk), ch;
    if (k0 < 0) k0 = 0;
    if (k0 > WHEEL_HUES - 1) k0 = WHEEL_HUES - 1;
    f = fk - k0;
    wheel_hue(k0, c0);
    wheel_hue((k0 + 1) % WHEEL_HUES, c1);
    for (ch = 0; ch < 3; ch++) {
        double c = (1.0 - f) * c0[ch] + f * c1[ch];
        c = rad <= 1.0 ? 1.0 - rad * (1.0 - c) : c * 0.75; /* past the edge: darker */
        out[ch] = (uint8_t)floor(255.0 * c);
    }
}

/* The field's scale (the heat map's rule) and a canvas with room for a legend beside it. */
static evr_status label_canvas(evr_canvas *c, int w, int h, int *scale, evr_error *err)
{
    int s = 1, W, H;
    if (w < 1 || h < 1 || w > 16384 || h > 16384) {
        snprintf(err->msg, sizeof err->msg, "label image size %dx%d is out of range", w, h);
        return EVR_ERR_ARG;
    }
    while (w * (s + 1) <= 640 && h * (s + 1) <= 640) s++;
    W = EVR_PLOT_LABEL_X + w * s + 180;
    H = EVR_PLOT_LABEL_Y + h * s + 10;
    if (H < 280) H = 280;
    *scale = s;
    return evr_canvas_init(c, W, H, err);
}

/* A grey frame just outside the field, so that white pixels (no motion, the nearest depth) show
 * where the field ends. */
static void field_frame(evr_canvas *c, int w, int h, int s)
{
    const int x0 = EVR_PLOT_LABEL_X - 1, y0 = EVR_PLOT_LABEL_Y - 1, x1 = EVR_PLOT_LABEL_X + w * s,
              y1 = EVR_PLOT_LABEL_Y + h * s;
    evr_canvas_rect(c, x0, y0, x1 + 1, y0 + 1, FRAME);
    evr_canvas_rect(c, x0, y1, x1 + 1, y1 + 1, FRAME);
    evr_canvas_rect(c, x0, y0, x0 + 1, y1 + 1, FRAME);
    evr_canvas_rect(c, x1, y0, x1 + 1, y1 + 1, FRAME);
}

static void put_pixel(evr_canvas *c, int x, int y, int s, const uint8_t col[3])
{
    evr_canvas_rect(c, EVR_PLOT_LABEL_X + x * s, EVR_PLOT_LABEL_Y + y * s,
                    EVR_PLOT_LABEL_X + (x + 1) * s, EVR_PLOT_LABEL_Y + (y + 1) * s, col);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The 99th percentile (the lower of the nearest ranks) of the finite flow magnitudes; 0 when
 * none is finite, -1 when out of memory. */
static double magnitude_p99(const float *flow, size_t n)
{
    double *m = malloc((n ? n : 1) * sizeof *m), p = 0.0;
    size_t i, k = 0;
    if (!m) return -1.0;
    for (i = 0; i < n; i++) {
        double u = flow[2 * i], v = flow[2 * i + 1];
        if (isfinite(u) && isfinite(v)) m[k++] = sqrt(u * u + v * v);
    }
    if (k) {
        qsort(m, k, sizeof *m, cmp_double);
        p = m[(size_t)floor(0.99 * (double)(k - 1))];
    }
    free(m);
    return p;
}

evr_status evr_plot_flow_png(const char *path, const float *flow, int w, int h, const char *title,
                             double *max_px_s, int *scale, evr_error *err)
{
    evr_canvas c;
    evr_status st;
    int s, x, y, cx, cy, r = 64;
    double max = *max_px_s;
    char lab[96];
    if ((st = label_canvas(&c, w, h, &s, err)) != EVR_OK) return st;
    if (!(max > 0.0)) max = magnitude_p99(flow, (size_t)w * (size_t)h);
    if (max < 0.0) {
        evr_canvas_release(&c);
        snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d flow field", w, h);
        return EVR_ERR_NOMEM;
    }
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            const float *f = flow + 2 * ((size_t)y * (size_t)w + (size_t)x);
            uint8_t col[3] = {0, 0, 0};
            if (isfinite(f[0]) && isfinite(f[1])) flow_colour(f[0], f[1], max, col);
            put_pixel(&c, x, y, s, col);
        }
    field_frame(&c, w, h, s);
    if (title) evr_canvas_text(&c, 4, 8, 2, title, BLACK);
    /* the legend: the wheel itself, its edge the maximum */
    cx = EVR_PLOT_LABEL_X + w * s + 24 + r;
    cy = EVR_PLOT_LABEL_Y + 14 + r;
    evr_canvas_text(&c, cx - r, EVR_PLOT_LABEL_Y, 1, "flow (x right, y down)", BLACK);
    for (y = -r; y <= r; y++)
        for (x = -r; x <= r; x++)
            if (x * x + y * y <= r * r) {
                uint8_t col[3];
                flow_colour(x, y, r, col);
                evr_canvas_rect(&c, cx + x, cy + y, cx + x + 1, cy + y + 1, col);
            }
    evr_canvas_text(&c, cx + r + 4, cy - 3, 1, "+x", BLACK);
    evr_canvas_text(&c, cx - 5, cy + r + 4, 1, "+y", BLACK);
    snprintf(lab, sizeof lab, "edge: %.4g px/s", max);
    evr_canvas_text(&c, cx - r, cy + r + 18, 1, lab, BLACK);
    evr_canvas_text(&c, cx - r, cy + r + 32, 1,
                    *max_px_s > 0.0 ? "(as chosen)" : "(99th percentile)", BLACK);
    evr_canvas_rect(&c, cx - r, cy + r + 48, cx - r + 10, cy + r + 58, BLACK);
    evr_canvas_text(&c, cx - r + 14, cy + r + 50, 1, "no surface", BLACK);
    st = evr_png_write(path, c.rgb, c.w, c.h, 3, 8, err);
    evr_canvas_release(&c);
    if (st == EVR_OK) {
        *max_px_s = max;
        if (scale) *scale = s;
    }
    return st;
}

evr_status evr_plot_depth_png(const char *path, const float *depth, int w, int h, const char *title,
                              double *near, double *far, int *scale, evr_error *err)
{
    evr_canvas c;
    evr_status st;
    int s, x, y, bar_x, bar_h;
    size_t i, n = (size_t)w * (size_t)h;
    double lo = INFINITY, hi = -INFINITY;
    char lab[96];
    if ((st = label_canvas(&c, w, h, &s, err)) != EVR_OK) return st;
    for (i = 0; i < n; i++)
        if (isfinite(depth[i])) {
            if (depth[i] < lo) lo = depth[i];
            if (depth[i] > hi) hi = depth[i];
        }
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            double d = depth[(size_t)y * (size_t)w + (size_t)x];
            uint8_t col[3];
            if (!isfinite(d)) memcpy(col, NO_SURFACE_DEPTH, 3);
            else evr_plot_colormap(hi > lo ? (hi - d) / (hi - lo) : 0.5, col); /* near: 1 */
            put_pixel(&c, x, y, s, col);
        }
    field_frame(&c, w, h, s);
    if (title) evr_canvas_text(&c, 4, 8, 2, title, BLACK);
    /* the colour bar: near at the top, far at the bottom */
    bar_x = EVR_PLOT_LABEL_X + w * s + 24;
    bar_h = 160;
    evr_canvas_text(&c, bar_x, EVR_PLOT_LABEL_Y, 1, "depth (scene units)", BLACK);
    for (y = 0; y < bar_h; y++) {
        uint8_t col[3];
        evr_plot_colormap(1.0 - (double)y / (bar_h - 1), col);
        evr_canvas_rect(&c, bar_x, EVR_PLOT_LABEL_Y + 14 + y, bar_x + 16, EVR_PLOT_LABEL_Y + 15 + y,
                        col);
    }
    if (lo <= hi) {
        snprintf(lab, sizeof lab, "%.5g near", lo);
        evr_canvas_text(&c, bar_x + 22, EVR_PLOT_LABEL_Y + 14, 1, lab, BLACK);
        snprintf(lab, sizeof lab, "%.5g far", hi);
        evr_canvas_text(&c, bar_x + 22, EVR_PLOT_LABEL_Y + 14 + bar_h - 7, 1, lab, BLACK);
    } else evr_canvas_text(&c, bar_x + 22, EVR_PLOT_LABEL_Y + 14, 1, "no surface seen", BLACK);
    evr_canvas_rect(&c, bar_x, EVR_PLOT_LABEL_Y + bar_h + 24, bar_x + 16,
                    EVR_PLOT_LABEL_Y + bar_h + 34, NO_SURFACE_DEPTH);
    evr_canvas_text(&c, bar_x + 22, EVR_PLOT_LABEL_Y + bar_h + 26, 1, "no surface", BLACK);
    st = evr_png_write(path, c.rgb, c.w, c.h, 3, 8, err);
    evr_canvas_release(&c);
    if (st == EVR_OK) {
        if (near) *near = lo <= hi ? lo : NAN;
        if (far) *far = lo <= hi ? hi : NAN;
        if (scale) *scale = s;
    }
    return st;
}
