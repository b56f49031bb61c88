/* Line plots and heat maps drawn in C; see plot.h. */
#include "io/plot.h"
#include "io/png.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* stb_easy_font is header-only and every function in it is static (no implementation define, no
 * symbols in libstb), so including it here cannot clash with another file; some of its functions
 * go unused. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-prototypes"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

static const uint8_t BLACK[3] = {0, 0, 0}, GRID[3] = {225, 225, 225};

evr_status evr_canvas_init(evr_canvas *c, int w, int h, evr_error *err)
{
    c->w = w;
    c->h = h;
    c->rgb = NULL;
    if (w < 1 || h < 1 || w > 16384 || h > 16384) {
        snprintf(err->msg, sizeof err->msg, "plot size %dx%d is out of range", w, h);
        return EVR_ERR_ARG;
    }
    c->rgb = malloc((size_t)w * (size_t)h * 3);
    if (!c->rgb) {
        snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d plot", w, h);
        return EVR_ERR_NOMEM;
    }
    memset(c->rgb, 255, (size_t)w * (size_t)h * 3);
    return EVR_OK;
}

void evr_canvas_release(evr_canvas *c)
{
    free(c->rgb);
    c->rgb = NULL;
}

void evr_canvas_rect(evr_canvas *c, int x0, int y0, int x1, int y1, const uint8_t col[3])
{
    int x, y;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > c->w) x1 = c->w;
    if (y1 > c->h) y1 = c->h;
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++)
            memcpy(c->rgb + ((size_t)y * (size_t)c->w + (size_t)x) * 3, col, 3);
}

void evr_canvas_line(evr_canvas *c, double x0, double y0, double x1, double y1, int thick,
                     const uint8_t col[3])
{
    double dx = x1 - x0, dy = y1 - y0, len = fabs(dx) > fabs(dy) ? fabs(dx) : fabs(dy);
    int steps = (int)ceil(len), k, lo = -(thick - 1) / 2, hi = thick / 2;
    if (!isfinite(len) || len > 1e5) return;
    if (steps < 1) steps = 1;
    for (k = 0; k <= steps; k++) {
        int x = (int)floor(x0 + dx * k / steps + 0.5), y = (int)floor(y0 + dy * k / steps + 0.5);
        evr_canvas_rect(c, x + lo, y + lo, x + hi + 1, y + hi + 1, col);
    }
}

/* stb_easy_font emits axis-aligned quads of 4 vertices, 16 bytes each (x, y, z floats, RGBA). */
void evr_canvas_text(evr_canvas *c, int x, int y, int scale, const char *text, const uint8_t col[3])
{
    char buf[60000];
    int q, nq;
    if (!text || !*text) return;
    nq = stb_easy_font_print(0.0f, 0.0f, (char *)text, NULL, buf, (int)sizeof buf);
    for (q = 0; q < nq; q++) {
        float xs[4], ys[4], mnx, mxx, mny, mxy;
        int v;
        for (v = 0; v < 4; v++) {
            memcpy(&xs[v], buf + (q * 4 + v) * 16, sizeof(float));
            memcpy(&ys[v], buf + (q * 4 + v) * 16 + 4, sizeof(float));
        }
        mnx = mxx = xs[0];
        mny = mxy = ys[0];
        for (v = 1; v < 4; v++) {
            if (xs[v] < mnx) mnx = xs[v];
            if (xs[v] > mxx) mxx = xs[v];
            if (ys[v] < mny) mny = ys[v];
            if (ys[v] > mxy) mxy = ys[v];
        }
        evr_canvas_rect(c, x + (int)lroundf(mnx * (float)scale),
                        y + (int)lroundf(mny * (float)scale), x + (int)lroundf(mxx * (float)scale),
                        y + (int)lroundf(mxy * (float)scale), col);
    }
}

int evr_text_width(const char *text, int scale)
{
    return stb_easy_font_width((char *)text) * scale;
}

/* A tick step of 1, 2 or 5 times a power of ten giving about `want` intervals over the range. */
static double nice_step(double range, int want)
{
    double raw = range / want, p = pow(10.0, floor(log10(raw))), f = raw / p;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * p;
}

static void fmt_tick(char *s, size_t n, double v, double step)
{
    if (fabs(v) < step * 1e-6) v = 0.0;
    if (fabs(v) >= 1e6 || (v != 0.0 && fabs(v) < 1e-3)) snprintf(s, n, "%.3g", v);
    else snprintf(s, n, "%.10g", v);
}

