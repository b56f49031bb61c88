/* Writing speed of the event writers as a run drives them: synthetic events (7 a microsecond
 * at random pixels of 1280x720, about the 30 s eye's rate on the GPU) pushed in segments of
 * 1/30 s through the writer thread (run/write_queue.h, flushing once a second), then finished.
 * Not a test: docs/benchmarks.md ("Writers") quotes it.
 *
 *   build/tests/bench_writers FORMAT[,FORMAT...]|all [EVENTS] [DIR] [ids|noids] [BATCH]
 *
 * BATCH: events a push (default a segment's, 233,333; a GPU run pushes pieces of up to 1,048,576).
 * With "ids", the events carry event ids as the eye's do (evr_writer_meta.event_ids): a few
 * instances, each covering a band of the image.
 * Prints the wall time from the first push to the last finish, the writer thread's busy time and
 * the process CPU time (every thread) per event. DIR (default /tmp) takes the files, which go
 * at the end; a tmpfs (/dev/shm) leaves the disk out of it. */
#include "io/event_formats.h"
#include "run/write_queue.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RATE 7 /* events a microsecond */

static double seconds(clockid_t c)
{
    struct timespec ts;
    clock_gettime(c, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t next(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return *s >> 33;
}

static int fail(const evr_error *err)
{
    fprintf(stderr, "bench_writers: %s\n", err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    const size_t n = argc > 2 ? (size_t)strtoull(argv[2], NULL, 10) : 20000000;
    const char *dir = argc > 3 ? argv[3] : "/tmp";
    const int ids = argc > 4 && strcmp(argv[4], "ids") == 0;
    const size_t seg = argc > 5 ? (size_t)strtoull(argv[5], NULL, 10) : RATE * 1000000 / 30;
    evr_event_writer *ws[EVR_WRITE_QUEUE_MAX_WRITERS];
    char paths[EVR_WRITE_QUEUE_MAX_WRITERS][512];
    int formats = 0, count, nw = 0;
    const evr_event_format *const *all = evr_event_formats(&count);
    evr_error err;
    evr_write_queue *q = NULL;
    uint64_t s = 7;
    evr_event *ev;
    if (argc < 2 || n == 0 || seg == 0) {
        fprintf(stderr,
                "usage: bench_writers FORMAT[,FORMAT...]|all [EVENTS] [DIR] [ids|noids] [BATCH]\n");
        return 2;
    }
    if (evr_event_formats_parse("bench_writers", argv[1], &formats, &err) != EVR_OK)
        return fail(&err);
    ev = malloc(n * sizeof *ev);
    if (!ev) return 1;
    for (size_t i = 0; i < n; i++) {
        ev[i].t = (int64_t)(i / RATE);
        ev[i].x = (uint16_t)(next(&s) % 1280);
        ev[i].y = (uint16_t)(next(&s) % 720);
        ev[i].p = (int8_t)(next(&s) & 1);
        ev[i].id = ids ? 1u + ev[i].x / 160u : 0u;
    }
    evr_writer_meta meta = {.width = 1280,
                            .height = 720,
                            .config_json = "{}",
                            .max_t_us = ev[n - 1].t,
                            .event_ids = ids};
    for (int i = 0; i < count && nw < EVR_WRITE_QUEUE_MAX_WRITERS; i++) {
        if (!(formats & 1 << i)) continue;
        snprintf(paths[nw], sizeof paths[nw], "%s/bench_%s", dir, all[i]->file);
        if (all[i]->open(paths[nw], &meta, &ws[nw], &err) != EVR_OK) return fail(&err);
        nw++;
    }
    const double w0 = seconds(CLOCK_MONOTONIC), c0 = seconds(CLOCK_PROCESS_CPUTIME_ID);
    if (evr_write_queue_start(ws, nw, EVR_WRITE_FLUSH_SECONDS, &q, &err) != EVR_OK)
        return fail(&err);
    for (size_t at = 0; at < n; at += seg) {
        const size_t len = n - at < seg ? n - at : seg;
        evr_event_vec v = {0};
        if (!evr_event_vec_append(&v, ev + at, len)) return 1;
        if (evr_write_queue_push_take(q, &v, len, &err) != EVR_OK) return fail(&err);
        evr_event_vec_free(&v);
    }
    if (evr_write_queue_drain(q, &err) != EVR_OK) return fail(&err);
    const double busy = evr_write_queue_busy_seconds(q);
    evr_write_queue_stop(q);
    for (int k = 0; k < nw; k++)
        if (ws[k]->finish(ws[k], ev[n - 1].t + 1, &err) != EVR_OK) return fail(&err);
    const double w1 = seconds(CLOCK_MONOTONIC), c1 = seconds(CLOCK_PROCESS_CPUTIME_ID);
    printf("%s: %zu events: wall %.3f s, writer thread busy %.3f s, CPU %.3f s (%.2f ns an "
           "event)\n",
           argv[1], n, w1 - w0, busy, c1 - c0, (c1 - c0) / (double)n * 1e9);
    for (int k = 0; k < nw; k++) remove(paths[k]);
    free(ev);
    return 0;
}
