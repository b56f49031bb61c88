/* Importing skins and morph targets (scene/import_deform.c, import_gltf_deform.c): the assets of
 * tests/deform_assets.py, written into a temporary folder, imported, their skin and morph data
 * checked, and evr_instance_deformed_at (scene/deform.c) checked against the motion each asset
 * is built to have; each of Assimp 5.2's quirks (f) to (n) in import.c is pinned here, and a
 * Collada skin (tests/data/import/skin.dae) goes through the same bones. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "check.h"
#include "scene/scene.h"

#define TOL 1e-5

static char dir[64] = "/tmp/evr_deform_XXXXXX";

static evr_scene *load(const char *name)
{
    char path[256];
    evr_scene *s = NULL;
    evr_error err;
    evr_status st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    st = evr_scene_load(path, &s, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) fprintf(stderr, "  %s: %s\n", name, err.msg);
    return st == EVR_OK ? s : NULL;
}

static int node_index(const evr_scene *s, const char *name)
{
    for (int i = 0; i < s->num_nodes; i++)
        if (!strcmp(s->nodes[i].name, name)) return i;
    return -1;
}

/* The first instance of the mesh named `name`, or -1. */
static int instance_of(const evr_scene *s, const char *name)
{
    for (int i = 0; i < s->num_instances; i++)
        if (!strcmp(s->meshes[s->instances[i].mesh].name, name)) return i;
    return -1;
}

/* Vertex v of instance inst at time t, in the world. */
static evr_v3 world_vertex(const evr_scene *s, int inst, double t, uint32_t v)
{
    const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
    float *p = malloc(sizeof(float) * 3 * m->num_vertices);
    evr_v3 q = evr_v3_make(NAN, NAN, NAN);
    if (p && evr_instance_deformed_at(s, inst, t, p, NULL)) {
        q = evr_v3_make(p[3 * v], p[3 * v + 1], p[3 * v + 2]);
        if (!m->skin) { /* a morphing mesh's vertices are in its node's space */
            evr_m34 w = evr_node_world_at(s, s->instances[inst].node, t);
            q = evr_m34_point(&w, q);
        }
    }
    free(p);
    return q;
}

/* Every vertex's weights sum to 1. */
static void check_normalized(const evr_skin *sk, uint32_t nv)
{
    for (uint32_t v = 0; v < nv; v++) {
        double sum = 0.0;
        for (int k = 0; k < sk->influences; k++) sum += sk->weights[v * sk->influences + k];
        CHECK_NEAR(sum, 1.0, 1e-6);
    }
}

static int m34_is_identity(const evr_m34 *m)
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            if (m->m[r][c] != (r == c ? 1.0f : 0.0f)) return 0;
    return 1;
}

/* The weight vertex v gives joint j (0 when none). */
static float weight_of(const evr_skin *sk, uint32_t v, int j)
{
    float w = 0.0f;
    for (int k = 0; k < sk->influences; k++)
        if (sk->joints[v * sk->influences + k] == j) w += sk->weights[v * sk->influences + k];
    return w;
}

/* The quad's right edge (vertices 1 and 2) at x = -0.5 + t, the left edge still, y and z as
 * built (a skinned mesh's node translation (5,5,5) ignored). */
static void check_slide(const evr_scene *s, const char *what)
{
    static const double times[] = {0.0, 0.25, 0.5, 1.0};
    int inst = instance_of(s, "quad");
    CHECK(inst >= 0);
    if (inst < 0) return;
    for (int k = 0; k < 4; k++) {
        double t = times[k];
        evr_v3 v0 = world_vertex(s, inst, t, 0), v1 = world_vertex(s, inst, t, 1),
               v2 = world_vertex(s, inst, t, 2), v3 = world_vertex(s, inst, t, 3);
        if (!(fabs(v1.x - (-0.5 + t)) <= TOL)) fprintf(stderr, "  %s at t = %g\n", what, t);
        CHECK_NEAR(v1.x, -0.5 + t, TOL);
        CHECK_NEAR(v2.x, -0.5 + t, TOL);
        CHECK_NEAR(v1.y, -2.0, TOL);
        CHECK_NEAR(v2.y, 2.0, TOL);
        CHECK_NEAR(v1.z, -1.0, TOL);
        CHECK_NEAR(v2.z, -1.0, TOL);
        CHECK_NEAR(v0.x, -2.0, TOL);
        CHECK_NEAR(v3.x, -2.0, TOL);
        CHECK_NEAR(v0.z, -1.0, TOL);
    }
}

