/* Prophesee EVT 2.0 RAW files: "% " header lines, then little-endian 32-bit words whose top 4 bits
 * are the type. CD_OFF (0x0) / CD_ON (0x1): bits 27..22 the timestamp's 6 low bits, 21..11 x,
 * 10..0 y. EV_TIME_HIGH (0x8): bits 27..0 the timestamp's upper 28 bits, written whenever they
 * change, so timestamps reach 2^34 us (4.7 h) and x, y stay below 2048. */
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <stdlib.h>

#define EVT2_MAX_T ((INT64_C(1) << 34) - 1)

typedef struct {
    evr_raw_stream s;  /* first: the interface pointer is the writer pointer */
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

evr_status evr_evt2_writer_open(const char *path, const evr_writer_meta *meta,
                                evr_event_writer **out, evr_error *err)
{
    char header[512];
    size_t len =
        evr_prophesee_header(header, sizeof header, "2.0", "EVT2", meta->width, meta->height);
    evr_status st = evr_raw_writer_open(sizeof(evt2_writer), path, "evt2 writer", 2048, EVT2_MAX_T,
                                        header, len, evt2_write, out, err);
    if (st == EVR_OK) ((evt2_writer *)*out)->time_high = -1;
    return st;
}

const evr_event_format evr_format_evt2 = {"evt2",
                                          NULL,
                                          "events_evt2.raw",
                                          evr_evt2_writer_open,
                                          "Prophesee EVT 2.0 RAW (Metavision, expelliarmus, evlib)",
                                          "evt2.raw"};
