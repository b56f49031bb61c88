#include "run/write_queue.h"
#include "host_clock.h"
#include "events.h"
#include "par_pool.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Batches that may wait, and the bytes of their buffers at most (a larger batch waits alone),
 * buffers kept for reuse included: enough to ride out the eye's bursts (eight whole segments
 * took the main thread's wait for the writer from 0.6-0.75 to 0.01 s of a 4.4-4.9 s run on the
 * H100, against two; a GPU run's pieces of up to 16 MB need the bytes), and a bound on the memory
 * a burst takes however many events it makes. */
#define QUEUE_SLOTS 32
#define QUEUE_BYTES ((size_t)96 << 20)

struct evr_write_queue {
    evr_event_writer *writers[EVR_WRITE_QUEUE_MAX_WRITERS];
    int num_writers;
    evr_par_pool *pool; /* threads for the writers at once (NULL: one writer) */
    double flush_seconds;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv; /* on CLOCK_MONOTONIC, the host clock, for the timed flush */
    evr_event_vec slots[QUEUE_SLOTS];
    /* Written batches' buffers, the last one written on top: push takes the top one for the
     * events it holds back. With buffers kept per slot, all eight came round in turn and each
     * grew to the largest batch it ever held, so a run's memory crept up with its bursts (a 160x90
     * eye: 77.7 MB at 1 s, 84.3 MB at 15 s); from the top of a stack, only as many buffers as
     * batches wait at once are ever used. */
    evr_event_vec spare[QUEUE_SLOTS];
    int nspare;
    /* A buffer's bytes in memory: the most events it has held (its pages touched; its capacity
     * may be twice that, untouched), for the slots, the spares and the buffer push gave out
     * last, which the caller fills and pushes next. The queue's bound counts these. */
    size_t slot_bytes[QUEUE_SLOTS], spare_held[QUEUE_SLOTS], out_bytes;
    size_t spare_bytes;  /* the spares' */
    int head, count;     /* pending batches: slots[head], slots[head + 1], ... */
    size_t queued_bytes; /* the pending batches' (the one being written too) */
    size_t max_bytes;    /* QUEUE_BYTES, or the hidden EVR_QUEUE_BYTES (for measuring) */
    int busy;            /* the thread is writing the batch at head, or flushing */
    int dirty;           /* batches written since the last flush */
    double last_flush;   /* host seconds */
    int stop;
    int flush_now;                              /* a flush asked for by evr_write_queue_flush */
    uint64_t accepted_events, accepted_batches; /* taken by every writer's write() */
    evr_status status;                          /* first error of the writer thread */
    evr_error err;
    double busy_seconds, wait_seconds;
};

/* One batch (or one flush) for every writer at once. */
typedef struct {
    evr_write_queue *q;
    const evr_event_vec *v; /* NULL: flush */
    evr_status st[EVR_WRITE_QUEUE_MAX_WRITERS];
    evr_error err[EVR_WRITE_QUEUE_MAX_WRITERS];
} writers_job;

static void run_writer(writers_job *j, int w)
{
    evr_event_writer *wr = j->q->writers[w];
    j->err[w].msg[0] = 0;
    j->st[w] = j->v ? wr->write(wr, j->v->data, j->v->n, &j->err[w]) : wr->flush(wr, &j->err[w]);
}

static void pool_writer(void *ctx, int k, int thread)
{
    (void)thread;
    run_writer(ctx, k);
}

/* Hands batch v (NULL: a flush) to every writer at the same time, on the pool's threads and this
 * one, so that several formats take about the slowest one's time, not their sum (the 30 s eye's
 * `--format all` on the H100 took 17 s with the writers in turn). The first failure, in writer
 * order, is the result. */
