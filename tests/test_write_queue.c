/* The writer thread: batches reach every writer in order, flushes follow the interval (after a
 * batch when it has passed, or once idle that long), errors come back to the caller. */
#include "check.h"
#include "run/write_queue.h"
#include "host_clock.h"

#include <pthread.h>
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

static evr_status fake_flush_none(evr_event_writer *base, evr_error *err)
{
    (void)base;
    (void)err;
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

/* Writers that meet: each but the first counts itself in and waits (up to 10 s) until all the
 * others have come, which they can only while they run at the same time; the first takes part
 * without waiting (it may run before, beside or after them: the queue hands a batch to every
 * writer at once); fail_at makes that write fail. */
static void sleep_s(double s);

typedef struct {
    _Atomic int arrived; /* the others' writes so far */
    int others;
} meeting;

typedef struct {
    evr_event_writer base;
    meeting *m;
    int first, writes, met, fail_at;
} meet_writer;

static evr_status meet_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    meet_writer *w = (meet_writer *)base;
    (void)ev;
    (void)n;
    w->writes++;
    if (w->first) {
        w->met++;
        return EVR_OK;
    }
    const int want = w->writes * w->m->others;
    atomic_fetch_add(&w->m->arrived, 1);
    double t0 = evr_host_seconds();
    while (atomic_load(&w->m->arrived) < want && evr_host_seconds() - t0 < 10.0) sleep_s(0.001);
    if (atomic_load(&w->m->arrived) >= want) w->met++;
    if (w->writes == w->fail_at) {
        snprintf(err->msg, sizeof err->msg, "meet writer: cannot write");
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

static void meet_init(meet_writer *w, meeting *m, int first)
{
    memset(w, 0, sizeof *w);
    w->base.write = meet_write;
    w->base.flush = fake_flush_none;
    w->m = m;
    w->first = first;
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

/* A writer that holds each write until the test opens its gate. */
typedef struct {
    evr_event_writer base;
    _Atomic int open;
} gate_writer;

static evr_status gate_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    gate_writer *w = (gate_writer *)base;
    (void)ev;
    (void)n;
    (void)err;
    double t0 = evr_host_seconds();
    while (!atomic_load(&w->open) && evr_host_seconds() - t0 < 20.0) sleep_s(0.001);
    return EVR_OK;
}

/* A queue whose one writer is g, its gate closed. */
static evr_status gated_queue(gate_writer *g, evr_write_queue **q, evr_error *err)
{
    evr_event_writer *ws[1] = {&g->base};
    memset(g, 0, sizeof *g);
    atomic_init(&g->open, 0);
    g->base.write = gate_write;
    g->base.flush = fake_flush_none;
    return evr_write_queue_start(ws, 1, 1000.0, q, err);
}

/* Pushes as the simulation does: one vector whose events beyond those pushed stay in it (in a
 * buffer the queue gives back); each of `rounds` pushes takes 1,000 of 2,000,000 events, so every
 * batch's buffer holds 32 MB in memory for its 16 KB of events. */
typedef struct {
    evr_write_queue *q;
    int rounds;
    _Atomic int pushed;
    evr_status st;
    evr_error err;
} held_pusher;

static void *held_push_main(void *arg)
{
    held_pusher *p = arg;
    evr_event_vec v = {0};
    int64_t t = 0;
    p->st = EVR_OK;
    for (int r = 0; r < p->rounds && p->st == EVR_OK; r++) {
        while (v.n < 2000000) {
            evr_event e = {0};
            e.t = t++;
            if (!evr_event_vec_push(&v, e)) {
                p->st = EVR_ERR_NOMEM;
                break;
            }
        }
        if (p->st == EVR_OK) p->st = evr_write_queue_push_take(p->q, &v, 1000, &p->err);
        atomic_fetch_add(&p->pushed, 1);
    }
    evr_event_vec_free(&v);
    return NULL;
}

/* A push on a thread of its own, for a push that may wait. */
typedef struct {
    evr_write_queue *q;
    int64_t t;
    size_t n;
    evr_status st;
    _Atomic int done;
    evr_error err;
} pusher;

static void *push_main(void *arg)
{
    pusher *p = arg;
    p->st = push(p->q, &p->t, p->n, &p->err);
    atomic_store(&p->done, 1);
    return NULL;
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
    /* no writer at all: batches and flushes go nowhere */
    {
        evr_write_queue *q = NULL;
        t = 0;
        CHECK_OK(evr_write_queue_start(NULL, 0, 0.0, &q, &err));
        CHECK_OK(push(q, &t, 10, &err));
        CHECK_OK(evr_write_queue_flush(q, &err));
        evr_write_queue_stop(q);
    }
    /* several writers at the same time; a failure of one of them is the queue's error, and its
     * batch is not accepted */
    {
        meeting m;
        meet_writer w[4];
        evr_event_writer *ws[4];
        evr_write_queue *q = NULL;
        evr_status st = EVR_OK;
        uint64_t events = 0, batches = 0;
        atomic_init(&m.arrived, 0);
        m.others = 3;
        for (i = 0; i < 4; i++) {
            meet_init(&w[i], &m, i == 0);
            ws[i] = &w[i].base;
        }
        w[2].fail_at = 4;
        t = 0;
        CHECK_OK(evr_write_queue_start(ws, 4, 1000.0, &q, &err));
        for (i = 0; i < 3; i++) CHECK_OK(push(q, &t, 100, &err));
        CHECK_OK(evr_write_queue_drain(q, &err));
        for (i = 0; i < 4; i++) CHECK(w[i].writes == 3 && w[i].met == 3);
        CHECK_OK(push(q, &t, 100, &err));
        st = evr_write_queue_drain(q, &err);
        CHECK(st == EVR_ERR_IO && strstr(err.msg, "meet writer: cannot write") != NULL);
        evr_write_queue_accepted(q, &events, &batches);
        CHECK(events == 300 && batches == 3);
        evr_write_queue_stop(q);
    }
    /* the queue's bound in bytes (96 MB, run/write_queue.c): with a batch of 51.2 MB being
     * written, a second one waits until the writer is done, though slots are free; a batch
     * larger than the bound still goes when the queue is empty */
    {
        gate_writer g;
        evr_write_queue *q = NULL;
        pusher p;
        pthread_t th;
        t = 0;
        CHECK_OK(gated_queue(&g, &q, &err));
        CHECK_OK(push(q, &t, 3200000, &err)); /* taken by the writer, which waits at the gate */
        memset(&p, 0, sizeof p);
        p.q = q;
        p.t = t;
        p.n = 3200000;
        atomic_init(&p.done, 0);
        CHECK(pthread_create(&th, NULL, push_main, &p) == 0);
        sleep_s(0.3);
        CHECK(!atomic_load(&p.done)); /* 102.4 MB would wait: it waits */
        atomic_store(&g.open, 1);
        pthread_join(th, NULL);
        CHECK(atomic_load(&p.done) && p.st == EVR_OK);
        t = p.t;
        CHECK_OK(evr_write_queue_drain(q, &err));
        CHECK_OK(push(q, &t, 7000000, &err)); /* 112 MB alone */
        CHECK_OK(evr_write_queue_drain(q, &err));
        uint64_t events = 0, batches = 0;
        evr_write_queue_accepted(q, &events, &batches);
        CHECK(events == (uint64_t)t && batches == 3);
        evr_write_queue_stop(q);
    }
    /* the bound counts the memory a batch's buffer holds, not its events: with the writer held
     * at the gate, three batches of 1,000 events in 32 MB buffers fill the 96 MB (counting by
     * events, all ten would wait, 320 MB of buffers) */
    {
        gate_writer g;
        evr_write_queue *q = NULL;
        held_pusher p;
        pthread_t th;
        CHECK_OK(gated_queue(&g, &q, &err));
        memset(&p, 0, sizeof p);
        p.q = q;
        p.rounds = 10;
        atomic_init(&p.pushed, 0);
        CHECK(pthread_create(&th, NULL, held_push_main, &p) == 0);
        for (double t0 = evr_host_seconds();
             atomic_load(&p.pushed) < 3 && evr_host_seconds() - t0 < 30.0;)
            sleep_s(0.01);
        sleep_s(0.3); /* time for a fourth, if it would not wait */
        CHECK(atomic_load(&p.pushed) == 3);
        atomic_store(&g.open, 1);
        pthread_join(th, NULL);
        CHECK(atomic_load(&p.pushed) == 10 && p.st == EVR_OK);
        CHECK_OK(evr_write_queue_drain(q, &err));
        uint64_t events = 0, batches = 0;
        evr_write_queue_accepted(q, &events, &batches);
        CHECK(events == 10000 && batches == 10);
        evr_write_queue_stop(q);
    }
    return check_report("test_write_queue");
}
