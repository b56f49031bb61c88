/* The streaming API (evr_sim_set_sink): the events a sink takes are exactly those events.h5 holds
 * for the same run, in the same order; a slow sink holds the run back (at most eight batches wait)
 * and changes no event; a sink that asks to stop ends the run as evr_sim_cancel does, with valid
 * files holding at least what it took; formats 0 runs with the sink alone; a second sink, or one
 * set after the run, is refused. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "evray.h"
#include "evray_experimental.h"

typedef struct {
    evr_event *ev;
    size_t n, cap;
    int calls;
    int stop_after;   /* calls; 0: never stop */
    long sleep_ns;    /* per call: a slow consumer */
    int64_t last_t;   /* the last event's time: batches come in time order */
    int out_of_order; /* an event earlier than the one before */
} collected;

static int collect(void *user, const evr_event *ev, size_t n)
{
    collected *c = user;
    if (c->n + n > c->cap) {
        size_t cap = (c->n + n) * 2;
        evr_event *p = realloc(c->ev, cap * sizeof *p);
        if (!p) return 1;
        c->ev = p;
        c->cap = cap;
    }
    for (size_t i = 0; i < n; i++) {
        if (ev[i].t < c->last_t) c->out_of_order++;
        c->last_t = ev[i].t;
    }
    memcpy(c->ev + c->n, ev, n * sizeof *ev);
    c->n += n;
    c->calls++;
    if (c->sleep_ns) {
        struct timespec ts = {0, c->sleep_ns};
        nanosleep(&ts, NULL);
    }
    return c->stop_after && c->calls >= c->stop_after;
}

static void square_config(evr_config *c, const char *out, int formats)
{
    evr_config_defaults(c);
    c->width = c->height = 48;
    c->fps = 30;
    c->samples_per_frame = 8;
    c->pos_thres = 0.3f;
    c->neg_thres = 0.25f;
    c->log_floor = 1e-4f;
    c->preview = EVR_PREVIEW_NONE;
    c->threads = 2;
    c->out_dir = out;
    c->formats = formats;
    c->force = 1;
}

static int same_events(const evr_event *a, const evr_event *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (a[i].t != b[i].t || a[i].x != b[i].x || a[i].y != b[i].y || a[i].p != b[i].p) return 0;
    return 1;
}

/* One run of the square into dir with sink c; its status. */
static evr_status run_square(const evr_scene *s, const char *dir, int formats, collected *c)
{
    evr_config cfg;
    evr_sim *sim = NULL;
    evr_error err = {{0}};
    square_config(&cfg, dir, formats);
    evr_status st = evr_sim_new(s, &cfg, &sim, &err);
    if (st != EVR_OK) {
        fprintf(stderr, "evr_sim_new: %s\n", err.msg);
        return st;
    }
    c->last_t = INT64_MIN;
    CHECK_OK(evr_sim_set_sink(sim, collect, c, &err));
    CHECK(evr_sim_set_sink(sim, collect, c, &err) == EVR_ERR_ARG); /* one sink */
    st = evr_sim_run(sim, NULL, NULL, &err);
    CHECK(evr_sim_set_sink(sim, collect, c, &err) == EVR_ERR_ARG); /* not after the run */
    const evr_stats *stats = evr_sim_stats(sim);
    if (st == EVR_OK) CHECK(stats->events_on + stats->events_off == c->n);
    evr_sim_release(sim);
    return st;
}

int main(void)
{
    char tmpl[] = "/tmp/evr_sink_XXXXXX";
    char dir[600], h5[700];
    evr_scene *s = NULL;
    evr_error err = {{0}};
    evr_event *file = NULL;
    size_t nfile = 0;
    int w, h;
    if (!mkdtemp(tmpl)) return 1;
    snprintf(dir, sizeof dir, "%s/run", tmpl);
    snprintf(h5, sizeof h5, "%s/events.h5", dir);
    if (evr_demo_load("square", &s, &err) != EVR_OK) {
        fprintf(stderr, "square: %s\n", err.msg);
        return 1;
    }

    /* the stream is events.h5 */
    collected all = {0};
    CHECK(run_square(s, dir, EVR_FORMAT_H5, &all) == EVR_OK);
    CHECK(all.n > 1000 && all.calls > 1 && all.out_of_order == 0);
    CHECK(evr_events_read(h5, &file, &nfile, &w, &h, &err) == EVR_OK);
    CHECK(nfile == all.n && file && same_events(file, all.ev, all.n));
    free(file);
    file = NULL;

    /* a slow consumer: the same events */
    collected slow = {0};
    slow.sleep_ns = 20 * 1000 * 1000;
    CHECK(run_square(s, dir, 0, &slow) == EVR_OK);
    CHECK(slow.n == all.n && same_events(slow.ev, all.ev, all.n));

    /* stopping from the sink: interrupted, the files valid and holding what it took first */
    collected stop = {0};
    stop.stop_after = 2;
    CHECK(run_square(s, dir, EVR_FORMAT_H5, &stop) == EVR_ERR_INTERRUPTED);
    CHECK(stop.calls == 2 && stop.n < all.n && same_events(stop.ev, all.ev, stop.n));
    CHECK(evr_events_read(h5, &file, &nfile, &w, &h, &err) == EVR_OK);
    CHECK(nfile >= stop.n && nfile < all.n && same_events(file, all.ev, nfile));
    free(file);

    free(all.ev);
    free(slow.ev);
    free(stop.ev);
    evr_scene_release(s);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpl);
    CHECK(system(cmd) == 0);
    return check_report("test_sink");
}
