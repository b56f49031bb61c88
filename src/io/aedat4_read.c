#include "io/aedat4_read.h"
#include "io/aedat4.h"
#include "io/byte_order.h"

#include <inttypes.h>
#include <lz4frame.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#define MAX_STREAMS 64
#define MAX_DEPTH 16
#define MAX_PACKET_BYTES ((size_t)1 << 31) /* FlatBuffers stay below 2 GB */

/* ---- FlatBuffers, every offset checked against the buffer ---- */

typedef struct {
    const unsigned char *p;
    size_t n;
} span;

/* A table of buffer b: where it starts, where its vtable starts and how long that is. */
typedef struct {
    span b;
    size_t at, vt, vlen;
} fb_table;

static uint64_t get_le64(const unsigned char *p)
{
    return (uint64_t)evr_get_le32(p) | (uint64_t)evr_get_le32(p + 4) << 32;
}

/* The table at offset at of b; 0 when it or its vtable falls outside. */
static int table_at(span b, size_t at, fb_table *t)
{
    int64_t vt;
    if (at > b.n || b.n - at < 4) return 0;
    vt = (int64_t)at - (int32_t)evr_get_le32(b.p + at);
    if (vt < 0 || (uint64_t)vt > b.n - 4) return 0;
    t->b = b;
    t->at = at;
    t->vt = (size_t)vt;
    t->vlen = evr_get_le16(b.p + vt);
    return t->vlen >= 4 && t->vlen % 2 == 0 && t->vlen <= b.n - t->vt;
}

/* The root table of a size-prefixed buffer b (its size prefix checked by the caller). */
static int root_table(span b, fb_table *t)
{
    return b.n >= 8 && table_at(b, 4 + (size_t)evr_get_le32(b.p + 4), t);
}

/* Field k's offset in the buffer when it is present and `size` bytes of it lie inside; 0 when it
 * is absent (its default); *bad is set when it runs past the buffer. */
static size_t field(const fb_table *t, int k, size_t size, int *bad)
{
    const size_t e = 4 + 2 * (size_t)k;
    size_t off;
    if (e + 2 > t->vlen) return 0;
    off = evr_get_le16(t->b.p + t->vt + e);
    if (!off) return 0;
    if (off > t->b.n - t->at || t->b.n - t->at - off < size) {
        *bad = 1;
        return 0;
    }
    return t->at + off;
}

/* The vector (or string) the offset field k points to: its first element and length (elements
 * of elem bytes). 1: all inside the buffer; 0: absent; -1: outside. */
static int vector(const fb_table *t, int k, size_t elem, size_t *first, size_t *len)
{
    int bad = 0;
    size_t f = field(t, k, 4, &bad), v;
    if (!f) return bad ? -1 : 0;
    v = f + evr_get_le32(t->b.p + f);
    if (v > t->b.n || t->b.n - v < 4) return -1;
    *len = evr_get_le32(t->b.p + v);
    *first = v + 4;
    return *len <= (t->b.n - *first) / elem ? 1 : -1;
}

/* ---- the infoNode: which stream holds events, and the sensor's size ---- */

typedef struct {
    long id;
    char type[8];
    int width, height;
} stream_info;

typedef struct {
    stream_info s[MAX_STREAMS];
    int n;
} stream_list;

static stream_info *stream_named(stream_list *l, const char *name)
{
    char *end;
    long id = strtol(name, &end, 10);
    if (end == name || *end || id < 0 || id > INT32_MAX) return NULL;
    for (int i = 0; i < l->n; i++)
        if (l->s[i].id == id) return &l->s[i];
    if (l->n == MAX_STREAMS) return NULL;
    stream_info *s = &l->s[l->n++];
    memset(s, 0, sizeof *s);
    s->id = id;
    s->width = s->height = -1;
    return s;
}