static void test_morph_slide(void)
{
    evr_scene *s = load("morph_slide.gltf");
    if (!s) return;
    int inst = instance_of(s, "quad"), n = node_index(s, "quad");
    CHECK(inst >= 0 && n >= 0);
    if (inst >= 0 && n >= 0) {
        const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
        const evr_node *nd = &s->nodes[n];
        CHECK(m->morph && !m->skin);
        if (m->morph) {
            static const float want[12] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0};
            CHECK(m->morph->num_targets == 1 && m->num_vertices == 4);
            for (int i = 0; i < 12; i++) CHECK_NEAR(m->morph->d_positions[i], want[i], 0);
            CHECK(m->morph->d_normals == NULL); /* the target has no NORMAL */
            CHECK(m->morph->default_weights[0] == 0.0f);
        }
        /* (f), (a): one channel named as the node, keys in seconds */
        CHECK(nd->num_weights == 1 && nd->weights[0] == 0.0f);
        CHECK(nd->w_curve.num_keys == 2 && nd->w_curve.interp == EVR_INTERP_LINEAR);
        if (nd->w_curve.num_keys == 2) {
            CHECK_NEAR(nd->w_curve.times[1], 1.0, 1e-9);
            CHECK(nd->w_curve.values[0] == 0.0f && nd->w_curve.values[1] == 1.0f);
        }
        CHECK(evr_instance_deforms(s, inst) && evr_instance_deform_animated(s, inst));
    }
    CHECK_NEAR(s->anim_start, 0.0, 1e-9);
    CHECK_NEAR(s->anim_end, 1.0, 1e-9);
    check_slide(s, "morph_slide");
    CHECK(evr_scene_warnings(s)[0] == 0);
    evr_scene_release(s);
}

/* skin_slide and its variants: joints [root, mover(, mover2)], identity bind matrices. */
static void check_skin_quad(const evr_scene *s, const char *what, int joints)
{
    int inst = instance_of(s, "quad");
    CHECK(inst >= 0);
    if (inst < 0) return;
    const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
    const evr_skin *sk = m->skin;
    CHECK(sk != NULL && !m->morph);
    if (!sk) return;
    CHECK(sk->num_joints == joints);
    CHECK(sk->joint_nodes[0] == node_index(s, "root"));
    CHECK(sk->joint_nodes[1] == node_index(s, "mover"));
    if (joints == 3) CHECK(sk->joint_nodes[2] == node_index(s, "mover2"));
    for (int j = 0; j < sk->num_joints; j++) CHECK(m34_is_identity(&sk->inverse_bind[j]));
    check_normalized(sk, m->num_vertices);
    CHECK(weight_of(sk, 0, 0) == 1.0f && weight_of(sk, 3, 0) == 1.0f);
    if (joints == 3) { /* JOINTS_1/WEIGHTS_1 read: half on mover, half on mover2 */
        CHECK(sk->influences == 2);
        CHECK(weight_of(sk, 1, 1) == 0.5f && weight_of(sk, 1, 2) == 0.5f);
        CHECK(weight_of(sk, 2, 1) == 0.5f && weight_of(sk, 2, 2) == 0.5f);
    } else {
        CHECK(sk->influences == 1);
        CHECK(weight_of(sk, 1, 1) == 1.0f && weight_of(sk, 2, 1) == 1.0f);
    }
    CHECK(evr_instance_deform_animated(s, inst));
    check_slide(s, what);
}

static void test_skin_slides(void)
{
    static const char *names[] = {"skin_slide.gltf", "skin_slide8.gltf", "skin_no_ibm.gltf",
                                  "skin_no_ibm.glb"};
    for (int i = 0; i < 4; i++) {
        evr_scene *s = load(names[i]);
        if (!s) continue;
        check_skin_quad(s, names[i], i == 1 ? 3 : 2);
        CHECK(evr_scene_warnings(s)[0] == 0);
        evr_scene_release(s);
    }
    /* (j) from memory too: the patched GLB is handed to Assimp as bytes */
    {
        char path[256];
        FILE *f;
        long n;
        unsigned char *buf;
        evr_scene *s = NULL;
        evr_error err;
        snprintf(path, sizeof path, "%s/skin_no_ibm.glb", dir);
        f = fopen(path, "rb");
        CHECK(f != NULL);
        if (!f) return;
        fseek(f, 0, SEEK_END);
        n = ftell(f);
        fseek(f, 0, SEEK_SET);
        buf = malloc((size_t)n);
        CHECK(buf && fread(buf, 1, (size_t)n, f) == (size_t)n);
        fclose(f);
        CHECK(evr_scene_load_memory(buf, (size_t)n, "glb", &s, &err) == EVR_OK);
        if (s) check_skin_quad(s, "skin_no_ibm.glb in memory", 2);
        evr_scene_release(s);
        free(buf);
    }
}

