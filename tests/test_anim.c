/* Animation evaluation (scene/anim.c) and the animation side of the importer: interpolation
 * modes, shortest-arc slerp, hierarchy composition, motion keys for fast spins, and the Assimp
 * 5.2 glTF quirks (a) key times in ms, (d) CUBICSPLINE, (e) matrix nodes and synthesized keys,
 * and STEP samplers. Scene files: tests/data/import/ (made by make_data.py there). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "scene/scene.h"

#define DATA EVR_TEST_DATA "/import/"
#define PI_D 3.14159265358979323846

/* ---- helpers ---- */

static int node_index(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_nodes; i++)
        if (!strcmp(s->nodes[i].name, name)) return i;
    fprintf(stderr, "no node named %s\n", name);
    return -1;
}

static evr_v3 world_pos(const evr_scene *s, int node, double t)
{
    evr_m34 m = evr_node_world_at(s, node, t);
    return evr_v3_make(m.m[0][3], m.m[1][3], m.m[2][3]);
}

static double m34_maxdiff(const evr_m34 *a, const evr_m34 *b)
{
    double d = 0;
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++) d = fmax(d, fabs((double)a->m[i][j] - (double)b->m[i][j]));
    return d;
}

/* Rotation about a unit axis as a quaternion (w x y z). */
static evr_quat qaxis(double x, double y, double z, double deg)
{
    double h = deg * PI_D / 360.0;
    return evr_quat_make((float)cos(h), (float)(x * sin(h)), (float)(y * sin(h)),
                         (float)(z * sin(h)));
}