/* The value of attribute name in the tag text tag[0 .. len) (quoted by " or '), copied to out. */
static int tag_attr(const char *tag, size_t len, const char *name, char *out, size_t cap)
{
    const size_t nl = strlen(name);
    for (size_t i = 0; i + nl + 2 < len; i++) {
        if ((i == 0 || tag[i - 1] == ' ' || tag[i - 1] == '\t' || tag[i - 1] == '\n' ||
             tag[i - 1] == '\r') &&
            !memcmp(tag + i, name, nl) && tag[i + nl] == '=' &&
            (tag[i + nl + 1] == '"' || tag[i + nl + 1] == '\'')) {
            const char q = tag[i + nl + 1];
            const char *v = tag + i + nl + 2, *e = memchr(v, q, len - (size_t)(v - tag));
            size_t vl;
            if (!e) return 0;
            vl = (size_t)(e - v);
            if (vl >= cap) vl = cap - 1;
            memcpy(out, v, vl);
            out[vl] = 0;
            return 1;
        }
    }
    return 0;
}

/* Reads the streams the infoNode's XML describes: the <node>s inside <node name="outInfo">,
 * named by their id, with their <attr key="typeIdentifier"> and, in their <node name="info">,
 * <attr key="sizeX"> and <attr key="sizeY">. Returns 0 on malformed XML. */
static int read_streams(const char *x, size_t len, stream_list *l)
{
    char names[MAX_DEPTH][32];
    int depth = 0;
    size_t i = 0;
    l->n = 0;
    while (i < len) {
        const char *lt = memchr(x + i, '<', len - i), *gt;
        size_t at, tl;
        if (!lt) break;
        at = (size_t)(lt - x);
        if (len - at >= 4 && !memcmp(lt, "<!--", 4)) { /* a comment */
            const char *e = NULL;
            for (size_t k = at + 4; k + 3 <= len && !e; k++)
                if (!memcmp(x + k, "-->", 3)) e = x + k;
            if (!e) return 0;
            i = (size_t)(e - x) + 3;
            continue;
        }
        gt = memchr(lt, '>', len - at);
        if (!gt) return 0;
        tl = (size_t)(gt - lt) + 1;
        i = at + tl;
        if (tl >= 6 && !memcmp(lt, "</node", 6)) {
            if (depth == 0) return 0;
            depth--;
        } else if (tl >= 6 && !memcmp(lt, "<node", 5) && (lt[5] == ' ' || lt[5] == '>')) {
            if (depth == MAX_DEPTH) return 0;
            if (!tag_attr(lt + 5, tl - 5, "name", names[depth], sizeof names[depth]))
                names[depth][0] = 0;
            depth++;
            if (lt[tl - 2] == '/') depth--; /* <node ... /> */
        } else if (tl >= 6 && !memcmp(lt, "<attr", 5) && (lt[5] == ' ' || lt[5] == '>')) {
            char key[32], value[32];
            const char *v = gt + 1, *e = memchr(v, '<', len - i);
            size_t vl = e ? (size_t)(e - v) : 0;
            stream_info *s = NULL;
            if (!e) return 0;
            if (!tag_attr(lt + 5, tl - 5, "key", key, sizeof key)) continue;
            if (vl >= sizeof value) vl = sizeof value - 1;
            memcpy(value, v, vl);
            value[vl] = 0;
            if (depth >= 2 && !strcmp(names[depth - 2], "outInfo") &&
                !strcmp(key, "typeIdentifier")) {
                if ((s = stream_named(l, names[depth - 1])))
                    snprintf(s->type, sizeof s->type, "%s", value);
            } else if (depth >= 3 && !strcmp(names[depth - 3], "outInfo") &&
                       !strcmp(names[depth - 1], "info") &&
                       (!strcmp(key, "sizeX") || !strcmp(key, "sizeY"))) {
                if ((s = stream_named(l, names[depth - 2]))) {
                    int *d = key[4] == 'X' ? &s->width : &s->height;
                    *d = atoi(value);
                }
            }
        }
    }
    return depth == 0;
}

/* ---- packets ---- */

typedef struct {
    unsigned char *p;
    size_t n, cap;
} bytes;

typedef struct {
    const char *path;
    evr_error *err;
    evr_event *ev;
    size_t n, cap;
    bytes out;      /* a packet, decompressed */
    LZ4F_dctx *lz4; /* made when first needed */
    ZSTD_DCtx *zstd;
    int nomem; /* the failure was memory */
} reader;

