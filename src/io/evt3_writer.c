/* Prophesee EVT 3.0 RAW files: "% " header lines, then little-endian 16-bit words whose top 4 bits
 * are the type and which update the decoder's state: EVT_ADDR_Y (0x0: y), EVT_ADDR_X (0x2: one
 * event at x with polarity bit 11), VECT_BASE_X (0x3: base x and polarity), VECT_12 / VECT_8
 * (0x4 / 0x5: a mask of events at base .. base + 11 / + 7, then base advances by 12 / 8),
 * EVT_TIME_LOW (0x6) and EVT_TIME_HIGH (0x8): the low and high 12 bits of a 24-bit us time.
 *
 * The time wraps every 2^24 us (16.8 s); a reader counts a wrap whenever EVT_TIME_HIGH goes down.
 * So TIME_HIGH words are written from 0 on and never more than EVT3_HIGH_STEP apart, even across
 * gaps without events, and every wrap shows as a decrease. Events of one timestamp, row and
 * polarity that follow each other with increasing x within 12 columns become one vector word. */
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <stdlib.h>

#define EVT3_MAX_T ((INT64_C(1) << 36) - 1) /* 19 h: one TIME_HIGH word per 4096 us from 0 */
#define EVT3_HIGH_STEP \
    1 /* time-high units between TIME_HIGH words: readers count wraps only on single steps */

enum {
    EVT3_ADDR_Y = 0x0,
    EVT3_ADDR_X = 0x2,
    EVT3_VECT_BASE_X = 0x3,
    EVT3_VECT_12 = 0x4,
    EVT3_VECT_8 = 0x5,
    EVT3_TIME_LOW = 0x6,
    EVT3_TIME_HIGH = 0x8
};

typedef struct {
    evr_raw_stream s;        /* first: the interface pointer is the writer pointer */
    int64_t time_high;       /* t >> 12 of the last TIME_HIGH word (unwrapped); -1: none yet */
    int low, y, base_x, pol; /* the decoder's state; -1: not set */
} evt3_writer;

static evr_status put(evt3_writer *w, unsigned type, unsigned payload, evr_error *err)
{
    evr_status st = evr_raw_stream_room(&w->s, 2, err);
    if (st != EVR_OK) return st;
    evr_put_le16(w->s.buf + w->s.len, (uint32_t)(type << 12 | (payload & 0xfff)));
    w->s.len += 2;
    /* readers differ in what other words do to the vector base (faery moves it with EVT_ADDR_X):
     * a vector continues from the base only right after a vector word */
    if (type != EVT3_VECT_BASE_X && type != EVT3_VECT_12 && type != EVT3_VECT_8) w->base_x = -1;
    return EVR_OK;
}

static evr_status put_time(evt3_writer *w, int64_t t, evr_error *err)
{
    const int64_t high = t >> 12;
    const int low = (int)(t & 0xfff);
    evr_status st = EVR_OK;
    while (st == EVR_OK && w->time_high < high) {
        if (w->time_high < 0) w->time_high = 0;
        else if (high - w->time_high > EVT3_HIGH_STEP) w->time_high += EVT3_HIGH_STEP;
        else w->time_high = high;
        st = put(w, EVT3_TIME_HIGH, (unsigned)(w->time_high & 0xfff), err);
        w->low = -1; /* readers differ in what TIME_HIGH does to the low bits: always resend them */
    }
    if (st == EVR_OK && w->low != low) {
        st = put(w, EVT3_TIME_LOW, (unsigned)low, err);
        w->low = low;
    }
    return st;
}

static evr_status evt3_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    evt3_writer *w = (evt3_writer *)base;
    size_t i = 0, j;
    while (i < n) {
        const evr_event *e = &ev[i];
        evr_status st = evr_raw_stream_check(&w->s, e, err);
        const int pol = e->p > 0;
        if (st == EVR_OK) st = put_time(w, e->t, err);
        if (st == EVR_OK && w->y != e->y) {
            st = put(w, EVT3_ADDR_Y, e->y, err);
            w->y = e->y;
        }
        if (st != EVR_OK) return st;
        /* the run that one vector word can hold */
        unsigned mask = 1;
        for (j = i + 1; j < n && ev[j].t == e->t && ev[j].y == e->y && (ev[j].p > 0) == pol &&
                        ev[j].x > ev[j - 1].x && ev[j].x < e->x + 12;
             j++) {
            if ((st = evr_raw_stream_check(&w->s, &ev[j], err)) != EVR_OK) return st;
            mask |= 1u << (ev[j].x - e->x);
        }
        if (j == i + 1) {
            st = put(w, EVT3_ADDR_X, (unsigned)pol << 11 | e->x, err);
        } else {
            if (w->base_x != e->x || w->pol != pol)
                st = put(w, EVT3_VECT_BASE_X, (unsigned)pol << 11 | e->x, err);
            w->pol = pol;
            if (st == EVR_OK && mask < 0x100) {
                st = put(w, EVT3_VECT_8, mask, err);
                w->base_x = e->x + 8;
            } else if (st == EVR_OK) {
                st = put(w, EVT3_VECT_12, mask, err);
                w->base_x = e->x + 12;
            }
        }
        if (st != EVR_OK) return st;
        i = j;
    }
    return EVR_OK;
}

evr_status evr_evt3_writer_open(const char *path, const evr_writer_meta *meta,
                                evr_event_writer **out, evr_error *err)
{
    char header[512];
    size_t len =
        evr_prophesee_header(header, sizeof header, "3.0", "EVT3", meta->width, meta->height);
    evr_status st = evr_raw_writer_open(sizeof(evt3_writer), path, "evt3 writer", 2048, EVT3_MAX_T,
                                        header, len, evt3_write, out, err);
    if (st == EVR_OK) {
        evt3_writer *w = (evt3_writer *)*out;
        w->time_high = -1;
        w->low = w->y = w->base_x = w->pol = -1;
    }
    return st;
}

const evr_event_format evr_format_evt3 = {"evt3",
                                          NULL,
                                          "events_evt3.raw",
                                          evr_evt3_writer_open,
                                          "Prophesee EVT 3.0 RAW (Metavision, evlib, evt3)",
                                          ".raw"};
