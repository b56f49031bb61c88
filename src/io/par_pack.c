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
    size_t n;
    unsigned char *big;
    int fd;
    off_t at;                    /* file offset of ev[0]'s bytes */
    int pass;                    /* 0: measure, 1: pack and write */
    size_t first[PAR_PACK_PARTS + 1]; /* part k: events [first[k], first[k + 1]) (cuts move
                                         both ends alike, so the parts tile the events) */
    size_t size[PAR_PACK_PARTS];      /* each part's bytes */
    size_t off[PAR_PACK_PARTS];  /* and where they start, in big and after at */
    int bad[PAR_PACK_PARTS];     /* a failed write */
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
    size_t a, b;
    (void)thread;
    if (j->pass == 0) {
        evr_par_share(j->n, PAR_PACK_PARTS, k, &a, &b);
        if (j->p->cut && k > 0) a = j->p->cut(j->p->ctx, j->ev, j->n, a);
        if (j->p->cut && b < j->n) b = j->p->cut(j->p->ctx, j->ev, j->n, b);
        j->first[k] = a;
        j->size[k] = a < b ? j->p->measure(j->p->ctx, j->ev, a, b) : 0;
        return;
    }
    a = j->first[k];
    b = j->first[k + 1];
    if (a >= b) return;
    j->p->pack(j->p->ctx, j->ev, a, b, j->big + j->off[k]);
    if (!write_at(j->fd, j->big + j->off[k], j->size[k], j->at + (off_t)j->off[k])) j->bad[k] = 1;
}

evr_par_pack_result evr_par_pack_write(evr_par_packing *pk, const evr_par_packer *p,
                                       const evr_event *ev, size_t n, FILE *f, size_t *bytes)
{
    pack_job j;
    size_t total = 0;
    *bytes = 0;
    if (!pk->pool) pk->pool = evr_par_pool_new(evr_par_threads(PAR_PACK_THREADS));
    if (!pk->pool) return EVR_PAR_PACK_SERIAL; /* the serial path needs no threads */
    memset(&j, 0, sizeof j);
    j.p = p;
    j.ev = ev;
    j.n = n;
    evr_par_pool_run(pk->pool, PAR_PACK_PARTS, pack_part, &j);
    j.first[PAR_PACK_PARTS] = n;
    for (int k = 0; k < PAR_PACK_PARTS; k++) {
        if (j.size[k] == SIZE_MAX) return EVR_PAR_PACK_SERIAL;
        j.off[k] = total;
        total += j.size[k];
    }
    if (total > pk->cap) {
        unsigned char *big = realloc(pk->big, total);
        if (!big) return EVR_PAR_PACK_SERIAL; /* the serial path needs no room */
        pk->big = big;
        pk->cap = total;
    }
    if (fflush(f) != 0) return EVR_PAR_PACK_FAILED;
    j.big = pk->big;
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
