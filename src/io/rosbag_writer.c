/* ROS1 bag files (format 2.0) of dvs_msgs/EventArray messages on /dvs/events, as rpg_dvs_ros and
 * ESIM record them. Messages at 30 Hz like rpg_dvs_ros's driver: message k holds the events of
 * [k/30 s, (k+1)/30 s) (at most MSG_MAX_EVENTS of them; empty windows send none), stamped with
 * its last event's time; seq counts messages from 0. ROS times are the events' microseconds
 * (secs, nsecs), so t must stay below 2^32 s and x, y below 2^16.
 *
 * The file: "#ROSBAG V2.0\n", the bag header record (padded to 4096 bytes), chunks of about
 * CHUNK_BYTES uncompressed (the first holds the connection record) each followed by its index
 * data record, then the connection record again and one chunk info record per chunk. flush()
 * writes the finished messages' chunk and that tail and rewrites the bag header, so the file is
 * a complete bag after every flush; the next chunk overwrites the tail.
 *
 * Speed: the bytes not written yet are laid out in one buffer as they will lie in the file
 * (finished chunks, then the current chunk with the gathering message last), the fixed-size
 * record headers filled in when their lengths are known. A write() first checks its events,
 * then finds where its messages begin (a search on the sorted times, not a test per event),
 * then packs the events at their places in parts on the pool; a large write's finished chunks
 * are then written by a thread of their own while the next write is checked and packed
 * (io/write_behind.h): the GPU run of the 30 s eye waited on one thread packing and copying its
 * gigabytes, and then on these phases one after the other. Its room is not claimed ahead (as
 * the AEDAT 4.0 writer does): with the packing off the file's path, a claim only adds to the
 * time the file is locked. Where messages and chunks end depends only on the events
 * and the flush() calls, not on how the events are cut into write() calls. */
#include "io/event_formats.h"
#include "io/write_at.h"
#include "io/write_behind.h"
#include "io/raw_stream.h"
#include "par_pool.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#define BAG_MAGIC "#ROSBAG V2.0\n"
#define BAG_HEADER_BYTES 4096           /* the bag header record, padded, as rosbag writes it */
#define CHUNK_BYTES ((size_t)768 << 10) /* rosbag's default chunk threshold */
#define MSG_HZ 30
#define MSG_MAX_EVENTS ((size_t)1 << 20)
#define EVENT_BYTES 13 /* uint16 x, uint16 y, time ts, bool polarity */
#define ROSBAG_MAX_T ((INT64_C(1) << 32) * 1000000 - 1)

/* The fixed-size record heads, up to their data (header_len, header fields, data_len): a chunk's
 * (op, compression=none, size), an index data record's (op, ver, conn, count) and a message's
 * (op, conn, time; then in its data the message's header, height, width and events[] length) */
#define CHUNK_HEAD (4 + 41 + 4)
#define INDEX_HEAD (4 + 47 + 4)
#define MSG_HEAD (4 + 38 + 4 + 28)
/* threads packing and writing a large write; the parts its events are packed in; bytes of a
 * part of the file written by one thread */
#define BAG_THREADS 8
#define BAG_PARTS 32
#define WRITE_PART ((size_t)4 << 20)
/* pend's written bytes go when the rest is this fraction of them or less (pend_at) */
#define PEND_MOVE_FRACTION 4

#define OP_MSG_DATA 0x02
#define OP_BAG_HEADER 0x03
#define OP_INDEX_DATA 0x04
#define OP_CHUNK 0x05
#define OP_CHUNK_INFO 0x06
#define OP_CONNECTION 0x07

static const char topic[] = "/dvs/events";
static const char msg_type[] = "dvs_msgs/EventArray";
static const char msg_md5[] = "5e8beee5a6c107e504c2e78903c224b8";
static const char msg_definition[] =
    "# This message contains an array of events\n"
    "# (0, 0) is at top-left corner of image\n"
    "#\n"
    "\n"
    "Header header\n"
    "\n"
    "uint32 height         # image height, that is, number of rows\n"
    "uint32 width          # image width, that is, number of columns\n"
    "\n"
    "# an array of events\n"
    "Event[] events\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: dvs_msgs/Event\n"
    "# A DVS event\n"
    "uint16 x\n"
    "uint16 y\n"
    "time ts\n"
    "bool polarity\n";

