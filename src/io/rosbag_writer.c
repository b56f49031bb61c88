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
 * a complete bag after every flush; the next chunk overwrites the tail. */
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <stdlib.h>
#include <string.h>

#define BAG_MAGIC "#ROSBAG V2.0\n"
#define BAG_HEADER_BYTES 4096           /* the bag header record, padded, as rosbag writes it */
#define CHUNK_BYTES ((size_t)768 << 10) /* rosbag's default chunk threshold */
#define MSG_HZ 30
#define MSG_MAX_EVENTS ((size_t)1 << 20)
#define EVENT_BYTES 13 /* uint16 x, uint16 y, time ts, bool polarity */
#define ROSBAG_MAX_T ((INT64_C(1) << 32) * 1000000 - 1)

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

typedef struct {
    evr_raw_stream s; /* first: the interface pointer is the writer pointer */
    /* the stream's own finish and abort, which these wrap */
    evr_status (*raw_finish)(evr_event_writer *w, int64_t duration_us, evr_error *err);
    void (*raw_abort)(evr_event_writer *w);
    uint32_t width, height, seq;
    bytes msg;       /* the gathering message's events, serialized */
    size_t msg_n;    /* its events */
    int64_t msg_win; /* its window */
    int64_t msg_t;   /* its last event's time */
    bytes chunk, index, out;
    uint64_t chunk_start, chunk_end;
    uint32_t chunk_n;
    int conn_in_chunk; /* the connection record went into a chunk */
    chunk_info *infos;
    size_t n_infos, cap_infos;
    uint64_t index_pos; /* where the next chunk (and now the tail) starts */
    int broken;         /* a write or flush failed: chunks may be cut, the tail overwritten */
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

/* Ends the gathering message: its message data record goes into the chunk. */
static void end_message(bag_writer *w)
{
    bytes hdr = {0};
    uint64_t time = ros_time(w->msg_t);
    if (!w->msg_n) return;
    if (!w->conn_in_chunk) {
        connection_record(&w->chunk);
        w->conn_in_chunk = 1;
    }
    field_u8(&hdr, "op", OP_MSG_DATA);
    field_u32(&hdr, "conn", 0);
    field_u64(&hdr, "time", time);
    put_u64(&w->index, time);
    put_u32(&w->index, (uint32_t)w->chunk.len);
    put_u32(&w->chunk, (uint32_t)hdr.len);
    put(&w->chunk, hdr.p, hdr.len);
    put_u32(&w->chunk, (uint32_t)(4 + 8 + 4 + 4 + 4 + 4 + w->msg.len));
    put_u32(&w->chunk, w->seq++);           /* header.seq */
    put_u64(&w->chunk, time);               /* header.stamp */
    put_u32(&w->chunk, 0);                  /* header.frame_id: "" */
    put_u32(&w->chunk, w->height);          /* height */
    put_u32(&w->chunk, w->width);           /* width */
    put_u32(&w->chunk, (uint32_t)w->msg_n); /* events[] length */
    put(&w->chunk, w->msg.p, w->msg.len);
    w->chunk.failed |= hdr.failed | w->msg.failed;
    free_bytes(&hdr);
    if (!w->chunk_n) w->chunk_start = time;
    w->chunk_end = time;
    w->chunk_n++;
    w->msg.len = 0;
    w->msg_n = 0;
}

static evr_status no_memory(bag_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: out of memory", w->s.who);
    return EVR_ERR_NOMEM;
}

static evr_status cannot_write(bag_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: cannot write %s", w->s.who, w->s.tmp);
    return EVR_ERR_IO;
}

/* Writes out bytes b at the file's current position (index_pos). */
static evr_status write_out(bag_writer *w, bytes *b, evr_error *err)
{
    if (b->failed) return no_memory(w, err);
    if (b->len && fwrite(b->p, 1, b->len, w->s.f) != b->len) return cannot_write(w, err);
    return EVR_OK;
}

/* Writes the gathered chunk and its index data record. */
static evr_status end_chunk(bag_writer *w, evr_error *err)
{
    bytes hdr = {0};
    evr_status st;
    if (!w->chunk_n) return EVR_OK;
    if (w->chunk.failed || w->index.failed) return no_memory(w, err);
    w->out.len = 0;
    field_u8(&hdr, "op", OP_CHUNK);
    field_str(&hdr, "compression", "none");
    field_u32(&hdr, "size", (uint32_t)w->chunk.len);
    record(&w->out, &hdr, w->chunk.p, w->chunk.len);
    hdr.len = 0;
    field_u8(&hdr, "op", OP_INDEX_DATA);
    field_u32(&hdr, "ver", 1);
    field_u32(&hdr, "conn", 0);
    field_u32(&hdr, "count", w->chunk_n);
    record(&w->out, &hdr, w->index.p, w->index.len);
    w->out.failed |= hdr.failed;
    free_bytes(&hdr);
    if (w->n_infos == w->cap_infos) {
        size_t cap = w->cap_infos ? 2 * w->cap_infos : 64;
        chunk_info *p = realloc(w->infos, cap * sizeof *p);
        if (!p) return no_memory(w, err);
        w->infos = p;
        w->cap_infos = cap;
    }
    st = write_out(w, &w->out, err);
    if (st != EVR_OK) return st;
    chunk_info *ci = &w->infos[w->n_infos++];
    ci->pos = w->index_pos;
    ci->start = w->chunk_start;
    ci->end = w->chunk_end;
    ci->count = w->chunk_n;
    w->index_pos += w->out.len;
    w->chunk.len = 0;
    w->index.len = 0;
    w->chunk_n = 0;
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

/* After the chunks: the connection record and the chunk infos; then the bag header pointing at
 * them. Leaves the file positioned at index_pos for the next chunk. */
static evr_status write_tail(bag_writer *w, evr_error *err)
{
    bytes hdr = {0};
    evr_status st;
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
    st = write_out(w, &w->out, err);
    if (st != EVR_OK) return st;
    w->out.len = 0;
    bag_header(&w->out, w->index_pos, 1, (uint32_t)w->n_infos);
    if (fseeko(w->s.f, (off_t)strlen(BAG_MAGIC), SEEK_SET) != 0) return cannot_write(w, err);
    st = write_out(w, &w->out, err);
    if (st != EVR_OK) return st;
    if (fflush(w->s.f) != 0 || fseeko(w->s.f, (off_t)w->index_pos, SEEK_SET) != 0)
        return cannot_write(w, err);
    return EVR_OK;
}

static evr_status bag_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    for (size_t i = 0; i < n; i++) {
        const evr_event *e = &ev[i];
        evr_status st = evr_raw_stream_check(&w->s, e, err);
        if (st != EVR_OK) return st; /* refused before anything changed */
        int64_t win = e->t * MSG_HZ / 1000000;
        if (w->msg_n && (win != w->msg_win || w->msg_n == MSG_MAX_EVENTS)) {
            end_message(w);
            if (w->chunk.len >= CHUNK_BYTES && (st = end_chunk(w, err)) != EVR_OK) {
                w->broken = 1;
                return st;
            }
        }
        w->msg_win = win;
        w->msg_t = e->t;
        unsigned char *p = reserve(&w->msg, EVENT_BYTES);
        if (!p) return no_memory(w, err);
        evr_put_le16(p, e->x);
        evr_put_le16(p + 2, e->y);
        evr_put_le32(p + 4, (uint32_t)(e->t / 1000000));
        evr_put_le32(p + 8, (uint32_t)(e->t % 1000000 * 1000));
        p[12] = e->p > 0;
        w->msg.len += EVENT_BYTES;
        w->msg_n++;
    }
    return EVR_OK;
}

/* The gathering message stays open: where messages end depends only on the events. */
static evr_status bag_flush(evr_event_writer *base, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    evr_status st = end_chunk(w, err);
    if (st == EVR_OK) st = write_tail(w, err);
    if (st != EVR_OK) w->broken = 1;
    return st;
}

static void free_bag(bag_writer *w)
{
    free_bytes(&w->msg);
    free_bytes(&w->chunk);
    free_bytes(&w->index);
    free_bytes(&w->out);
    free(w->infos);
}

static evr_status bag_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    bag_writer *w = (bag_writer *)base;
    evr_status st;
    end_message(w);
    st = bag_flush(base, err);
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
        w->index_pos = head.len;
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