static evr_m34 trs(evr_v3 t, evr_quat q, evr_v3 s)
{
    float r[3][3];
    evr_m34 m;
    int i;
    evr_quat_to_m33(q, r);
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

/* A hand-made node at rest (identity TRS), curves added by the tests. */
static void node_init(evr_node *n, const char *name, int parent)
{
    memset(n, 0, sizeof *n);
    snprintf(n->name, sizeof n->name, "%s", name);
    n->parent = parent;
    n->scale = evr_v3_make(1, 1, 1);
    n->rotation = evr_quat_make(1, 0, 0, 0);
    n->rest_matrix = evr_m34_identity();
}

/* ---- evaluation rules on hand-made nodes ---- */

static void test_handmade(void)
{
    double tt[3] = {0.0, 1.0, 2.0};
    float tv[9] = {0, 0, 0, 2, 4, 0, 2, 4, 6};
    float sv[6] = {1, 1, 1, 3, 1, 2};
    double st[2] = {0.0, 2.0};
    evr_node n;
    evr_m34 m;

    /* LINEAR translation: lerp inside, clamp outside */
    node_init(&n, "t", -1);
    n.animated = 1;
    n.t_curve.num_keys = 3;
    n.t_curve.times = tt;
    n.t_curve.values = tv;
    n.t_curve.interp = EVR_INTERP_LINEAR;
    m = evr_node_local_at(&n, 0.5);
    CHECK_NEAR(m.m[0][3], 1.0, 1e-6);
    CHECK_NEAR(m.m[1][3], 2.0, 1e-6);
    CHECK_NEAR(m.m[2][3], 0.0, 1e-6);
    m = evr_node_local_at(&n, 1.5);
    CHECK_NEAR(m.m[0][3], 2.0, 1e-6);
    CHECK_NEAR(m.m[1][3], 4.0, 1e-6);
    CHECK_NEAR(m.m[2][3], 3.0, 1e-6);
    m = evr_node_local_at(&n, -5.0);
    CHECK_NEAR(m.m[0][3], 0.0, 1e-6);
    m = evr_node_local_at(&n, 9.0);
    CHECK_NEAR(m.m[2][3], 6.0, 1e-6);
    /* STEP holds the previous key, switches exactly at the key time */
    n.t_curve.interp = EVR_INTERP_STEP;
    m = evr_node_local_at(&n, 0.999);
    CHECK_NEAR(m.m[0][3], 0.0, 1e-6);
    m = evr_node_local_at(&n, 1.0);
    CHECK_NEAR(m.m[0][3], 2.0, 1e-6);
    CHECK_NEAR(m.m[1][3], 4.0, 1e-6);
    m = evr_node_local_at(&n, 1.999);
    CHECK_NEAR(m.m[2][3], 0.0, 1e-6);
    /* rotation and scale absent: the rest values (identity here), no skew */
    CHECK_NEAR(m.m[0][0], 1.0, 1e-7);
    CHECK_NEAR(m.m[0][1], 0.0, 1e-7);

    /* scale LINEAR and STEP; translation falls back to the rest translation */
    node_init(&n, "s", -1);
    n.translation = evr_v3_make(7, 8, 9);
    n.s_curve.num_keys = 2;
    n.s_curve.times = st;
    n.s_curve.values = sv;
    n.s_curve.interp = EVR_INTERP_LINEAR;
    m = evr_node_local_at(&n, 1.0);
    CHECK_NEAR(m.m[0][0], 2.0, 1e-6);
    CHECK_NEAR(m.m[1][1], 1.0, 1e-6);
    CHECK_NEAR(m.m[2][2], 1.5, 1e-6);
    CHECK_NEAR(m.m[0][3], 7.0, 1e-6);
    CHECK_NEAR(m.m[2][3], 9.0, 1e-6);
    n.s_curve.interp = EVR_INTERP_STEP;
    m = evr_node_local_at(&n, 1.9);
    CHECK_NEAR(m.m[0][0], 1.0, 1e-6);
    m = evr_node_local_at(&n, 2.0);
    CHECK_NEAR(m.m[0][0], 3.0, 1e-6);
    CHECK_NEAR(m.m[2][2], 2.0, 1e-6);

    /* rotation keys q and -q are the same rotation: no motion in between */
    {
        float rv[8] = {1, 0, 0, 0, -1, 0, 0, 0};
        double rt[2] = {0.0, 1.0};
        node_init(&n, "r", -1);
        n.r_curve.num_keys = 2;
        n.r_curve.times = rt;
        n.r_curve.values = rv;
        m = evr_node_local_at(&n, 0.5);
        CHECK_NEAR(m.m[0][0], 1.0, 1e-6);
        CHECK_NEAR(m.m[1][1], 1.0, 1e-6);
        CHECK_NEAR(m.m[2][2], 1.0, 1e-6);
    }
    /* shortest arc: identity to -(90 degrees about Z) turns +45 at the middle, not -135 */
    {
        evr_quat q = qaxis(0, 0, 1, 90);
        float rv[8] = {1, 0, 0, 0, 0, 0, 0, 0};
        double rt[2] = {0.0, 1.0};
        rv[4] = -q.w;
        rv[5] = -q.x;
        rv[6] = -q.y;
        rv[7] = -q.z;
        node_init(&n, "r", -1);
        n.r_curve.num_keys = 2;
        n.r_curve.times = rt;
        n.r_curve.values = rv;
        m = evr_node_local_at(&n, 0.5);
        CHECK_NEAR(m.m[0][0], cos(PI_D / 4), 1e-6); /* x axis -> (cos 45, sin 45, 0) */
        CHECK_NEAR(m.m[1][0], sin(PI_D / 4), 1e-6);
    }
    /* no curves: the rest matrix exactly, skew included */
    {
        evr_m34 r = evr_m34_identity();
        r.m[0][1] = 0.5f;
        r.m[1][1] = 2.0f;
        r.m[2][2] = 3.0f;
        r.m[0][3] = 4.0f;
        node_init(&n, "m", -1);
        n.rest_matrix = r;
        m = evr_node_local_at(&n, 0.3);
        CHECK(m34_maxdiff(&m, &r) == 0.0);
    }
    /* parent * child */
    {
        evr_scene s;
        evr_node nodes[2];
        evr_m34 w, e;
        memset(&s, 0, sizeof s);
        node_init(&nodes[0], "p", -1);
        node_init(&nodes[1], "c", 0);
        nodes[0].rest_matrix = trs(evr_v3_make(0, 1, 0), qaxis(0, 1, 0, 90), evr_v3_make(2, 2, 2));
        nodes[1].rest_matrix = trs(evr_v3_make(1, 0, 0), qaxis(1, 0, 0, 30), evr_v3_make(1, 1, 1));
        s.nodes = nodes;
        s.num_nodes = 2;
        w = evr_node_world_at(&s, 1, 0.0);
        e = evr_m34_mul(nodes[0].rest_matrix, nodes[1].rest_matrix);
        CHECK(m34_maxdiff(&w, &e) < 1e-6);
        CHECK_NEAR(w.m[0][3], 0.0, 1e-6); /* (1,0,0) scaled 2, turned 90 about Y -> (0,0,-2) */
        CHECK_NEAR(w.m[1][3], 1.0, 1e-6);
        CHECK_NEAR(w.m[2][3], -2.0, 1e-6);
        /* a static hierarchy: one motion key */
        {
            evr_motion_key k[9];
            s.bounds_max = evr_v3_make(1, 1, 1);
            CHECK(evr_node_motion_keys(&s, 1, 0.0, 1.0, 1e-4f, k, 9) == 1);
            w = evr_motion_key_matrix(&k[0]);
            CHECK(m34_maxdiff(&w, &e) < 1e-5);
        }
    }
}

/* ---- imported animation: interpolation modes and quirks ---- */

static void test_imported(const evr_scene *s)
{
    int lin_t = node_index(s, "lin_t"), lin_s = node_index(s, "lin_s"),
        step_t = node_index(s, "step_t");
    int step_s = node_index(s, "step_s"), slerp = node_index(s, "slerp"),
        cubic = node_index(s, "cubic");
    int mat_skew = node_index(s, "mat_skew"), mat_anim = node_index(s, "mat_anim"),
        trs_rot = node_index(s, "trs_rot");
    int parent = node_index(s, "parent"), child = node_index(s, "child");
    evr_v3 p;
    evr_m34 m, e;
    if (lin_t < 0 || lin_s < 0 || step_t < 0 || step_s < 0 || slerp < 0 || cubic < 0 ||
        mat_skew < 0 || mat_anim < 0 || trs_rot < 0 || parent < 0 || child < 0) {
        CHECK(!"anim.gltf nodes missing");
        return;
    }

    /* quirk (a): Assimp's glTF key times are milliseconds (mTicksPerSecond 1000); ours seconds */
    CHECK(s->nodes[lin_t].t_curve.num_keys == 3);
    if (s->nodes[lin_t].t_curve.num_keys == 3) {
        CHECK_NEAR(s->nodes[lin_t].t_curve.times[1], 1.0, 1e-6);
        CHECK_NEAR(s->nodes[lin_t].t_curve.times[2], 2.0, 1e-6);
    }
    CHECK_NEAR(s->anim_start, 0.0, 1e-9);
    CHECK_NEAR(s->anim_end, 2.0, 1e-6);
    CHECK(s->frame_rate == 0.0); /* glTF has none */
    CHECK(s->num_animations == 1);

    /* LINEAR translation and scale */
    p = world_pos(s, lin_t, 0.5);
    CHECK_NEAR(p.x, 1.0, 1e-5);
    CHECK_NEAR(p.y, 2.0, 1e-5);
    CHECK_NEAR(p.z, 0.0, 1e-5);
    p = world_pos(s, lin_t, 1.5);
    CHECK_NEAR(p.x, 2.0, 1e-5);
    CHECK_NEAR(p.y, 4.0, 1e-5);
    CHECK_NEAR(p.z, 3.0, 1e-5);
    p = world_pos(s, lin_t, 5.0); /* clamped after the last key */
    CHECK_NEAR(p.z, 6.0, 1e-5);
    m = evr_node_world_at(s, lin_s, 1.0);
    CHECK_NEAR(m.m[0][0], 2.0, 1e-5);
    CHECK_NEAR(m.m[1][1], 1.0, 1e-5);
    CHECK_NEAR(m.m[2][2], 1.5, 1e-5);

    /* STEP: Assimp 5.2 passes STEP keys as plain keys; the importer reads the mode from the JSON */
    CHECK(s->nodes[step_t].t_curve.interp == EVR_INTERP_STEP);
    CHECK(s->nodes[lin_t].t_curve.interp == EVR_INTERP_LINEAR);
    p = world_pos(s, step_t, 0.5);
    CHECK_NEAR(p.x, 0.0, 1e-6); /* linear would give 2.5 */
    p = world_pos(s, step_t, 1.0);
    CHECK_NEAR(p.x, 5.0, 1e-6);
    p = world_pos(s, step_t, 1.75);
    CHECK_NEAR(p.x, 5.0, 1e-6); /* linear would give 6.5 */
    p = world_pos(s, step_t, 2.5);
    CHECK_NEAR(p.x, 7.0, 1e-6);
    m = evr_node_world_at(s, step_s, 0.9);
    CHECK_NEAR(m.m[0][0], 1.0, 1e-6);
    m = evr_node_world_at(s, step_s, 1.1);
    CHECK_NEAR(m.m[0][0], 2.0, 1e-6);

    /* slerp from q to -q': the shortest arc, +45 degrees about Y at t = 0.5 */
    m = evr_node_world_at(s, slerp, 0.5);
    CHECK_NEAR(m.m[0][0], cos(PI_D / 4), 1e-5);
    CHECK_NEAR(m.m[2][0], -sin(PI_D / 4), 1e-5); /* x axis -> (cos, 0, -sin) */
    m = evr_node_world_at(s, slerp, 1.0);
    CHECK_NEAR(m.m[2][0], -1.0, 1e-5);

    /* quirk (d): CUBICSPLINE keeps values only (no tangents as keys), interpolated linearly */
    CHECK(s->nodes[cubic].t_curve.num_keys == 3);
    if (s->nodes[cubic].t_curve.num_keys == 3) {
        const float *v = s->nodes[cubic].t_curve.values;
        CHECK_NEAR(v[0], 0.0, 1e-6);
        CHECK_NEAR(v[3], 1.0, 1e-6);
        CHECK_NEAR(v[4], 2.0, 1e-6);
        CHECK_NEAR(v[8], 6.0, 1e-6);
        CHECK_NEAR(s->nodes[cubic].t_curve.times[1], 1.0, 1e-6);
        CHECK(s->nodes[cubic].t_curve.interp == EVR_INTERP_LINEAR);
    }
    p = world_pos(s, cubic, 0.5);
    CHECK_NEAR(p.x, 0.5, 1e-5);
    CHECK_NEAR(p.y, 1.0, 1e-5);
    CHECK_NEAR(p.z, 1.5, 1e-5);
    p = world_pos(s, cubic, 1.5);
    CHECK_NEAR(p.x, 2.5, 1e-5);
    CHECK_NEAR(p.y, 3.5, 1e-5);
    CHECK_NEAR(p.z, 4.5, 1e-5);

    /* quirk (e): a matrix node without animation keeps its matrix exactly (skew 0.5 included) */
    CHECK(!s->nodes[mat_skew].animated);
    m = evr_node_world_at(s, mat_skew, 0.7);
    CHECK_NEAR(m.m[0][0], 1.0, 1e-7);
    CHECK_NEAR(m.m[0][1], 0.5, 1e-7);
    CHECK_NEAR(m.m[0][2], 0.0, 1e-7);
    CHECK_NEAR(m.m[1][0], 0.0, 1e-7);
    CHECK_NEAR(m.m[1][1], 2.0, 1e-7);
    CHECK_NEAR(m.m[2][2], 3.0, 1e-7);
    CHECK_NEAR(m.m[0][3], 4.0, 1e-7);
    CHECK_NEAR(m.m[1][3], 5.0, 1e-7);
    CHECK_NEAR(m.m[2][3], 6.0, 1e-7);
    /* ... and a matrix node with only a translation channel: the keys Assimp synthesizes for
     * rotation and scale are dropped; they come from the rest pose (90 deg about X, scale 1 2 3) */
    CHECK(s->nodes[mat_anim].t_curve.num_keys == 2);
    CHECK(s->nodes[mat_anim].r_curve.num_keys == 0);
    CHECK(s->nodes[mat_anim].s_curve.num_keys == 0);
    m = evr_node_world_at(s, mat_anim, 1.0);
    e = trs(evr_v3_make(1, 1, 3), qaxis(1, 0, 0, 90), evr_v3_make(1, 2, 3));
    CHECK(m34_maxdiff(&m, &e) < 1e-5);
    /* a TRS node with only a rotation channel keeps its rest translation and scale */
    CHECK(s->nodes[trs_rot].t_curve.num_keys == 0 && s->nodes[trs_rot].s_curve.num_keys == 0);
    m = evr_node_world_at(s, trs_rot, 2.0);
    e = trs(evr_v3_make(1, 2, 3), qaxis(1, 0, 0, 90), evr_v3_make(2, 2, 2));
    CHECK(m34_maxdiff(&m, &e) < 1e-5);
    /* static nodes have no curves at all (Assimp's constant keys are not kept) */
    CHECK(!s->nodes[node_index(s, "static")].animated);

    /* parent-child composition: parent turned 90 about Y at t = 0.1, child at (2,0,0) below it */
    m = evr_node_world_at(s, child, 0.1);
    e = evr_m34_mul(evr_node_local_at(&s->nodes[parent], 0.1),
                    evr_node_local_at(&s->nodes[child], 0.1));
    CHECK(m34_maxdiff(&m, &e) < 1e-6);
    CHECK_NEAR(m.m[0][3], 0.0, 1e-5);
    CHECK_NEAR(m.m[1][3], 1.0, 1e-5);
    CHECK_NEAR(m.m[2][3], -2.0, 1e-5);
    CHECK_NEAR(evr_v3_len(evr_v3_make(m.m[0][1], m.m[1][1], m.m[2][1])), 1.0 + 1.0 / 3.0, 1e-5);
}

/* Motion keys over [t0, t1] reproduce evr_node_world_at at 100 random times within rel * size. */
static void check_keys(const evr_scene *s, int node, double t0, double t1, float tol, int max_keys,
                       double rel, int *n_out)
{
    evr_motion_key keys[1025];
    evr_motion_track tr;
    double size = evr_v3_len(evr_v3_sub(s->bounds_max, s->bounds_min)), worst = 0;
    int n, i, pow2;
    unsigned seed = 12345u + (unsigned)node;
    n = evr_node_motion_keys(s, node, t0, t1, tol, keys, max_keys);
    *n_out = n;
    CHECK(n >= 1 && n <= max_keys);
    for (pow2 = 1; pow2 + 1 < n; pow2 *= 2) {}
    CHECK(n == 1 || n == pow2 + 1);
    for (i = 1; i < n; i++) {
        float d = evr_quat_dot(keys[i - 1].rot, keys[i].rot);
        CHECK(d >= 0.0f); /* neighbouring quaternions in one hemisphere */
        CHECK(d > 0.5f);  /* steps below 120 degrees */
    }
    tr.keys = keys;
    tr.n = n;
    for (i = 0; i < 100; i++) {
        double f, err;
        evr_m34 a, b;
        int k;
        seed = seed * 1664525u + 1013904223u;
        f = (double)(seed >> 8) / (double)(1u << 24);
        a = evr_motion_eval(tr, (float)f);
        b = evr_node_world_at(s, node, t0 + f * (t1 - t0));
        /* compare where they put the mesh corners and the unit axes (scaled by the scene size) */
        err = 0;
        for (k = 0; k < 12; k++) {
            evr_v3 q, pa, pb;
            if (k < 8) {
                const evr_node *nd = &s->nodes[node];
                q = evr_v3_make((k & 1) ? nd->bounds_max.x : nd->bounds_min.x,
                                (k & 2) ? nd->bounds_max.y : nd->bounds_min.y,
                                (k & 4) ? nd->bounds_max.z : nd->bounds_min.z);
            } else {
                q = evr_v3_make(k == 9 ? (float)size : 0.0f, k == 10 ? (float)size : 0.0f,
                                k == 11 ? (float)size : 0.0f);
            }
            pa = evr_m34_point(&a, q);
            pb = evr_m34_point(&b, q);
            err = fmax(err, evr_v3_len(evr_v3_sub(pa, pb)));
        }
        worst = fmax(worst, err);
    }
    if (!(worst <= rel * size))
        fprintf(stderr, "node %s: %d keys, worst error %g > %g\n", s->nodes[node].name, n, worst,
                rel * size);
    CHECK(worst <= rel * size);
}

static void test_motion_keys(const evr_scene *s)
{
    int n;
    int spin = node_index(s, "spin"), child = node_index(s, "child"),
        lin_t = node_index(s, "lin_t");
    int step_t = node_index(s, "step_t"), cam = node_index(s, "cam_main"),
        stat = node_index(s, "static");
    if (spin < 0 || child < 0 || lin_t < 0 || step_t < 0 || cam < 0 || stat < 0) return;

    /* 270 degrees about Z within one segment (0 to 0.3 s) through 4 keys */
    check_keys(s, spin, 0.0, 0.3, 2e-5f, 257, 1e-4, &n);
    CHECK(n >= 5); /* two keys would be 270 degrees apart: slerp would turn 90 the wrong way */
    /* a child carried on a circle by its parent spinning 270 degrees, scaling as it goes */
    check_keys(s, child, 0.0, 0.3, 2e-5f, 1025, 1e-4, &n);
    CHECK(n > 9);
    /* a segment inside the spin that crosses a key */
    check_keys(s, spin, 0.05, 0.17, 2e-5f, 257, 1e-4, &n);
    /* a bend in a linear translation */
    check_keys(s, lin_t, 0.5, 1.5, 1e-5f, 257, 1e-4, &n);
    /* straight motion: two keys are exact */
    check_keys(s, lin_t, 0.1, 0.9, 1e-5f, 257, 1e-4, &n);
    CHECK(n == 2);
    /* nothing moves: one key */
    check_keys(s, stat, 0.0, 2.0, 1e-5f, 257, 1e-4, &n);
    CHECK(n == 1);
    check_keys(s, cam, 0.0, 2.0, 1e-5f, 257, 1e-4, &n);
    CHECK(n == 1);
    check_keys(s, lin_t, 3.0, 4.0, 1e-5f, 257, 1e-4, &n); /* after the animation ended */
    CHECK(n == 1);
    /* a STEP jump cannot be matched by interpolation: the cap (largest 2^k+1 <= max_keys) */
    {
        evr_motion_key k[40];
        CHECK(evr_node_motion_keys(s, step_t, 0.5, 1.5, 1e-4f, k, 40) == 33);
        CHECK(evr_node_motion_keys(s, step_t, 0.5, 1.5, 1e-4f, k, 1) == 1);
        CHECK(evr_node_motion_keys(s, step_t, 0.5, 1.5, 1e-4f, k, 2) == 2);
    }
}

int main(void)
{
    evr_scene *s = NULL;
    evr_error err;

    test_handmade();

    if (evr_scene_load(DATA "anim.gltf", &s, &err) != EVR_OK) {
        fprintf(stderr, "%s\n", err.msg);
        CHECK(!"anim.gltf loads");
        return check_report("test_anim");
    }
    test_imported(s);
    test_motion_keys(s);
    evr_scene_release(s);
    return check_report("test_anim");
}