typedef struct {
    unsigned char *p;
    size_t len, cap;
    int failed; /* out of memory once: everything after is dropped, and finish fails */
} bytes;

typedef struct {
    uint64_t pos, start, end; /* file offset; first and last message time (ROS time as stored) */
    uint32_t count;           /* messages */
} chunk_info;

/* A write's events [first, end) go at pend's offset at. */
typedef struct {
    size_t first, end, at;
} piece;

typedef struct {
    evr_raw_stream s; /* first: the interface pointer is the writer pointer */
    /* the stream's own finish and abort, which these wrap */
    evr_status (*raw_finish)(evr_event_writer *w, int64_t duration_us, evr_error *err);
    void (*raw_abort)(evr_event_writer *w);
    uint32_t width, height, seq;
    /* the file's bytes from file_pos on, not written yet, are pend's from pend_at on: finished
     * chunks up to `ready`, then the current chunk, whose record starts at chunk_at (offsets in
     * pend). The bytes before pend_at were written; the rest moves down once it is a fraction of
     * them (moving the gathering message's megabytes down at every write was a large part of the
     * writer's time) */
    bytes pend;
    uint64_t file_pos;
    size_t pend_at, ready, chunk_at;
    bytes index; /* the current chunk's index entries */
    uint64_t chunk_start, chunk_end;
    uint32_t chunk_n;  /* its finished messages */
    int conn_in_chunk; /* the connection record went into a chunk */
    /* the gathering message: open, its record in pend, its events, window, last event's time */
    int msg_open;
    size_t msg_at, msg_n;
    int64_t msg_win, msg_t;
    bytes out; /* the tail */
    chunk_info *infos;
    size_t n_infos, cap_infos;
    piece *pieces; /* the current write's */
    size_t n_pieces, cap_pieces;
    int broken; /* a write or flush failed: chunks may be cut, the tail overwritten */
    /* a large write's finished chunks, written from pend while the next write is checked, laid
     * out and packed: pend's bytes stay in place until it is waited for (pend_room, settle) */
    evr_write_behind behind;
    int io_err; /* its failed write's errno, met where pend had to grow */
} bag_writer;

/* Room for n more bytes at b->p + b->len (NULL, and b->failed, when out of memory). */
static unsigned char *reserve(bytes *b, size_t n)
{
    if (b->failed) return NULL;
    if (b->cap - b->len < n) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap - b->len < n) cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (!p) {
            b->failed = 1;
            return NULL;
        }
        b->p = p;
        b->cap = cap;
    }
    return b->p + b->len;
}

/* Room for n more bytes in pend; a buffer that must move waits for the write behind first. */
static unsigned char *pend_room(bag_writer *w, size_t n)
{
    if (w->pend.cap - w->pend.len < n && !w->io_err) w->io_err = evr_write_behind_wait(&w->behind);
    return w->io_err ? NULL : reserve(&w->pend, n);
}

static void put(bytes *b, const void *data, size_t n)
{
    unsigned char *p = reserve(b, n);
    if (!p) return;
    memcpy(p, data, n);
    b->len += n;
}

static void put_u32(bytes *b, uint32_t v)
{
    unsigned char c[4];
    evr_put_le32(c, v);
    put(b, c, 4);
}
static void put_u64(bytes *b, uint64_t v)
{
    unsigned char c[8];
    evr_put_le64(c, v);
    put(b, c, 8);
}

