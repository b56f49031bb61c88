/* The camera a run renders through: the scene's camera with the configuration's overrides
 * (--fov, --look-from, --look-at), the automatic camera framed for the run's image, and the
 * camera path on top (--camera-path, scene/camera_path.h).
 *
 * Its pose at time t: the base pose (the camera node's world transform at t times the camera's
 * pose in its node; or a fixed world pose: --look-from/--look-at, or the automatic camera), then
 * the path's motions applied to it in order. So a path composes with the camera's own motion
 * (an animated camera keeps its animation, the path moves it further), except a trajectory file,
 * whose poses replace it; --look-from/--look-at replace the camera's own motion by a fixed pose
 * that the path then moves. */
#ifndef EVR_SCENE_CAMERA_RIG_H
#define EVR_SCENE_CAMERA_RIG_H

#include "scene/camera_path.h"

typedef struct {
    const evr_scene *s;
    int node;      /* the base pose: node's world transform at t times local; -1: local alone */
    evr_m34 local; /* the camera's pose in node's space (or the world) */
    int automatic; /* the automatic camera (the scene has none): framed for the run */
    int has_path;  /* the camera moves on a track of its own (evr_camera_rig_keys) */
    evr_camera_path path;
    int ortho;        /* the projection: orthographic with half height ymag */
    float yfov, ymag; /* radians; scene units */
    float size;       /* the scene's size (the key fitting's tolerance is relative to it) */
} evr_camera_rig;

/* Reads the camera and the path of configuration c (a trajectory file included). */
evr_status evr_camera_rig_init(evr_camera_rig *r, const evr_scene *s, int camera,
                               const evr_config *c, evr_error *err);
/* The scene time the path's trajectory ends at (the default end of a run of a still scene), or
 * -1 without one. */
double evr_camera_rig_path_end(const evr_camera_rig *r);
/* Frames and aims the camera for a run over [start, end] on a width x height image and binds
 * the path's defaults. */
evr_status evr_camera_rig_setup(evr_camera_rig *r, const evr_config *c, double start, double end,
                                evr_error *err);
void evr_camera_rig_free(evr_camera_rig *r);

/* The camera's pose at time t (world from camera, glTF's camera axes). */
evr_m34 evr_camera_rig_pose(const evr_camera_rig *r, double t);
/* Motion keys of that pose over [t0, t1] (evr_motion_fit_keys, tolerance tol of the scene's
 * size); returns their count. */
int evr_camera_rig_keys(const evr_camera_rig *r, double t0, double t1, float tol,
                        evr_motion_key *keys, int max_keys);

#endif
