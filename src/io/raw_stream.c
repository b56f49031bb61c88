#include "io/raw_stream.h"
#include "io/file_commit.h"

#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RAW_BUFFER ((size_t)1 << 20)

/* Frees the writer (the stream is its first member). */
static void free_stream(evr_raw_stream *s)
{
    free(s->path);
    free(s->tmp);
    free(s->buf);
    evr_par_packing_free(&s->parts);
    free(s);
}

static evr_status cannot_write(const evr_raw_stream *s, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: cannot write %s: %s", s->who, s->tmp, strerror(errno));
    return EVR_ERR_IO;
}

static evr_status drain(evr_raw_stream *s, evr_error *err)
{
    if (s->len && fwrite(s->buf, 1, s->len, s->f) != s->len) return cannot_write(s, err);
    s->handed += s->len;
    s->len = 0;
    return EVR_OK;
}

static evr_status raw_flush(evr_event_writer *base, evr_error *err)
{
    evr_raw_stream *s = (evr_raw_stream *)base;
    evr_status st = drain(s, err);
    if (st == EVR_OK && fflush(s->f) != 0) st = cannot_write(s, err);
    return st;
}

static evr_status raw_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    evr_raw_stream *s = (evr_raw_stream *)base;
    evr_status st = drain(s, err);
    (void)duration_us;
    st = evr_file_commit(s->f, s->tmp, s->path, st, s->who, err);
    free_stream(s);
    return st;
}

static evr_status raw_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    evr_raw_stream *s = (evr_raw_stream *)base;
    s->prev_count = s->count;
    s->prev_bytes = s->handed + s->len;
    evr_status st = s->write_fn(base, ev, n, err);
    if (st == EVR_OK) s->count += n;
    return st;
}

static evr_status raw_salvage(evr_event_writer *base, uint64_t events, int64_t duration_us,
                              evr_error *err)
{
    evr_raw_stream *s = (evr_raw_stream *)base;
    evr_status st;
    (void)duration_us;
    if (events != s->count && events != s->prev_count) {
        snprintf(err->msg, sizeof err->msg, "%s: cannot keep %llu events of %s", s->who,
                 (unsigned long long)events, s->path);
        evr_file_discard(s->f, s->tmp);
        st = EVR_ERR_IO;
    } else {
        st = evr_file_salvage(s->f, s->tmp, s->path,
                              events == s->count ? s->handed + s->len : s->prev_bytes,
                              s->handed + s->len, s->buf, s->len, NULL, 0, s->who, err);
    }
    free_stream(s);
    return st;
}

static void raw_abort(evr_event_writer *base)
{
    evr_raw_stream *s = (evr_raw_stream *)base;
    evr_file_discard(s->f, s->tmp);
    free_stream(s);
}

evr_status evr_raw_writer_open(size_t size, const char *path, const char *who, int max_xy,
                               int64_t max_t, const char *header, size_t len,
                               evr_status (*write)(evr_event_writer *w, const evr_event *ev,
                                                   size_t n, evr_error *err),
                               evr_event_writer **out, evr_error *err)
{
    evr_raw_stream *s;
    *out = NULL;
    if (!path || !*path) {
        snprintf(err->msg, sizeof err->msg, "%s: no path given", who);
        return EVR_ERR_ARG;
    }
    s = calloc(1, size);
    if (s) {
        s->path = strdup(path);
        s->tmp = evr_file_tmp_name(path);
        s->cap = RAW_BUFFER;
        s->buf = malloc(s->cap);
    }
    if (!s || !s->path || !s->tmp || !s->buf) {
        if (s) free_stream(s);
        snprintf(err->msg, sizeof err->msg, "%s: out of memory", who);
        return EVR_ERR_NOMEM;
    }
    s->who = who;
    s->max_xy = max_xy;
    s->max_t = max_t;
    s->f = evr_file_create(s->tmp, who, err);
    if (!s->f) {
        free_stream(s);
        return EVR_ERR_IO;
    }
    s->handed = len;
    if (fwrite(header, 1, len, s->f) != len) {
        cannot_write(s, err);
        evr_file_discard(s->f, s->tmp);
        free_stream(s);
        return EVR_ERR_IO;
    }
    s->write_fn = write;
    s->base.write = raw_write;
    s->base.flush = raw_flush;
    s->base.finish = raw_finish;
    s->base.abort = raw_abort;
    s->base.salvage = raw_salvage;
    *out = &s->base;
    return EVR_OK;
}

evr_status evr_raw_stream_check(evr_raw_stream *s, const evr_event *e, evr_error *err)
{
    if (s->have_last && e->t < s->last_t) {
        snprintf(err->msg, sizeof err->msg,
                 "%s: events out of time order (%" PRId64 " us after %" PRId64 " us)", s->who, e->t,
                 s->last_t);
        return EVR_ERR_ARG;
    }
    if (e->x >= s->max_xy || e->y >= s->max_xy) {
        snprintf(err->msg, sizeof err->msg,
                 "%s: pixel (%u, %u) past the format's %d x %d addresses", s->who, e->x, e->y,
                 s->max_xy, s->max_xy);
        return EVR_ERR_ARG;
    }
    if (e->t < 0 || e->t > s->max_t) {
        snprintf(err->msg, sizeof err->msg,
                 "%s: timestamp %" PRId64 " us outside the format's range (0 to %" PRId64 " us)",
                 s->who, e->t, s->max_t);
        return EVR_ERR_ARG;
    }
    s->last_t = e->t;
    s->have_last = 1;
    return EVR_OK;
}

int evr_raw_stream_write_parts(evr_raw_stream *s, const evr_par_packer *p, const evr_event *ev,
                               size_t n, evr_status *st, evr_error *err)
{
    size_t bytes;
    evr_par_pack_result r;
    *st = EVR_OK;
    if (n < EVR_PAR_PACK_MIN || (s->have_last && ev[0].t < s->last_t)) return 0;
    if ((*st = drain(s, err)) != EVR_OK) return 1;
    r = evr_par_pack_write(&s->parts, p, ev, n, s->f, &bytes);
    if (r == EVR_PAR_PACK_SERIAL) return 0;
    if (r == EVR_PAR_PACK_FAILED) {
        *st = cannot_write(s, err);
        return 1;
    }
    s->handed += bytes;
    s->last_t = ev[n - 1].t;
    s->have_last = 1;
    return 1;
}

evr_status evr_raw_stream_room(evr_raw_stream *s, size_t need, evr_error *err)
{
    return s->cap - s->len >= need ? EVR_OK : drain(s, err);
}

size_t evr_prophesee_header(char *out, size_t cap, const char *evt, const char *format, int width,
                            int height)
{
    char date[32] = "1970-01-01 00:00:00";
    time_t now = time(NULL);
    struct tm tmv;
    int n;
    if (gmtime_r(&now, &tmv)) strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", &tmv);
    if (evt)
        n = snprintf(out, cap,
                     "%% camera_integrator_name evray\n%% date %s\n%% evt %s\n"
                     "%% format %s;height=%d;width=%d\n%% geometry %dx%d\n"
                     "%% integrator_name evray\n%% end\n",
                     date, evt, format, height, width, width, height);
    else
        n = snprintf(out, cap,
                     "%% Data file containing CD events.\n%% Date %s\n%% Version 2\n"
                     "%% Height %d\n%% Width %d\n%% end\n",
                     date, height, width);
    return n > 0 && (size_t)n < cap ? (size_t)n : 0;
}