/* A header field: field_len, then "name=value". */
static void field(bytes *b, const char *name, const void *value, size_t len)
{
    size_t nl = strlen(name);
    put_u32(b, (uint32_t)(nl + 1 + len));
    put(b, name, nl);
    put(b, "=", 1);
    put(b, value, len);
}
static void field_u8(bytes *b, const char *name, uint32_t v)
{
    unsigned char c = (unsigned char)v;
    field(b, name, &c, 1);
}
static void field_u32(bytes *b, const char *name, uint32_t v)
{
    unsigned char c[4];
    evr_put_le32(c, v);
    field(b, name, c, 4);
}
static void field_u64(bytes *b, const char *name, uint64_t v)
{
    unsigned char c[8];
    evr_put_le64(c, v);
    field(b, name, c, 8);
}
static void field_str(bytes *b, const char *name, const char *s) { field(b, name, s, strlen(s)); }

/* The same fields at p, for the fixed-size heads filled in place; each returns the end. */
static unsigned char *field_at(unsigned char *p, const char *name, const void *value, size_t len)
{
    size_t nl = strlen(name);
    evr_put_le32(p, (uint32_t)(nl + 1 + len));
    memcpy(p + 4, name, nl);
    p[4 + nl] = '=';
    memcpy(p + 5 + nl, value, len);
    return p + 5 + nl + len;
}
static unsigned char *field_u8_at(unsigned char *p, const char *name, uint32_t v)
{
    unsigned char c = (unsigned char)v;
    return field_at(p, name, &c, 1);
}
static unsigned char *field_u32_at(unsigned char *p, const char *name, uint32_t v)
{
    unsigned char c[4];
    evr_put_le32(c, v);
    return field_at(p, name, c, 4);
}
static unsigned char *field_u64_at(unsigned char *p, const char *name, uint64_t v)
{
    unsigned char c[8];
    evr_put_le64(c, v);
    return field_at(p, name, c, 8);
}

/* A record: header_len, the header (built in hdr), data_len, the data. */
static void record(bytes *b, const bytes *hdr, const void *data, size_t len)
{
    put_u32(b, (uint32_t)hdr->len);
    put(b, hdr->p, hdr->len);
    put_u32(b, (uint32_t)len);
    put(b, data, len);
}

static void free_bytes(bytes *b) { free(b->p); }

/* ROS time as bag headers store it: secs in the low half, nsecs in the high. */
static uint64_t ros_time(int64_t t_us)
{
    return (uint64_t)(t_us / 1000000) | (uint64_t)(t_us % 1000000 * 1000) << 32;
}

static void connection_record(bytes *b)
{
    bytes hdr = {0}, data = {0};
    field_u8(&hdr, "op", OP_CONNECTION);
    field_u32(&hdr, "conn", 0);
    field_str(&hdr, "topic", topic);
    field_str(&data, "topic", topic);
    field_str(&data, "type", msg_type);
    field_str(&data, "md5sum", msg_md5);
    field_str(&data, "message_definition", msg_definition);
    field_str(&data, "latching", "0");
    record(b, &hdr, data.p, data.len);
    b->failed |= hdr.failed | data.failed;
    free_bytes(&hdr);
    free_bytes(&data);
}

/* A chunk record's head (CHUNK_HEAD bytes) for size bytes of data. */
static void chunk_head(unsigned char *p, uint32_t size)
{
    unsigned char *h = p + 4;
    h = field_u8_at(h, "op", OP_CHUNK);
    h = field_at(h, "compression", "none", 4);
    h = field_u32_at(h, "size", size);
    evr_put_le32(p, (uint32_t)(h - p - 4));
    evr_put_le32(h, size);
}

/* An index data record's head (INDEX_HEAD bytes) for count messages. */
static void index_head(unsigned char *p, uint32_t count)
{
    unsigned char *h = p + 4;
    h = field_u8_at(h, "op", OP_INDEX_DATA);
    h = field_u32_at(h, "ver", 1);
    h = field_u32_at(h, "conn", 0);
    h = field_u32_at(h, "count", count);
    evr_put_le32(p, (uint32_t)(h - p - 4));
    evr_put_le32(h, 12 * count);
}

