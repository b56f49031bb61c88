/* A caller's event sink (evr_sim_set_sink) as one more event writer of the write queue: it takes
 * the same time-sorted batches, in the same order, on the same thread as the format writers, so
 * the queue's eight slots are its back-pressure too. Its callback's non-zero stops the run as
 * evr_sim_cancel does, and no batch reaches it after that. */
#ifndef EVR_RUN_EVENT_SINK_H
#define EVR_RUN_EVENT_SINK_H

#include "io/event_writer.h"

/* cancel: the run's stop flag, set (atomically) when fn returns non-zero. NULL: out of memory.
 * The queue calls write() and flush(); free it with evr_event_sink_free once the queue stopped. */
evr_event_writer *evr_event_sink_new(evr_event_sink_fn fn, void *user, int *cancel);
void evr_event_sink_free(evr_event_writer *w);

#endif
