/* NumPy .npy (format 1.0) event files: one 1-D structured array of packed 13-byte records,
 * dtype [('t','<i8'), ('x','<u2'), ('y','<u2'), ('p','|i1')], which numpy.load reads as is;
 * with event ids (evr_writer_meta.event_ids) 15-byte records with a last field ('id','<u2').
 *
 * The count is known only at the end, so the header is written with room for a 20-digit shape
 * (padded with spaces, total header a multiple of 64 bytes) and rewritten in place at every
 * flush() and at finish(): the temporary file of an interrupted run is a valid array holding
 * every event up to the last flush. */
#include "io/event_formats.h"
#include "io/byte_order.h"
#include "io/file_commit.h"
#include "io/par_pack.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NPY_RECORD_MAX 15
#define NPY_BUFFER_RECORDS (1u << 16)
#define NPY_DESCR "[('t', '<i8'), ('x', '<u2'), ('y', '<u2'), ('p', '|i1')]"
#define NPY_DESCR_IDS "[('t', '<i8'), ('x', '<u2'), ('y', '<u2'), ('p', '|i1'), ('id', '<u2')]"

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    char *path, *tmp;
    FILE *f;
    size_t record; /* bytes a record: 13, or 15 with ids */
    int ids;
    unsigned char *buf;
    size_t nbuf;       /* records in buf */
    uint64_t count;    /* records in the file */
    size_t header_len; /* bytes before the first record */
    int64_t last_t;
    int have_last;
    uint64_t prev_given; /* records given (count + nbuf) as the last write() began (salvage) */
    /* large writes, packed in parts (io/par_pack.h): one thread packing and copying 2.84 GB into
     * the page cache kept the eye's 30 s waiting (H100 machine: writer busy 1.9-2.2 s, the loop
     * waiting 0.7-1.0 s) */
    evr_par_packing parts;
} npy_writer;

/* Builds the whole header (magic, version, length, dict, padding, newline) for count records.
 * total 0: the smallest multiple of 64 with room for any 64-bit count; else exactly total bytes. */
static size_t build_header(char *out, size_t cap, int ids, uint64_t count, size_t total)
{
    char dict[256];
    int n = snprintf(dict, sizeof dict,
                     "{'descr': %s, 'fortran_order': False, 'shape': (%" PRIu64 ",), }",
                     ids ? NPY_DESCR_IDS : NPY_DESCR, count);
    size_t digits = (size_t)snprintf(NULL, 0, "%" PRIu64, count);
    if (total == 0) total = ((10 + (size_t)n - digits + 20 + 1) + 63) / 64 * 64;
    if (total > cap || 10 + (size_t)n + 1 > total) return 0;
    memcpy(out, "\x93NUMPY\x01\x00", 8);
    out[8] = (char)((total - 10) & 0xff);
    out[9] = (char)((total - 10) >> 8);
    memcpy(out + 10, dict, (size_t)n);
    memset(out + 10 + n, ' ', total - 10 - (size_t)n - 1);
    out[total - 1] = '\n';
    return total;
}

static evr_status write_header(npy_writer *w, evr_error *err)
{
    char h[256];
    size_t n = build_header(h, sizeof h, w->ids, w->count, w->header_len);
    if (n != w->header_len || fseek(w->f, 0, SEEK_SET) != 0 || fwrite(h, 1, n, w->f) != n ||
        fseek(w->f, 0, SEEK_END) != 0) {
        snprintf(err->msg, sizeof err->msg, "npy writer: cannot write the header of %s: %s", w->tmp,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

/* The error of a failed write to the temporary file. */
static evr_status cannot_write(const npy_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "npy writer: cannot write %s: %s", w->tmp, strerror(errno));
    return EVR_ERR_IO;
}

static evr_status drain(npy_writer *w, evr_error *err)
{
    if (w->nbuf && fwrite(w->buf, w->record, w->nbuf, w->f) != w->nbuf) return cannot_write(w, err);
    w->count += w->nbuf;
    w->nbuf = 0;
    return EVR_OK;
}

static void free_writer(npy_writer *w)
{
    evr_par_packing_free(&w->parts);
    free(w->path);
    free(w->tmp);
    free(w->buf);
    free(w);
}

/* One record, little-endian whatever the host. */
static void pack(unsigned char *r, const evr_event *e, int ids)
{
    evr_put_le64(r, (uint64_t)e->t);
    evr_put_le16(r + 8, e->x);
    evr_put_le16(r + 10, e->y);
    r[12] = e->p ? 1 : 0;
    if (ids) evr_put_le16(r + 13, e->id);
}

/* A part of a large write (io/par_pack.h; ctx the writer): a record an event. */
static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ev;
    return (b - a) * ((const npy_writer *)ctx)->record;
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const npy_writer *w = (const npy_writer *)ctx;
    (void)room;
    for (size_t i = a; i < b; i++, out += w->record) {
        if (i > 0 && ev[i].t < ev[i - 1].t) return SIZE_MAX;
        pack(out, &ev[i], w->ids);
    }
    return (b - a) * w->record;
}

/* Writes ev[0 .. n) (n >= EVR_PAR_PACK_MIN, ev[0] not before the last event written) in parts
 * after the buffered records (*st: how it went); returns 0, nothing written, when an event is
 * out of order or there is no room to pack them: the serial path then writes them or reports it. */
static int write_parallel(npy_writer *w, const evr_event *ev, size_t n, evr_error *err,
                          evr_status *st)
{
    const evr_par_packer parts = {bound_part, pack_part, NULL, w};
    size_t bytes;
    evr_par_pack_result r;
    if ((*st = drain(w, err)) != EVR_OK) return 1;
    r = evr_par_pack_write(&w->parts, &parts, ev, n, w->f, &bytes);
    if (r == EVR_PAR_PACK_SERIAL) return 0;
    if (r == EVR_PAR_PACK_FAILED) {
        *st = cannot_write(w, err);
        return 1;
    }
    w->count += n;
    w->last_t = ev[n - 1].t;
    w->have_last = 1;
    return 1;
}

static evr_status npy_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    npy_writer *w = (npy_writer *)base;
    w->prev_given = w->count + w->nbuf;
    if (n >= EVR_PAR_PACK_MIN && !(w->have_last && ev[0].t < w->last_t)) {
        evr_status st;
        if (write_parallel(w, ev, n, err, &st)) return st;
    }
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        unsigned char *r;
        if (w->have_last && e->t < w->last_t) {
            snprintf(err->msg, sizeof err->msg,
                     "npy writer: events out of time order (%" PRId64 " us after %" PRId64 " us)",
                     e->t, w->last_t);
            return EVR_ERR_ARG;
        }
        w->last_t = e->t;
        w->have_last = 1;
        if (w->nbuf == NPY_BUFFER_RECORDS) {
            evr_status st = drain(w, err);
            if (st != EVR_OK) return st;
        }
        r = w->buf + w->nbuf * w->record;
        pack(r, e, w->ids);
        w->nbuf++;
    }
    return EVR_OK;
}

