/* Shuffle + deflate of dataset chunks, in parallel (see chunk_compress.h). HDF5 1.10's H5Z
 * shuffle filter transposes the bytes of the whole chunk (and leaves 1-byte elements untouched);
 * its deflate filter reads any zlib stream, which libdeflate makes faster than zlib's compress2,
 * with smaller output (docs/benchmarks.md: the writer thread 2.3x faster, files 2% smaller).
 * tests/test_writers.c reads the chunks back with zlib and through HDF5. */
#define _GNU_SOURCE   /* sched_getaffinity, CPU_COUNT */
#include "io/chunk_compress.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <libdeflate.h>

/* A thread's scratch (the shuffled chunk) and its compressor (made for one level at a time). */
struct evr_chunk_worker {
    unsigned char *scratch;
    struct libdeflate_compressor *comp;
    int level;
};

struct evr_chunk_pool {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    evr_chunk_job *jobs;        /* the list being compressed; every field under mu */
    size_t njobs, next, finished;
    int failed, stop;
    int threads;                /* the caller included */
    int started;                /* threads running */
    pthread_t *tid;
    evr_chunk_worker **workers; /* one per thread; [0] is the caller's */
    struct worker_arg { struct evr_chunk_pool *pool; int index; } *args;
};

size_t evr_chunk_bound(size_t raw_bytes)
{
    return libdeflate_zlib_compress_bound(NULL, raw_bytes);   /* any level */
}

evr_chunk_worker *evr_chunk_worker_new(size_t max_chunk_bytes)
{
    evr_chunk_worker *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    if (!(w->scratch = malloc(max_chunk_bytes ? max_chunk_bytes : 1))) {
        free(w);
        return NULL;
    }
    w->level = -1;
    return w;
}

void evr_chunk_worker_free(evr_chunk_worker *w)
{
    if (!w) return;
    libdeflate_free_compressor(w->comp);
    free(w->scratch);
    free(w);
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

int evr_chunk_compress(evr_chunk_job *job, evr_chunk_worker *w)
{
    const unsigned char *src = (const unsigned char *)job->src;
    unsigned char *scratch = w->scratch;
    size_t raw = job->chunk_elems * job->elem_size, count = job->count;
    if (count > job->chunk_elems) count = job->chunk_elems;
    if (!w->comp || w->level != job->level) {
        libdeflate_free_compressor(w->comp);
        w->comp = libdeflate_alloc_compressor(job->level);
        w->level = w->comp ? job->level : -1;
        if (!w->comp) {
            job->ok = 0;
            job->dst_size = 0;
            return 0;
        }
    }
    switch (job->elem_size) {
    case 1: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 1); break;
    case 2: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 2); break;
    case 4: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 4); break;
    case 8: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 8); break;
    default: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, job->elem_size); break;
    }
    const size_t len = libdeflate_zlib_compress(w->comp, scratch, raw, job->dst, evr_chunk_bound(raw));
    job->ok = len > 0;
    job->dst_size = len;
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
static void take_jobs(evr_chunk_pool *p, evr_chunk_worker *w)
{
    while (p->next < p->njobs) {
        evr_chunk_job *job = &p->jobs[p->next++];
        int ok;
        pthread_mutex_unlock(&p->mu);
        ok = evr_chunk_compress(job, w);
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
        take_jobs(p, p->workers[a->index]);
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
    p->workers = calloc((size_t)threads, sizeof *p->workers);
    p->args = calloc((size_t)threads, sizeof *p->args);
    if (!p->tid || !p->workers || !p->args || pthread_mutex_init(&p->mu, NULL) != 0) goto fail_alloc;
    if (pthread_cond_init(&p->work, NULL) != 0) goto fail_mu;
    if (pthread_cond_init(&p->done, NULL) != 0) goto fail_work;
    for (i = 0; i < threads; i++)
        if (!(p->workers[i] = evr_chunk_worker_new(max_chunk_bytes))) goto fail_all;
    /* threads that cannot be started leave a smaller pool */
    for (i = 1; i < threads; i++) {
        p->args[i].pool = p;
        p->args[i].index = i;
        if (pthread_create(&p->tid[p->started], NULL, worker_main, &p->args[i]) != 0) break;
        p->started++;
    }
    for (i = p->started + 1; i < threads; i++) {
        evr_chunk_worker_free(p->workers[i]);
        p->workers[i] = NULL;
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
    if (p->workers)
        for (i = 0; i < threads; i++) evr_chunk_worker_free(p->workers[i]);
    free(p->workers);
    free(p->tid);
    free(p->args);
    free(p);
    return NULL;
}

void evr_chunk_pool_start(evr_chunk_pool *p, evr_chunk_job *jobs, size_t n)
{
    pthread_mutex_lock(&p->mu);
    p->jobs = jobs;
    p->njobs = n;
    p->next = 0;
    p->finished = 0;
    p->failed = 0;
    if (p->started && n) pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
}

int evr_chunk_pool_wait(evr_chunk_pool *p)
{
    int failed;
    pthread_mutex_lock(&p->mu);
    take_jobs(p, p->workers[0]);   /* what the workers have not taken yet */
    while (p->finished < p->njobs) pthread_cond_wait(&p->done, &p->mu);
    failed = p->failed;
    p->jobs = NULL;
    p->njobs = p->next = p->finished = 0;
    pthread_mutex_unlock(&p->mu);
    return !failed;
}

int evr_chunk_pool_run(evr_chunk_pool *p, evr_chunk_job *jobs, size_t n)
{
    if (n == 0) return 1;
    evr_chunk_pool_start(p, jobs, n);
    return evr_chunk_pool_wait(p);
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
    for (i = 0; i < p->threads; i++) evr_chunk_worker_free(p->workers[i]);
    free(p->workers);
    free(p->tid);
    free(p->args);
    free(p);
}
