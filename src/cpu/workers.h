/* The CPU's worker threads: a function run on several threads at once, the calling thread one of
 * them. The workers share their work through an atomic counter of their own (tiles, rows, chunks
 * of photons), so a thread that cannot be started only leaves its share to the others. */
#ifndef EVR_CPU_WORKERS_H
#define EVR_CPU_WORKERS_H

/* threads <= 0: every online core (at least 1); else threads. */
int evr_cpu_threads(int threads);

/* Runs fn(arg) on `threads` threads (the caller's included) and returns when all are done;
 * 0 when out of memory for the thread handles (nothing was run). */
int evr_run_workers(void *(*fn)(void *), void *arg, int threads);

#endif
