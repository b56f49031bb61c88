#include "io/preview.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/png.h"

/* ---- event frames ---- */

evr_status evr_event_frame_init(evr_event_frame *f, int width, int height, evr_error *err)
{
    size_t n;
    memset(f, 0, sizeof *f);
    if (width <= 0 || height <= 0 || width > 65536 || height > 65536) {
        snprintf(err->msg, sizeof err->msg, "event frame: bad size %dx%d", width, height);
        return EVR_ERR_ARG;
    }
    n = (size_t)width * (size_t)height;
    f->width = width;
    f->height = height;
    f->on = calloc(n, sizeof *f->on);
    f->off = calloc(n, sizeof *f->off);
    f->last = calloc(n, sizeof *f->last);
    if (!f->on || !f->off || !f->last) {
        evr_event_frame_release(f);
        snprintf(err->msg, sizeof err->msg, "event frame: out of memory");
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

void evr_event_frame_clear(evr_event_frame *f)
{
    size_t n = (size_t)f->width * (size_t)f->height;
    memset(f->on, 0, n * sizeof *f->on);
    memset(f->off, 0, n * sizeof *f->off);
    memset(f->last, 0, n * sizeof *f->last);
    f->events = 0;
}

void evr_event_frame_add(evr_event_frame *f, const evr_event *ev, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        size_t k;
        if (ev[i].x >= f->width || ev[i].y >= f->height) continue;
        k = (size_t)ev[i].y * (size_t)f->width + ev[i].x;
        if (ev[i].p) {
            if (f->on[k] < UINT32_MAX) f->on[k]++;
        } else if (f->off[k] < UINT32_MAX) f->off[k]++;
        f->last[k] = ev[i].p ? 1 : 0;
        f->events++;
    }
}

void evr_event_frame_render(const evr_event_frame *f, uint8_t *rgb)
{
    size_t n = (size_t)f->width * (size_t)f->height;
    for (size_t k = 0; k < n; k++) {
        uint8_t *c = rgb + 3 * k;
        uint32_t on = f->on[k], off = f->off[k];
        if (!on && !off) {
            c[0] = c[1] = c[2] = 255;
            continue;
        }
        int is_on = on != off ? on > off : f->last[k];
        c[0] = is_on ? 0 : 255;
        c[1] = 0;
        c[2] = is_on ? 255 : 0;
    }
}

evr_status evr_event_frame_write_png(const evr_event_frame *f, const char *path, evr_error *err)
{
    uint8_t *rgb = malloc((size_t)f->width * (size_t)f->height * 3);
    evr_status st;
    if (!rgb) {
        snprintf(err->msg, sizeof err->msg, "event frame: out of memory");
        return EVR_ERR_NOMEM;
    }
    evr_event_frame_render(f, rgb);
    st = evr_png_write(path, rgb, f->width, f->height, 3, 8, err);
    free(rgb);
    return st;
}

void evr_event_frame_release(evr_event_frame *f)
{
    free(f->on);
    free(f->off);
    free(f->last);
    memset(f, 0, sizeof *f);
}

/* ---- series of event frames ---- */

struct evr_event_preview {
    evr_event_frame frame;
    int64_t window_us;
    int64_t index; /* window the frame accumulates */
    char *dir, *prefix;
    int frames;
};

evr_status evr_event_preview_new(int width, int height, int64_t window_us, const char *dir,
                                 const char *prefix, evr_event_preview **out, evr_error *err)
{
    evr_event_preview *p;
    evr_status st;
    *out = NULL;
    if (window_us <= 0 || !dir || !prefix) {
        snprintf(err->msg, sizeof err->msg, "event preview: bad window %lld us or no folder",
                 (long long)window_us);
        return EVR_ERR_ARG;
    }
    p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err->msg, sizeof err->msg, "event preview: out of memory");
        return EVR_ERR_NOMEM;
    }
    st = evr_event_frame_init(&p->frame, width, height, err);
    if (st != EVR_OK) {
        free(p);
        return st;
    }
    p->window_us = window_us;
    p->dir = malloc(strlen(dir) + 1);
    p->prefix = malloc(strlen(prefix) + 1);
    if (!p->dir || !p->prefix) {
        evr_event_preview_release(p);
        snprintf(err->msg, sizeof err->msg, "event preview: out of memory");
        return EVR_ERR_NOMEM;
    }
    strcpy(p->dir, dir);
    strcpy(p->prefix, prefix);
    *out = p;
    return EVR_OK;
}

/* Writes the open window's frame and opens the next one. */
static evr_status emit(evr_event_preview *p, evr_error *err)
{
    size_t len = strlen(p->dir) + strlen(p->prefix) + 32;
    char *path = malloc(len);
    evr_status st;
    if (!path) {
        snprintf(err->msg, sizeof err->msg, "event preview: out of memory");
        return EVR_ERR_NOMEM;
    }
    snprintf(path, len, "%s/%s_%06lld.png", p->dir, p->prefix, (long long)p->index);
    st = evr_event_frame_write_png(&p->frame, path, err);
    free(path);
    if (st != EVR_OK) return st;
    evr_event_frame_clear(&p->frame);
    p->index++;
    p->frames++;
    return EVR_OK;
}

