#include "io/par_pack.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>
#include "io/file_room.h"
#include "io/par_order.h"
#include "io/write_at.h"

#define PAR_PACK_THREADS 4
#define PAR_PACK_PARTS 16
/* Pipelined (pack_and_write) with a pool of this many threads or more: one of them then only
 * writes, which a pool of two or three misses more than the overlap gains. Then more parts than
 * threads, so that the first parts are written while later ones are packed. */
#define PIPELINE_MIN_THREADS 4
#define PIPELINE_PARTS EVR_PAR_ORDER_MAX

/* A large write's claim of room in its file (io/file_room.h): the first task of its pool job
 * claims [from, to) while the others pack; none when from == to. */
typedef struct {
    int fd;
    uint64_t from, to;
} par_claim;

/* The claim of a write to fd whose bytes end at `end`, from `at` or from where pk's earlier
 * writes claimed to, whichever is later (none unless pk->claim_room); recorded in pk. */
static par_claim claim_plan(evr_par_packing *pk, int fd, uint64_t at, uint64_t end)
{
    par_claim c = {fd, at > pk->claimed ? at : pk->claimed, 0};
    c.to = pk->claim_room && end > c.from ? end : c.from;
    if (c.to > c.from) pk->claimed = c.to;
    return c;
}

/* Tasks the claim adds to its job: 0 or 1. */
static int claim_tasks(const par_claim *c) { return c->to > c->from; }

/* For task *k of a job that starts with claim c's task: claims the room and returns 1 for that
 * task (no room is no error there: the writes then fail and say why); otherwise returns 0 with
 * *k the part the task packs. */
static int claim_task(const par_claim *c, int *k)
{
    if (!claim_tasks(c)) return 0;
    if (*k == 0) {
        evr_file_claim(c->fd, c->from, c->to - c->from);
        return 1;
    }
    --*k; /* task k packs part k - 1 */
    return 0;
}

typedef struct {
    const evr_par_packer *p;
    const evr_event *ev;
    unsigned char *big;
    int fd;
    off_t at;                         /* file offset of ev[0]'s bytes */
    int pass;                         /* 0: pack, 1: write (pack_then_write) */
    int pipelined;                    /* pack_and_write: parts are written as they are packed */
    int parts;                        /* PAR_PACK_PARTS, or PIPELINE_PARTS pipelined */
    par_claim claim;                  /* task 0 claims the parts' room when there is one */
    size_t first[PIPELINE_PARTS + 1]; /* part k: events [first[k], first[k + 1]) */
    size_t room[PIPELINE_PARTS];      /* its bound */
    size_t boff[PIPELINE_PARTS];      /* where its room starts in big */
    size_t size[PIPELINE_PARTS];      /* its bytes packed */
    size_t off[PIPELINE_PARTS];       /* their place after at */
    int bad[PIPELINE_PARTS];          /* a failed write: its errno (a pool thread's own) */
    evr_par_order packed;             /* pipelined (pack_and_write): the parts packed */
} pack_job;

static void pack_part(void *ctx, int k, int thread)
{
    pack_job *j = ctx;
    (void)thread;
    if (j->pass == 0 && claim_task(&j->claim, &k)) return;
    const size_t a = j->first[k], b = j->first[k + 1];
    if (j->pass == 0) {
        if (a < b) j->size[k] = j->p->pack(j->p->ctx, j->ev, a, b, j->big + j->boff[k], j->room[k]);
        if (j->pipelined) evr_par_order_done(&j->packed, k); /* the writing thread waits */
    } else if (a < b && !evr_write_at(j->fd, j->big + j->boff[k], j->size[k],
                                      (uint64_t)(j->at + (off_t)j->off[k]))) {
        j->bad[k] = errno ? errno : EIO;
    }
}

/* Packs the parts on the pool's threads while this one writes them in order, each as soon as it
 * is packed: writes to one file go one at a time in the kernel (its inode lock), so the text
 * writer's 15 GB took the packing's time plus the writing's when one followed the other. Returns
 * as evr_par_pack_write; on EVR_PAR_PACK_SERIAL the file is cut back to where it was. */
