/* A large write of events packed in parts on a pool of threads and written at its place in the
 * file (pwrite): one thread packing and copying gigabytes into the page cache kept the GPU run
 * waiting on its writer. With four threads or more, the calling thread writes the parts in order
 * while the others pack the later ones (writes to one file go one at a time in the kernel). The
 * format gives two functions over a part's events: measure (checks them and counts their bytes)
 * and pack; a prefix sum of the measures places each part, so formats whose records vary in size
 * (EVT 2.0's time-high words) are packed in parts too. A format whose packing outlasts its
 * writes (compression, text) has one of the pool's threads claim the parts' room in the file
 * while the others pack (io/file_room.h): the writes then only copy into claimed pages, not
 * allocate them (on tmpfs, where the page cache is the file, the larger part of a write); where the
 * writes are the bottleneck (NPY), the claim only held the file's lock longer. */
#ifndef EVR_IO_PAR_PACK_H
#define EVR_IO_PAR_PACK_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "evray.h"
#include "par_pool.h"

/* A write of this many events or more goes in parts; below it threads cost more than they save. */
#define EVR_PAR_PACK_MIN ((size_t)1 << 15)

typedef struct {
    /* At least the bytes ev[a .. b) can take, found cheaply (the events may be bad: see pack). */
    size_t (*bound)(const void *ctx, const evr_event *ev, size_t a, size_t b);
    /* Checks ev[a .. b) (each against the event before it when there is one; ev[0] against
     * what was written before is the caller's) and packs them at out, within the bound; returns
     * the bytes written, or SIZE_MAX when one of them cannot be written (or would pass the
     * bound): the serial path then reports the first bad event. The events before a are there
     * to read, for the state a part starts in. */
    size_t (*pack)(const void *ctx, const evr_event *ev, size_t a, size_t b, unsigned char *out,
                   size_t room);
    /* NULL, or the first index at or after `at` where a part may begin (n: none), for formats
     * whose words span several events: parts are cut there. */
    size_t (*cut)(const void *ctx, const evr_event *ev, size_t n, size_t at);
    const void *ctx;
} evr_par_packer;

/* What a writer keeps between large writes: the pool (started at the first) and the bytes. */
typedef struct {
    evr_par_pool *pool;
    unsigned char *big;
    size_t cap;
    int threads;    /* the pool's threads at most (0: 4); formats that compress ask for more */
    int claim_room; /* claim the parts' room while they are packed (set by the format) */
    /* the file's bytes before this offset are claimed; a writer that cuts its file shorter sets
     * it to 0, the cut having freed what was claimed past it */
    uint64_t claimed;
} evr_par_packing;

typedef enum {
    EVR_PAR_PACK_SERIAL, /* nothing written: an event cannot be written, or no memory */
    EVR_PAR_PACK_DONE,   /* every event written at the end of the file */
    EVR_PAR_PACK_FAILED  /* a write to the file failed (errno says why) */
} evr_par_pack_result;

/* Packs ev[0 .. n) with p and writes them at the end of f (flushed first; the stream goes on
 * after them); *bytes: how many were written. */
evr_par_pack_result evr_par_pack_write(evr_par_packing *pk, const evr_par_packer *p,
                                       const evr_event *ev, size_t n, FILE *f, size_t *bytes);

/* Stops the pool and frees the bytes (a zeroed packing is fine). */
void evr_par_packing_free(evr_par_packing *pk);

#endif
