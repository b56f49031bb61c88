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

/* threads packing a large write: its runs cost about twice a DAT event's packing, and four kept
 * it level with HDF5 only just on the H100 run (docs/benchmarks.md, "Writers") */
#define EVT3_THREADS 8

enum {
    EVT3_ADDR_Y = 0x0,
    EVT3_ADDR_X = 0x2,
    EVT3_VECT_BASE_X = 0x3,
    EVT3_VECT_12 = 0x4,
    EVT3_VECT_8 = 0x5,
    EVT3_TIME_LOW = 0x6,
    EVT3_TIME_HIGH = 0x8
};

/* The decoder's state the words build on. */
typedef struct {
    int64_t time_high;       /* t >> 12 of the last TIME_HIGH word (unwrapped); -1: none yet */
    int low, y, base_x, pol; /* -1: not set */
} evt3_state;

typedef struct {
    evr_raw_stream s; /* first: the interface pointer is the writer pointer */
    evt3_state st;
} evt3_writer;

/* Where words go: the stream (room made word by word), or a part of a large write. */
typedef struct {
    evt3_state *st;
    evr_raw_stream *s;  /* the serial path; NULL for a part */
    unsigned char *out; /* a part's words */
    size_t room;        /* and the bytes they may take */
    size_t bytes;       /* a part's bytes so far */
} evt3_words;

static evr_status put(evt3_words *o, unsigned type, unsigned payload, evr_error *err)
{
    const uint32_t word = (uint32_t)(type << 12 | (payload & 0xfff));
    if (o->s) {
        evr_status st = evr_raw_stream_room(o->s, 2, err);
        if (st != EVR_OK) return st;
        evr_put_le16(o->s->buf + o->s->len, word);
        o->s->len += 2;
    } else {
        if (o->room - o->bytes < 2) return EVR_ERR_NOMEM; /* the part goes serially */
        evr_put_le16(o->out + o->bytes, word);
        o->bytes += 2;
    }
    /* readers differ in what other words do to the vector base (faery moves it with EVT_ADDR_X):
     * a vector continues from the base only right after a vector word */
    if (type != EVT3_VECT_BASE_X && type != EVT3_VECT_12 && type != EVT3_VECT_8) o->st->base_x = -1;
    return EVR_OK;
}

static evr_status put_time(evt3_words *o, int64_t t, evr_error *err)
{
    evt3_state *w = o->st;
    const int64_t high = t >> 12;
    const int low = (int)(t & 0xfff);
    evr_status st = EVR_OK;
    while (st == EVR_OK && w->time_high < high) {
        if (w->time_high < 0) w->time_high = 0;
        else if (high - w->time_high > EVT3_HIGH_STEP) w->time_high += EVT3_HIGH_STEP;
        else w->time_high = high;
        st = put(o, EVT3_TIME_HIGH, (unsigned)(w->time_high & 0xfff), err);
        w->low = -1; /* readers differ in what TIME_HIGH does to the low bits: always resend them */
    }
    if (st == EVR_OK && w->low != low) {
        st = put(o, EVT3_TIME_LOW, (unsigned)low, err);
        w->low = low;
    }
    return st;
}

/* Whether ev[j] may share a vector word with ev[j - 1]: the same timestamp, row and polarity,
 * further right. Where it may not, a vector run starts. */
static int continues(const evr_event *ev, size_t j)
{
    return ev[j].t == ev[j - 1].t && ev[j].y == ev[j - 1].y && (ev[j].p > 0) == (ev[j - 1].p > 0) &&
           ev[j].x > ev[j - 1].x;
}

/* The end of the run starting at ev[i] that one vector word can hold (ev[.. n) read). */
static size_t run_end(const evr_event *ev, size_t i, size_t n)
{
    size_t j = i + 1;
    while (j < n && continues(ev, j) && ev[j].x < ev[i].x + 12) j++;
    return j;
}

