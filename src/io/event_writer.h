/* One interface for every event output format. The simulation hands each segment's events,
 * sorted by time, to every open writer; finish() completes the file (header counts, indices)
 * and renames it from its temporary name; abort() removes the temporary file. */
#ifndef EVR_IO_EVENT_WRITER_H
#define EVR_IO_EVENT_WRITER_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"

typedef struct evr_event_writer evr_event_writer;

struct evr_event_writer {
    /* Appends n events (sorted by t, and t not below any earlier call's). */
    evr_status (*write)(evr_event_writer *w, const evr_event *ev, size_t n, evr_error *err);
    /* Makes what has been written durable, so a killed run keeps it (the simulation calls it
     * about once a second: write_queue.h); the HDF5 writer keeps its last partial chunk's events
     * (fewer than 65,536) in memory, so that the timing of flushes changes no byte of its file. */
    evr_status (*flush)(evr_event_writer *w, evr_error *err);
    /* Completes the file; duration_us is the simulated time span (for indices such as ms_to_idx).
     * Frees the writer whatever the result. */
    evr_status (*finish)(evr_event_writer *w, int64_t duration_us, evr_error *err);
    /* Removes the partial file and frees the writer. */
    void (*abort)(evr_event_writer *w);
    /* Ends the file of a run that failed or stopped short (a failed write() or flush() of this
     * writer or another, or a failure elsewhere): keeps exactly the first `events` events it was
     * given, completes the file as finish() does (the HDF5 file's attribute complete stays 0)
     * and renames it to its final name. `events` is what every writer of the run took: all this
     * one was given, or all but the events of its last write() call. A writer that cannot hold
     * to that (the events are lost, or the file cannot be written) removes its file and says
     * why. Frees the writer whatever the result. */
    evr_status (*salvage)(evr_event_writer *w, uint64_t events, int64_t duration_us,
                          evr_error *err);
};

/* Metadata every writer may store: image size and the full configuration as JSON text; and
 * what a writer may size its fields by: max_t_us, no event's timestamp is larger (0: unknown;
 * timestamps are never negative). event_ids: the events carry evr_event.id, which the formats
 * with a place for it write, with the instances' names (id i + 1 is inst_node[i], inst_mesh[i]:
 * io/h5_instances.h) where the format can hold them. */
typedef struct {
    int width, height;
    const char *config_json;
    int64_t max_t_us;
    int event_ids;
    const char *const *inst_node, *const *inst_mesh;
    int num_instances;
} evr_writer_meta;

/* path is the final name; writers write to path + ".tmp" until finish(). */
evr_status evr_h5_writer_open(const char *path, const evr_writer_meta *meta, evr_event_writer **out,
                              evr_error *err);
evr_status evr_txt_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err);
evr_status evr_npy_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err);
evr_status evr_evt2_writer_open(const char *path, const evr_writer_meta *meta,
                                evr_event_writer **out, evr_error *err);
evr_status evr_evt3_writer_open(const char *path, const evr_writer_meta *meta,
                                evr_event_writer **out, evr_error *err);
evr_status evr_dat_writer_open(const char *path, const evr_writer_meta *meta,
                               evr_event_writer **out, evr_error *err);
evr_status evr_rosbag_writer_open(const char *path, const evr_writer_meta *meta,
                                  evr_event_writer **out, evr_error *err);
evr_status evr_aedat4_writer_open(const char *path, const evr_writer_meta *meta,
                                  evr_event_writer **out, evr_error *err);
/* AEDAT 4.0 with ZSTD packets instead of LZ4. */
evr_status evr_aedat4_zstd_writer_open(const char *path, const evr_writer_meta *meta,
                                       evr_event_writer **out, evr_error *err);

#endif
