/* The writer thread: batches reach every writer in order, flushes follow the interval (after a
 * batch when it has passed, or once idle that long), errors come back to the caller. */
#include "check.h"
#include "run/write_queue.h"
#include "host_clock.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* A writer that records what it is given; fail_flush makes every flush fail. */
typedef struct {
    evr_event_writer base;
    int64_t next_t; /* the t the next event must have (events are 0, 1, 2, ...) */
    int in_order;
    size_t events, writes, flushes;
    _Atomic size_t flushed_events; /* read by the test while the thread may flush */
    int fail_flush;
} fake_writer;

static evr_status fake_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    fake_writer *w = (fake_writer *)base;
    for (size_t i = 0; i < n; i++)
        if (ev[i].t != w->next_t++) w->in_order = 0;
    w->events += n;
    w->writes++;
    (void)err;
    return EVR_OK;
}

static evr_status fake_flush(evr_event_writer *base, evr_error *err)
{
    fake_writer *w = (fake_writer *)base;
    if (w->fail_flush) {
        snprintf(err->msg, sizeof err->msg, "fake writer: cannot flush");
        return EVR_ERR_IO;
    }
    w->flushes++;
    atomic_store(&w->flushed_events, w->events);
    return EVR_OK;
}

static void fake_init(fake_writer *w)
{
    memset(w, 0, sizeof *w);
    atomic_init(&w->flushed_events, 0);
    w->base.write = fake_write;
    w->base.flush = fake_flush;
    w->in_order = 1;
}

/* Pushes batches of n events continuing the time line at *t. */
static evr_status push(evr_write_queue *q, int64_t *t, size_t n, evr_error *err)
{
    evr_event_vec v = {0};
    for (size_t i = 0; i < n; i++) {
        evr_event e = {0};
        e.t = (*t)++;
        if (!evr_event_vec_push(&v, e)) return EVR_ERR_NOMEM;
    }
    evr_status st = evr_write_queue_push_take(q, &v, v.n, err);
    evr_event_vec_free(&v);
    return st;
}

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

int main(void)
{
    evr_error err;
    int64_t t;
    int i;

    /* a long interval: batches written in order, no flush during the run */
    {
        fake_writer a, b;
        evr_event_writer *ws[2] = {&a.base, &b.base};
        evr_write_queue *q = NULL;
        fake_init(&a);
        fake_init(&b);
        t = 0;
        CHECK_OK(evr_write_queue_start(ws, 2, 1000.0, &q, &err));
        for (i = 0; i < 20; i++) CHECK_OK(push(q, &t, 1000 + (size_t)i, &err));
        CHECK_OK(evr_write_queue_drain(q, &err));
        CHECK(a.flushes == 0 && b.flushes == 0);
        uint64_t events = 0, batches = 0;
        evr_write_queue_accepted(q, &events, &batches);
        CHECK(events == (uint64_t)t && batches == 20); /* every writer took every batch */
        /* a flush asked for: everything written, then every writer flushed */
        CHECK_OK(push(q, &t, 10, &err));
        CHECK_OK(evr_write_queue_flush(q, &err));
        CHECK(a.flushes == 1 && b.flushes == 1 && a.flushed_events == (size_t)t);
        evr_write_queue_stop(q);
        CHECK(a.in_order && b.in_order);
        CHECK(a.events == (size_t)t && b.events == (size_t)t);
        CHECK(a.writes == 21 && b.writes == 21);
    }
    /* interval 0: a flush after every batch */
    {
        fake_writer a;
        evr_event_writer *ws[1] = {&a.base};
        evr_write_queue *q = NULL;
        fake_init(&a);
        t = 0;
        CHECK_OK(evr_write_queue_start(ws, 1, 0.0, &q, &err));
        for (i = 0; i < 10; i++) CHECK_OK(push(q, &t, 500, &err));
        CHECK_OK(evr_write_queue_drain(q, &err));
        evr_write_queue_stop(q);
        CHECK(a.in_order && a.events == 5000);
        CHECK(a.flushes == 10 && a.flushed_events == 5000);
    }
    /* a short interval: an idle queue flushes what it wrote without another batch */
    {
        fake_writer a;
        evr_event_writer *ws[1] = {&a.base};
        evr_write_queue *q = NULL;
        fake_init(&a);
        t = 0;
        CHECK_OK(evr_write_queue_start(ws, 1, 0.05, &q, &err));
        CHECK_OK(push(q, &t, 300, &err));
        CHECK_OK(evr_write_queue_drain(q, &err));
        double t0 = evr_host_seconds();
        size_t flushed = 0;
        while (evr_host_seconds() - t0 < 10.0) {
            sleep_s(0.02);
            CHECK_OK(evr_write_queue_drain(q, &err)); /* after drain the thread is not in a flush */
            flushed = atomic_load(&a.flushed_events);
            if (flushed == 300) break;
        }
        CHECK(flushed == 300);
        CHECK(evr_write_queue_busy_seconds(q) >= 0.0);
        evr_write_queue_stop(q);
    }
    /* a failing timed flush is the error drain and the next push return */
    {
        fake_writer a;
        evr_event_writer *ws[1] = {&a.base};
        evr_write_queue *q = NULL;
        evr_status st = EVR_OK;
        fake_init(&a);
        a.fail_flush = 1;
        t = 0;
        CHECK_OK(evr_write_queue_start(ws, 1, 0.01, &q, &err));
        CHECK_OK(push(q, &t, 10, &err));
        double t0 = evr_host_seconds();
        while (st == EVR_OK && evr_host_seconds() - t0 < 10.0) {
            sleep_s(0.02);
            st = evr_write_queue_drain(q, &err);
        }
        CHECK(st == EVR_ERR_IO && strstr(err.msg, "cannot flush") != NULL);
        err.msg[0] = 0;
        CHECK(push(q, &t, 10, &err) == EVR_ERR_IO && strstr(err.msg, "cannot flush") != NULL);
        evr_write_queue_stop(q);
    }
    return check_report("test_write_queue");
}