/* The words of the run ev[i .. j). */
static evr_status put_run(evt3_words *o, const evr_event *ev, size_t i, size_t j, evr_error *err)
{
    evt3_state *w = o->st;
    const evr_event *e = &ev[i];
    const int pol = e->p > 0;
    unsigned mask = 0;
    evr_status st = put_time(o, e->t, err);
    if (st == EVR_OK && w->y != e->y) {
        st = put(o, EVT3_ADDR_Y, e->y, err);
        w->y = e->y;
    }
    if (st != EVR_OK) return st;
    if (j == i + 1) return put(o, EVT3_ADDR_X, (unsigned)pol << 11 | e->x, err);
    for (size_t k = i; k < j; k++) mask |= 1u << (ev[k].x - e->x);
    if (w->base_x != e->x || w->pol != pol)
        st = put(o, EVT3_VECT_BASE_X, (unsigned)pol << 11 | e->x, err);
    w->pol = pol;
    if (st == EVR_OK && mask < 0x100) {
        st = put(o, EVT3_VECT_8, mask, err);
        w->base_x = e->x + 8;
    } else if (st == EVR_OK) {
        st = put(o, EVT3_VECT_12, mask, err);
        w->base_x = e->x + 12;
    }
    return st;
}

/* A large write's part may begin where a run must begin. Runs have increasing x, so the search
 * stops within 2^16 events. */
static size_t cut_part(const void *ctx, const evr_event *ev, size_t n, size_t at)
{
    (void)ctx;
    while (at > 0 && at < n && continues(ev, at)) at++;
    return at;
}

/* The state after ev[0 .. a) (a a run's start, or a == n): that of the last run, found by going
 * run by run from where a run must begin before it. */
static evt3_state state_at(const evt3_writer *w, const evr_event *ev, size_t a)
{
    evt3_state s;
    size_t i, j;
    if (a == 0) return w->st;
    i = a - 1;
    while (i > 0 && continues(ev, i)) i--;
    while ((j = run_end(ev, i, a)) < a) i = j;
    s.time_high = ev[a - 1].t >> 12;
    s.low = (int)(ev[a - 1].t & 0xfff);
    s.y = ev[a - 1].y;
    s.pol = ev[i].p > 0;
    s.base_x = a - i == 1 ? -1 : ev[a - 1].x - ev[i].x < 8 ? ev[i].x + 8 : ev[i].x + 12;
    return s;
}

/* A part of a large write (io/par_pack.h): at most 4 words a run besides the TIME_HIGH words,
 * and these step from the part's first time high to its last (past which pack_part goes not). */
static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    const evt3_writer *w = ctx;
    int64_t from = a > 0 ? ev[a - 1].t >> 12 : w->st.time_high;
    int64_t to = ev[b - 1].t >> 12;
    if (to > w->s.max_t >> 12) to = w->s.max_t >> 12;
    if (from < 0) from = 0; /* and one word more, for time high 0 */
    return (b - a) * 8 + 2 * (to > from ? (size_t)(to - from) + 1 : 1);
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const evt3_writer *w = ctx;
    evt3_state s = state_at(w, ev, a);
    evt3_words o = {&s, NULL, out, room, 0};
    for (size_t i = a, j; i < b; i = j) {
        j = run_end(ev, i, b);
        for (size_t k = i; k < j; k++)
            if (!evr_raw_stream_fits(&w->s, &ev[k]) || (k > 0 && ev[k].t < ev[k - 1].t))
                return SIZE_MAX;
        if (put_run(&o, ev, i, j, NULL) != EVR_OK) return SIZE_MAX;
    }
    return o.bytes;
}

static evr_status evt3_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    evt3_writer *w = (evt3_writer *)base;
    const evr_par_packer parts = {bound_part, pack_part, cut_part, w};
    evt3_words o = {&w->st, &w->s, NULL, 0, 0};
    evr_status st;
    if (evr_raw_stream_write_parts(&w->s, &parts, ev, n, &st, err)) {
        if (st == EVR_OK) w->st = state_at(w, ev, n);
        return st;
    }
    for (size_t i = 0, j; i < n; i = j) {
        j = run_end(ev, i, n);
        for (size_t k = i; k < j; k++)
            if ((st = evr_raw_stream_check(&w->s, &ev[k], err)) != EVR_OK) return st;
        if ((st = put_run(&o, ev, i, j, err)) != EVR_OK) return st;
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
        w->s.parts.threads = EVT3_THREADS;
        w->st.time_high = -1;
        w->st.low = w->st.y = w->st.base_x = w->st.pol = -1;
    }
    return st;
}

const evr_event_format evr_format_evt3 = {"evt3",
                                          NULL,
                                          "events_evt3.raw",
                                          evr_evt3_writer_open,
                                          "Prophesee EVT 3.0 RAW (Metavision, evlib, evt3)",
                                          ".raw",
                                          0};