static evr_status each_writer(evr_write_queue *q, const evr_event_vec *v, evr_error *err)
{
    writers_job j;
    int w;
    j.q = q;
    j.v = v;
    if (q->num_writers == 0) return EVR_OK;
    if (q->num_writers > 1 && q->pool) {
        evr_par_pool_run(q->pool, q->num_writers, pool_writer, &j);
    } else {
        for (w = 0; w < q->num_writers; w++) run_writer(&j, w);
    }
    for (w = 0; w < q->num_writers; w++)
        if (j.st[w] != EVR_OK) {
            *err = j.err[w];
            return j.st[w];
        }
    return EVR_OK;
}

/* Writes batch v (NULL: none) to every writer (*taken: every one took it), then flushes them
 * all when flush is set; on the writer thread, without the lock. A batch a writer failed to
 * take is not accepted (salvage keeps the events before it, and the writers that took it keep
 * or drop it as their salvage says); a failed flush leaves it accepted. */
static evr_status write_batch(evr_write_queue *q, const evr_event_vec *v, int flush, int *taken,
                              evr_error *err)
{
    evr_status st = v ? each_writer(q, v, err) : EVR_OK;
    *taken = v && st == EVR_OK;
    if (flush && st == EVR_OK) st = each_writer(q, NULL, err);
    return st;
}

/* Runs write_batch with the lock released (held on entry and on return) and accounts for it. */
static void run_batch(evr_write_queue *q, const evr_event_vec *v, int flush)
{
    int failed = q->status != EVR_OK, taken = 0;
    evr_status st = EVR_OK;
    evr_error err;
    q->busy = 1;
    pthread_mutex_unlock(&q->mu);
    err.msg[0] = 0;
    double t = evr_host_seconds();
    if (!failed) st = write_batch(q, v, flush, &taken, &err);
    double t1 = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    q->busy_seconds += t1 - t;
    if (taken) {
        q->accepted_events += v->n;
        q->accepted_batches++;
    }
    if (flush) {
        q->dirty = 0;
        q->last_flush = t1;
    }
    if (st != EVR_OK && q->status == EVR_OK) {
        q->status = st;
        q->err = err;
    }
    q->busy = 0;
}

static struct timespec host_deadline(double seconds)
{
    struct timespec ts;
    ts.tv_sec = (time_t)seconds;
    ts.tv_nsec = (long)((seconds - (double)ts.tv_sec) * 1e9);
    if (ts.tv_nsec > 999999999L) ts.tv_nsec = 999999999L;
    return ts;
}

static void *writer_main(void *arg)
{
    evr_write_queue *q = (evr_write_queue *)arg;
    pthread_mutex_lock(&q->mu);
    for (;;) {
        while (!q->count && !q->stop && !q->flush_now) {
            double due = q->last_flush + q->flush_seconds;
            if (!q->dirty) {
                pthread_cond_wait(&q->cv, &q->mu);
            } else if (evr_host_seconds() >= due) {
                run_batch(q, NULL, 1); /* idle since a batch: make it durable now */
                pthread_cond_broadcast(&q->cv);
            } else {
                struct timespec ts = host_deadline(due);
                pthread_cond_timedwait(&q->cv, &q->mu, &ts);
            }
        }
        if (!q->count && q->flush_now) {
            run_batch(q, NULL, 1);
            q->flush_now = 0;
            pthread_cond_broadcast(&q->cv);
            continue;
        }
        if (!q->count) break; /* stop requested and nothing pending */
        evr_event_vec *v = &q->slots[q->head];
        q->dirty = 1;
        run_batch(q, v, evr_host_seconds() >= q->last_flush + q->flush_seconds);
        const size_t bytes = q->slot_bytes[q->head];
        evr_event_vec drop = {0};
        q->queued_bytes -= bytes;
        v->n = 0;
        /* kept for reuse while the spares and the queue stay within the queue's bound: else the
         * buffers a burst grew all stayed, and a long run's memory crept up with its bursts */
        if (q->queued_bytes + q->spare_bytes + bytes <= q->max_bytes) {
            q->spare_held[q->nspare] = bytes;
            q->spare[q->nspare++] = *v; /* at most one per slot */
            q->spare_bytes += bytes;
        } else drop = *v;
        v->data = NULL;
        v->cap = 0;
        q->head = (q->head + 1) % QUEUE_SLOTS;
        q->count--;
        pthread_cond_broadcast(&q->cv);
        if (drop.data) {
            pthread_mutex_unlock(&q->mu);
            evr_event_vec_free(&drop);
            pthread_mutex_lock(&q->mu);
        }
    }
    pthread_mutex_unlock(&q->mu);
    return NULL;
}

