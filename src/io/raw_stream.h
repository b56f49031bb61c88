/* The part every binary event stream writer shares (Prophesee EVT 2.0, EVT 3.0, DAT): a file
 * under its temporary name with a byte buffer in front, the checks of each event against what the
 * format can hold, and the header lines Prophesee's tools read ("% key value", ending "% end"). */
#ifndef EVR_IO_RAW_STREAM_H
#define EVR_IO_RAW_STREAM_H

#include <stdint.h>
#include <stdio.h>
#include "evray.h"
#include "io/byte_order.h"
#include "io/event_writer.h"
#include "io/par_pack.h"

/* The first member of each such writer: the interface, then the stream. */
typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    const char *who;       /* the writer, in messages */
    char *path, *tmp;
    FILE *f;
    unsigned char *buf;
    size_t len, cap;
    int64_t last_t;
    int have_last;
    int max_xy;            /* x and y must stay below it */
    int64_t max_t;         /* t must not pass it */
    evr_par_packing parts; /* large writes, packed in parts */
    /* the format's write(), which the stream's wraps to count (salvage): events it took, bytes
     * handed to stdio (the stream is `handed + len` bytes long), and both as the last write()
     * began */
    evr_status (*write_fn)(evr_event_writer *w, const evr_event *ev, size_t n, evr_error *err);
    uint64_t count, handed, prev_count, prev_bytes;
} evr_raw_stream;

/* Allocates a writer of size bytes (a struct whose first member is an evr_raw_stream, the rest
 * zeroed), creates path + ".tmp" holding header (len bytes), and gives it write and the stream's
 * flush, finish, abort and salvage (a stream of appends: a format that seeks has its own). */
evr_status evr_raw_writer_open(size_t size, const char *path, const char *who, int max_xy,
                               int64_t max_t, const char *header, size_t len,
                               evr_status (*write)(evr_event_writer *w, const evr_event *ev,
                                                   size_t n, evr_error *err),
                               evr_event_writer **out, evr_error *err);
/* Refuses an event out of time order, or one the format cannot hold, with one clear line. */
evr_status evr_raw_stream_check(evr_raw_stream *s, const evr_event *e, evr_error *err);
/* Whether the format can hold e (its pixel and timestamp; the order is checked apart). */
static inline int evr_raw_stream_fits(const evr_raw_stream *s, const evr_event *e)
{
    return e->x < s->max_xy && e->y < s->max_xy && e->t >= 0 && e->t <= s->max_t;
}
/* Writes a large batch ev[0 .. n) with p in parallel parts after what is buffered; returns 0,
 * nothing written, when the batch is small or an event cannot be written (the serial path then
 * writes them or reports the first bad one), else 1 with *st how it went. */
int evr_raw_stream_write_parts(evr_raw_stream *s, const evr_par_packer *p, const evr_event *ev,
                               size_t n, evr_status *st, evr_error *err);
/* Room for at least need more bytes at s->buf + s->len (writing out what is buffered). */
evr_status evr_raw_stream_room(evr_raw_stream *s, size_t need, evr_error *err);
/* Prophesee's header lines for a width x height sensor: for RAW files evt is "2.0" or "3.0" and
 * format "EVT2" or "EVT3"; for DAT files evt is NULL. Returns the length (0: no room). */
size_t evr_prophesee_header(char *out, size_t cap, const char *evt, const char *format, int width,
                            int height);

#endif
