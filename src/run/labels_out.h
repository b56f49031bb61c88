/* Ground truth in the run folder (README "Ground truth"): labels.h5 (dense labels at
 * --labels-fps, from the backends' primary hits through core/labels.h), and at 1 kHz imu.txt and
 * node_poses.txt (--trajectories) and eye.txt (--eye-labels). Each file is written under a
 * temporary name, appended to after every segment, renamed when the run closes and removed
 * when it fails. */
#ifndef EVR_RUN_LABELS_OUT_H
#define EVR_RUN_LABELS_OUT_H

#include "sim_state.h"

#define EVR_TRAJ_RATE 1000 /* trajectory and eye samples per second of scene time */

/* Label times and checks (before the backend exists: NULL state when nothing is wanted). */
evr_status evr_labels_plan(evr_sim *sim, evr_error *err);
/* Label frames of segment i: first index and count. */
void evr_labels_of_segment(const evr_sim *sim, int i, int *first, int *count);
/* Label frame times (absolute), or NULL. */
const double *evr_labels_times(const evr_sim *sim);
/* Creates the files (after the run folder is made). */
evr_status evr_labels_open(evr_sim *sim, evr_error *err);
/* Segment i over [t0, t1] is done: its label frames from hits (the backend's label_hits, NULL
 * without label frames) and the 1 kHz samples in [t0, t1) ([t0, t1] for the last). */
evr_status evr_labels_segment(evr_sim *sim, int i, double t0, double t1, int last,
                              const evr_hit *hits, evr_error *err);
/* Completes and renames every file. */
evr_status evr_labels_close(evr_sim *sim, evr_error *err);
/* Removes the files (a failed run). */
void evr_labels_discard(evr_sim *sim);
void evr_labels_free(evr_sim *sim);

#endif