/* A message data record's head (MSG_HEAD bytes) for n events, up to the events. */
static void message_head(unsigned char *p, uint64_t time, uint32_t seq, uint32_t height,
                         uint32_t width, uint32_t n)
{
    unsigned char *h = p + 4;
    h = field_u8_at(h, "op", OP_MSG_DATA);
    h = field_u32_at(h, "conn", 0);
    h = field_u64_at(h, "time", time);
    evr_put_le32(p, (uint32_t)(h - p - 4));
    evr_put_le32(h, (uint32_t)(28 + (size_t)n * EVENT_BYTES));
    evr_put_le32(h + 4, seq);     /* header.seq */
    evr_put_le64(h + 8, time);    /* header.stamp */
    evr_put_le32(h + 16, 0);      /* header.frame_id: "" */
    evr_put_le32(h + 20, height); /* height */
    evr_put_le32(h + 24, width);  /* width */
    evr_put_le32(h + 28, n);      /* events[] length */
}

/* Ends the current chunk before the gathering message (if any): fills in its head, puts its index
 * data record after it and room for the next chunk's head, moving the gathering message on. */
static int close_chunk(bag_writer *w)
{
    const size_t upto = w->msg_open ? w->msg_at : w->pend.len;
    const size_t index_len = INDEX_HEAD + w->index.len, gap = index_len + CHUNK_HEAD;
    const size_t tail = w->pend.len - upto;
    if (w->index.failed || !pend_room(w, gap)) return 0;
    if (w->n_infos == w->cap_infos) {
        size_t cap = w->cap_infos ? 2 * w->cap_infos : 64;
        chunk_info *p = realloc(w->infos, cap * sizeof *p);
        if (!p) return 0;
        w->infos = p;
        w->cap_infos = cap;
    }
    unsigned char *p = w->pend.p;
    memmove(p + upto + gap, p + upto, tail);
    chunk_head(p + w->chunk_at, (uint32_t)(upto - w->chunk_at - CHUNK_HEAD));
    index_head(p + upto, w->chunk_n);
    memcpy(p + upto + INDEX_HEAD, w->index.p, w->index.len);
    w->pend.len += gap;
    chunk_info *ci = &w->infos[w->n_infos++];
    ci->pos = w->file_pos + (w->chunk_at - w->pend_at);
    ci->start = w->chunk_start;
    ci->end = w->chunk_end;
    ci->count = w->chunk_n;
    w->ready = upto + index_len;
    w->chunk_at = w->ready;
    if (w->msg_open) w->msg_at += gap;
    w->index.len = 0;
    w->chunk_n = 0;
    return 1;
}

/* Starts a message of window win: room for its head (and the connection record before the
 * first). */
static int begin_message(bag_writer *w, int64_t win)
{
    if (!w->conn_in_chunk) {
        if (!pend_room(w, 4096)) return 0; /* the record's few hundred bytes */
        connection_record(&w->pend);
        w->conn_in_chunk = 1;
    }
    if (!pend_room(w, MSG_HEAD)) return 0;
    w->msg_at = w->pend.len;
    w->pend.len += MSG_HEAD;
    w->msg_open = 1;
    w->msg_n = 0;
    w->msg_win = win;
    return 1;
}

/* Ends the gathering message (its events are in pend, or placed there by this write's pieces):
 * its head, its index entry, and the chunk's end once the chunk is large enough. */
static int end_message(bag_writer *w)
{
    const uint64_t time = ros_time(w->msg_t);
    message_head(w->pend.p + w->msg_at, time, w->seq++, w->height, w->width, (uint32_t)w->msg_n);
    put_u64(&w->index, time);
    put_u32(&w->index, (uint32_t)(w->msg_at - w->chunk_at - CHUNK_HEAD));
    if (!w->chunk_n) w->chunk_start = time;
    w->chunk_end = time;
    w->chunk_n++;
    w->msg_open = 0;
    if (w->pend.len - w->chunk_at - CHUNK_HEAD >= CHUNK_BYTES) return close_chunk(w);
    return 1;
}

static evr_status no_memory(bag_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: out of memory", w->s.who);
    return EVR_ERR_NOMEM;
}

static evr_status cannot_write(bag_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: cannot write %s: %s", w->s.who, w->s.tmp,
             strerror(errno));
    return EVR_ERR_IO;
}

