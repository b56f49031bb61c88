/* Deformation (scene/deform.c) and its per-segment vertex keys (prep/deform_keys.c), on scenes
 * built by hand: a quad whose edge a morph target slides at constant speed, and a two-joint
 * strip whose second joint turns 90 degrees. Checks the analytic vertex positions, that the
 * keys' interpolation follows the deformation within the tolerance at every time, that the
 * swept box holds every position, still segments (one key, bit for bit the previous pose,
 * not "moved"), and the skinned mesh's node transform being ignored. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "backend.h"
#include "prep/deform_keys.h"
#include "scene/scene.h"

#define PI_D 3.14159265358979323846
#define TOL 1e-5f

static float quad_pos[12] = {-2, -2, -1, -0.5f, -2, -1, -0.5f, 2, -1, -2, 2, -1};
static float quad_nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
static uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};

static void rest_node(evr_node *n, const char *name, int parent)
{
    memset(n, 0, sizeof *n);
    snprintf(n->name, sizeof n->name, "%s", name);
    n->parent = parent;
    n->scale = evr_v3_make(1, 1, 1);
    n->rotation = evr_quat_make(1, 0, 0, 0);
    n->rest_matrix = evr_m34_identity();
}

static void set_mesh(evr_mesh *m, float *pos, float *nrm, uint32_t nv, uint32_t *idx, uint32_t nt)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "mesh");
    m->positions = pos;
    m->normals = nrm;
    m->indices = idx;
    m->num_vertices = nv;
    m->num_triangles = nt;
    m->bounds_min = evr_v3_make(-2, -2, -1);
    m->bounds_max = evr_v3_make(2, 2, 1);
}

static void host_of(const evr_scene *s, evr_render_host *h, int *deform_instance)
{
    memset(h, 0, sizeof *h);
    h->num_deforms = 0;
    for (int i = 0; i < s->num_instances; i++)
        if (evr_instance_deforms(s, i)) deform_instance[h->num_deforms++] = i;
    h->deform_instance = deform_instance;
    h->scene_size = 4.0f;
}

/* The interpolated keys against the deformation itself at many times of [t0, t1]; the box. */
static void check_keys(const evr_scene *s, const evr_deform_keys *k, double t0, double t1)
{
    const evr_deform_view *v = &k->views[0];
    const uint32_t nv = v->num_vertices;
    float *truth = malloc(sizeof(float) * 6 * nv);
    double worst = 0.0;
    int outside = 0;
    for (int j = 0; j <= 200; j++) {
        const float f = (float)j / 200.0f;
        CHECK(evr_instance_deformed_at(s, 0, t0 + (t1 - t0) * f, truth, truth + 3 * nv));
        for (uint32_t i = 0; i < nv; i++) {
            const evr_v3 p = evr_deform_lerp(v, v->positions, i, f);
            const float q[3] = {p.x, p.y, p.z};
            for (int c = 0; c < 3; c++) {
                worst = fmax(worst, fabs((double)q[c] - truth[3 * i + c]));
                if (q[c] < k->motion[0].lo[c] || q[c] > k->motion[0].hi[c]) outside++;
            }
        }
    }
    /* the tolerance is on distances; per coordinate it is at most that */
    CHECK(worst <= TOL * 4.0 * 1.01);
    CHECK(outside == 0);
    free(truth);
}

