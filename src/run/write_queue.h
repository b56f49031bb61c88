/* Writes event batches on a thread of its own, so that the host writes segment i while the
 * backend renders segment i + 1. Batches are written in the order pushed; each batch goes to
 * the first writer, then to all the others at once on threads of their own (a writer is only
 * ever called by one thread at a time; the first, HDF5 when asked for, always by this one).
 * Every writer is flushed (a valid file up to there) after a batch when flush_seconds have
 * passed since the last flush, and otherwise once the thread has been idle until then: a killed
 * run's files lag at most about flush_seconds (plus the batch being written, and the HDF5
 * writer's last partial chunk) behind the batches pushed, and a fast run does not flush per
 * segment. At most 32 batches wait, holding at most 96 MB of buffers with the ones kept for
 * reuse (write_queue.c). A stopped or failed run completes the files itself (run/run_files.h),
 * with what every writer took (evr_write_queue_accepted). */
#ifndef EVR_WRITE_QUEUE_H
#define EVR_WRITE_QUEUE_H

#include <stddef.h>
#include <stdint.h>
#include "events.h"
#include "io/event_writer.h"

/* Writers a queue takes at most: a run's formats (sim_state.h's EVR_MAX_WRITERS) and a caller's
 * sink (run/event_sink.h). */
#define EVR_WRITE_QUEUE_MAX_WRITERS 17

/* The simulation's flush interval: a second of work at most is lost when a run is killed. */
#define EVR_WRITE_FLUSH_SECONDS 1.0

typedef struct evr_write_queue evr_write_queue;

evr_status evr_write_queue_start(evr_event_writer *const *writers, int num_writers,
                                 double flush_seconds, evr_write_queue **out, evr_error *err);
/* Adds writer w (not owned: the caller frees it after evr_write_queue_stop) before the first
 * push; EVR_ERR_ARG after it. The queue calls only its write() and flush(). */
evr_status evr_write_queue_add(evr_write_queue *q, evr_event_writer *w, evr_error *err);
/* Queues the first n events of v for writing and returns (waits only while the queue is full)
 * without copying them: the queue takes v's buffer and gives v one of its own holding
 * the rest of v (v->data[n .. v->n)), which is usually short. Fails with the writer thread's
 * first error, if any. */
evr_status evr_write_queue_push_take(evr_write_queue *q, evr_event_vec *v, size_t n,
                                     evr_error *err);
/* Waits until everything pushed is written (not necessarily flushed: the writers' finish()
 * completes the files); returns the first error, if any. */
evr_status evr_write_queue_drain(evr_write_queue *q, evr_error *err);
/* Waits until everything pushed is written, then flushes every writer; returns the first error,
 * if any. */
evr_status evr_write_queue_flush(evr_write_queue *q, evr_error *err);
/* The events and batches (counted from the first push) that every writer took: after a failure,
 * what the files can keep (io/event_writer.h, salvage). */
void evr_write_queue_accepted(evr_write_queue *q, uint64_t *events, uint64_t *batches);
/* Seconds the writer thread spent writing and flushing, and the caller spent waiting in
 * push/drain. */
double evr_write_queue_busy_seconds(evr_write_queue *q);
double evr_write_queue_wait_seconds(evr_write_queue *q);
/* Stops the thread (after the pending batches, without a last flush) and frees the queue. */
void evr_write_queue_stop(evr_write_queue *q);

#endif
