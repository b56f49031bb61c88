/* The run folder: its creation, the event writers, previews, run.json, and cleanup on failure. */
#ifndef EVR_RUN_FILES_H
#define EVR_RUN_FILES_H

#include "sim_state.h"

evr_status evr_run_dir_prepare(evr_sim *sim, evr_error *err);
evr_status evr_run_writers_open(evr_sim *sim, evr_error *err);
/* Accumulates time-ordered events into the previews' event frames; no event before limit_us is
 * to come after them (INT64_MAX: the run's last), so the windows that end by then are done. */
evr_status evr_run_preview_events(evr_sim *sim, const evr_event *ev, size_t n, int64_t limit_us,
                                  evr_error *err);
/* Whether a segment ending at absolute time t ends a preview window (so its intensities are due). */
int evr_run_preview_due(const evr_sim *sim, double t, int last);
/* At a segment end (absolute time t): writes the intensity previews of the windows it ends. */
evr_status evr_run_preview_intensity(evr_sim *sim, const float *intensity, double t, int last,
                                     evr_error *err);
/* Completes every writer, the last preview and the frames' list, with every event before
 * st.complete_until. When that fails: evr_run_fail's end, or, past the writers' last flush,
 * run.json names the error and the outputs lost (their files removed). */
evr_status evr_run_close(evr_sim *sim, evr_error *err);
/* The end of a run that failed with st (err's message): the files keep every event the writers
 * had all taken (io/event_writer.h, salvage), previews and frames are completed, and run.json
 * says that the run failed, with what it could not keep; if run.json cannot be written, nothing
 * is left (evr_run_dir_discard). st.outputs_kept says which. Returns st, err unchanged. */
evr_status evr_run_fail(evr_sim *sim, evr_status st, evr_error *err);
/* Writes run.json (after evr_run_close, with the statistics final). */
evr_status evr_run_write_json(evr_sim *sim, evr_error *err);
/* Removes what this run wrote (temporary files, previews, the folder if it made it). */
void evr_run_dir_discard(evr_sim *sim);
/* Removes the files evray writes from run folder dir (event files, run.json, previews, their
 * temporary files), leaving any other file: --force starts from there. */
void evr_run_dir_clean(const char *dir);

#endif