static void test_morph_slide(void)
{
    evr_scene s;
    evr_node node;
    evr_mesh mesh;
    evr_morph morph;
    evr_instance inst = {0, 0};
    float d_pos[12] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0};
    float defw[1] = {0}, restw[1] = {0};
    double times[2] = {0.0, 1.0};
    float values[2] = {0.0f, 1.0f};
    int dinst[1];
    evr_render_host h;
    evr_deform_tracker t;
    evr_deform_keys k;

    memset(&s, 0, sizeof s);
    rest_node(&node, "quad", -1);
    node.num_weights = 1;
    node.weights = restw;
    node.w_curve.num_keys = 2;
    node.w_curve.times = times;
    node.w_curve.values = values;
    set_mesh(&mesh, quad_pos, quad_nrm, 4, quad_idx, 2);
    morph.num_targets = 1;
    morph.d_positions = d_pos;
    morph.d_normals = NULL;
    morph.default_weights = defw;
    mesh.morph = &morph;
    s.nodes = &node;
    s.num_nodes = 1;
    s.meshes = &mesh;
    s.num_meshes = 1;
    s.instances = &inst;
    s.num_instances = 1;
    CHECK(evr_instance_deforms(&s, 0));
    CHECK(evr_instance_deform_animated(&s, 0));

    /* analytic: the right edge at x = -0.5 + t, clamped after the last key */
    float pos[12], nrm[12];
    const double ts[4] = {0.0, 0.25, 1.0, 3.0};
    const double xs[4] = {-0.5, -0.25, 0.5, 0.5};
    for (int i = 0; i < 4; i++) {
        CHECK(evr_instance_deformed_at(&s, 0, ts[i], pos, nrm));
        CHECK_NEAR(pos[3], xs[i], 1e-6);
        CHECK_NEAR(pos[6], xs[i], 1e-6);
        CHECK_NEAR(pos[0], -2.0, 0);
        CHECK_NEAR(nrm[2], 1.0, 1e-6);
    }

    host_of(&s, &h, dinst);
    memset(&k, 0, sizeof k);
    CHECK(evr_deform_tracker_init(&t, &s, &h));
    /* moving at constant speed: linear, two keys suffice */
    CHECK(evr_deform_keys_make(&t, &s, &h, 0.5, 0.6, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys == 2);
    CHECK(k.moved[0]);
    CHECK_NEAR(k.views[0].positions[3], 0.0, 1e-6);
    CHECK_NEAR(k.views[0].positions[12 + 3], 0.1, 1e-6);
    check_keys(&s, &k, 0.5, 0.6);
    /* the segment over the curve's end bends at t = 1: more keys, still within tolerance */
    CHECK(evr_deform_keys_make(&t, &s, &h, 0.95, 1.05, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys > 2);
    check_keys(&s, &k, 0.95, 1.05);
    /* the last key holds still after the bend: bit for bit the key before it */
    {
        const evr_deform_view *v = &k.views[0];
        const size_t per = 3 * (size_t)v->num_vertices;
        CHECK(!memcmp(v->positions + (size_t)(v->num_keys - 1) * per,
                      v->positions + (size_t)(v->num_keys - 2) * per, per * sizeof(float)));
    }
    /* after it: one key, the previous pose bit for bit, and not moved */
    CHECK(evr_deform_keys_make(&t, &s, &h, 1.05, 1.15, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys == 1);
    CHECK(!k.moved[0]);
    CHECK_NEAR(k.motion[0].jump, 0.0, 0);
    CHECK(evr_deform_keys_make(&t, &s, &h, 1.15, 1.25, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys == 1 && !k.moved[0]);
    /* a jump back (a new run of segments from the start) counts as moved */
    CHECK(evr_deform_keys_make(&t, &s, &h, 0.0, 0.0, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys == 1 && k.moved[0]);
    CHECK_NEAR(k.motion[0].jump, 1.0, 1e-6);
    evr_deform_keys_free(&k);
    evr_deform_tracker_free(&t);
}

/* A strip along +X from 0 to 2, joints j0 (origin) and j1 (at x = 1, turning about +Z from 0
 * to 90 degrees over [0, 1]); vertices with x <= 1 follow j0, the others j1. The mesh's node is
 * far away: a skinned mesh's node does not move it. */
static void test_skin_bend(void)
{
    enum { N = 9 };
    float pos[2 * N * 3], nrm[2 * N * 3];
    uint32_t idx[(N - 1) * 6];
    uint16_t joints[2 * N];
    float weights[2 * N];
    int joint_nodes[2] = {1, 2};
    evr_m34 ibm[2];
    evr_node nodes[3];
    evr_mesh mesh;
    evr_skin skin;
    evr_instance inst = {0, 0};
    double times[2] = {0.0, 1.0};
    float rot[8];
    evr_scene s;
    int dinst[1];
    evr_render_host h;
    evr_deform_tracker t;
    evr_deform_keys k;

    for (int i = 0; i < N; i++)
        for (int r = 0; r < 2; r++) {
            const int v = 2 * i + r;
            pos[3 * v] = 2.0f * (float)i / (N - 1);
            pos[3 * v + 1] = r ? 0.1f : -0.1f;
            pos[3 * v + 2] = 0.0f;
            nrm[3 * v] = nrm[3 * v + 1] = 0.0f;
            nrm[3 * v + 2] = 1.0f;
            joints[v] = pos[3 * v] <= 1.0f ? 0 : 1;
            weights[v] = 1.0f;
        }
    for (int i = 0; i + 1 < N; i++) {
        uint32_t a = 2 * i, b = a + 1, c = a + 2, d = a + 3;
        uint32_t *q = idx + 6 * i;
        q[0] = a, q[1] = c, q[2] = d, q[3] = a, q[4] = d, q[5] = b;
    }
    memset(&s, 0, sizeof s);
    rest_node(&nodes[0], "strip", -1);
    nodes[0].translation = evr_v3_make(50, 50, 50);
    nodes[0].rest_matrix.m[0][3] = 50; /* ignored for a skinned mesh */
    rest_node(&nodes[1], "j0", -1);
    rest_node(&nodes[2], "j1", 1);
    nodes[2].translation = evr_v3_make(1, 0, 0);
    nodes[2].rest_matrix.m[0][3] = 1;
    nodes[2].animated = 1;
    nodes[2].r_curve.num_keys = 2;
    nodes[2].r_curve.times = times;
    nodes[2].r_curve.values = rot;
    rot[0] = 1, rot[1] = 0, rot[2] = 0, rot[3] = 0;
    rot[4] = (float)cos(PI_D / 4), rot[5] = 0, rot[6] = 0, rot[7] = (float)sin(PI_D / 4);
    ibm[0] = evr_m34_identity();
    ibm[1] = evr_m34_identity();
    ibm[1].m[0][3] = -1;
    skin.num_joints = 2;
    skin.joint_nodes = joint_nodes;
    skin.inverse_bind = ibm;
    skin.influences = 1;
    skin.joints = joints;
    skin.weights = weights;
    set_mesh(&mesh, pos, nrm, 2 * N, idx, 2 * (N - 1));
    mesh.skin = &skin;
    s.nodes = nodes;
    s.num_nodes = 3;
    s.meshes = &mesh;
    s.num_meshes = 1;
    s.instances = &inst;
    s.num_instances = 1;
    CHECK(evr_instance_deform_animated(&s, 0));

    /* analytic: at t = 1 the tip's centre line (2, +-0.1, 0) is at (1 -+ 0.1, 1, 0) */
    float p[2 * N * 3], n[2 * N * 3];
    CHECK(evr_instance_deformed_at(&s, 0, 1.0, p, n));
    const int tip = 2 * (N - 1);
    CHECK_NEAR(p[3 * tip], 1.1, 1e-5);
    CHECK_NEAR(p[3 * tip + 1], 1.0, 1e-5);
    CHECK_NEAR(p[3 * (tip + 1)], 0.9, 1e-5);
    CHECK_NEAR(n[3 * tip + 2], 1.0, 1e-6);
    CHECK(evr_instance_deformed_at(&s, 0, 0.0, p, n));
    CHECK_NEAR(p[3 * tip], 2.0, 1e-6); /* the node's (50, 50, 50) is ignored */

    host_of(&s, &h, dinst);
    memset(&k, 0, sizeof k);
    CHECK(evr_deform_tracker_init(&t, &s, &h));
    /* a quarter turn in a third of a second: a chord error of 1e-5 needs many keys */
    CHECK(evr_deform_keys_make(&t, &s, &h, 0.0, 1.0 / 3.0, TOL, EVR_MAX_KEYS, &k));
    CHECK(k.views[0].num_keys > 9);
    check_keys(&s, &k, 0.0, 1.0 / 3.0);
    /* with a cap of 5 keys it keeps 5 (the tolerance is not met; the box still holds all) */
    CHECK(evr_deform_keys_make(&t, &s, &h, 1.0 / 3.0, 2.0 / 3.0, TOL, 5, &k));
    CHECK(k.views[0].num_keys == 5);
    evr_deform_keys_free(&k);
    evr_deform_tracker_free(&t);
}

/* A mesh of 8,192 vertices or more is evaluated in parts on the tracker's threads: its keys are
 * the same floats as one evaluation on this thread (a sheet of 100 x 100 vertices on the morph
 * target's slide). */
static void test_large_threaded(void)
{
    enum { SIDE = 100, NV = SIDE * SIDE };
    float *pos = malloc(sizeof(float) * 3 * NV), *nrm = malloc(sizeof(float) * 3 * NV);
    float *dpos = malloc(sizeof(float) * 3 * NV), *truth = malloc(sizeof(float) * 6 * NV);
    uint32_t idx[6] = {0, 1, SIDE + 1, 0, SIDE + 1, SIDE};
    float defw[1] = {0}, restw[1] = {0}, values[2] = {0.0f, 1.0f};
    double times[2] = {0.0, 1.0};
    evr_scene s;
    evr_node node;
    evr_mesh mesh;
    evr_morph morph;
    evr_instance inst = {0, 0};
    int dinst[1];
    evr_render_host h;
    evr_deform_tracker t;
    evr_deform_keys k;
    CHECK(pos && nrm && dpos && truth);
    if (!pos || !nrm || !dpos || !truth) return;
    for (int v = 0; v < NV; v++) {
        const float x = (float)(v % SIDE) / SIDE, y = (float)(v / SIDE) / SIDE;
        pos[3 * v] = x, pos[3 * v + 1] = y, pos[3 * v + 2] = -1.0f;
        nrm[3 * v] = 0.0f, nrm[3 * v + 1] = 0.0f, nrm[3 * v + 2] = 1.0f;
        dpos[3 * v] = x * x, dpos[3 * v + 1] = 0.5f * y, dpos[3 * v + 2] = 0.0f;
    }
    memset(&s, 0, sizeof s);
    rest_node(&node, "sheet", -1);
    node.num_weights = 1;
    node.weights = restw;
    node.w_curve.num_keys = 2;
    node.w_curve.times = times;
    node.w_curve.values = values;
    set_mesh(&mesh, pos, nrm, NV, idx, 2);
    morph.num_targets = 1;
    morph.d_positions = dpos;
    morph.d_normals = NULL;
    morph.default_weights = defw;
    mesh.morph = &morph;
    s.nodes = &node;
    s.num_nodes = 1;
    s.meshes = &mesh;
    s.num_meshes = 1;
    s.instances = &inst;
    s.num_instances = 1;
    host_of(&s, &h, dinst);
    memset(&k, 0, sizeof k);
    CHECK(evr_deform_tracker_init(&t, &s, &h));
    CHECK(evr_deform_keys_make(&t, &s, &h, 0.25, 0.5, TOL, EVR_MAX_KEYS, &k));
    const evr_deform_view *v = &k.views[0];
    for (int key = 0; key < v->num_keys; key++) {
        const double at = 0.25 + 0.25 * key / (v->num_keys > 1 ? v->num_keys - 1 : 1);
        CHECK(evr_instance_deformed_at(&s, 0, at, truth, truth + 3 * NV));
        CHECK(!memcmp(v->positions + (size_t)key * 3 * NV, truth, sizeof(float) * 3 * NV));
        CHECK(!memcmp(v->normals + (size_t)key * 3 * NV, truth + 3 * NV, sizeof(float) * 3 * NV));
    }
    evr_deform_keys_free(&k);
    evr_deform_tracker_free(&t);
    free(pos);
    free(nrm);
    free(dpos);
    free(truth);
}

int main(void)
{
    test_morph_slide();
    test_skin_bend();
    test_large_threaded();
    return check_report("test_deform_keys");
}
