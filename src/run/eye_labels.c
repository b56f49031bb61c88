/* eye.txt (run/eye_labels.h): evaluated from the eye's nodes' analytic animation. */
#include "run/eye_labels.h"
#include "core/labels.h"
#include "io/file_commit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EYE_STEP 5e-4 /* seconds: the eyeball's angular speed's central difference */
#define RAD_TO_DEG 57.29577951308232

struct evr_eye_labels {
    const evr_scene *s;
    int eyeball, pupil, upper, lower;
    evr_v3 centre; /* the pupil's centre in its node's space */
    float radius;
    FILE *f;
    char *path, *tmp;
};

static int find_node(const evr_scene *s, const char *name)
{
    for (int i = 0; i < s->num_nodes; i++)
        if (!strcmp(s->nodes[i].name, name)) return i;
    return -1;
}

evr_status evr_eye_labels_new(const evr_scene *s, evr_eye_labels **out, evr_error *err)
{
    *out = NULL;
    int eyeball = find_node(s, "eyeball"), pupil = find_node(s, "pupil");
    if (eyeball < 0 || pupil < 0 || !s->nodes[pupil].has_bounds) {
        snprintf(err->msg, sizeof err->msg,
                 "--eye-labels: the scene has no eye (nodes \"eyeball\" and \"pupil\" with a "
                 "mesh)");
        return EVR_ERR_ARG;
    }
    evr_eye_labels *e = calloc(1, sizeof *e);
    if (!e) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    const evr_node *p = &s->nodes[pupil];
    e->s = s;
    e->eyeball = eyeball;
    e->pupil = pupil;
    e->upper = find_node(s, "upper_lid");
    e->lower = find_node(s, "lower_lid");
    e->centre = evr_v3_scale(evr_v3_add(p->bounds_min, p->bounds_max), 0.5f);
    e->radius = 0.5f * (p->bounds_max.x - p->bounds_min.x);
    *out = e;
    return EVR_OK;
}

evr_status evr_eye_labels_open(evr_eye_labels *e, const char *dir, evr_error *err)
{
    size_t n = strlen(dir) + 9;
    if (!(e->path = malloc(n))) goto nomem;
    snprintf(e->path, n, "%s/eye.txt", dir);
    if (!(e->tmp = evr_file_tmp_name(e->path))) goto nomem;
    if (!(e->f = evr_file_create(e->tmp, "eye.txt", err))) return EVR_ERR_IO;
    fprintf(e->f, "# eye-tracking labels (README \"Ground truth\"); phase 0 fixation, 1 saccade, "
                  "2 blink\n# t gx gy gz cx cy cz px py pr openness phase\n");
    return EVR_OK;
nomem:
    snprintf(err->msg, sizeof err->msg, "out of memory");
    return EVR_ERR_NOMEM;
}

static evr_v3 unit_axis(const evr_m34 *m, int j)
{
    return evr_v3_norm(evr_v3_make(m->m[0][j], m->m[1][j], m->m[2][j]));
}

/* The signed rotation (radians) about X that takes b's frame to a's, seen in b's frame. */
static double x_angle(const evr_m34 *a, const evr_m34 *b)
{
    evr_v3 za = unit_axis(a, 2), zb = unit_axis(b, 2), yb = unit_axis(b, 1);
    /* a's Z in b's (Y, Z) plane: turning down (towards -Y) is positive */
    return atan2(-(double)evr_v3_dot(za, yb), (double)evr_v3_dot(za, zb));
}

