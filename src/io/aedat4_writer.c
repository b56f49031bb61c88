/* AEDAT 4.0 files (io/aedat4.h) the way dv-processing's MonoCameraWriter writes an event-only
 * recording: one stream, id 0, named "events", of type EVTS, compressed by LZ4 (DV's default and
 * the fastest; every AEDAT 4.0 reader decodes it), or by ZSTD at a fast level (--format
 * aedat4-zstd: a smaller file, more CPU). Timestamps are the run's microseconds.
 *
 * Packets hold the events of one millisecond (t / PACKET_US), at most PACKET_MAX_EVENTS of them (a
 * denser millisecond takes several): where packets end depends only on the events, so the file's
 * bytes do too. Large writes pack and compress whole packets in parallel parts (io/par_pack.h).
 *
 * The FlatBuffers are written by hand, every field of each schema emitted (offsets below):
 *   IOHeader            compression, dataTablePosition, infoNode
 *   EventPacket         elements (the Event structs: t, x, y, on)
 *   FileDataTable       Table
 *   FileDataDefinition  ByteOffset (where the packet's compressed bytes start, after its
 *                       PacketHeader, as dv-processing writes it), PacketInfo (stream id, size),
 *                       NumElements, TimestampStart, TimestampEnd
 *
 * flush() writes the open packet and the data table after the closed packets and points the
 * header's dataTablePosition at the table: the temporary file is then a complete AEDAT 4.0 file
 * holding every event so far. The next write sets dataTablePosition back to -1 (no table:
 * readers take packets up to the end of the file), cuts that tail off and goes on after the last
 * closed packet; the open packet continues. */
#include "io/aedat4.h"
#include "io/event_formats.h"
#include "io/raw_stream.h"

#include <lz4frame.h>
#include <zstd.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PACKET_US 1000
/* At most this many events a packet: a piece of 2^20 events (what a GPU run hands over at once)
 * then makes 128 packets or more for the compressing threads; 32,768 left threads idle in the
 * eye's bursts, one packet being one thread's work (docs/benchmarks.md) */
#define PACKET_MAX_EVENTS ((size_t)1 << 13)
#define PACKET_HEADER 8                               /* int32 stream id, int32 size */
#define EVENT_PACKET_HEAD 32                          /* an EventPacket before its events */
#define IOHEADER_DTP_AT (EVR_AEDAT4_VERSION_LEN + 32) /* dataTablePosition's file offset */
#define TABLE_ENTRY_BYTES 48                          /* a FileDataDefinition and padding */
/* Compression threads for large writes (as many as the machine has, up to this): LZ4 takes tens
 * of ns an event, and the eye's events come at about 100 M a second from the H100 */
#define COMPRESS_THREADS 16
/* ZSTD's level for --format aedat4-zstd: one of its fast levels, so that the writer keeps up
 * with the GPU while the file stays well below LZ4's (docs/benchmarks.md, "Writers") */
#define ZSTD_LEVEL (-4)
/* What a compressing thread packs with, kept for reuse: one per thread (the pool's and the caller) */
#define PACK_SLOTS (COMPRESS_THREADS + 1)
#define RAW_BYTES (EVENT_PACKET_HEAD + EVR_AEDAT4_EVENT_BYTES * PACKET_MAX_EVENTS)

/* Room for one uncompressed EventPacket and, with ZSTD, a context, each slot taken by one thread
 * at a time: a fresh room per part of a write (512 KB, allocated and freed) cost page faults at
 * every write, and a fresh ZSTD context per packet allocated and cleared its tables every
 * millisecond of events. */
typedef struct {
    atomic_int taken[PACK_SLOTS];
    ZSTD_CCtx *cctx[PACK_SLOTS];
    unsigned char *raw[PACK_SLOTS];
} pack_slots;

typedef struct {
    int64_t offset; /* the packet's compressed bytes */
    int64_t count, t0, t1;
    uint32_t size; /* their length */
} table_entry;

