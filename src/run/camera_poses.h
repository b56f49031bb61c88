/* camera_poses.txt in the run folder: the camera's pose as the backends render it (the motion
 * keys of each segment interpolated by core/motion.h), every millisecond of scene time from the
 * run's start to its end, in the TUM format ("t tx ty tz qx qy qz qw": seconds, the position,
 * and the rotation from the camera's optical frame, x right, y down, z forward, to the world),
 * which --camera-path tum:FILE reads back. Written under a temporary name, renamed when the run
 * closes, removed when it fails. */
#ifndef EVR_CAMERA_POSES_H
#define EVR_CAMERA_POSES_H

#include "sim_state.h"

#define EVR_POSE_RATE 1000 /* poses per second of scene time */

/* Creates the temporary file (after the run folder is made). */
evr_status evr_camera_poses_open(evr_sim *sim, evr_error *err);
/* Appends the poses of segment i, whose keys rs holds, at the times k / EVR_POSE_RATE in
 * [t0, t1) (the last segment: [t0, t1]). */
evr_status evr_camera_poses_segment(evr_sim *sim, const evr_render_scene *rs, double t0, double t1,
                                    int last, evr_error *err);
/* Renames the file into place. */
evr_status evr_camera_poses_close(evr_sim *sim, evr_error *err);
/* Removes it (a failed run). */
void evr_camera_poses_discard(evr_sim *sim);

#endif
