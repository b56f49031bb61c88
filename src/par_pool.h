/* A small pool of threads that run the parts of one job at a time, the calling thread working too
 * (the per-segment passes over a segment's events: decoding the GPU's keys, counting). Starting
 * threads for every segment cost more than the work on the GPU machine (900 segments, 7 threads
 * each). */
#ifndef EVR_PAR_POOL_H
#define EVR_PAR_POOL_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct evr_par_pool evr_par_pool;

/* A pool of `threads` threads, the caller counted (threads - 1 are started; fewer when they
 * cannot be). NULL when out of memory. */
evr_par_pool *evr_par_pool_new(int threads);

/* Threads the pool runs a job on, the caller counted. */
int evr_par_pool_threads(const evr_par_pool *p);

/* Runs fn(ctx, k) for k = 0 .. parts - 1 on the pool and the caller; returns when all are done.
 * A NULL pool runs them all on the caller. */
void evr_par_pool_run(evr_par_pool *p, int parts, void (*fn)(void *ctx, int part), void *ctx);

/* Stops the threads and frees the pool (NULL is fine). */
void evr_par_pool_free(evr_par_pool *p);

#ifdef __cplusplus
}
#endif
#endif