typedef struct {
    evr_raw_stream s; /* first: the interface pointer is the writer pointer */
    /* the stream's own finish and abort, which these wrap */
    evr_status (*raw_finish)(evr_event_writer *w, int64_t duration_us, evr_error *err);
    void (*raw_abort)(evr_event_writer *w);
    int compression; /* EVR_AEDAT4_LZ4 or EVR_AEDAT4_ZSTD */
    LZ4F_preferences_t lz4;
    int64_t end;     /* file offset after the last closed packet */
    int tail;        /* a flush wrote the open packet and the table after end */
    int dirty;       /* events written since the last flush */
    evr_event *open; /* the open packet's events */
    size_t n_open;
    unsigned char *raw; /* one EventPacket, uncompressed */
    table_entry *table; /* the closed packets */
    size_t n_table, cap_table;
    size_t *starts, *sizes; /* a write's packets: where each starts, its compressed bytes */
    size_t cap_starts;
    unsigned char *buf; /* the data table, built then compressed */
    size_t cap_buf;
    pack_slots *slots;
} aedat_writer;

/* The packets of a large write, for the parallel parts: packet q is ev[start[q] .. start[q + 1]),
 * but with first_open packet 0 is the open packet, which ev[0 .. start[1]) close (copied after
 * its events in w->open, first_open of them in all). */
typedef struct {
    const aedat_writer *w;
    const size_t *start;
    size_t np;
    size_t first_open;
    size_t *size; /* packet q's compressed bytes, set by pack */
} packet_list;

static evr_status no_memory(aedat_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: out of memory", w->s.who);
    return EVR_ERR_NOMEM;
}

static evr_status cannot_write(aedat_writer *w, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "%s: cannot write %s", w->s.who, w->s.tmp);
    return EVR_ERR_IO;
}

/* ---- FlatBuffers ---- */

/* An EventPacket (size-prefixed, identifier "EVTS") of ev[0 .. n) at out; returns its bytes.
 *   0 size  4 root offset (16: the table at 20)  8 "EVTS"  12 padding
 *   14 vtable: 6 (its size), 8 (the table's), 4 (elements)
 *   20 the table: 6 (to its vtable), 24: 4 (to the vector)
 *   28 the vector's length, 32 its Event structs (8-aligned) */
static size_t event_packet(unsigned char *out, const evr_event *ev, size_t n)
{
    unsigned char *p = out + EVENT_PACKET_HEAD;
    evr_put_le32(out, (uint32_t)(EVENT_PACKET_HEAD - 4 + EVR_AEDAT4_EVENT_BYTES * n));
    evr_put_le32(out + 4, 16);
    memcpy(out + 8, "EVTS", 4);
    evr_put_le16(out + 12, 0);
    evr_put_le16(out + 14, 6);
    evr_put_le16(out + 16, 8);
    evr_put_le16(out + 18, 4);
    evr_put_le32(out + 20, 6);
    evr_put_le32(out + 24, 4);
    evr_put_le32(out + 28, (uint32_t)n);
    /* each Event built in a local, then copied: stores through p could alias ev, which kept the
     * compiler from merging the byte stores */
    for (size_t i = 0; i < n; i++, p += EVR_AEDAT4_EVENT_BYTES) {
        const evr_event e = ev[i];
        unsigned char rec[EVR_AEDAT4_EVENT_BYTES];
        evr_put_le64(rec, (uint64_t)e.t);
        evr_put_le16(rec + 8, e.x);
        evr_put_le16(rec + 10, e.y);
        evr_put_le32(rec + 12, e.p > 0);
        memcpy(p, rec, sizeof rec);
    }
    return EVENT_PACKET_HEAD + EVR_AEDAT4_EVENT_BYTES * n;
}

/* Bytes of the FileDataTable of n entries before the first entry's table (4 mod 8, so that the
 * entries' int64 fields at +12 .. +36 are 8-aligned). */
static size_t table_head(size_t n)
{
    size_t head = 48 + 4 * n;
    return head % 8 == 4 ? head : head + 4;
}