/* One job on the pool: checking, packing or writing a write()'s parts. */
typedef struct {
    bag_writer *w;
    const evr_event *ev;
    size_t n;
    int parts;
    int bad[BAG_PARTS]; /* check: an event the bag cannot hold; write: a failed write (errno) */
    size_t from;        /* write: pend's bytes [from, from + n) */
} bag_job;

/* Part k of a check: its events fit and keep time order (the first against the event before). */
static void check_part(void *ctx, int k, int thread)
{
    bag_job *j = ctx;
    size_t a, b;
    (void)thread;
    evr_par_share(j->n, j->parts, k, &a, &b);
    for (size_t i = a; i < b; i++)
        if (!evr_raw_stream_fits(&j->w->s, &j->ev[i]) || (i > 0 && j->ev[i].t < j->ev[i - 1].t)) {
            j->bad[k] = 1;
            return;
        }
}

static void pack_events(unsigned char *o, const evr_event *ev, size_t n)
{
    for (size_t i = 0; i < n; i++, o += EVENT_BYTES) {
        const int64_t t = ev[i].t;
        const int64_t sec = t / 1000000;
        evr_put_le16(o, ev[i].x);
        evr_put_le16(o + 2, ev[i].y);
        evr_put_le32(o + 4, (uint32_t)sec);
        evr_put_le32(o + 8, (uint32_t)((t - sec * 1000000) * 1000));
        o[12] = ev[i].p > 0;
    }
}

/* Part k of packing: its share of the write's events, at their pieces' places. */
static void pack_part(void *ctx, int k, int thread)
{
    bag_job *j = ctx;
    const piece *pc = j->w->pieces;
    size_t a, b, lo = 0, hi = j->w->n_pieces;
    (void)thread;
    evr_par_share(j->n, j->parts, k, &a, &b);
    if (a >= b) return;
    while (hi - lo > 1) { /* the piece holding event a */
        const size_t mid = lo + (hi - lo) / 2;
        if (pc[mid].first <= a) lo = mid;
        else hi = mid;
    }
    for (; a < b; lo++) {
        const size_t end = pc[lo].end < b ? pc[lo].end : b;
        pack_events(j->w->pend.p + pc[lo].at + (a - pc[lo].first) * EVENT_BYTES, j->ev + a,
                    end - a);
        a = end;
    }
}

/* Part k of writing the finished chunks: its share of their bytes. */
static void write_part(void *ctx, int k, int thread)
{
    bag_job *j = ctx;
    size_t a, b;
    (void)thread;
    evr_par_share(j->n, j->parts, k, &a, &b);
    a += j->from;
    b += j->from;
    if (!evr_write_at(fileno(j->w->s.f), j->w->pend.p + a, b - a,
                      j->w->file_pos + (a - j->w->pend_at)))
        j->bad[k] = errno ? errno : EIO;
}

/* The pool, started at the first large write (NULL, and one thread, when it cannot be). */
static evr_par_pool *pool_for(bag_writer *w, size_t work, size_t large)
{
    if (work < large) return NULL;
    if (!w->s.parts.pool) w->s.parts.pool = evr_par_pool_new(evr_par_threads(BAG_THREADS));
    return w->s.parts.pool;
}

/* Refuses the write when an event cannot go in the bag, with the first such event's line;
 * nothing changes then. */
static evr_status check_events(bag_writer *w, const evr_event *ev, size_t n, evr_error *err)
{
    bag_job j;
    int bad = w->s.have_last && ev[0].t < w->s.last_t;
    memset(&j, 0, sizeof j);
    j.w = w;
    j.ev = ev;
    j.n = n;
    j.parts = n < EVR_PAR_PACK_MIN ? 1 : BAG_PARTS;
    evr_par_pool_run(pool_for(w, n, EVR_PAR_PACK_MIN), j.parts, check_part, &j);
    for (int k = 0; k < j.parts; k++) bad |= j.bad[k];
    if (bad) {
        const int64_t last_t = w->s.last_t;
        const int have_last = w->s.have_last;
        for (size_t i = 0; i < n; i++) {
            evr_status st = evr_raw_stream_check(&w->s, &ev[i], err);
            if (st != EVR_OK) {
                w->s.last_t = last_t;
                w->s.have_last = have_last;
                return st;
            }
        }
    }
    w->s.last_t = ev[n - 1].t;
    w->s.have_last = 1;
    return EVR_OK;
}