static void test_bend_cylinder(void)
{
    evr_scene *s = load("bend_cylinder.gltf");
    if (!s) return;
    int inst = instance_of(s, "cylinder");
    CHECK(inst >= 0);
    if (inst >= 0) {
        const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
        const evr_skin *sk = m->skin;
        uint32_t tip = UINT32_MAX, mid = UINT32_MAX;
        CHECK(sk && sk->num_joints == 2 && sk->influences == 2);
        CHECK(m->num_vertices == 17 * 12 + 2 * 13);
        for (uint32_t v = 0; v < m->num_vertices; v++) {
            const float *p = m->positions + 3 * v;
            if (p[0] == 2.0f && p[1] == 0.0f && p[2] == 0.0f) tip = v;
            if (p[0] == 1.0f && mid == UINT32_MAX) mid = v;
        }
        CHECK(tip != UINT32_MAX && mid != UINT32_MAX);
        if (sk && tip != UINT32_MAX && mid != UINT32_MAX) {
            const evr_m34 *ib = &sk->inverse_bind[1];
            CHECK(sk->joint_nodes[0] == node_index(s, "j0"));
            CHECK(sk->joint_nodes[1] == node_index(s, "j1"));
            CHECK(m34_is_identity(&sk->inverse_bind[0]));
            CHECK(ib->m[0][0] == 1.0f && ib->m[1][1] == 1.0f && ib->m[2][2] == 1.0f);
            CHECK(ib->m[0][3] == -1.0f && ib->m[1][3] == 0.0f && ib->m[2][3] == 0.0f);
            check_normalized(sk, m->num_vertices);
            CHECK_NEAR(weight_of(sk, mid, 0), 0.5, 1e-6); /* halfway between x = 0.8 and 1.2 */
            CHECK_NEAR(weight_of(sk, mid, 1), 0.5, 1e-6);
            CHECK(weight_of(sk, tip, 1) == 1.0f);
            evr_v3 p0 = world_vertex(s, inst, 0.0, tip), p5 = world_vertex(s, inst, 0.5, tip),
                   p1 = world_vertex(s, inst, 1.0, tip);
            CHECK_NEAR(p0.x, 2.0, TOL);
            CHECK_NEAR(p0.y, 0.0, TOL);
            CHECK_NEAR(p5.x, 1.0 + sqrt(0.5), TOL);
            CHECK_NEAR(p5.y, sqrt(0.5), TOL);
            CHECK_NEAR(p1.x, 1.0, TOL);
            CHECK_NEAR(p1.y, 1.0, TOL);
            CHECK_NEAR(p1.z, 0.0, TOL);
        }
    }
    evr_scene_release(s);
}

/* (h): node.weights override mesh.weights */
static void test_node_weights(void)
{
    evr_scene *s = load("morph_node_weights.gltf");
    if (!s) return;
    int inst = instance_of(s, "quad"), n = node_index(s, "quad");
    CHECK(n >= 0 && s->nodes[n].num_weights == 1 && s->nodes[n].weights[0] == 0.5f);
    CHECK(s->meshes[s->instances[inst].mesh].morph->default_weights[0] == 0.0f);
    CHECK(!evr_instance_deform_animated(s, inst));
    CHECK_NEAR(world_vertex(s, inst, 0.0, 1).x, 0.0, TOL);
    evr_scene_release(s);
}

/* (f): CUBICSPLINE keeps the values (tangents 2..5 dropped) and warns; STEP from the JSON */
static void test_weight_interpolation(void)
{
    evr_scene *s = load("morph_cubic.gltf");
    if (s) {
        int inst = instance_of(s, "quad"), n = node_index(s, "quad");
        const evr_curve *c = &s->nodes[n].w_curve;
        CHECK(c->num_keys == 2 && c->interp == EVR_INTERP_LINEAR);
        if (c->num_keys == 2) CHECK(c->values[0] == 0.0f && c->values[1] == 1.0f);
        CHECK(strstr(evr_scene_warnings(s), "CUBICSPLINE") != NULL);
        CHECK(strchr(evr_scene_warnings(s), '\n') == strrchr(evr_scene_warnings(s), '\n'));
        CHECK_NEAR(world_vertex(s, inst, 0.5, 1).x, 0.0, TOL);
        evr_scene_release(s);
    }
    s = load("morph_step.gltf");
    if (s) {
        int inst = instance_of(s, "quad"), n = node_index(s, "quad");
        CHECK(s->nodes[n].w_curve.interp == EVR_INTERP_STEP);
        CHECK_NEAR(world_vertex(s, inst, 0.5, 1).x, -0.5, TOL);
        CHECK_NEAR(world_vertex(s, inst, 1.0, 1).x, 0.5, TOL);
        evr_scene_release(s);
    }
}

