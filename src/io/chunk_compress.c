/* Shuffle + deflate of dataset chunks, in parallel (see chunk_compress.h). The bytes must equal
 * what HDF5 1.10's H5Z shuffle and deflate filters make: H5Z__filter_shuffle transposes the
 * bytes of the whole chunk (and returns 1-byte elements untouched), H5Z__filter_deflate calls
 * compress2(level) on the result. tests/test_writers.c compares the two byte for byte. */
#define _GNU_SOURCE   /* sched_getaffinity, CPU_COUNT */
#include "io/chunk_compress.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

struct evr_chunk_pool {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    evr_chunk_job *jobs;        /* the list being compressed; every field under mu */
    size_t njobs, next, finished;
    int failed, stop;
    int threads;                /* the caller included */
    int started;                /* threads running */
    pthread_t *tid;
    unsigned char **scratch;    /* one per thread; [0] is the caller's */
    struct worker_arg { struct evr_chunk_pool *pool; int index; } *args;
};

size_t evr_chunk_bound(size_t raw_bytes)
{
    return (size_t)compressBound((uLong)raw_bytes);
}

/* The shuffle for one element size: es is a constant where it is inlined, so the inner loop is
 * unrolled. One pass over the source writes es output streams. */
static inline void shuffle_es(unsigned char *out, const unsigned char *src, size_t stride, size_t count,
                              size_t chunk_elems, size_t es)
{
    for (size_t i = 0; i < count; i++) {
        const unsigned char *e = src + i * stride;
        for (size_t b = 0; b < es; b++) out[b * chunk_elems + i] = e[b];
    }
    if (count < chunk_elems)
        for (size_t b = 0; b < es; b++) memset(out + b * chunk_elems + count, 0, chunk_elems - count);
}

int evr_chunk_compress(evr_chunk_job *job, unsigned char *scratch)
{
    const unsigned char *src = (const unsigned char *)job->src;
    size_t raw = job->chunk_elems * job->elem_size, count = job->count;
    uLongf len = (uLongf)evr_chunk_bound(raw);
    if (count > job->chunk_elems) count = job->chunk_elems;
    switch (job->elem_size) {
    case 1: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 1); break;
    case 2: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 2); break;
    case 4: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 4); break;
    case 8: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 8); break;
    default: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, job->elem_size); break;
    }
    job->ok = compress2(job->dst, &len, scratch, (uLong)raw, job->level) == Z_OK;
    job->dst_size = job->ok ? (size_t)len : 0;
    return job->ok;
}

int evr_chunk_threads(int max)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
#ifdef __linux__
    /* the processors this process may run on (taskset, container cpusets) */
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0 && CPU_COUNT(&set) < n) n = CPU_COUNT(&set);
#endif
    if (n > max) n = max;
    return n < 1 ? 1 : (int)n;
}

/* Takes jobs until none is left; called with mu held, returns with it held. */
static void take_jobs(evr_chunk_pool *p, unsigned char *scratch)
{
    while (p->next < p->njobs) {
        evr_chunk_job *job = &p->jobs[p->next++];
        int ok;
        pthread_mutex_unlock(&p->mu);
        ok = evr_chunk_compress(job, scratch);
        pthread_mutex_lock(&p->mu);
        if (!ok) p->failed = 1;
        if (++p->finished == p->njobs) pthread_cond_signal(&p->done);
    }
}

static void *worker_main(void *arg)
{
    struct worker_arg *a = (struct worker_arg *)arg;
    evr_chunk_pool *p = a->pool;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (!p->stop && p->next >= p->njobs) pthread_cond_wait(&p->work, &p->mu);
        if (p->stop) break;
        take_jobs(p, p->scratch[a->index]);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

evr_chunk_pool *evr_chunk_pool_new(int threads, size_t max_chunk_bytes)
{
    evr_chunk_pool *p = calloc(1, sizeof *p);
    int i;
    if (threads < 1) threads = 1;
    if (!p) return NULL;
    p->threads = threads;
    p->tid = calloc((size_t)threads, sizeof *p->tid);
    p->scratch = calloc((size_t)threads, sizeof *p->scratch);
    p->args = calloc((size_t)threads, sizeof *p->args);
    if (!p->tid || !p->scratch || !p->args || pthread_mutex_init(&p->mu, NULL) != 0) goto fail_alloc;
    if (pthread_cond_init(&p->work, NULL) != 0) goto fail_mu;
    if (pthread_cond_init(&p->done, NULL) != 0) goto fail_work;
    for (i = 0; i < threads; i++)
        if (!(p->scratch[i] = malloc(max_chunk_bytes ? max_chunk_bytes : 1))) goto fail_all;
    /* threads that cannot be started leave a smaller pool */
    for (i = 1; i < threads; i++) {
        p->args[i].pool = p;
        p->args[i].index = i;
        if (pthread_create(&p->tid[p->started], NULL, worker_main, &p->args[i]) != 0) break;
        p->started++;
    }
    for (i = p->started + 1; i < threads; i++) {
        free(p->scratch[i]);
        p->scratch[i] = NULL;
    }
    p->threads = p->started + 1;
    return p;
fail_all:
    pthread_cond_destroy(&p->done);
fail_work:
    pthread_cond_destroy(&p->work);
fail_mu:
    pthread_mutex_destroy(&p->mu);
fail_alloc:
    if (p->scratch)
        for (i = 0; i < threads; i++) free(p->scratch[i]);
    free(p->scratch);
    free(p->tid);
    free(p->args);
    free(p);
    return NULL;
}

int evr_chunk_pool_run(evr_chunk_pool *p, evr_chunk_job *jobs, size_t n)
{
    int failed;
    if (n == 0) return 1;
    pthread_mutex_lock(&p->mu);
    p->jobs = jobs;
    p->njobs = n;
    p->next = 0;
    p->finished = 0;
    p->failed = 0;
    if (p->started) pthread_cond_broadcast(&p->work);
    take_jobs(p, p->scratch[0]);
    while (p->finished < p->njobs) pthread_cond_wait(&p->done, &p->mu);
    failed = p->failed;
    p->jobs = NULL;
    p->njobs = p->next = p->finished = 0;
    pthread_mutex_unlock(&p->mu);
    return !failed;
}

int evr_chunk_pool_threads(const evr_chunk_pool *p)
{
    return p->threads;
}

void evr_chunk_pool_free(evr_chunk_pool *p)
{
    int i;
    if (!p) return;
    pthread_mutex_lock(&p->mu);
    p->stop = 1;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
    for (i = 0; i < p->started; i++) pthread_join(p->tid[i], NULL);
    pthread_cond_destroy(&p->done);
    pthread_cond_destroy(&p->work);
    pthread_mutex_destroy(&p->mu);
    for (i = 0; i < p->threads; i++) free(p->scratch[i]);
    free(p->scratch);
    free(p->tid);
    free(p->args);
    free(p);
}
