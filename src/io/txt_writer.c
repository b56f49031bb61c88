/* Text event files: one event per line, "t x y p", t in seconds with exactly six decimals (printed
 * from the integer microseconds, so no rounding), p 1 (ON) or 0 (OFF). No header line, so that
 * numpy.loadtxt and the usual event-camera tools read the file as is. */
#include "io/event_formats.h"
#include "io/file_commit.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TXT_BUFFER (1u << 20)
#define TXT_LINE_MAX 64 /* "-9223372036854.775808 65535 65535 1\n" fits easily */

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    char *path, *tmp;
    FILE *f;
    char *buf;
    size_t len;
    int64_t last_t;
    int have_last;
    /* events and text bytes given so far (written and buffered), and as the last write() began
     * (salvage) */
    uint64_t count, bytes, prev_count, prev_bytes;
} txt_writer;

static char *put_uint(char *o, uint64_t v)
{
    char d[20];
    int n = 0;
    do {
        d[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n) *o++ = d[--n];
    return o;
}

static char *format_event(char *o, const evr_event *e)
{
    uint64_t u = (uint64_t)e->t, frac;
    if (e->t < 0) {
        *o++ = '-';
        u = 0 - u;
    }
    o = put_uint(o, u / 1000000u);
    *o++ = '.';
    frac = u % 1000000u;
    for (uint64_t div = 100000u; div; div /= 10) *o++ = (char)('0' + (frac / div) % 10);
    *o++ = ' ';
    o = put_uint(o, e->x);
    *o++ = ' ';
    o = put_uint(o, e->y);
    *o++ = ' ';
    *o++ = e->p ? '1' : '0';
    *o++ = '\n';
    return o;
}

static evr_status drain(txt_writer *w, evr_error *err)
{
    if (w->len && fwrite(w->buf, 1, w->len, w->f) != w->len) {
        snprintf(err->msg, sizeof err->msg, "text writer: cannot write %s: %s", w->tmp,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    w->len = 0;
    return EVR_OK;
}

static void free_writer(txt_writer *w)
{
    free(w->path);
    free(w->tmp);
    free(w->buf);
    free(w);
}

static evr_status txt_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    txt_writer *w = (txt_writer *)base;
    w->prev_count = w->count;
    w->prev_bytes = w->bytes;
    for (size_t i = 0; i < n; i++) {
        if (w->have_last && ev[i].t < w->last_t) {
            snprintf(err->msg, sizeof err->msg,
                     "text writer: events out of time order (%" PRId64 " us after %" PRId64 " us)",
                     ev[i].t, w->last_t);
            return EVR_ERR_ARG;
        }
        w->last_t = ev[i].t;
        w->have_last = 1;
        if (w->len + TXT_LINE_MAX > TXT_BUFFER) {
            evr_status st = drain(w, err);
            if (st != EVR_OK) return st;
        }
        size_t len = (size_t)(format_event(w->buf + w->len, &ev[i]) - w->buf);
        w->bytes += len - w->len;
        w->len = len;
        w->count++;
    }
    return EVR_OK;
}

static evr_status txt_flush(evr_event_writer *base, evr_error *err)
{
    txt_writer *w = (txt_writer *)base;
    evr_status st = drain(w, err);
    if (st != EVR_OK) return st;
    if (fflush(w->f) != 0) {
        snprintf(err->msg, sizeof err->msg, "text writer: cannot write %s: %s", w->tmp,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

static void txt_abort(evr_event_writer *base)
{
    txt_writer *w = (txt_writer *)base;
    evr_file_discard(w->f, w->tmp);
    free_writer(w);
}

static evr_status txt_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    txt_writer *w = (txt_writer *)base;
    evr_status st = drain(w, err);
    (void)duration_us;
    st = evr_file_commit(w->f, w->tmp, w->path, st, "text writer", err);
    w->f = NULL;
    free_writer(w);
    return st;
}

static evr_status txt_salvage(evr_event_writer *base, uint64_t events, int64_t duration_us,
                              evr_error *err)
{
    txt_writer *w = (txt_writer *)base;
    evr_status st;
    (void)duration_us;
    if (events != w->count && events != w->prev_count) {
        snprintf(err->msg, sizeof err->msg, "text writer: cannot keep %llu events of %s",
                 (unsigned long long)events, w->path);
        evr_file_discard(w->f, w->tmp);
        st = EVR_ERR_IO;
    } else {
        st = evr_file_salvage(w->f, w->tmp, w->path, events == w->count ? w->bytes : w->prev_bytes,
                              w->bytes, (const unsigned char *)w->buf, w->len, NULL, 0,
                              "text writer", err);
    }
    free_writer(w);
    return st;
}

evr_status evr_txt_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err)
{
    txt_writer *w;
    (void)meta;
    *out = NULL;
    if (!path || !*path) {
        snprintf(err->msg, sizeof err->msg, "text writer: no path given");
        return EVR_ERR_ARG;
    }
    w = calloc(1, sizeof *w);
    if (w) {
        w->path = strdup(path);
        w->tmp = evr_file_tmp_name(path);
        w->buf = malloc(TXT_BUFFER);
    }
    if (!w || !w->path || !w->tmp || !w->buf) {
        if (w) free_writer(w);
        snprintf(err->msg, sizeof err->msg, "text writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    w->f = evr_file_create(w->tmp, "text writer", err);
    if (!w->f) {
        free_writer(w);
        return EVR_ERR_IO;
    }
    w->base.write = txt_write;
    w->base.flush = txt_flush;
    w->base.finish = txt_finish;
    w->base.abort = txt_abort;
    w->base.salvage = txt_salvage;
    *out = &w->base;
    return EVR_OK;
}

const evr_event_format evr_format_txt = {
    "txt", NULL, "events.txt", evr_txt_writer_open, "text, one event a line (t x y p)", ".txt"};