/* The first event at or after ev[i] (which comes before it) whose time is t or later; n: none.
 * A galloping search: messages hold from one event to millions. */
static size_t first_from(const evr_event *ev, size_t i, size_t n, int64_t t)
{
    size_t lo = i, hi = i + 1, step = 1;
    while (hi < n && ev[hi].t < t) {
        lo = hi;
        step *= 2;
        hi = n - lo > step ? lo + step : n;
    }
    while (hi - lo > 1) {
        const size_t mid = lo + (hi - lo) / 2;
        if (ev[mid].t < t) lo = mid;
        else hi = mid;
    }
    return hi;
}

static int add_piece(bag_writer *w, size_t first, size_t end, size_t at)
{
    if (w->n_pieces == w->cap_pieces) {
        size_t cap = w->cap_pieces ? 2 * w->cap_pieces : 64;
        piece *p = realloc(w->pieces, cap * sizeof *p);
        if (!p) return 0;
        w->pieces = p;
        w->cap_pieces = cap;
    }
    w->pieces[w->n_pieces].first = first;
    w->pieces[w->n_pieces].end = end;
    w->pieces[w->n_pieces].at = at;
    w->n_pieces++;
    return 1;
}

/* Lays out ev[0 .. n) (checked): messages and chunks end where they would event by event, and
 * each message's run of events gets its place in pend (a piece). */
static int lay_out(bag_writer *w, const evr_event *ev, size_t n)
{
    w->n_pieces = 0;
    if (!pend_room(w, n * EVENT_BYTES + MSG_HEAD)) return 0;
    for (size_t i = 0; i < n;) {
        const int64_t win = ev[i].t * MSG_HZ / 1000000;
        const int64_t next = ((win + 1) * 1000000 + MSG_HZ - 1) / MSG_HZ; /* the next window */
        size_t end;
        if (w->msg_open && (win != w->msg_win || w->msg_n == MSG_MAX_EVENTS) && !end_message(w))
            return 0;
        if (!w->msg_open && !begin_message(w, win)) return 0;
        end = first_from(ev, i, n, next);
        if (end - i > MSG_MAX_EVENTS - w->msg_n) end = i + (MSG_MAX_EVENTS - w->msg_n);
        if (!pend_room(w, (end - i) * EVENT_BYTES) || !add_piece(w, i, end, w->pend.len)) return 0;
        w->pend.len += (end - i) * EVENT_BYTES;
        w->msg_n += end - i;
        w->msg_t = ev[end - 1].t;
        i = end;
    }
    return 1;
}

/* Waits for the write behind, then moves pend's unwritten bytes down once they are a fraction of
 * the written ones. */
static evr_status settle(bag_writer *w, evr_error *err)
{
    const int e = w->io_err ? w->io_err : evr_write_behind_wait(&w->behind);
    if (e) {
        w->io_err = e;
        errno = e;
        return cannot_write(w, err);
    }
    if ((w->pend.len - w->pend_at) * PEND_MOVE_FRACTION <= w->pend_at) {
        const size_t at = w->pend_at;
        memmove(w->pend.p, w->pend.p + at, w->pend.len - at);
        w->pend.len -= at;
        w->ready -= at;
        w->chunk_at -= at;
        if (w->msg_open) w->msg_at -= at;
        w->pend_at = 0;
    }
    return EVR_OK;
}

/* Writes the finished chunks at their place in the file, in parts on the pool; pend keeps the
 * current chunk. */