static evr_status npy_flush(evr_event_writer *base, evr_error *err)
{
    npy_writer *w = (npy_writer *)base;
    evr_status st = drain(w, err);
    if (st == EVR_OK) st = write_header(w, err);
    if (st == EVR_OK && fflush(w->f) != 0) st = cannot_write(w, err);
    return st;
}

static void npy_abort(evr_event_writer *base)
{
    npy_writer *w = (npy_writer *)base;
    evr_file_discard(w->f, w->tmp);
    free_writer(w);
}

static evr_status npy_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    npy_writer *w = (npy_writer *)base;
    evr_status st = drain(w, err);
    (void)duration_us;
    if (st == EVR_OK) st = write_header(w, err);
    st = evr_file_commit(w->f, w->tmp, w->path, st, "npy writer", err);
    w->f = NULL;
    free_writer(w);
    return st;
}

static evr_status npy_salvage(evr_event_writer *base, uint64_t events, int64_t duration_us,
                              evr_error *err)
{
    npy_writer *w = (npy_writer *)base;
    const uint64_t given = w->count + w->nbuf;
    char h[256];
    evr_status st;
    (void)duration_us;
    if ((events != given && events != w->prev_given) ||
        build_header(h, sizeof h, w->ids, events, w->header_len) != w->header_len) {
        snprintf(err->msg, sizeof err->msg, "npy writer: cannot keep %llu events of %s",
                 (unsigned long long)events, w->path);
        evr_file_discard(w->f, w->tmp);
        st = EVR_ERR_IO;
    } else {
        st = evr_file_salvage(w->f, w->tmp, w->path, w->header_len + events * w->record,
                              w->header_len + given * w->record, w->buf, w->nbuf * w->record, h,
                              w->header_len, "npy writer", err);
    }
    w->f = NULL;
    free_writer(w);
    return st;
}

evr_status evr_npy_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err)
{
    npy_writer *w;
    char h[256];
    *out = NULL;
    if (!path || !*path || !meta) {
        snprintf(err->msg, sizeof err->msg, "npy writer: no path given");
        return EVR_ERR_ARG;
    }
    w = calloc(1, sizeof *w);
    if (w) {
        w->path = strdup(path);
        w->tmp = evr_file_tmp_name(path);
        w->ids = meta->event_ids != 0;
        w->record = w->ids ? NPY_RECORD_MAX : NPY_RECORD_MAX - 2;
        w->buf = malloc((size_t)NPY_BUFFER_RECORDS * w->record);
    }
    if (!w || !w->path || !w->tmp || !w->buf) {
        if (w) free_writer(w);
        snprintf(err->msg, sizeof err->msg, "npy writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    w->header_len = build_header(h, sizeof h, w->ids, 0, 0);
    w->f = evr_file_create(w->tmp, "npy writer", err);
    if (!w->f) {
        free_writer(w);
        return EVR_ERR_IO;
    }
    if (fwrite(h, 1, w->header_len, w->f) != w->header_len) {
        cannot_write(w, err);
        evr_file_discard(w->f, w->tmp);
        free_writer(w);
        return EVR_ERR_IO;
    }
    w->base.write = npy_write;
    w->base.flush = npy_flush;
    w->base.finish = npy_finish;
    w->base.abort = npy_abort;
    w->base.salvage = npy_salvage;
    *out = &w->base;
    return EVR_OK;
}

const evr_event_format evr_format_npy = {
    "npy",  NULL, "events.npy", evr_npy_writer_open, "NumPy structured array (t, x, y, p)",
    ".npy", 1};