static evr_status fail(reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* One line naming the file: what is wrong. */
static evr_status fail(reader *r, const char *fmt, ...)
{
    char why[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    snprintf(r->err->msg, sizeof r->err->msg, "%s: %s", r->path, why);
    return EVR_ERR_FORMAT;
}

static evr_status out_of_memory(reader *r)
{
    snprintf(r->err->msg, sizeof r->err->msg, "out of memory reading %s", r->path);
    return EVR_ERR_NOMEM;
}

/* Room for `need` more bytes in r->out (at most MAX_PACKET_BYTES in all); 0 when none. */
static int out_room(reader *r, size_t need)
{
    bytes *b = &r->out;
    if (b->cap - b->n >= need) return 1;
    if (b->n + need > MAX_PACKET_BYTES) return 0;
    size_t cap = b->cap ? b->cap : 1 << 20;
    while (cap - b->n < need) cap *= 2;
    unsigned char *p = realloc(b->p, cap);
    if (!p) {
        r->nomem = 1;
        return 0;
    }
    b->p = p;
    b->cap = cap;
    return 1;
}

/* One LZ4 frame src[0 .. len) into r->out; NULL, or what is wrong. */
static const char *unlz4(reader *r, const unsigned char *src, size_t len)
{
    size_t in = 0;
    if (!r->lz4 && LZ4F_isError(LZ4F_createDecompressionContext(&r->lz4, LZ4F_VERSION))) {
        r->nomem = 1;
        return "out of memory";
    }
    LZ4F_resetDecompressionContext(r->lz4);
    for (;;) {
        if (!out_room(r, 1 << 16)) return r->nomem ? "out of memory" : "packet too large";
        size_t dst = r->out.cap - r->out.n, srcn = len - in;
        size_t left = LZ4F_decompress(r->lz4, r->out.p + r->out.n, &dst, src + in, &srcn, NULL);
        if (LZ4F_isError(left)) return "corrupt LZ4 frame";
        in += srcn;
        r->out.n += dst;
        if (left == 0) return NULL;
        if (in == len && dst == 0) return "truncated LZ4 frame";
    }
}

/* One ZSTD frame src[0 .. len) into r->out; NULL, or what is wrong. */
static const char *unzstd(reader *r, const unsigned char *src, size_t len)
{
    ZSTD_inBuffer in = {src, len, 0};
    if (!r->zstd && !(r->zstd = ZSTD_createDCtx())) {
        r->nomem = 1;
        return "out of memory";
    }
    ZSTD_DCtx_reset(r->zstd, ZSTD_reset_session_only);
    for (;;) {
        if (!out_room(r, 1 << 17)) return r->nomem ? "out of memory" : "packet too large";
        ZSTD_outBuffer out = {r->out.p + r->out.n, r->out.cap - r->out.n, 0};
        size_t left = ZSTD_decompressStream(r->zstd, &out, &in);
        if (ZSTD_isError(left)) return "corrupt ZSTD frame";
        r->out.n += out.pos;
        if (left == 0) return NULL;
        if (in.pos == in.size && out.pos < out.size) return "truncated ZSTD frame";
    }
}

/* The events of one EventPacket b (a size-prefixed FlatBuffer), appended; at is the packet's
 * file offset, for messages. */
static evr_status event_packet(reader *r, span b, size_t at)
{
    fb_table t;
    size_t first = 0, count = 0;
    int has;
    if (b.n < 12 || evr_get_le32(b.p) > b.n - 4)
        return fail(r, "corrupt AEDAT 4.0 event packet at byte %zu (size past its end)", at);
    b.n = 4 + evr_get_le32(b.p);
    if (b.n < 12 || memcmp(b.p + 8, "EVTS", 4) != 0)
        return fail(
            r, "packet at byte %zu of the event stream is no EventPacket (identifier not EVTS)",
            at);
    if (!root_table(b, &t)) return fail(r, "corrupt AEDAT 4.0 event packet at byte %zu", at);
    has = vector(&t, 0, EVR_AEDAT4_EVENT_BYTES, &first, &count);
    if (has < 0)
        return fail(r, "corrupt AEDAT 4.0 event packet at byte %zu (elements past its end)", at);
    if (has == 0) return EVR_OK; /* no elements */
    if (count > r->cap - r->n) {
        size_t cap = r->cap ? r->cap : 1 << 16;
        while (cap - r->n < count) cap *= 2;
        evr_event *e = realloc(r->ev, cap * sizeof *e);
        if (!e) return out_of_memory(r);
        r->ev = e;
        r->cap = cap;
    }
    for (size_t i = 0; i < count; i++) {
        const unsigned char *p = b.p + first + EVR_AEDAT4_EVENT_BYTES * i;
        const int x = (int16_t)evr_get_le16(p + 8), y = (int16_t)evr_get_le16(p + 10);
        evr_event *e = &r->ev[r->n++];
        if (x < 0 || y < 0)
            return fail(r, "corrupt AEDAT 4.0 event packet at byte %zu (pixel (%d, %d))", at, x, y);
        memset(e, 0, sizeof *e);
        e->t = (int64_t)get_le64(p);
        e->x = (uint16_t)x;
        e->y = (uint16_t)y;
        e->p = (int8_t)(p[12] ? 1 : 0);
        e->id = 0;
    }
    return EVR_OK;
}

/* Decompresses src[0 .. len) (compression as the header says) into r->out, or points *b at it
 * (NONE); what it is and its file offset at, for messages. */
static evr_status unpack(reader *r, const unsigned char *src, size_t len, int compression,
                         const char *what, size_t at, span *b)
{
    static const char *const names[] = {"NONE", "LZ4", "LZ4_HIGH", "ZSTD", "ZSTD_HIGH"};
    const char *why = NULL;
    r->out.n = 0;
    *b = (span){src, len};
    if (compression == EVR_AEDAT4_LZ4 || compression == EVR_AEDAT4_LZ4_HIGH)
        why = unlz4(r, src, len);
    else if (compression == EVR_AEDAT4_ZSTD || compression == EVR_AEDAT4_ZSTD_HIGH)
        why = unzstd(r, src, len);
    if (r->nomem) return out_of_memory(r);
    if (why)
        return fail(r, "%s in %s at byte %zu (compression %s)", why, what, at, names[compression]);
    if (compression != EVR_AEDAT4_NONE) *b = (span){r->out.p, r->out.n};
    return EVR_OK;
}

/* The FileDataTable at the end (file offset at): only checked to be whole, a size-prefixed
 * FlatBuffer "FTAB" with its table of packets; the packets are read in file order. */
static evr_status data_table(reader *r, const unsigned char *src, size_t len, int compression,
                             size_t at)
{
    span b;
    fb_table t;
    size_t first, count;
    evr_status st = unpack(r, src, len, compression, "the data table", at, &b);
    if (st != EVR_OK) return st;
    if (b.n < 12 || evr_get_le32(b.p) > b.n - 4 || memcmp(b.p + 8, "FTAB", 4) != 0)
        return fail(r, "corrupt AEDAT 4.0 data table at byte %zu", at);
    b.n = 4 + evr_get_le32(b.p);
    if (!root_table(b, &t) || vector(&t, 0, 4, &first, &count) < 0)
        return fail(r, "corrupt AEDAT 4.0 data table at byte %zu", at);
    return EVR_OK;
}

/* The IOHeader b: compression, data table position and the infoNode's streams. */
static evr_status io_header(reader *r, span b, int *compression, int64_t *table,
                            stream_list *streams)
{
    fb_table t;
    int bad = 0;
    size_t c, d, xml = 0, xlen = 0;
    if (!root_table(b, &t)) return fail(r, "corrupt AEDAT 4.0 header (IOHeader FlatBuffer)");
    c = field(&t, 0, 4, &bad);
    d = field(&t, 1, 8, &bad);
    if (bad || vector(&t, 2, 1, &xml, &xlen) != 1)
        return fail(r, "corrupt AEDAT 4.0 header (IOHeader FlatBuffer%s)",
                    bad ? "" : " without its infoNode");
    *compression = c ? (int32_t)evr_get_le32(b.p + c) : EVR_AEDAT4_NONE;
    *table = d ? (int64_t)get_le64(b.p + d) : -1;
    if (!read_streams((const char *)b.p + xml, xlen, streams))
        return fail(r, "corrupt AEDAT 4.0 header (its infoNode is no well-formed XML)");
    return EVR_OK;
}

evr_status evr_aedat4_parse(const char *path, const unsigned char *data, size_t size,
                            evr_event **ev, size_t *n, int *width, int *height, evr_error *err)
{
    reader r;
    stream_list streams;
    const stream_info *events = NULL;
    int compression = 0;
    int64_t table = -1;
    size_t pos, end;
    evr_status st = EVR_OK;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.err = err;
    *ev = NULL;
    *n = 0;
    if (size < 9 || memcmp(data, "#!AER-DAT", 9) != 0)
        return fail(&r, "not an AEDAT file (no #!AER-DAT4.0 line)");
    if (size < EVR_AEDAT4_VERSION_LEN && !memcmp(data, EVR_AEDAT4_VERSION, size))
        return fail(&r, "truncated AEDAT 4.0 header (in its version line)");
    if (size < EVR_AEDAT4_VERSION_LEN || memcmp(data, EVR_AEDAT4_VERSION, EVR_AEDAT4_VERSION_LEN)) {
        size_t v = 9;
        while (v < size && v < 16 && data[v] != '\r' && data[v] != '\n') v++;
        return fail(&r, "AEDAT version '%.*s' is not read (4.0 is)", (int)(v - 9),
                    (const char *)data + 9);
    }
    pos = EVR_AEDAT4_VERSION_LEN;
    if (size - pos < 4 || evr_get_le32(data + pos) > size - pos - 4)
        return fail(&r, "truncated AEDAT 4.0 header");
    end = pos + 4 + evr_get_le32(data + pos);
    st = io_header(&r, (span){data + pos, end - pos}, &compression, &table, &streams);
    if (st != EVR_OK) return st;
    if (compression < 0 || compression > EVR_AEDAT4_ZSTD_HIGH)
        return fail(&r, "unknown AEDAT 4.0 compression %d (NONE, LZ4, LZ4_HIGH, ZSTD, ZSTD_HIGH)",
                    compression);
    if (table != -1 && table < (int64_t)end)
        return fail(&r, "corrupt AEDAT 4.0 header (data table position %" PRId64 ")", table);
    if (table > 0 && (uint64_t)table >= size)
        return fail(&r,
                    "truncated AEDAT 4.0 file (its data table at byte %" PRId64
                    " is past its %zu bytes)",
                    table, size);
    for (int i = 0; i < streams.n && !events; i++)
        if (!strcmp(streams.s[i].type, "EVTS")) events = &streams.s[i];
    if (!events) return fail(&r, "no event stream (typeIdentifier EVTS) in the AEDAT 4.0 header");
    pos = end;
    end = table >= 0 ? (size_t)table : size;
    while (pos < end && st == EVR_OK) {
        int32_t id, len;
        if (end - pos < 8) {
            st = fail(&r, "truncated AEDAT 4.0 packet header at byte %zu", pos);
            break;
        }
        id = (int32_t)evr_get_le32(data + pos);
        len = (int32_t)evr_get_le32(data + pos + 4);
        if (len < 0) {
            st = fail(&r, "corrupt AEDAT 4.0 packet header at byte %zu (size %" PRId32 ")", pos,
                      len);
            break;
        }
        if ((size_t)len > end - pos - 8) {
            st = fail(&r, "truncated AEDAT 4.0 packet at byte %zu (%" PRId32 " bytes, %zu left)",
                      pos, len, end - pos - 8);
            break;
        }
        if (id == events->id) {
            span b;
            st = unpack(&r, data + pos + 8, (size_t)len, compression, "the packet", pos, &b);
            if (st == EVR_OK) st = event_packet(&r, b, pos);
        }
        pos += 8 + (size_t)len;
    }
    if (st == EVR_OK && table >= 0) st = data_table(&r, data + end, size - end, compression, end);
    free(r.out.p);
    LZ4F_freeDecompressionContext(r.lz4);
    ZSTD_freeDCtx(r.zstd);
    if (st != EVR_OK) {
        free(r.ev);
        return st;
    }
    *ev = r.ev;
    *n = r.n;
    if (!r.n) {
        free(r.ev);
        *ev = NULL;
    }
    if (width) *width = events->width;
    if (height) *height = events->height;
    return EVR_OK;
}