evr_status evr_plot_lines_png(const char *path, const evr_plot_spec *spec,
                              const evr_plot_series *series, int nseries, evr_error *err)
{
    evr_canvas c;
    evr_status st;
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY, xs, ys, v;
    int i, left = 78, right = 24, top = 40, bottom = 56, pw, ph;
    size_t k;
    char s[64];
    if ((st = evr_canvas_init(&c, spec->width, spec->height, err)) != EVR_OK) return st;
    for (i = 0; i < nseries; i++)
        for (k = 0; k < series[i].n; k++) {
            if (!isfinite(series[i].x[k]) || !isfinite(series[i].y[k])) continue;
            if (series[i].x[k] < xmin) xmin = series[i].x[k];
            if (series[i].x[k] > xmax) xmax = series[i].x[k];
            if (series[i].y[k] < ymin) ymin = series[i].y[k];
            if (series[i].y[k] > ymax) ymax = series[i].y[k];
        }
    if (!(xmin <= xmax)) {
        xmin = 0.0;
        xmax = 1.0;
        ymin = 0.0;
        ymax = 1.0;
    }
    if (spec->y_from_zero && ymin > 0.0) ymin = 0.0;
    if (xmax - xmin <= 0.0) {
        xmin -= 0.5;
        xmax += 0.5;
    }
    if (ymax - ymin <= 0.0) {
        ymax += ymax != 0.0 ? fabs(ymax) * 0.1 : 1.0;
    }
    ymax += (ymax - ymin) * 0.04; /* headroom: the highest point does not touch the frame */
    ys = nice_step(ymax - ymin, 5);
    ymax = ceil(ymax / ys - 1e-9) * ys;
    if (!spec->y_from_zero) ymin = floor(ymin / ys + 1e-9) * ys;
    xs = nice_step(xmax - xmin, 6);
    pw = c.w - left - right;
    ph = c.h - top - bottom;
    if (pw < 10 || ph < 10) {
        evr_canvas_release(&c);
        snprintf(err->msg, sizeof err->msg, "plot size %dx%d is too small", spec->width,
                 spec->height);
        return EVR_ERR_ARG;
    }
#define PX(X) (left + ((X)-xmin) / (xmax - xmin) * pw)
#define PY(Y) (top + ph - ((Y)-ymin) / (ymax - ymin) * ph)
    /* grid and ticks */
    for (v = ceil(ymin / ys - 1e-9) * ys; v <= ymax + ys * 1e-6; v += ys) {
        int y = (int)lround(PY(v));
        evr_canvas_rect(&c, left, y, left + pw, y + 1, GRID);
        evr_canvas_rect(&c, left - 5, y, left, y + 1, BLACK);
        fmt_tick(s, sizeof s, v, ys);
        evr_canvas_text(&c, left - 8 - evr_text_width(s, 1), y - 3, 1, s, BLACK);
    }
    for (v = ceil(xmin / xs - 1e-9) * xs; v <= xmax + xs * 1e-6; v += xs) {
        int x = (int)lround(PX(v));
        evr_canvas_rect(&c, x, top, x + 1, top + ph, GRID);
        evr_canvas_rect(&c, x, top + ph, x + 1, top + ph + 5, BLACK);
        fmt_tick(s, sizeof s, v, xs);
        evr_canvas_text(&c, x - evr_text_width(s, 1) / 2, top + ph + 9, 1, s, BLACK);
    }
    /* series */
    for (i = 0; i < nseries; i++) {
        const evr_plot_series *se = &series[i];
        for (k = 0; k + 1 < se->n; k++)
            evr_canvas_line(&c, PX(se->x[k]), PY(se->y[k]), PX(se->x[k + 1]), PY(se->y[k + 1]), 2,
                            se->color);
        if (se->markers)
            for (k = 0; k < se->n; k++) {
                int x = (int)lround(PX(se->x[k])), y = (int)lround(PY(se->y[k]));
                evr_canvas_rect(&c, x - 3, y - 3, x + 4, y + 4, se->color);
            }
    }
#undef PX
#undef PY
    /* frame, labels, legend */
    evr_canvas_rect(&c, left, top, left + pw, top + 1, BLACK);
    evr_canvas_rect(&c, left, top + ph, left + pw + 1, top + ph + 1, BLACK);
    evr_canvas_rect(&c, left, top, left + 1, top + ph, BLACK);
    evr_canvas_rect(&c, left + pw, top, left + pw + 1, top + ph, BLACK);
    if (spec->title)
        evr_canvas_text(&c, (c.w - evr_text_width(spec->title, 2)) / 2, 8, 2, spec->title, BLACK);
    if (spec->xlabel)
        evr_canvas_text(&c, left + (pw - evr_text_width(spec->xlabel, 1)) / 2, c.h - 22, 1,
                        spec->xlabel, BLACK);
    if (spec->ylabel) evr_canvas_text(&c, 6, top - 14, 1, spec->ylabel, BLACK);
    {
        int ly = top + 8;
        for (i = 0; i < nseries; i++) {
            int tw;
            if (!series[i].label) continue;
            tw = evr_text_width(series[i].label, 1);
            evr_canvas_rect(&c, left + pw - tw - 36, ly + 2, left + pw - tw - 16, ly + 5,
                            series[i].color);
            evr_canvas_text(&c, left + pw - tw - 10, ly, 1, series[i].label, BLACK);
            ly += 14;
        }
    }
    st = evr_png_write(path, c.rgb, c.w, c.h, 3, 8, err);
    evr_canvas_release(&c);
    return st;
}

