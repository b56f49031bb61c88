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

#define EVT2_TIME_HIGH(t) ((t) >> 6)

/* The words of one event: an EV_TIME_HIGH word when the timestamp's upper bits differ from
 * *time_high (updated), then the CD word. Returns the bytes written at p (4 or 8). */
static size_t pack_event(unsigned char *p, const evr_event *e, int64_t *time_high)
{
    size_t at = 0;
    if (EVT2_TIME_HIGH(e->t) != *time_high) {
        *time_high = EVT2_TIME_HIGH(e->t);
        evr_put_le32(p, UINT32_C(0x8) << 28 | (uint32_t)*time_high);
        at = 4;
    }
    evr_put_le32(p + at, (uint32_t)(e->p > 0) << 28 | (uint32_t)(e->t & 63) << 22 |
                             (uint32_t)e->x << 11 | (uint32_t)e->y);
    return at + 4;
}

/* The time-high state part [a, ...) of a large write starts in: the event before it's. */
static int64_t part_time_high(const evt2_writer *w, const evr_event *ev, size_t a)
{
    return a > 0 ? EVT2_TIME_HIGH(ev[a - 1].t) : w->time_high;
}

/* A part of a large write (io/par_pack.h): a word an event, one more at each time-high change. */
static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ctx;
    (void)ev;
    return (b - a) * 8;
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const evt2_writer *w = ctx;
    int64_t time_high = part_time_high(w, ev, a);
    unsigned char *p = out;
    (void)room;
    for (size_t i = a; i < b; i++) {
        if (!evr_raw_stream_fits(&w->s, &ev[i]) || (i > 0 && ev[i].t < ev[i - 1].t))
            return SIZE_MAX;
        p += pack_event(p, &ev[i], &time_high);
    }
    return (size_t)(p - out);
}

static evr_status evt2_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    evt2_writer *w = (evt2_writer *)base;
    const evr_par_packer parts = {bound_part, pack_part, NULL, w};
    evr_status st;
    if (evr_raw_stream_write_parts(&w->s, &parts, ev, n, &st, err)) {
        if (st == EVR_OK) w->time_high = EVT2_TIME_HIGH(ev[n - 1].t);
        return st;
    }
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        st = evr_raw_stream_check(&w->s, e, err);
        if (st == EVR_OK) st = evr_raw_stream_room(&w->s, 8, err);
        if (st != EVR_OK) return st;
        w->s.len += pack_event(w->s.buf + w->s.len, e, &w->time_high);
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
                                          "evt2.raw",
                                          0};