evr_status evr_write_queue_start(evr_event_writer *const *writers, int num_writers,
                                 double flush_seconds, evr_write_queue **out, evr_error *err)
{
    evr_write_queue *q = calloc(1, sizeof *q);
    pthread_condattr_t ca;
    int i, ok;
    if (!q || num_writers > EVR_WRITE_QUEUE_MAX_WRITERS) {
        free(q);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (i = 0; i < num_writers; i++) q->writers[i] = writers[i];
    q->num_writers = num_writers;
    /* the writers at once (no pool, when it cannot be made: in turn) */
    if (num_writers > 1) q->pool = evr_par_pool_new(num_writers);
    q->flush_seconds = flush_seconds;
    q->max_bytes = QUEUE_BYTES;
    const char *mb = getenv("EVR_QUEUE_BYTES");
    const unsigned long long want = mb ? strtoull(mb, NULL, 10) : 0;
    if (want > 0) q->max_bytes = (size_t)want;
    q->last_flush = evr_host_seconds(); /* the writers' files are valid when opened */
    q->status = EVR_OK;
    pthread_mutex_init(&q->mu, NULL);
    ok = pthread_condattr_init(&ca) == 0;
    if (ok) {
        ok = pthread_condattr_setclock(&ca, CLOCK_MONOTONIC) == 0 &&
             pthread_cond_init(&q->cv, &ca) == 0;
        pthread_condattr_destroy(&ca);
    }
    if (ok && pthread_create(&q->thread, NULL, writer_main, q) != 0) {
        pthread_cond_destroy(&q->cv);
        ok = 0;
    }
    if (!ok) {
        pthread_mutex_destroy(&q->mu);
        evr_par_pool_free(q->pool);
        free(q);
        snprintf(err->msg, sizeof err->msg, "cannot start the writer thread");
        return EVR_ERR_IO;
    }
    *out = q;
    return EVR_OK;
}

evr_status evr_write_queue_add(evr_write_queue *q, evr_event_writer *w, evr_error *err)
{
    pthread_mutex_lock(&q->mu);
    /* before the first push: the thread touches the writers only for a batch or after one */
    int ok = q->num_writers < EVR_WRITE_QUEUE_MAX_WRITERS && !q->accepted_batches && !q->count &&
             !q->busy && !q->dirty;
    if (ok) q->writers[q->num_writers++] = w;
    pthread_mutex_unlock(&q->mu);
    if (!ok) {
        snprintf(err->msg, sizeof err->msg,
                 "a writer can only be added to the write queue before the run starts");
        return EVR_ERR_ARG;
    }
    return EVR_OK;
}

evr_status evr_write_queue_push_take(evr_write_queue *q, evr_event_vec *v, size_t n, evr_error *err)
{
    double t = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    /* v's buffer is the one given out last (or one of the caller's own): its pages touched */
    size_t bytes = v->n * sizeof(evr_event);
    if (bytes < q->out_bytes) bytes = q->out_bytes;
    if (bytes > v->cap * sizeof(evr_event)) bytes = v->cap * sizeof(evr_event);
    while ((q->count == QUEUE_SLOTS || (q->count > 0 && q->queued_bytes + bytes > q->max_bytes)) &&
           q->status == EVR_OK)
        pthread_cond_wait(&q->cv, &q->mu);
    q->wait_seconds += evr_host_seconds() - t;
    if (q->status != EVR_OK) {
        *err = q->err;
        evr_status st = q->status;
        pthread_mutex_unlock(&q->mu);
        return st;
    }
    const int at = (q->head + q->count) % QUEUE_SLOTS;
    evr_event_vec *slot = &q->slots[at];
    evr_event_vec rest = {0};
    size_t rest_bytes = 0;
    if (q->nspare) { /* the last written: warm, and large enough */
        rest = q->spare[--q->nspare];
        rest_bytes = q->spare_held[q->nspare];
        q->spare_bytes -= rest_bytes;
    }
    pthread_mutex_unlock(&q->mu);
    /* this slot is not pending, so the thread does not touch it; the spare buffer takes v's rest */
    rest.n = 0;
    if (!evr_event_vec_append(&rest, v->data + n, v->n - n)) {
        evr_event_vec_free(&rest);
        snprintf(err->msg, sizeof err->msg, "out of memory queueing events for writing");
        return EVR_ERR_NOMEM;
    }
    slot->data = v->data;
    slot->cap = v->cap;
    slot->n = n;
    *v = rest;
    if (rest_bytes < rest.n * sizeof(evr_event)) rest_bytes = rest.n * sizeof(evr_event);
    pthread_mutex_lock(&q->mu);
    q->slot_bytes[at] = bytes;
    q->out_bytes = rest_bytes;
    q->count++;
    q->queued_bytes += bytes;
    pthread_cond_broadcast(&q->cv);
    pthread_mutex_unlock(&q->mu);
    return EVR_OK;
}

evr_status evr_write_queue_drain(evr_write_queue *q, evr_error *err)
{
    double t = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    while (q->count > 0 || q->busy) pthread_cond_wait(&q->cv, &q->mu);
    q->wait_seconds += evr_host_seconds() - t;
    evr_status st = q->status;
    if (st != EVR_OK) *err = q->err;
    pthread_mutex_unlock(&q->mu);
    return st;
}

evr_status evr_write_queue_flush(evr_write_queue *q, evr_error *err)
{
    double t = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    q->flush_now = 1;
    pthread_cond_broadcast(&q->cv);
    while (q->flush_now || q->count > 0 || q->busy) pthread_cond_wait(&q->cv, &q->mu);
    q->wait_seconds += evr_host_seconds() - t;
    evr_status st = q->status;
    if (st != EVR_OK) *err = q->err;
    pthread_mutex_unlock(&q->mu);
    return st;
}

void evr_write_queue_accepted(evr_write_queue *q, uint64_t *events, uint64_t *batches)
{
    pthread_mutex_lock(&q->mu);
    *events = q->accepted_events;
    *batches = q->accepted_batches;
    pthread_mutex_unlock(&q->mu);
}

double evr_write_queue_busy_seconds(evr_write_queue *q)
{
    pthread_mutex_lock(&q->mu);
    double s = q->busy_seconds;
    pthread_mutex_unlock(&q->mu);
    return s;
}

double evr_write_queue_wait_seconds(evr_write_queue *q)
{
    pthread_mutex_lock(&q->mu);
    double s = q->wait_seconds;
    pthread_mutex_unlock(&q->mu);
    return s;
}

void evr_write_queue_stop(evr_write_queue *q)
{
    int i;
    if (!q) return;
    pthread_mutex_lock(&q->mu);
    q->stop = 1;
    pthread_cond_broadcast(&q->cv);
    pthread_mutex_unlock(&q->mu);
    pthread_join(q->thread, NULL);
    evr_par_pool_free(q->pool);
    pthread_mutex_destroy(&q->mu);
    pthread_cond_destroy(&q->cv);
    for (i = 0; i < QUEUE_SLOTS; i++) evr_event_vec_free(&q->slots[i]);
    for (i = 0; i < q->nspare; i++) evr_event_vec_free(&q->spare[i]);
    free(q);
}
