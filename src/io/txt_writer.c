/* Text event files: one event per line, "t x y p", t in seconds with exactly six decimals (printed
 * from the integer microseconds, so no rounding), p 1 (ON) or 0 (OFF). No header line, so that
 * numpy.loadtxt and the usual event-camera tools read the file as is. With event ids
 * (evr_writer_meta.event_ids) a fifth column: evr_event.id. */
#include "io/event_formats.h"
#include "io/file_commit.h"
#include "io/par_pack.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TXT_BUFFER (1u << 20)
#define TXT_LINE_MAX 64 /* "-9223372036854.775808 65535 65535 1 4294967295\n" fits */

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    char *path, *tmp;
    FILE *f;
    char *buf;
    size_t len;
    int ids; /* a fifth column */
    int64_t last_t;
    int have_last;
    /* events and text bytes given so far (written and buffered), and as the last write() began
     * (salvage) */
    uint64_t count, bytes, prev_count, prev_bytes;
    evr_par_packing parts; /* large writes, formatted on threads */
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

static char *format_event(char *o, const evr_event *e, int ids)
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
    if (ids) {
        *o++ = ' ';
        o = put_uint(o, e->id);
    }
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
    evr_par_packing_free(&w->parts);
    free(w->path);
    free(w->tmp);
    free(w->buf);
    free(w);
}

/* A part of a large write (io/par_pack.h; ctx the writer): a line an event. */
static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ctx;
    (void)ev;
    return (b - a) * TXT_LINE_MAX;
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const txt_writer *w = (const txt_writer *)ctx;
    char *o = (char *)out;
    (void)room;
    for (size_t i = a; i < b; i++) {
        if (i > 0 && ev[i].t < ev[i - 1].t) return SIZE_MAX;
        o = format_event(o, &ev[i], w->ids);
    }
    return (size_t)(o - (char *)out);
}

/* Writes ev[0 .. n) (n >= EVR_PAR_PACK_MIN, ev[0] not before the last event written) in parts
 * after the buffered text (*st: how it went); returns 0, nothing written, when an event is out of
 * order or there is no room to format them: the serial path then writes them or reports it. */
static int write_parallel(txt_writer *w, const evr_event *ev, size_t n, evr_error *err,
                          evr_status *st)
{
    const evr_par_packer parts = {bound_part, pack_part, NULL, w};
    size_t bytes;
    evr_par_pack_result r;
    if ((*st = drain(w, err)) != EVR_OK) return 1;
    r = evr_par_pack_write(&w->parts, &parts, ev, n, w->f, &bytes);
    if (r == EVR_PAR_PACK_SERIAL) return 0;
    if (r == EVR_PAR_PACK_FAILED) {
        snprintf(err->msg, sizeof err->msg, "text writer: cannot write %s: %s", w->tmp,
                 strerror(errno));
        *st = EVR_ERR_IO;
        return 1;
    }
    w->count += n;
    w->bytes += bytes;
    w->last_t = ev[n - 1].t;
    w->have_last = 1;
    return 1;
}

static evr_status txt_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    txt_writer *w = (txt_writer *)base;
    w->prev_count = w->count;
    w->prev_bytes = w->bytes;
    if (n >= EVR_PAR_PACK_MIN && !(w->have_last && ev[0].t < w->last_t)) {
        evr_status st;
        if (write_parallel(w, ev, n, err, &st)) return st;
    }
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
        size_t len = (size_t)(format_event(w->buf + w->len, &ev[i], w->ids) - w->buf);
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
    *out = NULL;
    if (!path || !*path || !meta) {
        snprintf(err->msg, sizeof err->msg, "text writer: no path given");
        return EVR_ERR_ARG;
    }
    w = calloc(1, sizeof *w);
    if (w) {
        w->path = strdup(path);
        w->tmp = evr_file_tmp_name(path);
        w->buf = malloc(TXT_BUFFER);
        w->ids = meta->event_ids != 0;
        w->parts.threads = 16; /* formatting text costs several times npy's packing */
        w->parts.claim_room = 1;
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
    "txt", NULL, "events.txt", evr_txt_writer_open, "text, one event a line (t x y p)", ".txt", 1};
