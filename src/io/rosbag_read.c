#include "io/rosbag_read.h"
#include "io/byte_order.h"

#include <bzlib.h>
#include <lz4frame.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BAG_MAGIC "#ROSBAG V2.0\n"
#define EVENT_BYTES 13 /* uint16 x, uint16 y, time ts, bool polarity */
/* A compressed chunk's data, uncompressed, at most (rosbag's chunks are about 768 KB; this
 * bounds what a corrupt size field makes the reader allocate) */
#define CHUNK_MAX ((size_t)1 << 30)

typedef struct {
    const unsigned char *p;
    size_t n;
} span;

typedef struct {
    int64_t conn;  /* the EventArray connection read; -1: none seen yet */
    evr_event *ev; /* NULL: only counting */
    size_t n;      /* events counted or stored */
    int width, height;
    const char *why; /* what is wrong, for the one line */
} bag_reader;

/* Takes n bytes off the front of s into out; 0 when s is shorter. */
static int take(span *s, size_t n, span *out)
{
    if (s->n < n) return 0;
    out->p = s->p;
    out->n = n;
    s->p += n;
    s->n -= n;
    return 1;
}

/* The next length-prefixed block (uint32 length, then the bytes). */
static int take_block(span *s, span *out)
{
    span len;
    return take(s, 4, &len) && take(s, evr_get_le32(len.p), out);
}

/* The value of header field name ("name=value" blocks); 0 when absent or the header is corrupt. */
static int field(span h, const char *name, span *value)
{
    size_t nl = strlen(name);
    span f;
    while (h.n) {
        if (!take_block(&h, &f)) return 0;
        if (f.n > nl && f.p[nl] == '=' && !memcmp(f.p, name, nl)) {
            value->p = f.p + nl + 1;
            value->n = f.n - nl - 1;
            return 1;
        }
    }
    return 0;
}

static int field_u32(span h, const char *name, uint32_t *v)
{
    span f;
    if (!field(h, name, &f) || f.n != 4) return 0;
    *v = evr_get_le32(f.p);
    return 1;
}

static int field_is(span h, const char *name, const char *text)
{
    span f;
    return field(h, name, &f) && f.n == strlen(text) && !memcmp(f.p, text, f.n);
}

/* One dvs_msgs/EventArray message: counts or stores its events. */
static int message(bag_reader *r, span m)
{
    span head, frame, sizes, count, evs;
    if (!take(&m, 12, &head) || !take_block(&m, &frame) || !take(&m, 8, &sizes) ||
        !take(&m, 4, &count) || !take(&m, (size_t)evr_get_le32(count.p) * EVENT_BYTES, &evs)) {
        r->why = "truncated dvs_msgs/EventArray message";
        return 0;
    }
    if (r->width < 0) {
        r->height = (int)evr_get_le32(sizes.p);
        r->width = (int)evr_get_le32(sizes.p + 4);
    }
    if (r->ev)
        for (const unsigned char *p = evs.p; p < evs.p + evs.n; p += EVENT_BYTES) {
            evr_event *e = &r->ev[r->n++];
            memset(e, 0, sizeof *e);
            e->x = (uint16_t)evr_get_le16(p);
            e->y = (uint16_t)evr_get_le16(p + 2);
            e->t = (int64_t)evr_get_le32(p + 4) * 1000000 + evr_get_le32(p + 8) / 1000;
            e->p = (int8_t)(p[12] ? 1 : 0);
            e->id = 0;
        }
    else r->n += evr_get_le32(count.p);
    return 1;
}

static int records(bag_reader *r, span s, int in_chunk);

/* LZ4 chunks are LZ4 frames (roslz4, rosbags); out holds exactly size bytes. */
static int lz4_chunk(span in, unsigned char *out, size_t size)
{
    LZ4F_dctx *dctx = NULL;
    size_t at = 0, used = 0, ret = 1;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&dctx, LZ4F_VERSION))) return 0;
    while (ret != 0 && used < in.n) {
        size_t src = in.n - used, dst = size - at;
        ret = LZ4F_decompress(dctx, out + at, &dst, in.p + used, &src, NULL);
        if (LZ4F_isError(ret) || (src == 0 && dst == 0)) break;
        used += src;
        at += dst;
    }
    LZ4F_freeDecompressionContext(dctx);
    return ret == 0 && at == size && used == in.n;
}

