/* The run's camera: see camera_rig.h. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/camera_rig.h"
#include "scene/framing.h"

evr_status evr_camera_rig_init(evr_camera_rig *r, const evr_scene *s, int camera,
                               const evr_config *c, evr_error *err)
{
    const evr_camera_desc *cam = &s->cameras[camera];
    memset(r, 0, sizeof *r);
    r->s = s;
    r->node = cam->node;
    r->local = cam->local;
    r->automatic = cam->automatic;
    r->ortho = cam->ortho;
    r->ymag = cam->ymag;
    r->yfov = evr_camera_yfov(cam, (float)c->width / (float)c->height);
    r->size = evr_motion_fit_size(s);
    if (c->fov > 0.0) {
        if (cam->ortho) {
            snprintf(err->msg, sizeof err->msg,
                     "--fov: camera '%s' is orthographic (its view is %g scene units high, not "
                     "an angle)",
                     cam->name, 2.0 * cam->ymag);
            return EVR_ERR_ARG;
        }
        r->yfov = (float)(c->fov * EVR_PI_D / 180.0);
    }
    if (c->camera_path) {
        evr_status st = evr_camera_path_parse(c->camera_path, 1, &r->path, err);
        if (st != EVR_OK) return st;
        r->has_path = 1;
    }
    return EVR_OK;
}

double evr_camera_rig_path_end(const evr_camera_rig *r)
{
    return r->has_path ? evr_camera_path_end(&r->path) : -1.0;
}

static evr_m34 base_pose(const evr_camera_rig *r, double t)
{
    if (r->node < 0) return r->local;
    evr_m34 w = evr_node_world_at(r->s, r->node, t);
    return evr_m34_mul(w, r->local);
}

static int path_orbits(const evr_camera_rig *r)
{
    for (int i = 0; r->has_path && i < r->path.num; i++)
        if (r->path.m[i].kind == EVR_MOTION_ORBIT) return 1;
    return 0;
}

static evr_v3 position(const evr_m34 *m) { return evr_v3_make(m->m[0][3], m->m[1][3], m->m[2][3]); }

evr_status evr_camera_rig_setup(evr_camera_rig *r, const evr_config *c, double start, double end,
                                evr_error *err)
{
    const evr_scene *s = r->s;
    const float aspect = (float)c->width / (float)c->height;
    evr_v3 lo, hi;
    if (!r->automatic && !c->look_from_set && !c->look_at_set && !r->has_path) return EVR_OK;
    /* the scene over its whole animation (its rest bounds when that fails) */
    (void)evr_frame_swept_bounds(s, s->anim_start, s->anim_end, &lo, &hi);
    const evr_v3 centre = c->look_at_set ? evr_v3_make((float)c->look_at[0], (float)c->look_at[1],
                                                       (float)c->look_at[2])
                                         : evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
    if (r->automatic) {
        /* framed again for this image, this field of view, and all around for an orbit; from
         * the direction the import chose (the camera's +Z points back at it) */
        const evr_v3 dir =
            evr_v3_norm(evr_v3_make(r->local.m[0][2], r->local.m[1][2], r->local.m[2][2]));
        r->local = evr_frame_box(lo, hi, dir, r->yfov, aspect, path_orbits(r), NULL);
    }
    if (c->look_from_set || c->look_at_set) {
        const evr_m34 now = base_pose(r, start);
        const evr_v3 from = c->look_from_set
                                ? evr_v3_make((float)c->look_from[0], (float)c->look_from[1],
                                              (float)c->look_from[2])
                                : position(&now);
        if (evr_v3_len(evr_v3_sub(centre, from)) == 0.0f) {
            snprintf(err->msg, sizeof err->msg,
                     "--look-from: the camera would sit at the point it looks at (%g, %g, %g)",
                     centre.x, centre.y, centre.z);
            return EVR_ERR_ARG;
        }
        r->local = evr_frame_look_at(from, centre);
        r->node = -1;
    }
    if (!r->has_path) return EVR_OK;
    const evr_m34 base = base_pose(r, start);
    evr_path_context ctx;
    ctx.start = start;
    ctx.end = end;
    ctx.centre = centre;
    ctx.distance = evr_v3_len(evr_v3_sub(position(&base), centre));
    if (!(ctx.distance > 0.0f)) ctx.distance = r->size;
    ctx.seed = c->seed;
    return evr_camera_path_bind(&r->path, &ctx, base, err);
}

void evr_camera_rig_free(evr_camera_rig *r) { evr_camera_path_free(&r->path); }

evr_m34 evr_camera_rig_pose(const evr_camera_rig *r, double t)
{
    return evr_camera_path_apply(&r->path, t, base_pose(r, t));
}

static evr_m34 rig_pose_at(const void *user, double t)
{
    return evr_camera_rig_pose((const evr_camera_rig *)user, t);
}

int evr_camera_rig_keys(const evr_camera_rig *r, double t0, double t1, float tol,
                        evr_motion_key *keys, int max_keys)
{
    evr_v3 probes[4];
    double inner[EVR_MAX_INNER_TIMES];
    evr_motion_fit fit;
    int n = 0;
    memset(&fit, 0, sizeof fit);
    fit.pose = rig_pose_at;
    fit.user = r;
    fit.moves = r->has_path || evr_node_chain_animated(r->s, r->node);
    fit.limit = (tol > 0.0f ? tol : 1e-4f) * r->size;
    fit.probes = probes;
    fit.num_probes = evr_motion_frame_probes(r->size, probes);
    if (r->node >= 0)
        n = evr_node_inner_key_times(r->s, r->node, t0, t1, inner, n, EVR_MAX_INNER_TIMES);
    n = evr_camera_path_bends(&r->path, t0, t1, inner, n, EVR_MAX_INNER_TIMES);
    fit.inner = inner;
    fit.num_inner = n;
    return evr_motion_fit_keys(&fit, t0, t1, keys, max_keys);
}