void evr_eye_labels_eval(const evr_eye_labels *e, double t, const evr_m34 *camera,
                         const evr_camera_intr *c, evr_eye_sample *o)
{
    const evr_scene *s = e->s;
    double w2c[3][4];
    int i;
    evr_label_world_to_camera(camera, w2c);
    evr_m34 eb = evr_node_world_at(s, e->eyeball, t);
    evr_v3 g = unit_axis(&eb, 2);
    o->gaze[0] = g.x, o->gaze[1] = g.y, o->gaze[2] = g.z;
    double gc[3];
    for (i = 0; i < 3; i++) gc[i] = w2c[i][0] * g.x + w2c[i][1] * g.y + w2c[i][2] * g.z;
    o->gaze_cam[0] = gc[0], o->gaze_cam[1] = -gc[1], o->gaze_cam[2] = -gc[2]; /* optical frame */
    /* the pupil: its centre and four rim points through the camera (a pose of no triangle's:
     * the points themselves as the triangle's first vertex) */
    evr_label_pose pp;
    pp.inst = evr_node_world_at(s, e->pupil, t);
    memcpy(pp.w2c, w2c, sizeof w2c);
    memset(pp.tri, 0, sizeof pp.tri);
    double cx = 0.0, cy = 0.0, x = 0.0, y = 0.0, sum = 0.0;
    int ok;
    pp.tri[0] = e->centre.x, pp.tri[1] = e->centre.y, pp.tri[2] = e->centre.z;
    ok = evr_label_project(c, evr_label_camera_point(&pp, 0.0f, 0.0f), &cx, &cy);
    for (i = 0; ok && i < 4; i++) {
        pp.tri[0] = e->centre.x + (i == 0 ? e->radius : i == 1 ? -e->radius : 0.0f);
        pp.tri[1] = e->centre.y + (i == 2 ? e->radius : i == 3 ? -e->radius : 0.0f);
        ok = evr_label_project(c, evr_label_camera_point(&pp, 0.0f, 0.0f), &x, &y);
        sum += sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy));
    }
    o->pupil[0] = ok ? cx : NAN;
    o->pupil[1] = ok ? cy : NAN;
    o->radius = ok ? 0.25 * sum : NAN;
    o->openness = 1.0;
    if (e->upper >= 0 && e->lower >= 0) {
        evr_m34 up = evr_node_world_at(s, e->upper, t), lo = evr_node_world_at(s, e->lower, t);
        double a = x_angle(&up, &lo) * RAD_TO_DEG;
        double op = 1.0 - a / EVR_EYE_LID_GAP_DEG;
        o->openness = op < 0.0 ? 0.0 : op > 1.0 ? 1.0 : op;
    }
    evr_m34 em = evr_node_world_at(s, e->eyeball, t - EYE_STEP),
            ep = evr_node_world_at(s, e->eyeball, t + EYE_STEP);
    evr_v3 gm = unit_axis(&em, 2), gp = unit_axis(&ep, 2);
    double d = evr_v3_dot(gm, gp);
    d = d > 1.0 ? 1.0 : d < -1.0 ? -1.0 : d;
    const double speed = acos(d) * RAD_TO_DEG / (2.0 * EYE_STEP);
    o->phase = o->openness < EVR_EYE_BLINK_OPEN ? 2 : speed > EVR_EYE_SACCADE_DEG_S ? 1 : 0;
}

void evr_eye_labels_sample(evr_eye_labels *e, double t, const evr_m34 *camera,
                           const evr_camera_intr *c)
{
    evr_eye_sample o;
    evr_eye_labels_eval(e, t, camera, c, &o);
    fprintf(e->f, "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.4f %.4f %.4f %.5f %d\n", t, o.gaze[0],
            o.gaze[1], o.gaze[2], o.gaze_cam[0], o.gaze_cam[1], o.gaze_cam[2], o.pupil[0],
            o.pupil[1], o.radius, o.openness, o.phase);
}

evr_status evr_eye_labels_flush(evr_eye_labels *e, evr_error *err)
{
    if (e->f && (ferror(e->f) || fflush(e->f))) {
        snprintf(err->msg, sizeof err->msg, "cannot write %s", e->tmp);
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

evr_status evr_eye_labels_close(evr_eye_labels *e, evr_status st, evr_error *err)
{
    if (!e->f) return st;
    FILE *f = e->f;
    e->f = NULL;
    return evr_file_commit(f, e->tmp, e->path, st, "eye.txt", err);
}

void evr_eye_labels_discard(evr_eye_labels *e)
{
    if (e->f) evr_file_discard(e->f, e->tmp);
    e->f = NULL;
}

void evr_eye_labels_free(evr_eye_labels *e)
{
    if (!e) return;
    evr_eye_labels_discard(e);
    free(e->path);
    free(e->tmp);
    free(e);
}