/* bz2 chunks are one bzip2 stream. */
static int bz2_chunk(span in, unsigned char *out, size_t size)
{
    unsigned int len = (unsigned int)size;
    if (in.n > UINT32_MAX) return 0;
    return BZ2_bzBuffToBuffDecompress((char *)out, &len, (char *)(uintptr_t)in.p,
                                      (unsigned int)in.n, 0, 0) == BZ_OK &&
           len == size;
}

/* A chunk's records: as they are, or uncompressed first (bz2, lz4) into a buffer of its size
 * field's bytes. */
static int chunk(bag_reader *r, span hdr, span data)
{
    span comp;
    uint32_t size;
    int lz4;
    if (!field(hdr, "compression", &comp)) {
        r->why = "corrupt ROS bag chunk header (no compression field)";
        return 0;
    }
    if (comp.n == 4 && !memcmp(comp.p, "none", 4)) return records(r, data, 1);
    lz4 = comp.n == 3 && !memcmp(comp.p, "lz4", 3);
    if (!lz4 && !(comp.n == 3 && !memcmp(comp.p, "bz2", 3))) {
        r->why = "ROS bag chunk compression is none of none, bz2, lz4";
        return 0;
    }
    if (!field_u32(hdr, "size", &size) || size > CHUNK_MAX) {
        r->why = "corrupt ROS bag chunk header (no size field, or past 1 GB)";
        return 0;
    }
    unsigned char *buf = malloc(size ? size : 1);
    if (!buf) {
        r->why = "out of memory uncompressing a ROS bag chunk";
        return 0;
    }
    int ok = lz4 ? lz4_chunk(data, buf, size) : bz2_chunk(data, buf, size);
    if (!ok) r->why = lz4 ? "corrupt lz4 ROS bag chunk" : "corrupt bz2 ROS bag chunk";
    else {
        span plain = {buf, size};
        ok = records(r, plain, 1);
    }
    free(buf);
    return ok;
}

/* The records of s (the file after its magic line, or a chunk's data). */
static int records(bag_reader *r, span s, int in_chunk)
{
    span hdr, data, op;
    uint32_t conn;
    while (s.n) {
        if (!take_block(&s, &hdr) || !take_block(&s, &data)) {
            r->why = "truncated ROS bag (a record runs past the end)";
            return 0;
        }
        if (!field(hdr, "op", &op) || op.n != 1) {
            r->why = "corrupt ROS bag record header (no op field)";
            return 0;
        }
        if (op.p[0] == 0x05 && !in_chunk) {
            if (!chunk(r, hdr, data)) return 0;
        } else if (op.p[0] == 0x07 && r->conn < 0) {
            if (!field_u32(hdr, "conn", &conn)) {
                r->why = "corrupt ROS bag connection record (no conn field)";
                return 0;
            }
            if (field_is(data, "type", "dvs_msgs/EventArray")) r->conn = conn;
        } else if (op.p[0] == 0x02 && in_chunk) {
            if (!field_u32(hdr, "conn", &conn)) {
                r->why = "corrupt ROS bag message record (no conn field)";
                return 0;
            }
            if (conn == r->conn && !message(r, data)) return 0;
        }
    }
    return 1;
}

evr_status evr_rosbag_parse(const char *path, const unsigned char *data, size_t size,
                            evr_event **ev, size_t *n, int *width, int *height, evr_error *err)
{
    bag_reader r;
    span head;
    size_t magic = strlen(BAG_MAGIC);
    span all = {data, size};
    memset(&r, 0, sizeof r);
    r.conn = -1;
    r.width = r.height = -1;
    *ev = NULL;
    *n = 0;
    if (!take(&all, magic, &head) || memcmp(head.p, BAG_MAGIC, magic) != 0)
        r.why = "not a ROS bag 2.0 file (no #ROSBAG V2.0 line)";
    else if (records(&r, all, 0) && r.conn < 0)
        r.why = "no dvs_msgs/EventArray connection in the ROS bag";
    if (!r.why && r.n) {
        /* Counted first: the events fill one allocation. */
        r.ev = malloc(r.n * sizeof *r.ev);
        if (!r.ev) {
            snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
            return EVR_ERR_NOMEM;
        }
        r.n = 0;
        r.conn = -1;
        records(&r, all, 0);
    }
    if (r.why) {
        free(r.ev);
        snprintf(err->msg, sizeof err->msg, "%s: %s", path, r.why);
        return EVR_ERR_FORMAT;
    }
    *ev = r.ev;
    *n = r.n;
    if (width) *width = r.width;
    if (height) *height = r.height;
    return EVR_OK;
}
