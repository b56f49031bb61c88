/* The pool of par_pool.h: one job at a time, its parts handed out under one lock. */
#include "par_pool.h"

#include <pthread.h>
#include <stdlib.h>

struct evr_par_pool {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    pthread_t *tid;
    int started;
    int stop;
    unsigned long generation;   /* counts the jobs: a worker joins each new one once */
    void (*fn)(void *ctx, int part);
    void *ctx;
    int parts, next, finished;
};

/* Takes parts until none is left; called with mu held, returns with it held. */
static void take_parts(evr_par_pool *p)
{
    while (p->next < p->parts) {
        const int k = p->next++;
        pthread_mutex_unlock(&p->mu);
        p->fn(p->ctx, k);
        pthread_mutex_lock(&p->mu);
        if (++p->finished == p->parts) pthread_cond_signal(&p->done);
    }
}

static void *worker_main(void *arg)
{
    evr_par_pool *p = arg;
    unsigned long seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (!p->stop && p->generation == seen) pthread_cond_wait(&p->work, &p->mu);
        if (p->stop) break;
        seen = p->generation;
        take_parts(p);
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
    if (!p->tid || pthread_mutex_init(&p->mu, NULL) != 0) {
        free(p->tid);
        free(p);
        return NULL;
    }
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->done, NULL);
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&p->tid[p->started], NULL, worker_main, p) != 0) break;
        p->started++;
    }
    return p;
}

int evr_par_pool_threads(const evr_par_pool *p)
{
    return p ? p->started + 1 : 1;
}

void evr_par_pool_run(evr_par_pool *p, int parts, void (*fn)(void *ctx, int part), void *ctx)
{
    if (parts <= 0) return;
    if (!p) {
        for (int k = 0; k < parts; k++) fn(ctx, k);
        return;
    }
    pthread_mutex_lock(&p->mu);
    p->fn = fn;
    p->ctx = ctx;
    p->parts = parts;
    p->next = 0;
    p->finished = 0;
    p->generation++;
    if (p->started && parts > 1) pthread_cond_broadcast(&p->work);
    take_parts(p);
    while (p->finished < p->parts) pthread_cond_wait(&p->done, &p->mu);
    p->parts = p->next = p->finished = 0;
    pthread_mutex_unlock(&p->mu);
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
    free(p);
}