/* The FileDataTable (size-prefixed, identifier "FTAB") of e[0 .. n) at out (table_head(n) +
 * TABLE_ENTRY_BYTES * n bytes); returns its bytes.
 *   0 size  4 root offset (16: the table at 20)  8 "FTAB"
 *   12 the root's vtable: 6, 8, 4 (Table)  18 padding
 *   20 the root table: 8 (to its vtable), 24: 20 (to the vector at 44)
 *   28 the entries' one vtable: 14, 44, then ByteOffset 12, PacketInfo 4, NumElements 20,
 *      TimestampStart 28, TimestampEnd 36  42 padding
 *   44 the vector's length, 48 its offsets to the entries; padding to table_head(n)
 *   each entry (48 bytes): to the vtable, PacketInfo (stream id 0, size), ByteOffset,
 *   NumElements, TimestampStart, TimestampEnd, 4 bytes of padding */
static size_t data_table(unsigned char *out, const table_entry *e, size_t n)
{
    static const uint16_t vtable[7] = {14, 44, 12, 4, 20, 28, 36};
    const size_t head = table_head(n), total = head + TABLE_ENTRY_BYTES * n;
    memset(out, 0, head);
    evr_put_le32(out, (uint32_t)(total - 4));
    evr_put_le32(out + 4, 16);
    memcpy(out + 8, "FTAB", 4);
    evr_put_le16(out + 12, 6);
    evr_put_le16(out + 14, 8);
    evr_put_le16(out + 16, 4);
    evr_put_le32(out + 20, 8);
    evr_put_le32(out + 24, 20);
    for (int k = 0; k < 7; k++) evr_put_le16(out + 28 + 2 * k, vtable[k]);
    evr_put_le32(out + 44, (uint32_t)n);
    for (size_t i = 0; i < n; i++) {
        const size_t at = head + TABLE_ENTRY_BYTES * i;
        unsigned char *t = out + at;
        evr_put_le32(out + 48 + 4 * i, (uint32_t)(at - (48 + 4 * i)));
        evr_put_le32(t, (uint32_t)(at - 28));
        evr_put_le32(t + 4, 0);
        evr_put_le32(t + 8, e[i].size);
        evr_put_le64(t + 12, (uint64_t)e[i].offset);
        evr_put_le64(t + 20, (uint64_t)e[i].count);
        evr_put_le64(t + 28, (uint64_t)e[i].t0);
        evr_put_le64(t + 36, (uint64_t)e[i].t1);
        evr_put_le32(t + 44, 0);
    }
    return total;
}

/* The version line and the IOHeader (size-prefixed, identifier "IOHE") with dataTablePosition -1;
 * *len is set to its bytes; NULL when out of memory.
 *   0 size  4 root offset (20: the table at 24)  8 "IOHE"
 *   12 vtable: 10, 20, then compression 4, dataTablePosition 8, infoNode 16  22 padding
 *   24 the table: 12 (to its vtable), 28 compression, 32 dataTablePosition (8-aligned),
 *   40: 4 (to the string at 44)  44 the string's length, its bytes, a 0, padding */
static unsigned char *io_header(int width, int height, int compression, size_t *len)
{
    char xml[1024];
    int n = snprintf(
        xml, sizeof xml,
        "<dv version=\"2.0\">\n"
        "    <node name=\"outInfo\" path=\"/outInfo/\">\n"
        "        <node name=\"0\" path=\"/outInfo/0/\">\n"
        "            <attr key=\"compression\" type=\"string\">%s</attr>\n"
        "            <attr key=\"originalModuleName\" type=\"string\">evray</attr>\n"
        "            <attr key=\"originalOutputName\" type=\"string\">events</attr>\n"
        "            <attr key=\"typeDescription\" type=\"string\">Array of events (polarity ON/OFF).</attr>\n"
        "            <attr key=\"typeIdentifier\" type=\"string\">EVTS</attr>\n"
        "            <node name=\"info\" path=\"/outInfo/0/info/\">\n"
        "                <attr key=\"sizeX\" type=\"int\">%d</attr>\n"
        "                <attr key=\"sizeY\" type=\"int\">%d</attr>\n"
        "                <attr key=\"source\" type=\"string\">evray</attr>\n"
        "            </node>\n"
        "        </node>\n"
        "    </node>\n"
        "</dv>\n",
        compression == EVR_AEDAT4_ZSTD ? "ZSTD" : "LZ4", width, height);
    const size_t at = EVR_AEDAT4_VERSION_LEN, body = (48 + (size_t)n + 1 + 7) / 8 * 8;
    unsigned char *out = n > 0 && (size_t)n < sizeof xml ? calloc(1, at + body) : NULL;
    if (!out) return NULL;
    unsigned char *b = out + at;
    memcpy(out, EVR_AEDAT4_VERSION, EVR_AEDAT4_VERSION_LEN);
    evr_put_le32(b, (uint32_t)(body - 4));
    evr_put_le32(b + 4, 20);
    memcpy(b + 8, "IOHE", 4);
    evr_put_le16(b + 12, 10);
    evr_put_le16(b + 14, 20);
    evr_put_le16(b + 16, 4);
    evr_put_le16(b + 18, 8);
    evr_put_le16(b + 20, 16);
    evr_put_le32(b + 24, 12);
    evr_put_le32(b + 28, (uint32_t)compression);
    evr_put_le64(b + 32, UINT64_MAX); /* -1: no data table yet */
    evr_put_le32(b + 40, 4);
    evr_put_le32(b + 44, (uint32_t)n);
    memcpy(b + 48, xml, (size_t)n);
    *len = at + body;
    return out;
}