static evr_status write_ready(bag_writer *w, evr_error *err)
{
    bag_job j;
    if (w->pend.failed || w->index.failed) return no_memory(w, err);
    evr_status st = settle(w, err);
    if (st != EVR_OK || w->ready == w->pend_at) return st;
    memset(&j, 0, sizeof j);
    j.w = w;
    j.n = w->ready - w->pend_at;
    j.parts = j.n / WRITE_PART < BAG_PARTS ? (int)(j.n / WRITE_PART) + 1 : BAG_PARTS;
    j.from = w->pend_at;
    evr_par_pool_run(pool_for(w, j.n, 2 * WRITE_PART), j.parts, write_part, &j);
    for (int k = 0; k < j.parts; k++)
        if (j.bad[k]) {
            errno = j.bad[k];
            return cannot_write(w, err);
        }
    w->file_pos += w->ready - w->pend_at;
    w->pend_at = w->ready;
    return EVR_OK;
}

/* Starts writing the finished chunks behind (the previous ones waited for), or writes them now
 * when no thread can. */
static evr_status write_behind(bag_writer *w, evr_error *err)
{
    if (w->pend.failed || w->index.failed) return no_memory(w, err);
    evr_status st = settle(w, err);
    if (st != EVR_OK || w->ready == w->pend_at) return st;
    const size_t len = w->ready - w->pend_at;
    if (evr_write_behind_start(&w->behind, fileno(w->s.f), w->pend.p + w->pend_at, len,
                               w->file_pos) != 0)
        return write_ready(w, err);
    w->file_pos += len;
    w->pend_at = w->ready;
    return EVR_OK;
}

/* The bag header record, padded to BAG_HEADER_BYTES. */
static void bag_header(bytes *b, uint64_t index_pos, uint32_t conns, uint32_t chunks)
{
    bytes hdr = {0};
    char pad[BAG_HEADER_BYTES];
    field_u8(&hdr, "op", OP_BAG_HEADER);
    field_u64(&hdr, "index_pos", index_pos);
    field_u32(&hdr, "conn_count", conns);
    field_u32(&hdr, "chunk_count", chunks);
    memset(pad, ' ', sizeof pad);
    record(b, &hdr, pad, BAG_HEADER_BYTES - 8 - hdr.len);
    b->failed |= hdr.failed;
    free_bytes(&hdr);
}

/* After the written chunks: the connection record and the chunk infos; then the bag header
 * pointing at them. The next chunks overwrite them. */
static evr_status write_tail(bag_writer *w, evr_error *err)
{
    bytes hdr = {0};
    const int fd = fileno(w->s.f);
    w->out.len = 0;
    connection_record(&w->out);
    for (size_t i = 0; i < w->n_infos; i++) {
        const chunk_info *ci = &w->infos[i];
        hdr.len = 0;
        field_u8(&hdr, "op", OP_CHUNK_INFO);
        field_u32(&hdr, "ver", 1);
        field_u64(&hdr, "chunk_pos", ci->pos);
        field_u64(&hdr, "start_time", ci->start);
        field_u64(&hdr, "end_time", ci->end);
        field_u32(&hdr, "count", 1);
        put_u32(&w->out, (uint32_t)hdr.len);
        put(&w->out, hdr.p, hdr.len);
        put_u32(&w->out, 8);
        put_u32(&w->out, 0); /* conn */
        put_u32(&w->out, ci->count);
    }
    w->out.failed |= hdr.failed;
    free_bytes(&hdr);
    if (w->out.failed) return no_memory(w, err);
    if (!evr_write_at(fd, w->out.p, w->out.len, w->file_pos)) return cannot_write(w, err);
    w->out.len = 0;
    bag_header(&w->out, w->file_pos, 1, (uint32_t)w->n_infos);
    if (w->out.failed) return no_memory(w, err);
    if (!evr_write_at(fd, w->out.p, w->out.len, strlen(BAG_MAGIC))) return cannot_write(w, err);
    return EVR_OK;
}

static evr_status bag_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    bag_job j;
    evr_status st;
    if (n == 0) return EVR_OK;
    st = check_events(w, ev, n, err);
    if (st != EVR_OK) return st; /* refused before anything changed */
    if (!lay_out(w, ev, n)) {
        w->broken = 1;
        if (!w->io_err) return no_memory(w, err);
        errno = w->io_err;
        return cannot_write(w, err);
    }
    memset(&j, 0, sizeof j);
    j.w = w;
    j.ev = ev;
    j.n = n;
    j.parts = n < EVR_PAR_PACK_MIN ? 1 : BAG_PARTS;
    evr_par_pool *pool = pool_for(w, n, EVR_PAR_PACK_MIN);
    evr_par_pool_run(pool, j.parts, pack_part, &j);
    st = pool ? write_behind(w, err) : write_ready(w, err);
    if (st != EVR_OK) w->broken = 1;
    return st;
}