static evr_par_pack_result pack_and_write(evr_par_pool *pool, pack_job *j, size_t *bytes)
{
    size_t total = 0;
    int serial = 0, failed = 0;
    if (evr_par_order_init(&j->packed) != 0) return EVR_PAR_PACK_SERIAL;
    evr_par_pool_start(pool, j->parts + claim_tasks(&j->claim), pack_part, j);
    for (int k = 0; k < j->parts; k++) {
        /* the pool's threads take every part, in order: part k comes */
        evr_par_order_wait(&j->packed, k);
        if (serial || failed) continue;
        if (j->size[k] == SIZE_MAX) serial = 1;
        else if (j->size[k] && !evr_write_at(j->fd, j->big + j->boff[k], j->size[k],
                                             (uint64_t)(j->at + (off_t)total)))
            failed = errno ? errno : EIO;
        else total += j->size[k];
    }
    evr_par_pool_wait(pool);
    evr_par_order_destroy(&j->packed);
    if (failed) {
        errno = failed; /* the caller's message says why */
        return EVR_PAR_PACK_FAILED;
    }
    if (serial)
        return total && ftruncate(j->fd, j->at) != 0 ? EVR_PAR_PACK_FAILED : EVR_PAR_PACK_SERIAL;
    *bytes = total;
    return EVR_PAR_PACK_DONE;
}

/* Packs every part on the pool, then writes them all at their places, each part on a thread.
 * Returns as evr_par_pack_write; nothing is written when a part cannot be packed. */
static evr_par_pack_result pack_then_write(evr_par_pool *pool, pack_job *j, size_t *bytes)
{
    size_t total = 0;
    evr_par_pool_run(pool, j->parts + claim_tasks(&j->claim), pack_part, j);
    for (int k = 0; k < j->parts; k++) {
        if (j->size[k] == SIZE_MAX) return EVR_PAR_PACK_SERIAL;
        j->off[k] = total;
        total += j->size[k];
    }
    j->pass = 1;
    evr_par_pool_run(pool, j->parts, pack_part, j);
    for (int k = 0; k < j->parts; k++)
        if (j->bad[k]) {
            errno = j->bad[k]; /* a pool thread's: the caller's message says why */
            return EVR_PAR_PACK_FAILED;
        }
    *bytes = total;
    return EVR_PAR_PACK_DONE;
}

evr_par_pack_result evr_par_pack_write(evr_par_packing *pk, const evr_par_packer *p,
                                       const evr_event *ev, size_t n, FILE *f, size_t *bytes)
{
    pack_job j;
    size_t room = 0;
    evr_par_pack_result r;
    *bytes = 0;
    if (!pk->pool)
        pk->pool =
            evr_par_pool_new(evr_par_threads(pk->threads > 0 ? pk->threads : PAR_PACK_THREADS));
    if (!pk->pool) return EVR_PAR_PACK_SERIAL; /* the serial path needs no threads */
    memset(&j, 0, sizeof j);
    j.pipelined = evr_par_pool_threads(pk->pool) >= PIPELINE_MIN_THREADS;
    j.parts = j.pipelined ? PIPELINE_PARTS : PAR_PACK_PARTS;
    j.p = p;
    j.ev = ev;
    /* the parts and their room, on the caller: cuts and bounds are quick */
    for (int k = 1; k < j.parts; k++) {
        size_t a, b;
        evr_par_share(n, j.parts, k, &a, &b);
        j.first[k] = p->cut ? p->cut(p->ctx, ev, n, a) : a; /* cuts keep the order */
    }
    j.first[j.parts] = n;
    for (int k = 0; k < j.parts; k++) {
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
    if (fflush(f) != 0) return EVR_PAR_PACK_FAILED;
    j.fd = fileno(f);
    j.at = ftello(f);
    if (j.at < 0) return EVR_PAR_PACK_FAILED;
    j.claim = claim_plan(pk, j.fd, (uint64_t)j.at, (uint64_t)j.at + room);
    r = j.pipelined ? pack_and_write(pk->pool, &j, bytes) : pack_then_write(pk->pool, &j, bytes);
    if (r == EVR_PAR_PACK_SERIAL) pk->claimed = 0; /* the file may have been cut back */
    /* the stream goes on after the bytes written past it */
    if (r == EVR_PAR_PACK_DONE && fseeko(f, 0, SEEK_END) != 0) return EVR_PAR_PACK_FAILED;
    return r;
}

void evr_par_packing_free(evr_par_packing *pk)
{
    evr_par_pool_free(pk->pool);
    free(pk->big);
    pk->pool = NULL;
    pk->big = NULL;
    pk->cap = 0;
}