/* ---- packets ---- */

/* ---- compression: one LZ4 or ZSTD frame a packet, and one for the data table ---- */

/* Bytes the frame of len bytes takes at most. */
static size_t frame_bound(const aedat_writer *w, size_t len)
{
    return w->compression == EVR_AEDAT4_ZSTD ? ZSTD_compressBound(len)
                                             : LZ4F_compressFrameBound(len, &w->lz4);
}

/* A free slot of z (taken until slot_give), or -1 when more threads than slots pack. */
static int slot_take(pack_slots *z)
{
    for (int i = 0; i < PACK_SLOTS; i++)
        if (!atomic_exchange(&z->taken[i], 1)) return i;
    return -1;
}

static void slot_give(pack_slots *z, int i)
{
    if (i >= 0) atomic_store(&z->taken[i], 0);
}

/* Slot i's ZSTD context, made at its first use (NULL: no memory). */
static ZSTD_CCtx *slot_cctx(pack_slots *z, int i)
{
    if (i >= 0 && !z->cctx[i]) z->cctx[i] = ZSTD_createCCtx();
    return i >= 0 ? z->cctx[i] : NULL;
}

/* ZSTD's frame of src[0 .. len) at dst, in cctx (NULL: a context of its own). */
static size_t zstd_frame(ZSTD_CCtx *cctx, unsigned char *dst, size_t room, const unsigned char *src,
                         size_t len)
{
    return cctx ? ZSTD_compressCCtx(cctx, dst, room, src, len, ZSTD_LEVEL)
                : ZSTD_compress(dst, room, src, len, ZSTD_LEVEL);
}

static void pack_slots_free(pack_slots *z)
{
    if (!z) return;
    for (int i = 0; i < PACK_SLOTS; i++) {
        ZSTD_freeCCtx(z->cctx[i]);
        free(z->raw[i]);
    }
    free(z);
}

/* The frame of src[0 .. len) at dst (room bytes), with ZSTD in cctx (NULL: a free slot's, or a
 * context of its own); its bytes, 0 when the compressor failed. */
static size_t frame(const aedat_writer *w, ZSTD_CCtx *cctx, unsigned char *dst, size_t room,
                    const unsigned char *src, size_t len)
{
    size_t c;
    if (w->compression == EVR_AEDAT4_ZSTD) {
        if (cctx) c = zstd_frame(cctx, dst, room, src, len);
        else {
            const int i = slot_take(w->slots);
            c = zstd_frame(slot_cctx(w->slots, i), dst, room, src, len);
            slot_give(w->slots, i);
        }
        return ZSTD_isError(c) ? 0 : c;
    }
    c = LZ4F_compressFrame(dst, room, src, len, &w->lz4);
    return LZ4F_isError(c) ? 0 : c;
}

/* Bytes a packet of n events takes at most in the file. */
static size_t packet_bound(const aedat_writer *w, size_t n)
{
    return PACKET_HEADER + frame_bound(w, EVENT_PACKET_HEAD + EVR_AEDAT4_EVENT_BYTES * n);
}