/* (g), (h), (f): two primitives, two targets (normals on the first), node weights */
static void test_two_prims(void)
{
    evr_scene *s = load("morph_two_prims.gltf");
    if (!s) return;
    int n = node_index(s, "pair"), found = 0;
    CHECK(n >= 0);
    if (n >= 0) {
        const evr_node *nd = &s->nodes[n];
        static const float keys[6] = {0.0f, 0.1f, 0.2f, 0.3f, 1.0f, 0.9f};
        CHECK(nd->num_weights == 2 && nd->weights[0] == 0.75f && nd->weights[1] == 0.125f);
        CHECK(nd->w_curve.num_keys == 3);
        if (nd->w_curve.num_keys == 3) {
            for (int i = 0; i < 6; i++) CHECK(nd->w_curve.values[i] == keys[i]);
            CHECK_NEAR(nd->w_curve.times[1], 0.5, 1e-9);
        }
    }
    for (int i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        const evr_morph *mo = m->morph;
        float pos[12], nrm[12];
        found++;
        CHECK(mo && mo->num_targets == 2 && mo->d_normals);
        if (!mo || !mo->d_normals) continue;
        CHECK(mo->default_weights[0] == 0.25f && mo->default_weights[1] == 0.5f);
        CHECK_NEAR(mo->d_normals[3 * 1 + 1], 0.5, 1e-6); /* target 0, vertex 1 */
        CHECK(mo->d_normals[12 + 3 * 1 + 1] == 0.0f);    /* target 1 has no NORMAL */
        CHECK_NEAR(mo->d_positions[12 + 3 * 1 + 1], 1.0, 1e-6);
        /* t = 0.5: weights (0.2, 0.3) */
        CHECK(evr_instance_deformed_at(s, i, 0.5, pos, nrm));
        CHECK_NEAR(pos[3], -0.5 + 0.2, TOL);
        CHECK_NEAR(pos[4], m->positions[4] + 0.3, TOL);
        CHECK_NEAR(nrm[4], 0.1 / sqrt(1.01), TOL);
        CHECK_NEAR(nrm[5], 1.0 / sqrt(1.01), TOL);
    }
    CHECK(found == 2);
    evr_scene_release(s);
}

static void test_normalize_shared_seam(void)
{
    evr_scene *s = load("skin_unnormalized.gltf");
    if (s) {
        const evr_skin *sk = s->meshes[0].skin;
        static const float want[4][2] = {{0.25f, 0.75f}, {0.5f, 0.5f}, {0.5f, 0.5f}, {0.0f, 1.0f}};
        CHECK(sk != NULL);
        for (uint32_t v = 0; sk && v < 4; v++) {
            CHECK_NEAR(weight_of(sk, v, 0), want[v][0], 1e-6);
            CHECK_NEAR(weight_of(sk, v, 1), want[v][1], 1e-6);
        }
        evr_scene_release(s);
    }
    s = load("skin_shared.gltf"); /* (n): each node its own copy of the mesh and its skin */
    if (s) {
        int a = -1, b = -1;
        for (int i = 0; i < s->num_instances; i++) {
            if (s->instances[i].node == node_index(s, "quad")) a = i;
            if (s->instances[i].node == node_index(s, "quad2")) b = i;
        }
        CHECK(a >= 0 && b >= 0 && s->instances[a].mesh != s->instances[b].mesh);
        if (a >= 0 && b >= 0) {
            const evr_skin *sa = s->meshes[s->instances[a].mesh].skin,
                           *sb = s->meshes[s->instances[b].mesh].skin;
            CHECK(sa && sb && sa->joint_nodes[0] == sb->joint_nodes[1] &&
                  sa->joint_nodes[1] == sb->joint_nodes[0]);
            CHECK_NEAR(world_vertex(s, a, 0.5, 1).x, 0.0, TOL);
            CHECK_NEAR(world_vertex(s, a, 0.5, 0).x, -2.0, TOL);
            CHECK_NEAR(world_vertex(s, b, 0.5, 1).x, -0.5, TOL);
            CHECK_NEAR(world_vertex(s, b, 0.5, 0).x, -1.5, TOL);
        }
        CHECK(evr_scene_warnings(s)[0] == 0);
        evr_scene_release(s);
    }
    s = load("seam.gltf"); /* (i): vertices 1 and 4 differ only in joint and target */
    if (s) {
        const evr_mesh *m = &s->meshes[0];
        CHECK(m->num_vertices == 5 && m->skin && m->morph);
        if (m->num_vertices == 5 && m->skin && m->morph) {
            CHECK(weight_of(m->skin, 1, 1) == 1.0f && weight_of(m->skin, 1, 0) == 0.0f);
            CHECK(weight_of(m->skin, 4, 0) == 1.0f && weight_of(m->skin, 4, 1) == 0.0f);
            CHECK(m->morph->d_positions[3] == 1.0f && m->morph->d_positions[12] == 0.0f);
            CHECK_NEAR(world_vertex(s, 0, 0.0, 1).x, 0.5, TOL); /* mesh weight 1 */
            CHECK_NEAR(world_vertex(s, 0, 0.0, 4).x, -0.5, TOL);
        }
        evr_scene_release(s);
    }
}

