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
    evr_raw_stream s; /* first: the interface pointer is the writer pointer */
} dat_writer;

static void pack_event(unsigned char *p, const evr_event *e)
{
    evr_put_le32(p, (uint32_t)e->t);
    evr_put_le32(p + 4, (uint32_t)(e->p > 0) << 28 | (uint32_t)e->y << 14 | (uint32_t)e->x);
}

/* A part of a large write (io/par_pack.h): 8 bytes an event. */
static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ctx;
    (void)ev;
    return (b - a) * DAT_EVENT_SIZE;
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const dat_writer *w = ctx;
    (void)room;
    for (size_t i = a; i < b; i++, out += DAT_EVENT_SIZE) {
        if (!evr_raw_stream_fits(&w->s, &ev[i]) || (i > 0 && ev[i].t < ev[i - 1].t))
            return SIZE_MAX;
        pack_event(out, &ev[i]);
    }
    return (b - a) * DAT_EVENT_SIZE;
}

static evr_status dat_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    dat_writer *w = (dat_writer *)base;
    const evr_par_packer parts = {bound_part, pack_part, NULL, w};
    evr_status st;
    if (evr_raw_stream_write_parts(&w->s, &parts, ev, n, &st, err)) return st;
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        st = evr_raw_stream_check(&w->s, e, err);
        if (st == EVR_OK) st = evr_raw_stream_room(&w->s, DAT_EVENT_SIZE, err);
        if (st != EVR_OK) return st;
        pack_event(w->s.buf + w->s.len, e);
        w->s.len += DAT_EVENT_SIZE;
    }
    return EVR_OK;
}

evr_status evr_dat_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err)
{
    char header[512];
    size_t len = evr_prophesee_header(header, sizeof header, NULL, NULL, meta->width, meta->height);
    header[len++] = DAT_TYPE_CD; /* the event type and size follow the header lines */
    header[len++] = DAT_EVENT_SIZE;
    evr_status st = evr_raw_writer_open(sizeof(dat_writer), path, "dat writer", 1 << 14, DAT_MAX_T,
                                        header, len, dat_write, out, err);
    return st;
}

const evr_event_format evr_format_dat = {
    "dat",  NULL, "events_td.dat", evr_dat_writer_open, "Prophesee DAT of CD events (expelliarmus)",
    ".dat", 0};
