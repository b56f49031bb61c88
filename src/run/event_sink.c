#include "run/event_sink.h"

#include <stdlib.h>

typedef struct {
    evr_event_writer base; /* first: the writer is the sink */
    evr_event_sink_fn fn;
    void *user;
    int *cancel;
    int stopped; /* fn asked to stop: it is not called again */
} event_sink;

static evr_status sink_write(evr_event_writer *w, const evr_event *ev, size_t n, evr_error *err)
{
    event_sink *s = (event_sink *)w;
    (void)err;
    if (s->stopped || n == 0) return EVR_OK;
    if (s->fn(s->user, ev, n)) {
        s->stopped = 1;
        __atomic_store_n(s->cancel, 1, __ATOMIC_RELAXED); /* as evr_sim_cancel */
    }
    /* the files still take the batch: stopping is not a failure of the run */
    return EVR_OK;
}

static evr_status sink_flush(evr_event_writer *w, evr_error *err)
{
    (void)w;
    (void)err;
    return EVR_OK; /* nothing held back: every batch went to the callback */
}

evr_event_writer *evr_event_sink_new(evr_event_sink_fn fn, void *user, int *cancel)
{
    event_sink *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->base.write = sink_write;
    s->base.flush = sink_flush;
    s->fn = fn;
    s->user = user;
    s->cancel = cancel;
    return &s->base;
}

void evr_event_sink_free(evr_event_writer *w) { free(w); }
