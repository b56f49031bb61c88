#include "io/par_pack.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#define PAR_PACK_THREADS 4
#define PAR_PACK_PARTS 16

typedef struct {
    const evr_par_packer *p;
    const evr_event *ev;
    unsigned char *big;
    int fd;
    off_t at;                         /* file offset of ev[0]'s bytes */
    int pass;                         /* 0: pack, 1: write */
    size_t first[PAR_PACK_PARTS + 1]; /* part k: events [first[k], first[k + 1]) */
    size_t room[PAR_PACK_PARTS];      /* its bound */
    size_t boff[PAR_PACK_PARTS];      /* where its room starts in big */
    size_t size[PAR_PACK_PARTS];      /* its bytes packed */
    size_t off[PAR_PACK_PARTS];       /* their place after at */
    int bad[PAR_PACK_PARTS];          /* a failed write */
} pack_job;

/* Writes len bytes at the file offset at. */
static int write_at(int fd, const unsigned char *src, size_t len, off_t at)
{
    while (len > 0) {
        const ssize_t wrote = pwrite(fd, src, len, at);
        if (wrote <= 0) {
            if (wrote < 0 && errno == EINTR) continue;
            return 0;
        }
        src += wrote;
        len -= (size_t)wrote;
        at += wrote;
    }
    return 1;
}

static void pack_part(void *ctx, int k, int thread)
{
    pack_job *j = ctx;
    const size_t a = j->first[k], b = j->first[k + 1];
    (void)thread;
    if (a >= b) return;
    if (j->pass == 0)
        j->size[k] = j->p->pack(j->p->ctx, j->ev, a, b, j->big + j->boff[k], j->room[k]);
    else if (!write_at(j->fd, j->big + j->boff[k], j->size[k], j->at + (off_t)j->off[k]))
        j->bad[k] = 1;
}

evr_par_pack_result evr_par_pack_write(evr_par_packing *pk, const evr_par_packer *p,
                                       const evr_event *ev, size_t n, FILE *f, size_t *bytes)
{
    pack_job j;
    size_t room = 0, total = 0;
    *bytes = 0;
    if (!pk->pool)
        pk->pool =
            evr_par_pool_new(evr_par_threads(pk->threads > 0 ? pk->threads : PAR_PACK_THREADS));
    if (!pk->pool) return EVR_PAR_PACK_SERIAL; /* the serial path needs no threads */
    memset(&j, 0, sizeof j);
    j.p = p;
    j.ev = ev;
    /* the parts and their room, on the caller: cuts and bounds are quick */
    for (int k = 1; k < PAR_PACK_PARTS; k++) {
        size_t a, b;
        evr_par_share(n, PAR_PACK_PARTS, k, &a, &b);
        j.first[k] = p->cut ? p->cut(p->ctx, ev, n, a) : a; /* cuts keep the order */
    }
    j.first[PAR_PACK_PARTS] = n;
    for (int k = 0; k < PAR_PACK_PARTS; k++) {
        j.boff[k] = room;
        if (j.first[k] < j.first[k + 1])
            j.room[k] = p->bound(p->ctx, ev, j.first[k], j.first[k + 1]);
        if (j.room[k] > SIZE_MAX / 2 - room) return EVR_PAR_PACK_SERIAL;
        room += j.room[k];
    }
    if (room > pk->cap) {
        unsigned char *big = realloc(pk->big, room);
        if (!big) return EVR_PAR_PACK_SERIAL; /* the serial path needs no room */
        pk->big = big;
        pk->cap = room;
    }
    j.big = pk->big;
    evr_par_pool_run(pk->pool, PAR_PACK_PARTS, pack_part, &j);
    for (int k = 0; k < PAR_PACK_PARTS; k++) {
        if (j.size[k] == SIZE_MAX) return EVR_PAR_PACK_SERIAL;
        j.off[k] = total;
        total += j.size[k];
    }
    if (fflush(f) != 0) return EVR_PAR_PACK_FAILED;
    j.fd = fileno(f);
    j.at = ftello(f);
    if (j.at < 0) return EVR_PAR_PACK_FAILED;
    j.pass = 1;
    evr_par_pool_run(pk->pool, PAR_PACK_PARTS, pack_part, &j);
    for (int k = 0; k < PAR_PACK_PARTS; k++)
        if (j.bad[k]) return EVR_PAR_PACK_FAILED;
    /* the stream goes on after the bytes written past it */
    if (fseeko(f, 0, SEEK_END) != 0) return EVR_PAR_PACK_FAILED;
    *bytes = total;
    return EVR_PAR_PACK_DONE;
}

void evr_par_packing_free(evr_par_packing *pk)
{
    evr_par_pool_free(pk->pool);
    free(pk->big);
    pk->pool = NULL;
    pk->big = NULL;
    pk->cap = 0;
}
