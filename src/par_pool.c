/* The pool of par_pool.h: one job at a time, its parts handed out under one lock. */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT */
#include "par_pool.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <unistd.h>

struct worker_arg {
    struct evr_par_pool *pool;
    int thread;
};

struct evr_par_pool {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    pthread_t *tid;
    struct worker_arg *args;
    int started;
    int stop;
    unsigned long generation; /* counts the jobs: a worker joins each new one once */
    evr_par_fn fn;
    void *ctx;
    int parts, next, finished;
};

int evr_par_threads(int max)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    /* hidden, for tests: pools of this many threads whatever the machine (their code paths for
     * many cores then run on two) */
    const char *force = getenv("EVR_PAR_THREADS");
    if (force && atol(force) > 0) n = atol(force);
    else {
#ifdef __linux__
        /* the processors this process may run on (taskset, container cpusets) */
        cpu_set_t set;
        if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0 &&
            CPU_COUNT(&set) < n)
            n = CPU_COUNT(&set);
#endif
    }
    if (n > max) n = max;
    return n < 1 ? 1 : (int)n;
}

/* Takes parts until none is left; called with mu held, returns with it held. */
static void take_parts(evr_par_pool *p, int thread)
{
    while (p->next < p->parts) {
        const int k = p->next++;
        pthread_mutex_unlock(&p->mu);
        p->fn(p->ctx, k, thread);
        pthread_mutex_lock(&p->mu);
        if (++p->finished == p->parts) pthread_cond_signal(&p->done);
    }
}

static void *worker_main(void *arg)
{
    const struct worker_arg *a = arg;
    evr_par_pool *p = a->pool;
    unsigned long seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (!p->stop && p->generation == seen) pthread_cond_wait(&p->work, &p->mu);
        if (p->stop) break;
        seen = p->generation;
        take_parts(p, a->thread);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

evr_par_pool *evr_par_pool_new(int threads)
{
    evr_par_pool *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    if (threads < 1) threads = 1;
    p->tid = calloc((size_t)threads, sizeof *p->tid);
    p->args = calloc((size_t)threads, sizeof *p->args);
    if (!p->tid || !p->args || pthread_mutex_init(&p->mu, NULL) != 0) {
        free(p->tid);
        free(p->args);
        free(p);
        return NULL;
    }
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->done, NULL);
    /* threads that cannot be started leave a smaller pool */
    for (int i = 1; i < threads; i++) {
        p->args[p->started].pool = p;
        p->args[p->started].thread = p->started + 1;
        if (pthread_create(&p->tid[p->started], NULL, worker_main, &p->args[p->started]) != 0)
            break;
        p->started++;
    }
    return p;
}

int evr_par_pool_threads(const evr_par_pool *p) { return p ? p->started + 1 : 1; }

void evr_par_pool_start(evr_par_pool *p, int parts, evr_par_fn fn, void *ctx)
{
    if (!p) return;
    pthread_mutex_lock(&p->mu);
    p->fn = fn;
    p->ctx = ctx;
    p->parts = parts > 0 ? parts : 0;
    p->next = 0;
    p->finished = 0;
    p->generation++;
    if (p->started && p->parts > 0) pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
}

void evr_par_pool_wait(evr_par_pool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->mu);
    take_parts(p, 0); /* what the pool's threads have not taken yet */
    while (p->finished < p->parts) pthread_cond_wait(&p->done, &p->mu);
    p->parts = p->next = p->finished = 0;
    pthread_mutex_unlock(&p->mu);
}

void evr_par_pool_run(evr_par_pool *p, int parts, evr_par_fn fn, void *ctx)
{
    if (parts <= 0) return;
    if (!p || parts == 1) { /* no pool, or nothing to share */
        for (int k = 0; k < parts; k++) fn(ctx, k, 0);
        return;
    }
    evr_par_pool_start(p, parts, fn, ctx);
    evr_par_pool_wait(p);
}

void evr_par_pool_free(evr_par_pool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->mu);
    p->stop = 1;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
    for (int i = 0; i < p->started; i++) pthread_join(p->tid[i], NULL);
    pthread_cond_destroy(&p->done);
    pthread_cond_destroy(&p->work);
    pthread_mutex_destroy(&p->mu);
    free(p->tid);
    free(p->args);
    free(p);
}
