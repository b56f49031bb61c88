/* Animation evaluation: curves -> local transforms -> world transforms -> per-segment motion keys.
 *
 * Curves hold key times in seconds (the importer converts Assimp's ticks). LINEAR curves lerp
 * translation and scale and slerp rotation along the shortest arc (as glTF specifies); STEP
 * curves hold the previous key; before the first and after the last key a curve is clamped.
 * A node without curves uses its rest matrix exactly (it may hold skew); a node with some curves
 * takes the missing properties from its rest translation, rotation and scale. */
#include <math.h>
#include <string.h>
#include "scene/scene.h"

/* Index i of the interval [times[i], times[i+1]) holding t, for 0 < i+1 < n; the caller has
 * handled t before the first and after the last key. */
static int curve_interval(const evr_curve *c, double t)
{
    int lo = 0, hi = c->num_keys - 1; /* times[lo] <= t < times[hi] */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (c->times[mid] <= t) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Evaluates a translation or scale curve. */
static evr_v3 curve_v3(const evr_curve *c, double t)
{
    const float *v = c->values;
    int n = c->num_keys, i;
    if (n == 1 || t <= c->times[0]) return evr_v3_make(v[0], v[1], v[2]);
    if (t >= c->times[n - 1])
        return evr_v3_make(v[3 * (n - 1)], v[3 * (n - 1) + 1], v[3 * (n - 1) + 2]);
    i = curve_interval(c, t);
    {
        const float *a = v + 3 * i, *b = v + 3 * (i + 1);
        double dt = c->times[i + 1] - c->times[i];
        float f;
        /* a value held between two equal keys is held exactly (float lerp can be off in the last
         * bit, which would count as motion) */
        if (c->interp == EVR_INTERP_STEP || dt <= 0.0 || !memcmp(a, b, 3 * sizeof *a))
            return evr_v3_make(a[0], a[1], a[2]);
        f = (float)((t - c->times[i]) / dt);
        return evr_v3_lerp(evr_v3_make(a[0], a[1], a[2]), evr_v3_make(b[0], b[1], b[2]), f);
    }
}

/* Evaluates a rotation curve (w x y z per key). */
static evr_quat curve_quat(const evr_curve *c, double t)
{
    const float *v = c->values;
    int n = c->num_keys, i;
    if (n == 1 || t <= c->times[0]) return evr_quat_make(v[0], v[1], v[2], v[3]);
    if (t >= c->times[n - 1]) {
        const float *l = v + 4 * (n - 1);
        return evr_quat_make(l[0], l[1], l[2], l[3]);
    }
    i = curve_interval(c, t);
    {
        const float *a = v + 4 * i, *b = v + 4 * (i + 1);
        double dt = c->times[i + 1] - c->times[i];
        evr_quat qa = evr_quat_make(a[0], a[1], a[2], a[3]);
        if (c->interp == EVR_INTERP_STEP || dt <= 0.0 || !memcmp(a, b, 4 * sizeof *a))
            return qa; /* held exactly */
        return evr_quat_slerp(qa, evr_quat_make(b[0], b[1], b[2], b[3]),
                              (float)((t - c->times[i]) / dt));
    }
}

/* T * R * S as a matrix. */
static evr_m34 trs_matrix(evr_v3 t, evr_quat q, evr_v3 s)
{
    float r[3][3];
    evr_m34 m;
    int i;
    evr_quat_to_m33(evr_quat_normalize(q), r);
    for (i = 0; i < 3; i++) {
        m.m[i][0] = r[i][0] * s.x;
        m.m[i][1] = r[i][1] * s.y;
        m.m[i][2] = r[i][2] * s.z;
    }
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    return m;
}

evr_m34 evr_node_local_at(const evr_node *n, double t)
{
    evr_v3 tr, sc;
    evr_quat q;
    if (n->t_curve.num_keys <= 0 && n->r_curve.num_keys <= 0 && n->s_curve.num_keys <= 0)
        return n->rest_matrix;
    tr = n->t_curve.num_keys > 0 ? curve_v3(&n->t_curve, t) : n->translation;
    q = n->r_curve.num_keys > 0 ? curve_quat(&n->r_curve, t) : n->rotation;
    sc = n->s_curve.num_keys > 0 ? curve_v3(&n->s_curve, t) : n->scale;
    return trs_matrix(tr, q, sc);
}

evr_m34 evr_node_world_at(const evr_scene *s, int node, double t)
{
    evr_m34 m = evr_m34_identity();
    int guard = 0;
    if (!s || node < 0 || node >= s->num_nodes) return m;
    m = evr_node_local_at(&s->nodes[node], t);
    node = s->nodes[node].parent;
    /* The importer gives parents smaller indices than their children; the guard only protects
     * against a hand-made scene with a cycle. */
    while (node >= 0 && node < s->num_nodes && guard++ < s->num_nodes) {
        m = evr_m34_mul(evr_node_local_at(&s->nodes[node], t), m);
        node = s->nodes[node].parent;
    }
    return m;
}

/* ---- motion keys ---- */

int evr_node_chain_animated(const evr_scene *s, int node)
{
    int guard = 0;
    while (node >= 0 && node < s->num_nodes && guard++ <= s->num_nodes) {
        if (s->nodes[node].animated) return 1;
        node = s->nodes[node].parent;
    }
    return 0;
}

/* The probe points whose motion must be reproduced: the corners of the node's mesh bounds (when
 * it places meshes) and its origin and unit axes scaled by the scene size (so that rotation is
 * checked even for a node whose mesh is tiny, and for cameras, lights and groups). Returns the
 * count (at most 12). */
static int probe_points(const evr_scene *s, int node, float size, evr_v3 *p)
{
    const evr_node *n = &s->nodes[node];
    int i, np = 0;
    if (n->has_bounds) {
        for (i = 0; i < 8; i++)
            p[np++] = evr_v3_make((i & 1) ? n->bounds_max.x : n->bounds_min.x,
                                  (i & 2) ? n->bounds_max.y : n->bounds_min.y,
                                  (i & 4) ? n->bounds_max.z : n->bounds_min.z);
    }
    return np + evr_motion_frame_probes(size, p + np);
}

/* Largest distance between where a and b put the probe points. */
static float probe_error(const evr_m34 *a, const evr_m34 *b, const evr_v3 *p, int np)
{
    float worst = 0.0f;
    int i;
    for (i = 0; i < np; i++) {
        float d = evr_v3_len(evr_v3_sub(evr_m34_point(a, p[i]), evr_m34_point(b, p[i])));
        if (d > worst || d != d) worst = (d != d) ? INFINITY : d;
    }
    return worst;
}

int evr_node_inner_key_times(const evr_scene *s, int node, double t0, double t1, double *out, int n,
                             int cap)
{
    int guard = 0;
    while (node >= 0 && node < s->num_nodes && guard++ <= s->num_nodes) {
        const evr_node *nd = &s->nodes[node];
        const evr_curve *cv[3];
        int c, k;
        cv[0] = &nd->t_curve;
        cv[1] = &nd->r_curve;
        cv[2] = &nd->s_curve;
        for (c = 0; c < 3; c++) {
            for (k = 0; k < cv[c]->num_keys && n < cap; k++) {
                double tk = cv[c]->times[k];
                if (tk > t0 && tk < t1) out[n++] = tk;
            }
        }
        node = nd->parent;
    }
    return n;
}

/* Rotation step between two unit quaternions is below 120 degrees: |dot| > cos(60 degrees). */
static int rotation_step_ok(evr_quat a, evr_quat b) { return fabsf(evr_quat_dot(a, b)) > 0.5f; }

int evr_motion_fit_keys(const evr_motion_fit *fit, double t0, double t1, evr_motion_key *keys,
                        int max_keys)
{
    const evr_v3 *probes = fit->probes;
    const double *inner = fit->inner;
    const int np = fit->num_probes, ninner = fit->num_inner;
    const float limit = fit->limit;
    int cap, n, i, k;

    if (!keys || max_keys < 1) return 0;
    {
        evr_m34 m0 = fit->pose(fit->user, t0);
        keys[0] = evr_motion_key_from_matrix(&m0);
    }
    if (max_keys < 2 || !(t1 > t0) || !fit->moves) return 1;

    /* Largest 2^k + 1 that fits. */
    cap = 2;
    while ((cap - 1) * 2 + 1 <= max_keys) cap = (cap - 1) * 2 + 1;

    /* Start with the two end keys, then double the number of intervals, reusing old keys. */
    {
        evr_m34 m1 = fit->pose(fit->user, t1);
        keys[1] = evr_motion_key_from_matrix(&m1);
    }
    n = 2;
    for (;;) {
        int ok = 1;
        evr_motion_track tr;
        double span = t1 - t0;

        /* Shortest arcs: neighbouring quaternions in the same hemisphere. */
        for (i = 1; i < n; i++) {
            if (evr_quat_dot(keys[i - 1].rot, keys[i].rot) < 0.0f) {
                keys[i].rot =
                    evr_quat_make(-keys[i].rot.w, -keys[i].rot.x, -keys[i].rot.y, -keys[i].rot.z);
            }
        }
        for (i = 1; i < n && ok; i++) ok = rotation_step_ok(keys[i - 1].rot, keys[i].rot);

        tr.keys = keys;
        tr.n = n;
        /* Quarter, middle and three-quarter points of every interval. */
        for (i = 0; i + 1 < n && ok; i++) {
            static const double fr[3] = {0.25, 0.5, 0.75};
            for (k = 0; k < 3 && ok; k++) {
                double f = ((double)i + fr[k]) / (double)(n - 1);
                evr_m34 truth = fit->pose(fit->user, t0 + span * f);
                evr_m34 approx = evr_motion_eval(tr, (float)f);
                if (probe_error(&truth, &approx, probes, np) > limit) ok = 0;
            }
        }
        /* Where the motion bends. */
        for (i = 0; i < ninner && ok; i++) {
            double f = (inner[i] - t0) / span;
            evr_m34 truth = fit->pose(fit->user, inner[i]);
            evr_m34 approx = evr_motion_eval(tr, (float)f);
            if (probe_error(&truth, &approx, probes, np) > limit) ok = 0;
        }

        if (ok && n == 2) {
            /* Still in the segment (every checked point where the first key is): one key. The
             * world matrices are compared, not the keys' matrices (a key's rebuilt matrix is off
             * by rounding from the matrix it came from). */
            evr_m34 a = fit->pose(fit->user, t0), b = fit->pose(fit->user, t1);
            if (probe_error(&a, &b, probes, np) <= limit * 1e-3f) {
                int still = 1;
                for (i = 0; i < ninner && still; i++) {
                    evr_m34 m = fit->pose(fit->user, inner[i]);
                    if (probe_error(&a, &m, probes, np) > limit * 1e-3f) still = 0;
                }
                for (k = 1; k < 4 && still; k++) {
                    evr_m34 m = fit->pose(fit->user, t0 + span * 0.25 * k);
                    if (probe_error(&a, &m, probes, np) > limit * 1e-3f) still = 0;
                }
                if (still) return 1;
            }
        }
        if (ok || n >= cap) return n;

        /* Double: old key j moves to 2j, new keys at the odd places. */
        {
            int n2 = (n - 1) * 2 + 1;
            for (i = n - 1; i >= 1; i--) keys[2 * i] = keys[i];
            for (i = 1; i < n2; i += 2) {
                evr_m34 m = fit->pose(fit->user, t0 + span * (double)i / (double)(n2 - 1));
                keys[i] = evr_motion_key_from_matrix(&m);
            }
            n = n2;
        }
    }
}

float evr_motion_fit_size(const evr_scene *s)
{
    evr_v3 ext = evr_v3_sub(s->bounds_max, s->bounds_min);
    float size = evr_v3_len(ext);
    if (!(size > 0.0f) || !isfinite(size)) size = 1.0f;
    return size;
}

int evr_motion_frame_probes(float size, evr_v3 *p)
{
    p[0] = evr_v3_make(0, 0, 0);
    p[1] = evr_v3_make(size, 0, 0);
    p[2] = evr_v3_make(0, size, 0);
    p[3] = evr_v3_make(0, 0, size);
    return 4;
}

typedef struct {
    const evr_scene *s;
    int node;
} node_pose;

static evr_m34 node_pose_at(const void *user, double t)
{
    const node_pose *np = user;
    return evr_node_world_at(np->s, np->node, t);
}

int evr_node_motion_keys(const evr_scene *s, int node, double t0, double t1, float tol,
                         evr_motion_key *keys, int max_keys)
{
    evr_v3 probes[12];
    double inner[EVR_MAX_INNER_TIMES];
    node_pose np = {s, node};
    evr_motion_fit fit;
    float size;

    if (!s || !keys || max_keys < 1) return 0;
    memset(&fit, 0, sizeof fit);
    fit.pose = node_pose_at;
    fit.user = &np;
    fit.moves = node >= 0 && node < s->num_nodes && evr_node_chain_animated(s, node);
    if (fit.moves && max_keys >= 2 && t1 > t0) {
        size = evr_motion_fit_size(s);
        fit.limit = (tol > 0.0f ? tol : 1e-4f) * size;
        fit.probes = probes;
        fit.num_probes = probe_points(s, node, size, probes);
        fit.inner = inner;
        fit.num_inner = evr_node_inner_key_times(s, node, t0, t1, inner, 0, EVR_MAX_INNER_TIMES);
    }
    return evr_motion_fit_keys(&fit, t0, t1, keys, max_keys);
}
