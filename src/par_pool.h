/* A small pool of threads that run the parts of one job at a time, the calling thread working too:
 * the per-segment passes over a segment's events (decoding the GPU's keys, counting) and the HDF5
 * writer's chunk compression (io/chunk_compress.c). Starting threads for every segment cost more
 * than the work on the GPU machine (900 segments, 7 threads each). */
#ifndef EVR_PAR_POOL_H
#define EVR_PAR_POOL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct evr_par_pool evr_par_pool;

/* Part k of n items cut into `parts` shares as equal as can be: items [*begin, *end). */
static inline void evr_par_share(size_t n, int parts, int k, size_t *begin, size_t *end)
{
    *begin = n * (size_t)k / (size_t)parts;
    *end = n * (size_t)(k + 1) / (size_t)parts;
}

/* Part `part` of a job, run by thread `thread`: 0 the caller's, 1 .. threads - 1 the pool's (for
 * state kept per thread). */
typedef void (*evr_par_fn)(void *ctx, int part, int thread);

/* The number of threads a pool should have here: the processors this process may run on, at
 * most max. */
int evr_par_threads(int max);

/* A pool of `threads` threads, the caller counted (threads - 1 are started; fewer when they
 * cannot be). NULL when out of memory. */
evr_par_pool *evr_par_pool_new(int threads);

/* Threads the pool runs a job on, the caller counted (1 for a NULL pool). */
int evr_par_pool_threads(const evr_par_pool *p);

/* Runs fn(ctx, k, thread) for k = 0 .. parts - 1 on the pool and the caller; returns when all
 * are done. A NULL pool runs them all on the caller. */
void evr_par_pool_run(evr_par_pool *p, int parts, evr_par_fn fn, void *ctx);

/* The same in two steps: start hands the parts to the pool's threads and returns at once (ctx
 * and what it refers to must stay as they are); wait runs the parts not taken yet on the caller
 * (all of them in a pool of one thread) and returns when all are done. One job at a time: start,
 * then wait, before the next. */
void evr_par_pool_start(evr_par_pool *p, int parts, evr_par_fn fn, void *ctx);
void evr_par_pool_wait(evr_par_pool *p);

/* Stops the threads and frees the pool (NULL is fine). */
void evr_par_pool_free(evr_par_pool *p);

#ifdef __cplusplus
}
#endif
#endif
