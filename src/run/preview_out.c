#include "run/preview_out.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/apng.h"
#include "io/mkdir_p.h"
#include "io/png.h"

/* Finished images waiting for their other half (video): oldest first. */
typedef struct {
    uint8_t **img;
    int head, count, cap;
} fifo;

struct evr_preview_out {
    int kind, width, height;
    size_t npix;
    int64_t start_us, window_us;
    char *dir; /* the run folder */
    /* events */
    evr_event_frame events;
    int64_t event_index; /* the window the event frame accumulates */
    /* intensity */
    int64_t gray_index;    /* the next intensity frame to go out */
    evr_exposure exposure; /* fixed once exposure_fixed */
    int exposure_fixed;    /* 1 once fixed */
    float *held;           /* up to EVR_PREVIEW_EXPOSURE_FRAMES frames waiting for it */
    int num_held;
    /* video */
    evr_apng *video;
    fifo ev_rgb, gray;
    uint8_t *both;    /* one video frame: 2 width x height RGB */
    int video_failed; /* a frame's write failed: the video may end inside it */
};

static evr_status nomem(evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "previews: out of memory");
    return EVR_ERR_NOMEM;
}

static int fifo_push(fifo *f, uint8_t *img)
{
    if (f->count == f->cap) {
        int ncap = f->cap ? 2 * f->cap : 8, i;
        uint8_t **n = malloc((size_t)ncap * sizeof *n);
        if (!n) return 0;
        for (i = 0; i < f->count; i++) n[i] = f->img[(f->head + i) % f->cap];
        free(f->img);
        f->img = n;
        f->head = 0;
        f->cap = ncap;
    }
    f->img[(f->head + f->count++) % f->cap] = img;
    return 1;
}

static uint8_t *fifo_pop(fifo *f)
{
    uint8_t *img = f->img[f->head];
    f->head = (f->head + 1) % f->cap;
    f->count--;
    return img;
}

static void fifo_free(fifo *f)
{
    while (f->count) free(fifo_pop(f));
    free(f->img);
    memset(f, 0, sizeof *f);
}

/* The frame delay of a window as a fraction of a second whose parts fit APNG's 16 bits. */
static void window_delay(int64_t us, unsigned *num, unsigned *den)
{
    int64_t a = us, b = 1000000;
    while (b) { /* gcd */
        int64_t t = a % b;
        a = b;
        b = t;
    }
    if (us / a <= 65535 && 1000000 / a <= 65535) {
        *num = (unsigned)(us / a);
        *den = (unsigned)(1000000 / a);
    } else if ((us + 500) / 1000 <= 65535) { /* to the millisecond */
        *num = (unsigned)((us + 500) / 1000);
        *den = 1000;
    } else { /* to the second */
        int64_t s = (us + 500000) / 1000000;
        *num = (unsigned)(s > 65535 ? 65535 : s);
        *den = 1;
    }
    if (*num == 0) *num = 1;
}

