#include "write_queue.h"
#include "host_clock.h"
#include "events.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define QUEUE_SLOTS 2

struct evr_write_queue {
    evr_event_writer *writers[8];
    int num_writers;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    evr_event_vec slots[QUEUE_SLOTS];
    int head, count;       /* pending batches: slots[head], slots[head + 1], ... */
    int busy;              /* the thread is writing the batch at head */
    int stop;
    evr_status status;     /* first error of the writer thread */
    evr_error err;
    double busy_seconds, wait_seconds;
};

static void *writer_main(void *arg)
{
    evr_write_queue *q = (evr_write_queue *)arg;
    pthread_mutex_lock(&q->mu);
    for (;;) {
        while (!q->count && !q->stop) pthread_cond_wait(&q->cv, &q->mu);
        if (!q->count) break;   /* stop requested and nothing pending */
        evr_event_vec *v = &q->slots[q->head];
        q->busy = 1;
        int failed = q->status != EVR_OK;
        pthread_mutex_unlock(&q->mu);
        evr_status st = EVR_OK;
        evr_error err;
        err.msg[0] = 0;
        double t = evr_host_seconds();
        int w;
        for (w = 0; !failed && w < q->num_writers && st == EVR_OK; w++) st = q->writers[w]->write(q->writers[w], v->data, v->n, &err);
        for (w = 0; !failed && w < q->num_writers && st == EVR_OK; w++) st = q->writers[w]->flush(q->writers[w], &err);
        double dt = evr_host_seconds() - t;
        pthread_mutex_lock(&q->mu);
        q->busy_seconds += dt;
        if (st != EVR_OK && q->status == EVR_OK) {
            q->status = st;
            q->err = err;
        }
        v->n = 0;
        q->head = (q->head + 1) % QUEUE_SLOTS;
        q->count--;
        q->busy = 0;
        pthread_cond_broadcast(&q->cv);
    }
    pthread_mutex_unlock(&q->mu);
    return NULL;
}

evr_status evr_write_queue_start(evr_event_writer *const *writers, int num_writers, evr_write_queue **out, evr_error *err)
{
    evr_write_queue *q = calloc(1, sizeof *q);
    int i;
    if (!q || num_writers > 8) {
        free(q);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (i = 0; i < num_writers; i++) q->writers[i] = writers[i];
    q->num_writers = num_writers;
    q->status = EVR_OK;
    pthread_mutex_init(&q->mu, NULL);
    pthread_cond_init(&q->cv, NULL);
    if (pthread_create(&q->thread, NULL, writer_main, q) != 0) {
        pthread_mutex_destroy(&q->mu);
        pthread_cond_destroy(&q->cv);
        free(q);
        snprintf(err->msg, sizeof err->msg, "cannot start the writer thread");
        return EVR_ERR_IO;
    }
    *out = q;
    return EVR_OK;
}

evr_status evr_write_queue_push_take(evr_write_queue *q, evr_event_vec *v, size_t n, evr_error *err)
{
    double t = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    while (q->count == QUEUE_SLOTS && q->status == EVR_OK) pthread_cond_wait(&q->cv, &q->mu);
    q->wait_seconds += evr_host_seconds() - t;
    if (q->status != EVR_OK) {
        *err = q->err;
        evr_status st = q->status;
        pthread_mutex_unlock(&q->mu);
        return st;
    }
    evr_event_vec *slot = &q->slots[(q->head + q->count) % QUEUE_SLOTS];
    pthread_mutex_unlock(&q->mu);
    /* this slot is not pending, so the thread does not touch it: its buffer takes v's rest */
    evr_event_vec rest = *slot;
    rest.n = 0;
    if (!evr_event_vec_append(&rest, v->data + n, v->n - n)) {
        *slot = rest;
        snprintf(err->msg, sizeof err->msg, "out of memory queueing events for writing");
        return EVR_ERR_NOMEM;
    }
    slot->data = v->data;
    slot->cap = v->cap;
    slot->n = n;
    *v = rest;
    pthread_mutex_lock(&q->mu);
    q->count++;
    pthread_cond_broadcast(&q->cv);
    pthread_mutex_unlock(&q->mu);
    return EVR_OK;
}

evr_status evr_write_queue_drain(evr_write_queue *q, evr_error *err)
{
    double t = evr_host_seconds();
    pthread_mutex_lock(&q->mu);
    while (q->count > 0) pthread_cond_wait(&q->cv, &q->mu);
    q->wait_seconds += evr_host_seconds() - t;
    evr_status st = q->status;
    if (st != EVR_OK) *err = q->err;
    pthread_mutex_unlock(&q->mu);
    return st;
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
    pthread_mutex_destroy(&q->mu);
    pthread_cond_destroy(&q->cv);
    for (i = 0; i < QUEUE_SLOTS; i++) evr_event_vec_free(&q->slots[i]);
    free(q);
}