/* Compresses the EventPacket of ev[0 .. n) (built in raw) to a PacketHeader and a frame at out;
 * returns the frame's bytes, 0 when the compressor failed. */
static size_t pack_packet(const aedat_writer *w, ZSTD_CCtx *cctx, unsigned char *raw,
                          const evr_event *ev, size_t n, unsigned char *out, size_t room)
{
    const size_t len = event_packet(raw, ev, n);
    const size_t c = frame(w, cctx, out + PACKET_HEADER, room - PACKET_HEADER, raw, len);
    if (c == 0 || c > INT32_MAX) return 0;
    evr_put_le32(out, 0);
    evr_put_le32(out + 4, (uint32_t)c);
    return c;
}

static evr_status add_entry(aedat_writer *w, uint32_t size, const evr_event *ev, size_t n,
                            evr_error *err)
{
    if (w->n_table == w->cap_table) {
        size_t cap = w->cap_table ? 2 * w->cap_table : 1024;
        table_entry *t = realloc(w->table, cap * sizeof *t);
        if (!t) return no_memory(w, err);
        w->table = t;
        w->cap_table = cap;
    }
    table_entry *e = &w->table[w->n_table++];
    e->offset = w->end + PACKET_HEADER;
    e->size = size;
    e->count = (int64_t)n;
    e->t0 = ev[0].t;
    e->t1 = ev[n - 1].t;
    w->end += PACKET_HEADER + size;
    return EVR_OK;
}

/* Appends the packet of ev[0 .. n) (checked) through the stream's buffer. */
static evr_status put_packet(aedat_writer *w, const evr_event *ev, size_t n, evr_error *err)
{
    const size_t need = packet_bound(w, n);
    evr_status st = evr_raw_stream_room(&w->s, need, err);
    if (st != EVR_OK) return st;
    size_t c = pack_packet(w, NULL, w->raw, ev, n, w->s.buf + w->s.len, need);
    if (!c) return no_memory(w, err);
    w->s.len += PACKET_HEADER + c;
    return add_entry(w, (uint32_t)c, ev, n, err);
}

/* The end of the packet that starts at ev[a], of millisecond ms: the first event of a later
 * millisecond, at most room events on. A binary search: the events are sorted (where they are
 * not, the checks that follow refuse them). */