evr_status evr_preview_out_new(int kind, const char *run_dir, int width, int height,
                               int64_t start_us, int64_t window_us, evr_preview_out **out,
                               evr_error *err)
{
    evr_preview_out *p;
    evr_status st;
    size_t n = strlen(run_dir) + 32;
    *out = NULL;
    if ((kind != EVR_PREVIEW_PNG && kind != EVR_PREVIEW_VIDEO) || window_us < 1) {
        snprintf(err->msg, sizeof err->msg, "previews: bad kind %d or window %lld us", kind,
                 (long long)window_us);
        return EVR_ERR_ARG;
    }
    if (!(p = calloc(1, sizeof *p)) || !(p->dir = malloc(n))) {
        free(p);
        return nomem(err);
    }
    strcpy(p->dir, run_dir);
    p->kind = kind;
    p->width = width;
    p->height = height;
    p->npix = (size_t)width * (size_t)height;
    p->start_us = start_us;
    p->window_us = window_us;
    if ((st = evr_event_frame_init(&p->events, width, height, err)) != EVR_OK) {
        evr_preview_out_release(p);
        return st;
    }
    if (kind == EVR_PREVIEW_PNG) {
        char path[4200];
        snprintf(path, sizeof path, "%s/preview", run_dir);
        if (evr_mkdir_p(path) != 0) {
            snprintf(err->msg, sizeof err->msg, "cannot create %s: %s", path, strerror(errno));
            evr_preview_out_release(p);
            return EVR_ERR_IO;
        }
    } else {
        char path[4200];
        unsigned num, den;
        window_delay(window_us, &num, &den);
        snprintf(path, sizeof path, "%s/preview.apng", run_dir);
        if (!(p->both = malloc(p->npix * 6))) {
            evr_preview_out_release(p);
            return nomem(err);
        }
        if ((st = evr_apng_open(path, 2 * width, height, 3, num, den, &p->video, err)) != EVR_OK) {
            evr_preview_out_release(p);
            return st;
        }
    }
    *out = p;
    return EVR_OK;
}

/* Video frames whose halves are both there. */
static evr_status pair(evr_preview_out *p, evr_error *err)
{
    while (p->ev_rgb.count && p->gray.count) {
        uint8_t *ev = fifo_pop(&p->ev_rgb), *gray = fifo_pop(&p->gray);
        const size_t w = (size_t)p->width;
        evr_status st;
        for (int y = 0; y < p->height; y++) {
            uint8_t *row = p->both + (size_t)y * w * 6;
            memcpy(row, ev + (size_t)y * w * 3, w * 3);
            for (size_t x = 0; x < w; x++)
                row[3 * (w + x)] = row[3 * (w + x) + 1] = row[3 * (w + x) + 2] =
                    gray[(size_t)y * w + x];
        }
        free(ev);
        free(gray);
        if ((st = evr_apng_add(p->video, p->both, err)) != EVR_OK) {
            p->video_failed = 1;
            return st;
        }
    }
    return EVR_OK;
}

/* The finished event frame of window event_index goes out; the next window opens. */
static evr_status event_frame_done(evr_preview_out *p, evr_error *err)
{
    evr_status st = EVR_OK;
    if (p->kind == EVR_PREVIEW_PNG) {
        char path[4200];
        snprintf(path, sizeof path, "%s/preview/events_%06lld.png", p->dir,
                 (long long)p->event_index);
        st = evr_event_frame_write_png(&p->events, path, err);
    } else {
        uint8_t *rgb = malloc(p->npix * 3);
        if (!rgb) return nomem(err);
        evr_event_frame_render(&p->events, rgb);
        if (!fifo_push(&p->ev_rgb, rgb)) {
            free(rgb);
            return nomem(err);
        }
        st = pair(p, err);
    }
    evr_event_frame_clear(&p->events);
    p->event_index++;
    return st;
}

evr_status evr_preview_out_events(evr_preview_out *p, const evr_event *ev, size_t n, evr_error *err)
{
    size_t i = 0, j;
    evr_status st;
    while (i < n && ev[i].t < p->start_us) i++;
    while (i < n) {
        int64_t frame = (ev[i].t - p->start_us) / p->window_us;
        while (frame > p->event_index) /* windows without events go out too */
            if ((st = event_frame_done(p, err)) != EVR_OK) return st;
        int64_t end_us = p->start_us + (p->event_index + 1) * p->window_us;
        for (j = i; j < n && ev[j].t < end_us; j++) {}
        evr_event_frame_add(&p->events, ev + i, j - i);
        i = j;
    }
    return EVR_OK;
}

evr_status evr_preview_out_advance(evr_preview_out *p, int64_t t_us, evr_error *err)
{
    while (p->start_us + (p->event_index + 1) * p->window_us <= t_us) {
        evr_status st = event_frame_done(p, err);
        if (st != EVR_OK) return st;
    }
    return EVR_OK;
}

