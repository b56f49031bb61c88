/* Prophesee DAT files of CD events: "% " header lines (Date, Version 2, Height, Width), the event
 * type 0x0C and size 8 bytes, then 8-byte little-endian records: a uint32 timestamp in us and a
 * uint32 with x in bits 0..13, y in bits 14..27, the polarity in bits 28..31. So timestamps stay
 * below 2^32 us (71 min) and x, y below 16384. */
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <stdlib.h>
#include <string.h>

#define DAT_MAX_T ((INT64_C(1) << 32) - 1)
#define DAT_TYPE_CD 0x0C
#define DAT_EVENT_SIZE 8

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    evr_raw_stream s;
} dat_writer;

static evr_status dat_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    dat_writer *w = (dat_writer *)base;
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        evr_status st = evr_raw_stream_check(&w->s, e, err);
        if (st == EVR_OK) st = evr_raw_stream_room(&w->s, DAT_EVENT_SIZE, err);
        if (st != EVR_OK) return st;
        unsigned char *p = w->s.buf + w->s.len;
        evr_put_le32(p, (uint32_t)e->t);
        evr_put_le32(p + 4, (uint32_t)(e->p > 0) << 28 | (uint32_t)e->y << 14 | (uint32_t)e->x);
        w->s.len += DAT_EVENT_SIZE;
    }
    return EVR_OK;
}

static evr_status dat_flush(evr_event_writer *base, evr_error *err)
{
    return evr_raw_stream_flush(&((dat_writer *)base)->s, err);
}

static evr_status dat_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    dat_writer *w = (dat_writer *)base;
    evr_status st = evr_raw_stream_finish(&w->s, err);
    (void)duration_us;
    free(w);
    return st;
}

static void dat_abort(evr_event_writer *base)
{
    dat_writer *w = (dat_writer *)base;
    evr_raw_stream_abort(&w->s);
    free(w);
}

evr_status evr_dat_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err)
{
    char header[512];
    size_t len = evr_prophesee_header(header, sizeof header, NULL, NULL, meta->width,
                                      meta->height);
    dat_writer *w = calloc(1, sizeof *w);
    evr_status st;
    *out = NULL;
    if (!w) {
        snprintf(err->msg, sizeof err->msg, "dat writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    header[len++] = DAT_TYPE_CD;
    header[len++] = DAT_EVENT_SIZE;
    st = evr_raw_stream_open(&w->s, path, "dat writer", 1 << 14, DAT_MAX_T, header, len, err);
    if (st != EVR_OK) {
        free(w);
        return st;
    }
    w->base.write = dat_write;
    w->base.flush = dat_flush;
    w->base.finish = dat_finish;
    w->base.abort = dat_abort;
    *out = &w->base;
    return EVR_OK;
}

const evr_event_format evr_format_dat = {"dat", NULL, "events_td.dat", evr_dat_writer_open,
                                         "Prophesee DAT of CD events (expelliarmus)"};