evr_status evr_event_preview_advance(evr_event_preview *p, int64_t t_us, evr_error *err)
{
    while ((p->index + 1) * p->window_us <= t_us) {
        evr_status st = emit(p, err);
        if (st != EVR_OK) return st;
    }
    return EVR_OK;
}

evr_status evr_event_preview_add(evr_event_preview *p, const evr_event *ev, size_t n,
                                 evr_error *err)
{
    size_t i = 0;
    while (i < n && ev[i].t < 0) i++;
    while (i < n) {
        int64_t end = (p->index + 1) * p->window_us;
        size_t j = i;
        while (j < n && ev[j].t < end) j++;
        evr_event_frame_add(&p->frame, ev + i, j - i);
        if (j == n) break;
        evr_status st = evr_event_preview_advance(p, ev[j].t, err);
        if (st != EVR_OK) return st;
        i = j;
    }
    return EVR_OK;
}

evr_status evr_event_preview_finish(evr_event_preview *p, int64_t end_us, evr_error *err)
{
    while (p->index * p->window_us < end_us) {
        evr_status st = emit(p, err);
        if (st != EVR_OK) return st;
    }
    return EVR_OK;
}

int evr_event_preview_frames(const evr_event_preview *p) { return p->frames; }

void evr_event_preview_release(evr_event_preview *p)
{
    if (!p) return;
    evr_event_frame_release(&p->frame);
    free(p->dir);
    free(p->prefix);
    free(p);
}

/* ---- intensity frames ---- */

/* The k-th smallest of v[0..n-1] (v is reordered; no NaN): Hoare's selection, expected linear
 * time, and fine with many equal values (black backgrounds). */
static float select_kth(float *v, size_t n, size_t k)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, kk = (ptrdiff_t)k;
    while (lo < hi) {
        float pivot = v[lo + (hi - lo) / 2];
        ptrdiff_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pivot) i++;
            while (v[j] > pivot) j--;
            if (i <= j) {
                float t = v[i];
                v[i] = v[j];
                v[j] = t;
                i++;
                j--;
            }
        }
        /* now v[lo..j] <= pivot <= v[i..hi], and everything between equals the pivot */
        if (kk <= j) hi = j;
        else if (kk >= i) lo = i;
        else break;
    }
    return v[kk];
}

/* Negative and NaN values count as black, +infinity as the largest float. */
static float clean(float v)
{
    if (v > 0.0f) return v <= FLT_MAX ? v : FLT_MAX;
    return 0.0f;
}

evr_status evr_exposure_of(const float *linear, size_t n, evr_exposure *e, evr_error *err)
{
    float *vis;
    size_t m = 0, k999, k99;
    double median, p99, p999;
    e->scale = 0.0;
    e->white = 1.0;
    if (n == 0) return EVR_OK;
    if (!(vis = malloc(n * sizeof *vis))) {
        snprintf(err->msg, sizeof err->msg, "tone mapping: out of memory");
        return EVR_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        float v = clean(linear[i]);
        if (v > 0.0f) vis[m++] = v;
    }
    if (m == 0) {
        free(vis);
        return EVR_OK;
    }
    /* from the top down: each selection leaves the k smallest values below index k, where the
     * next one looks */
    k999 = (size_t)floor(0.999 * (double)(m - 1) + 0.5);
    k99 = (size_t)floor(0.99 * (double)(m - 1) + 0.5);
    p999 = select_kth(vis, m, k999);
    p99 = select_kth(vis, k999 + 1, k99);
    median = select_kth(vis, k99 + 1, (m - 1) / 2);
    free(vis);
    e->scale = EVR_EXPOSURE_KEY / median;
    if (p99 * e->scale > 1.0) e->scale = 1.0 / p99;
    if (p999 * e->scale > 1.0) e->white = p999 * e->scale;
    if (!(e->white < 1e30)) e->white = 1e30; /* an infinite pixel: the curve stays finite */
    return EVR_OK;
}

void evr_tonemap_exposed(const float *linear, size_t n, const evr_exposure *e, uint8_t *out)
{
    const double w2 = e->white * e->white;
    for (size_t i = 0; i < n; i++) {
        double l = (double)clean(linear[i]) * e->scale, v;
        if (e->white <= 1.0) v = l;      /* the curve with white 1 is the identity */
        else if (l >= e->white) v = 1.0; /* it reaches 1 at the white point */
        else v = l * (1.0 + l / w2) / (1.0 + l);
        if (v > 1.0) v = 1.0;
        v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
        long q = lround(v * 255.0);
        out[i] = (uint8_t)(q < 0 ? 0 : q > 255 ? 255 : q);
    }
}

evr_status evr_tonemap_frame(const float *linear, size_t n, uint8_t *out, evr_error *err)
{
    evr_exposure e;
    evr_status st = evr_exposure_of(linear, n, &e, err);
    if (st == EVR_OK) evr_tonemap_exposed(linear, n, &e, out);
    return st;
}