/* A tone mapped intensity frame goes out (gray: malloc'ed, owned from here on). */
static evr_status gray_done(evr_preview_out *p, uint8_t *gray, evr_error *err)
{
    evr_status st;
    if (p->kind == EVR_PREVIEW_PNG) {
        char path[4200];
        snprintf(path, sizeof path, "%s/preview/intensity_%06lld.png", p->dir,
                 (long long)p->gray_index);
        st = evr_png_write(path, gray, p->width, p->height, 1, 8, err);
        free(gray);
    } else if (!fifo_push(&p->gray, gray)) {
        free(gray);
        st = nomem(err);
    } else st = pair(p, err);
    p->gray_index++;
    return st;
}

static evr_status tone_map_out(evr_preview_out *p, const float *linear, evr_error *err)
{
    uint8_t *gray = malloc(p->npix);
    if (!gray) return nomem(err);
    evr_tonemap_exposed(linear, p->npix, &p->exposure, gray);
    return gray_done(p, gray, err);
}

/* The exposure from the held frames, which then go out. */
static evr_status fix_exposure(evr_preview_out *p, evr_error *err)
{
    evr_status st = evr_exposure_of(p->held, (size_t)p->num_held * p->npix, &p->exposure, err);
    for (int k = 0; k < p->num_held && st == EVR_OK; k++)
        st = tone_map_out(p, p->held + (size_t)k * p->npix, err);
    p->exposure_fixed = 1;
    p->num_held = 0;
    free(p->held);
    p->held = NULL;
    return st;
}

evr_status evr_preview_out_intensity(evr_preview_out *p, const float *linear, evr_error *err)
{
    int visible = 0;
    if (p->exposure_fixed) return tone_map_out(p, linear, err);
    for (size_t i = 0; i < p->npix && !visible; i++) visible = linear[i] > 0.0f;
    if (!visible && !p->num_held) { /* black under any exposure */
        uint8_t *gray = calloc(p->npix, 1);
        return gray ? gray_done(p, gray, err) : nomem(err);
    }
    if (!p->held && !(p->held = malloc(EVR_PREVIEW_EXPOSURE_FRAMES * p->npix * sizeof *p->held)))
        return nomem(err);
    memcpy(p->held + (size_t)p->num_held++ * p->npix, linear, p->npix * sizeof *linear);
    if (p->num_held == EVR_PREVIEW_EXPOSURE_FRAMES) return fix_exposure(p, err);
    return EVR_OK;
}

evr_status evr_preview_out_finish(evr_preview_out *p, int64_t dur_us, evr_error *err)
{
    evr_status st = EVR_OK;
    int64_t last = (dur_us - 1) / p->window_us; /* the last window that starts before the end */
    while (st == EVR_OK && p->event_index <= last) st = event_frame_done(p, err);
    if (st == EVR_OK && !p->exposure_fixed) st = fix_exposure(p, err);
    if (st == EVR_OK && p->video_failed) {
        snprintf(err->msg, sizeof err->msg,
                 "previews: preview.apng not kept (a frame's write failed)");
        st = EVR_ERR_IO;
    }
    if (st == EVR_OK && p->video) {
        /* a half without its other (a window without its intensity) is left out */
        st = evr_apng_finish(p->video, err);
        p->video = NULL;
    }
    return st;
}

int evr_preview_out_windows(const evr_preview_out *p) { return p ? (int)p->event_index : 0; }

evr_exposure evr_preview_out_exposure(const evr_preview_out *p) { return p->exposure; }

void evr_preview_out_release(evr_preview_out *p)
{
    if (!p) return;
    evr_apng_abort(p->video);
    evr_event_frame_release(&p->events);
    fifo_free(&p->ev_rgb);
    fifo_free(&p->gray);
    free(p->held);
    free(p->both);
    free(p->dir);
    free(p);
}
