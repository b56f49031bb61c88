/* camera_poses.txt: see camera_poses.h. */
#include "run/camera_poses.h"
#include "io/file_commit.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const WHO = "camera poses";

evr_status evr_camera_poses_open(evr_sim *sim, evr_error *err)
{
    char path[4200];
    if ((size_t)snprintf(path, sizeof path, "%s/camera_poses.txt", sim->out_dir) >= sizeof path) {
        snprintf(err->msg, sizeof err->msg, "output path too long: %s", sim->out_dir);
        return EVR_ERR_ARG;
    }
    sim->poses_tmp = evr_file_tmp_name(path);
    if (!sim->poses_tmp) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    if (!(sim->poses = evr_file_create(sim->poses_tmp, WHO, err))) return EVR_ERR_IO;
    fputs("# evray camera poses, TUM format: t tx ty tz qx qy qz qw (seconds of scene time; "
          "the camera's optical frame, x right, y down, z forward, to the world)\n",
          sim->poses);
    return EVR_OK;
}

evr_status evr_camera_poses_segment(evr_sim *sim, const evr_render_scene *rs, double t0, double t1,
                                    int last, evr_error *err)
{
    if (!sim->poses) return EVR_OK;
    const double r = EVR_POSE_RATE;
    const long long k0 = (long long)ceil(t0 * r - 1e-6);
    const long long k1 =
        last ? (long long)floor(t1 * r + 1e-6) : (long long)ceil(t1 * r - 1e-6) - 1;
    for (long long k = k0; k <= k1; k++) {
        const double t = (double)k / r;
        const float f = t1 > t0 ? (float)((t - t0) / (t1 - t0)) : 0.0f;
        const evr_m34 pose = evr_rs_camera_pose(rs, f);
        const evr_motion_key key = evr_motion_key_from_matrix(&pose); /* the rotation, unscaled */
        /* glTF's camera axes (y up, z backward) turned half a turn about x: the optical frame */
        evr_quat q = evr_quat_normalize(evr_quat_mul(key.rot, evr_quat_make(0, 1, 0, 0)));
        if (evr_quat_dot(q, sim->poses_last) < 0.0f) q = evr_quat_make(-q.w, -q.x, -q.y, -q.z);
        sim->poses_last = q;
        if (fprintf(sim->poses, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", t, pose.m[0][3],
                    pose.m[1][3], pose.m[2][3], q.x, q.y, q.z, q.w) < 0) {
            snprintf(err->msg, sizeof err->msg, "%s: cannot write %s: %s", WHO, sim->poses_tmp,
                     strerror(errno));
            return EVR_ERR_IO;
        }
    }
    return EVR_OK;
}

evr_status evr_camera_poses_close(evr_sim *sim, evr_error *err)
{
    char path[4200];
    if (!sim->poses) return EVR_OK;
    snprintf(path, sizeof path, "%s/camera_poses.txt", sim->out_dir);
    evr_status st = evr_file_commit(sim->poses, sim->poses_tmp, path, EVR_OK, WHO, err);
    sim->poses = NULL;
    return st;
}

void evr_camera_poses_discard(evr_sim *sim)
{
    if (sim->poses) evr_file_discard(sim->poses, sim->poses_tmp);
    sim->poses = NULL;
}
