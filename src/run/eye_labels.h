/* eye.txt: eye-tracking labels at 1 kHz for a scene with an eye (README "Ground truth").
 *
 * Any scene names its eye by its nodes: "eyeball" (required: the eye looks along its node's +Z
 * axis, and rotates about its node's origin), "pupil" (required: a disc facing the node's +Z,
 * its meshes' bounds giving the centre and, half their X extent, the radius), "upper_lid" and
 * "lower_lid" (optional: rotating about their nodes' X axes, closing as the upper turns down
 * against the lower). The built-in eye and eye-drift scenes follow it (the blink scene names its
 * eye the same, but its lids blink by morph targets: openness stays 1 there). Per line:
 *
 *   t  gx gy gz  cx cy cz  px py pr  openness  phase
 *
 * g: the gaze direction in the world (unit), c: the same in the camera's optical frame (x right,
 * y down, z forward); p: the pupil's centre in the image (pixels, x right, y down, pixel x's
 * centre at x + 0.5) and radius (the mean projected distance from the centre to four rim points,
 * +-X and +-Y of the disc; NaN behind the camera); openness: 1 - (upper lid's downward rotation
 * relative to the lower, degrees) / EVR_EYE_LID_GAP_DEG, clamped to [0, 1] (1 without lids);
 * phase: 2 blink (openness below EVR_EYE_BLINK_OPEN), else 1 saccade (the eyeball turning faster
 * than EVR_EYE_SACCADE_DEG_S, the I-VT rule), else 0 fixation. */
#ifndef EVR_RUN_EYE_LABELS_H
#define EVR_RUN_EYE_LABELS_H

#include "core/camera.h"
#include "scene/scene.h"

#define EVR_EYE_LID_GAP_DEG 38.0   /* the built-in eye's margins' angular gap at rest */
#define EVR_EYE_BLINK_OPEN 0.8     /* openness below this: a blink */
#define EVR_EYE_SACCADE_DEG_S 30.0 /* eyeball speed above this: a saccade */

typedef struct evr_eye_labels evr_eye_labels;

/* Finds the eye's nodes; an error naming what is missing when the scene has no eye. */
evr_status evr_eye_labels_new(const evr_scene *s, evr_eye_labels **out, evr_error *err);
evr_status evr_eye_labels_open(evr_eye_labels *e, const char *dir, evr_error *err);
/* One line at t, the camera's pose (camera to world, glTF axes) and projection. */
typedef struct {
    double gaze[3], gaze_cam[3], pupil[2], radius, openness;
    int phase;
} evr_eye_sample;
void evr_eye_labels_eval(const evr_eye_labels *e, double t, const evr_m34 *camera,
                         const evr_camera_intr *c, evr_eye_sample *out);
void evr_eye_labels_sample(evr_eye_labels *e, double t, const evr_m34 *camera,
                           const evr_camera_intr *c);
evr_status evr_eye_labels_flush(evr_eye_labels *e, evr_error *err);
/* Commits eye.txt (st: the status so far). */
evr_status evr_eye_labels_close(evr_eye_labels *e, evr_status st, evr_error *err);
void evr_eye_labels_discard(evr_eye_labels *e);
void evr_eye_labels_free(evr_eye_labels *e);

#endif
