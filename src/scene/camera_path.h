/* Camera paths (--camera-path): built-in motions in scene units and seconds, and trajectories
 * from TUM files, applied to the camera's own pose. The camera then moves on a motion track of
 * its own whose keys are fitted per segment by the same code as every node's (evr_motion_fit_keys,
 * scene/anim.c) and interpolated by core/motion.h on both backends.
 *
 * A path is one motion or several joined by '+', applied left to right, each to the pose so far:
 *   orbit[:period=S][:centre=X,Y,Z][:axis=X,Y,Z]  turns the pose about the axis (default +Y)
 *       through the centre (default: --look-at, else the centre of the scene's bounds over its
 *       animation), once per period seconds (default 10; negative: the other way)
 *   dolly[:speed=U][:dir=X,Y,Z]  (or fly) moves the pose along the world direction dir (default:
 *       where the camera looks at the start) at speed scene units per second (default a tenth
 *       of the camera's distance to the centre; negative: backwards)
 *   pan[:rate=D] | pan:amp=D[:period=S]  turns the camera about its own vertical axis, at rate
 *       degrees per second (default 10; positive: to the right), or sweeping back and forth
 *       amp degrees to each side (default 10) once per period seconds (default 4)
 *   tilt[...]  the same about the camera's horizontal axis (positive: up)
 *   shake[:amp=D][:tremor=D][:move=U][:seed=N]  hand-held shake: drift and tremor turns of the
 *       camera about its own axes and small moves along them (docs/camera.md has the spectrum
 *       and why: RMS amp degrees of drift, default 0.25, and tremor degrees at 8-12 Hz,
 *       default 0.02; move scene units of drift, default 0.2% of the camera's distance to the
 *       centre; seed, default the run's)
 *   tum:FILE (or FILE alone, when it has a '.' or '/')  the poses of a TUM trajectory file
 *       (its name without '+'), which replace the camera's own (only first in a path): lines
 *       "t tx ty tz qx qy qz qw" (# comments, blank lines),
 *       t in seconds strictly increasing (the first line is scene time 0), the camera's optical
 *       frame (x right, y down, z forward, as TUM, EuRoC and ESIM) to world, poses between
 *       lines interpolated by core/motion.h (lerp and shortest-arc slerp)
 * Time 0 of the motions is the run's start. */
#ifndef EVR_SCENE_CAMERA_PATH_H
#define EVR_SCENE_CAMERA_PATH_H

#include <stdint.h>
#include "scene/scene.h"

#define EVR_PATH_MAX_MOTIONS 8
#define EVR_SHAKE_WAVES 20 /* sinusoids per axis: 12 of drift, 8 of tremor */

typedef enum {
    EVR_MOTION_ORBIT,
    EVR_MOTION_DOLLY,
    EVR_MOTION_PAN,
    EVR_MOTION_TILT,
    EVR_MOTION_SHAKE,
    EVR_MOTION_TUM
} evr_motion_kind;

typedef struct {
    double freq, amp, phase; /* Hz, radians or scene units, radians */
} evr_wave;

typedef struct {
    evr_motion_kind kind;
    /* parameters; given: bits of EVR_PARAM_* */
    unsigned given;
    double period, speed, rate, amp, tremor, move;
    double centre[3], axis[3], dir[3];
    uint64_t seed;
    /* resolved by evr_camera_path_bind */
    evr_v3 c, a, d;                    /* orbit centre and unit axis; dolly unit direction */
    evr_wave wave[6][EVR_SHAKE_WAVES]; /* shake: turns about x, y, z, then moves along them */
    /* tum */
    int n;
    double *t;            /* n times, relative to the first line */
    evr_motion_key *keys; /* n poses (world from the camera, glTF's camera axes) */
} evr_path_motion;

typedef struct {
    int num;
    evr_path_motion m[EVR_PATH_MAX_MOTIONS];
    double start; /* the run's start: the motions' time 0 */
} evr_camera_path;

/* Reads spec into p (zeroed first; release with evr_camera_path_free). read_files 0 checks the
 * syntax only (a TUM file is not opened). One line in err on a bad spec or file. */
evr_status evr_camera_path_parse(const char *spec, int read_files, evr_camera_path *p,
                                 evr_error *err);
void evr_camera_path_free(evr_camera_path *p);

/* The scene time the path's trajectory file ends at (its span), or -1 without one. */
double evr_camera_path_end(const evr_camera_path *p);

/* What the motions' defaults are made of. */
typedef struct {
    double start, end; /* the run's time range */
    evr_v3 centre;     /* the centre of the scene's bounds over its animation, or --look-at */
    float distance;    /* the camera's distance to the centre at the start */
    uint64_t seed;     /* the run's seed */
} evr_path_context;

/* Resolves the defaults; base(start) is the camera's pose at the start without the path.
 * Fails when a trajectory does not cover [start, end]. */
evr_status evr_camera_path_bind(evr_camera_path *p, const evr_path_context *ctx, evr_m34 base,
                                evr_error *err);

/* The pose at time t of a camera whose own pose is base. */
evr_m34 evr_camera_path_apply(const evr_camera_path *p, double t, evr_m34 base);

/* The times inside (t0, t1) where the path bends (a trajectory's lines) into out (at most
 * cap, after the n already there); returns the new count. */
int evr_camera_path_bends(const evr_camera_path *p, double t0, double t1, double *out, int n,
                          int cap);

#endif