/* The gathering message stays open: where messages end depends only on the events. */
static evr_status bag_flush(evr_event_writer *base, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    evr_status st = EVR_OK;
    if (w->chunk_n && !close_chunk(w)) st = no_memory(w, err);
    if (st == EVR_OK) st = write_ready(w, err);
    if (st == EVR_OK) st = write_tail(w, err);
    if (st != EVR_OK) w->broken = 1;
    return st;
}

static void free_bag(bag_writer *w)
{
    evr_write_behind_stop(&w->behind); /* it reads pend */
    free_bytes(&w->pend);
    free_bytes(&w->index);
    free_bytes(&w->out);
    free(w->infos);
    free(w->pieces);
}

static evr_status bag_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    evr_status st = EVR_OK;
    if (w->msg_open && !end_message(w)) st = no_memory(w, err);
    if (st == EVR_OK) st = bag_flush(base, err);
    free_bag(w);
    if (st != EVR_OK) {
        w->raw_abort(base);
        return st;
    }
    return w->raw_finish(base, duration_us, err);
}

/* A bag's chunks and tail are rewritten in place: it is kept only when it took every event it
 * was given without a failure (it then ends as finish() ends it). */
static evr_status bag_salvage(evr_event_writer *base, uint64_t events, int64_t duration_us,
                              evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    if (!w->broken && events == w->s.count) return bag_finish(base, duration_us, err);
    snprintf(err->msg, sizeof err->msg,
             "rosbag writer: cannot keep %llu events of %s (a bag cut short is not kept)",
             (unsigned long long)events, w->s.path);
    free_bag(w);
    w->raw_abort(base);
    return EVR_ERR_IO;
}

static void bag_abort(evr_event_writer *base)
{
    bag_writer *w = (bag_writer *)base;
    free_bag(w);
    w->raw_abort(base);
}

evr_status evr_rosbag_writer_open(const char *path, const evr_writer_meta *meta,
                                  evr_event_writer **out, evr_error *err)
{
    bytes head = {0};
    put(&head, BAG_MAGIC, strlen(BAG_MAGIC));
    bag_header(&head, 0, 0, 0);
    if (head.failed) {
        free_bytes(&head);
        snprintf(err->msg, sizeof err->msg, "rosbag writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    evr_status st =
        evr_raw_writer_open(sizeof(bag_writer), path, "rosbag writer", 65536, ROSBAG_MAX_T,
                            (const char *)head.p, head.len, bag_write, out, err);
    if (st == EVR_OK) {
        bag_writer *w = (bag_writer *)*out;
        w->raw_finish = w->s.base.finish;
        w->raw_abort = w->s.base.abort;
        w->s.base.flush = bag_flush;
        w->s.base.finish = bag_finish;
        w->s.base.abort = bag_abort;
        w->s.base.salvage = bag_salvage;
        w->width = (uint32_t)meta->width;
        w->height = (uint32_t)meta->height;
        w->file_pos = head.len;
        /* the current chunk's head goes first; everything after the header goes by pwrite */
        if (!reserve(&w->pend, CHUNK_HEAD)) st = no_memory(w, err);
        else if (fflush(w->s.f) != 0) st = cannot_write(w, err);
        w->pend.len = CHUNK_HEAD;
        if (st != EVR_OK) {
            bag_abort(*out);
            *out = NULL;
        }
    }
    free_bytes(&head);
    return st;
}

const evr_event_format evr_format_rosbag = {
    "rosbag",
    NULL,
    "events.bag",
    evr_rosbag_writer_open,
    "ROS1 bag of dvs_msgs/EventArray at 30 Hz (rosbags, ROS)",
    ".bag",
    0};
