/* Prophesee EVT 2.0 RAW files: "% " header lines, then little-endian 32-bit words whose top 4 bits
 * are the type. CD_OFF (0x0) / CD_ON (0x1): bits 27..22 the timestamp's 6 low bits, 21..11 x,
 * 10..0 y. EV_TIME_HIGH (0x8): bits 27..0 the timestamp's upper 28 bits, written whenever they
 * change, so timestamps reach 2^34 us (4.7 h) and x, y stay below 2048. */
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <stdlib.h>

#define EVT2_MAX_T ((INT64_C(1) << 34) - 1)

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    evr_raw_stream s;
    int64_t time_high; /* the last EV_TIME_HIGH written; -1: none yet */
} evt2_writer;

static evr_status evt2_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    evt2_writer *w = (evt2_writer *)base;
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        evr_status st = evr_raw_stream_check(&w->s, e, err);
        if (st == EVR_OK) st = evr_raw_stream_room(&w->s, 8, err);
        if (st != EVR_OK) return st;
        unsigned char *p = w->s.buf + w->s.len;
        if (e->t >> 6 != w->time_high) {
            w->time_high = e->t >> 6;
            evr_put_le32(p, UINT32_C(0x8) << 28 | (uint32_t)w->time_high);
            p += 4;
        }
        evr_put_le32(p, (uint32_t)(e->p > 0) << 28 | (uint32_t)(e->t & 63) << 22 |
                            (uint32_t)e->x << 11 | (uint32_t)e->y);
        w->s.len = (size_t)(p + 4 - w->s.buf);
    }
    return EVR_OK;
}

static evr_status evt2_flush(evr_event_writer *base, evr_error *err)
{
    return evr_raw_stream_flush(&((evt2_writer *)base)->s, err);
}

static evr_status evt2_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    evt2_writer *w = (evt2_writer *)base;
    evr_status st = evr_raw_stream_finish(&w->s, err);
    (void)duration_us;
    free(w);
    return st;
}

static void evt2_abort(evr_event_writer *base)
{
    evt2_writer *w = (evt2_writer *)base;
    evr_raw_stream_abort(&w->s);
    free(w);
}

evr_status evr_evt2_writer_open(const char *path, const evr_writer_meta *meta,
                                evr_event_writer **out, evr_error *err)
{
    char header[512];
    size_t len = evr_prophesee_header(header, sizeof header, "2.0", "EVT2", meta->width,
                                      meta->height);
    evt2_writer *w = calloc(1, sizeof *w);
    evr_status st;
    *out = NULL;
    if (!w) {
        snprintf(err->msg, sizeof err->msg, "evt2 writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    st = evr_raw_stream_open(&w->s, path, "evt2 writer", 2048, EVT2_MAX_T, header, len, err);
    if (st != EVR_OK) {
        free(w);
        return st;
    }
    w->time_high = -1;
    w->base.write = evt2_write;
    w->base.flush = evt2_flush;
    w->base.finish = evt2_finish;
    w->base.abort = evt2_abort;
    *out = &w->base;
    return EVR_OK;
}

const evr_event_format evr_format_evt2 = {"evt2", NULL, "events_evt2.raw", evr_evt2_writer_open,
                                          "Prophesee EVT 2.0 RAW (Metavision, expelliarmus, evlib)"};