static size_t packet_end(const evr_event *ev, size_t a, size_t n, int64_t ms, size_t room)
{
    size_t lo = a, hi = n - a > room ? a + room : n;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (ev[mid].t / PACKET_US > ms) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* Room in w->starts and w->sizes for `need` entries. */
static int reserve_starts(aedat_writer *w, size_t need, evr_error *err)
{
    if (need <= w->cap_starts) return 1;
    size_t cap = w->cap_starts ? 2 * w->cap_starts : 4096;
    while (cap < need) cap *= 2;
    size_t *s = realloc(w->starts, cap * sizeof *s), *z;
    if (s) w->starts = s;
    z = s ? realloc(w->sizes, cap * sizeof *z) : NULL;
    if (!z) {
        no_memory(w, err);
        return 0;
    }
    w->sizes = z;
    w->cap_starts = cap;
    return 1;
}

/* Cuts ev[0 .. n) (n > 0) into packets: w->starts[0 .. np] with starts[np] = n; returns np (0:
 * no memory). With open, ev[0 .. a) (perhaps none) is the first packet: they close the open one. */
static size_t cut_packets(aedat_writer *w, const evr_event *ev, size_t n, size_t a, int open,
                          evr_error *err)
{
    size_t np = 0;
    if (open) {
        if (!reserve_starts(w, 2, err)) return 0;
        w->starts[np++] = 0;
    }
    while (a < n) {
        if (!reserve_starts(w, np + 2, err)) return 0;
        w->starts[np++] = a;
        a = packet_end(ev, a, n, ev[a].t / PACKET_US, PACKET_MAX_EVENTS);
    }
    w->starts[np] = n;
    return np;
}

/* The first packet of list l at or after event `at`. */
static size_t packet_at(const packet_list *l, size_t at)
{
    size_t lo = 0, hi = l->np;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (l->start[mid] < at) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* ---- the parallel parts (io/par_pack.h): each part whole packets ---- */

static size_t cut_part(const void *ctx, const evr_event *ev, size_t n, size_t at)
{
    const packet_list *l = ctx;
    const size_t q = packet_at(l, at);
    (void)ev;
    return q < l->np ? l->start[q] : n;
}

/* Packet q's events (*n of them): in ev, or the open packet's in w->open. */
static const evr_event *packet_events(const packet_list *l, const evr_event *ev, size_t q,
                                      size_t *n)
{
    if (q == 0 && l->first_open) {
        *n = l->first_open;
        return l->w->open;
    }
    *n = l->start[q + 1] - l->start[q];
    return ev + l->start[q];
}

static size_t bound_part(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    const packet_list *l = ctx;
    size_t bytes = 0, n;
    for (size_t q = packet_at(l, a); q < l->np && l->start[q] < b; q++) {
        packet_events(l, ev, q, &n);
        bytes += packet_bound(l->w, n);
    }
    return bytes;
}

static size_t pack_part(const void *ctx, const evr_event *ev, size_t a, size_t b,
                        unsigned char *out, size_t room)
{
    const packet_list *l = ctx;
    const evr_raw_stream *s = &l->w->s;
    pack_slots *z = l->w->slots;
    for (size_t k = a; k < b; k++)
        if (!evr_raw_stream_fits(s, &ev[k]) || (k > 0 && ev[k].t < ev[k - 1].t)) return SIZE_MAX;
    const int i = slot_take(z);
    if (i >= 0 && !z->raw[i]) z->raw[i] = malloc(RAW_BYTES);
    unsigned char *raw = i >= 0 ? z->raw[i] : malloc(RAW_BYTES);
    ZSTD_CCtx *cctx = l->w->compression == EVR_AEDAT4_ZSTD ? slot_cctx(z, i) : NULL;
    size_t bytes = 0;
    for (size_t q = packet_at(l, a); raw && q < l->np && l->start[q] < b; q++) {
        size_t n;
        const evr_event *pe = packet_events(l, ev, q, &n);
        const size_t c = pack_packet(l->w, cctx, raw, pe, n, out + bytes, room - bytes);
        if (!c) {
            bytes = SIZE_MAX;
            break;
        }
        l->size[q] = c;
        bytes += PACKET_HEADER + c;
    }
    if (!raw) bytes = SIZE_MAX;
    if (i < 0) free(raw);
    slot_give(z, i);
    return bytes;
}

/* Writes the closed packets of list l in parallel parts; returns 0 (nothing written) when they
 * go serially. */
static int write_parallel(aedat_writer *w, const packet_list *l, const evr_event *ev,
                          evr_status *st, evr_error *err)
{
    const evr_par_packer parts = {bound_part, pack_part, cut_part, l};
    if (!evr_raw_stream_write_parts(&w->s, &parts, ev, l->start[l->np], st, err)) return 0;
    for (size_t q = 0; q < l->np && *st == EVR_OK; q++) {
        size_t n;
        const evr_event *pe = packet_events(l, ev, q, &n);
        *st = add_entry(w, (uint32_t)w->sizes[q], pe, n, err);
    }
    return 1;
}

/* ---- the file's tail: the open packet and the data table after a flush ---- */

static evr_status set_table_position(aedat_writer *w, int64_t pos, evr_error *err)
{
    unsigned char b[8];
    evr_put_le64(b, (uint64_t)pos);
    if (fflush(w->s.f) != 0 || fseeko(w->s.f, IOHEADER_DTP_AT, SEEK_SET) != 0 ||
        fwrite(b, 1, 8, w->s.f) != 8 || fflush(w->s.f) != 0 || fseeko(w->s.f, 0, SEEK_END) != 0)
        return cannot_write(w, err);
    return EVR_OK;
}

/* Before writing after a flush: no table (-1), and the file ends after the last closed packet. */
static evr_status cut_tail(aedat_writer *w, evr_error *err)
{
    evr_status st;
    if (!w->tail) return EVR_OK;
    if ((st = set_table_position(w, -1, err)) != EVR_OK) return st;
    if (ftruncate(fileno(w->s.f), (off_t)w->end) != 0 || fseeko(w->s.f, 0, SEEK_END) != 0)
        return cannot_write(w, err);
    w->s.parts.claimed = 0; /* the cut freed what was claimed past it */
    w->tail = 0;
    return EVR_OK;
}

/* Writes the open packet and the data table after the closed packets and points the header at
 * the table; with keep_open the open packet stays open (a flush), else it is closed (finish). */
static evr_status write_tail(aedat_writer *w, int keep_open, evr_error *err)
{
    const int64_t end = w->end;
    const size_t n_table = w->n_table;
    evr_status st = cut_tail(w, err);
    if (st == EVR_OK && w->n_open) st = put_packet(w, w->open, w->n_open, err);
    if (st == EVR_OK) st = evr_raw_stream_room(&w->s, w->s.cap, err); /* drained */
    if (st != EVR_OK) return st;
    const size_t len = table_head(w->n_table) + TABLE_ENTRY_BYTES * w->n_table;
    const size_t bound = frame_bound(w, len);
    if (len + bound > w->cap_buf) {
        unsigned char *b = realloc(w->buf, len + bound);
        if (!b) return no_memory(w, err);
        w->buf = b;
        w->cap_buf = len + bound;
    }
    data_table(w->buf, w->table, w->n_table);
    const size_t c = frame(w, NULL, w->buf + len, bound, w->buf, len);
    if (c == 0) return no_memory(w, err);
    if (fwrite(w->buf + len, 1, c, w->s.f) != c) return cannot_write(w, err);
    st = set_table_position(w, w->end, err);
    if (st != EVR_OK) return st;
    if (keep_open) { /* the next write overwrites the open packet's bytes */
        w->end = end;
        w->n_table = n_table;
    } else w->n_open = 0;
    w->tail = 1;
    w->dirty = 0;
    return EVR_OK;
}

/* ---- the interface ---- */

/* Checks ev[0 .. n) one by one (reporting the first the format cannot hold). */
static evr_status check_all(aedat_writer *w, const evr_event *ev, size_t n, evr_error *err)
{
    for (size_t k = 0; k < n; k++) {
        evr_status st = evr_raw_stream_check(&w->s, &ev[k], err);
        if (st != EVR_OK) return st;
    }
    return EVR_OK;
}

static evr_status aedat_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    aedat_writer *w = (aedat_writer *)base;
    size_t i = 0, first_open = 0, np, closed;
    evr_status st;
    if (!n) return EVR_OK;
    if ((st = cut_tail(w, err)) != EVR_OK) return st;
    w->dirty = 1;
    /* the open packet takes the events of its millisecond, as many as it has room for; when the
     * write goes on past them, it is closed and packed with the write's other packets */
    if (w->n_open) {
        i = packet_end(ev, 0, n, w->open[0].t / PACKET_US, PACKET_MAX_EVENTS - w->n_open);
        if (i == n) {
            if ((st = check_all(w, ev, n, err)) != EVR_OK) return st;
            memcpy(w->open + w->n_open, ev, n * sizeof *ev);
            w->n_open += n;
            return EVR_OK;
        }
        /* ev[0 .. i) close it: copied after its events, checked with the write's packets */
        memcpy(w->open + w->n_open, ev, i * sizeof *ev);
        first_open = w->n_open + i;
    }
    /* the packets, the last left open */
    np = cut_packets(w, ev, n, i, first_open > 0, err);
    if (!np) return EVR_ERR_NOMEM;
    closed = w->starts[np - 1];
    const packet_list l = {w, w->starts, np - 1, first_open, w->sizes};
    if (np > 1 && !write_parallel(w, &l, ev, &st, err)) {
        if ((st = check_all(w, ev, closed, err)) != EVR_OK) return st;
        for (size_t q = 0; q + 1 < np && st == EVR_OK; q++) {
            size_t m;
            const evr_event *pe = packet_events(&l, ev, q, &m);
            st = put_packet(w, pe, m, err);
        }
    }
    if (st == EVR_OK) st = check_all(w, ev + closed, n - closed, err);
    if (st != EVR_OK) return st;
    memcpy(w->open, ev + closed, (n - closed) * sizeof *ev);
    w->n_open = n - closed;
    return EVR_OK;
}

static evr_status aedat_flush(evr_event_writer *base, evr_error *err)
{
    aedat_writer *w = (aedat_writer *)base;
    evr_status st = w->dirty || !w->tail ? write_tail(w, 1, err) : EVR_OK;
    if (st == EVR_OK && fflush(w->s.f) != 0) st = cannot_write(w, err);
    return st;
}

static void free_writer(aedat_writer *w)
{
    free(w->open);
    free(w->raw);
    free(w->table);
    free(w->starts);
    free(w->sizes);
    free(w->buf);
    pack_slots_free(w->slots);
    w->slots = NULL;
}

static evr_status aedat_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    aedat_writer *w = (aedat_writer *)base;
    /* after a flush with nothing written since, the file is already complete */
    evr_status st = w->dirty || !w->tail ? write_tail(w, 0, err) : EVR_OK;
    free_writer(w);
    if (st != EVR_OK) {
        w->raw_abort(base);
        return st;
    }
    return w->raw_finish(base, duration_us, err);
}