/* A perceptual-ish dark-to-bright map (black, purple, red, orange, yellow, white), v in [0, 1]. */
void evr_plot_colormap(double v, uint8_t out[3])
{
    static const double stops[6][3] = {{0, 0, 4},     {87, 16, 110},   {188, 55, 84},
                                       {249, 142, 9}, {252, 255, 164}, {255, 255, 255}};
    double t = (v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v) * 5.0;
    int i = (int)t, ch;
    if (i > 4) i = 4;
    t -= i;
    for (ch = 0; ch < 3; ch++)
        out[ch] = (uint8_t)lround(stops[i][ch] + (stops[i + 1][ch] - stops[i][ch]) * t);
}

evr_status evr_plot_heatmap_png(const char *path, const uint32_t *counts, int w, int h,
                                const char *title, int *out_w, int *out_h, evr_error *err)
{
    evr_canvas c;
    evr_status st;
    uint32_t mx = 0;
    size_t i, n = (size_t)w * (size_t)h;
    int s = 1, top = 40, bar_x, x, y, W, H, bar_h;
    double lm;
    char lab[64];
    if (w < 1 || h < 1) {
        snprintf(err->msg, sizeof err->msg, "heat map size %dx%d is out of range", w, h);
        return EVR_ERR_ARG;
    }
    while (w * (s + 1) <= 640 && h * (s + 1) <= 640) s++;
    W = w * s + 110;
    H = h * s + top + 10;
    if (H < 200) H = 200;
    if ((st = evr_canvas_init(&c, W, H, err)) != EVR_OK) return st;
    for (i = 0; i < n; i++)
        if (counts[i] > mx) mx = counts[i];
    lm = log1p((double)(mx ? mx : 1));
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            uint8_t col[3];
            evr_plot_colormap(log1p((double)counts[(size_t)y * (size_t)w + (size_t)x]) / lm, col);
            evr_canvas_rect(&c, x * s, top + y * s, (x + 1) * s, top + (y + 1) * s, col);
        }
    if (title) evr_canvas_text(&c, 4, 8, 2, title, BLACK);
    /* colour bar: log scale from 0 (bottom) to max (top), labelled at powers of ten */
    bar_x = w * s + 12;
    bar_h = H - top - 20;
    for (y = 0; y < bar_h; y++) {
        uint8_t col[3];
        evr_plot_colormap(1.0 - (double)y / (bar_h - 1), col);
        evr_canvas_rect(&c, bar_x, top + y, bar_x + 16, top + y + 1, col);
    }
    {
        double p;
        for (p = 1.0; p <= (double)mx; p *= 10.0) {
            int yy = top + (int)lround((1.0 - log1p(p) / lm) * (bar_h - 1));
            evr_canvas_rect(&c, bar_x + 16, yy, bar_x + 20, yy + 1, BLACK);
            snprintf(lab, sizeof lab, "%.0f", p);
            evr_canvas_text(&c, bar_x + 23, yy - 3, 1, lab, BLACK);
        }
        snprintf(lab, sizeof lab, "max %lu", (unsigned long)mx);
        evr_canvas_text(&c, bar_x, top - 12, 1, lab, BLACK);
        evr_canvas_text(&c, bar_x + 23, top + bar_h - 4, 1, "0", BLACK);
    }
    st = evr_png_write(path, c.rgb, c.w, c.h, 3, 8, err);
    if (st == EVR_OK) {
        if (out_w) *out_w = W;
        if (out_h) *out_h = H;
    }
    evr_canvas_release(&c);
    return st;
}