/* Another format through the same bones: Collada's mOffsetMatrix holds the inverse bind matrix
 * times the bind shape matrix (z = 0 -> -1), the mesh node's (5,5,5) is ignored, and the
 * joint's keys come in milliseconds (tests/data/import/skin.dae). */
static void test_collada_skin(void)
{
    evr_scene *s = NULL;
    evr_error err;
    CHECK(evr_scene_load(EVR_TEST_DATA "/import/skin.dae", &s, &err) == EVR_OK);
    if (!s) {
        fprintf(stderr, "  skin.dae: %s\n", err.msg);
        return;
    }
    const evr_mesh *m = &s->meshes[0];
    int edge = 0;
    CHECK(m->skin && m->skin->num_joints == 2 && m->skin->influences == 1);
    CHECK_NEAR(s->anim_end, 1.0, 1e-9);
    for (uint32_t v = 0; m->skin && v < m->num_vertices; v++) {
        const int right = m->positions[3 * v] == -0.5f;
        for (double t = 0.0; t <= 1.0; t += 0.25) {
            evr_v3 p = world_vertex(s, 0, t, v);
            CHECK_NEAR(p.x, right ? -0.25 + t : -2.0, TOL);
            CHECK_NEAR(p.y, m->positions[3 * v + 1], TOL);
            CHECK_NEAR(p.z, -1.0, TOL);
        }
        edge += right;
    }
    CHECK(edge > 0);
    evr_scene_release(s);
}

/* (k), (l), (m) and a weightless vertex: one line naming the mesh */
static void test_bad(void)
{
    static const char *names[] = {"bad_joint_index.gltf", "bad_ibm_count.gltf",
                                  "bad_morph_count.gltf", "bad_weights_zero.gltf"};
    static const char *why[] = {"joint index", "inverse bind", "morph target", "no joint weight"};
    for (int i = 0; i < 4; i++) {
        char path[256];
        evr_scene *s = NULL;
        evr_error err;
        evr_status st;
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        st = evr_scene_load(path, &s, &err);
        CHECK(st == EVR_ERR_FORMAT && s == NULL);
        CHECK(strstr(err.msg, "mesh 'quad'") != NULL && strstr(err.msg, why[i]) != NULL);
        CHECK(strchr(err.msg, '\n') == NULL);
        if (st != EVR_ERR_FORMAT || !strstr(err.msg, why[i]))
            fprintf(stderr, "  %s: %d '%s'\n", names[i], (int)st, err.msg);
    }
}

int main(void)
{
    char cmd[512];
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s/../deform_assets.py %s >/dev/null",
             EVR_TEST_DATA, dir);
    CHECK(system(cmd) == 0);
    if (check_failures) return check_report("test_deform_import");
    test_morph_slide();
    test_skin_slides();
    test_bend_cylinder();
    test_node_weights();
    test_weight_interpolation();
    test_two_prims();
    test_normalize_shared_seam();
    test_collada_skin();
    test_bad();
    if (!check_failures) {
        snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
        CHECK(system(cmd) == 0);
    }
    return check_report("test_deform_import");
}