static void aedat_abort(evr_event_writer *base)
{
    aedat_writer *w = (aedat_writer *)base;
    free_writer(w);
    w->raw_abort(base);
}

static evr_status aedat_open(const char *path, const evr_writer_meta *meta, int compression,
                             evr_event_writer **out, evr_error *err)
{
    size_t len = 0;
    unsigned char *head = io_header(meta->width, meta->height, compression, &len);
    evr_status st;
    *out = NULL;
    if (!head) {
        snprintf(err->msg, sizeof err->msg, "aedat4 writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    st = evr_raw_writer_open(sizeof(aedat_writer), path, "aedat4 writer", EVR_AEDAT4_MAX_XY,
                             INT64_MAX, (const char *)head, len, aedat_write, out, err);
    free(head);
    if (st != EVR_OK) return st;
    aedat_writer *w = (aedat_writer *)*out;
    w->raw_finish = w->s.base.finish;
    w->raw_abort = w->s.base.abort;
    w->s.base.flush = aedat_flush;
    w->s.base.finish = aedat_finish;
    w->s.base.abort = aedat_abort;
    w->compression = compression;
    memset(&w->lz4, 0, sizeof w->lz4); /* LZ4's defaults: fast, 64 KB linked blocks */
    w->s.parts.threads = COMPRESS_THREADS;
    w->s.parts.claim_room = 1;
    w->end = (int64_t)len;
    w->open = malloc(PACKET_MAX_EVENTS * sizeof *w->open);
    w->raw = malloc(RAW_BYTES);
    w->slots = calloc(1, sizeof *w->slots);
    if (!w->open || !w->raw || !w->slots) {
        aedat_abort(*out);
        *out = NULL;
        snprintf(err->msg, sizeof err->msg, "aedat4 writer: out of memory");
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

evr_status evr_aedat4_writer_open(const char *path, const evr_writer_meta *meta,
                                  evr_event_writer **out, evr_error *err)
{
    return aedat_open(path, meta, EVR_AEDAT4_LZ4, out, err);
}

evr_status evr_aedat4_zstd_writer_open(const char *path, const evr_writer_meta *meta,
                                       evr_event_writer **out, evr_error *err)
{
    return aedat_open(path, meta, EVR_AEDAT4_ZSTD, out, err);
}

const evr_event_format evr_format_aedat4 = {
    "aedat4",
    NULL,
    "events.aedat4",
    evr_aedat4_writer_open,
    "iniVation AEDAT 4.0, LZ4 packets with a data table (DV, dv-processing, aedat)",
    ".aedat4",
    0};

const evr_event_format evr_format_aedat4_zstd = {
    "aedat4-zstd",
    NULL,
    "events_zstd.aedat4",
    evr_aedat4_zstd_writer_open,
    "iniVation AEDAT 4.0, ZSTD packets (smaller, slower to write)",
    "zstd.aedat4",
    0};
