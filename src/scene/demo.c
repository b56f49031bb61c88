/* The built-in scenes: generated as binary glTF in memory and loaded through the same importer
 * as any user file, so `evray demo --export x.glb` writes exactly what the simulator renders. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/motion.h"
#include "scene/demo_scenes.h"

/* name, builder, whether the builder reads evr_gltf_variant (takes a seed) */
#define EVR_DEMO_TABLE(X)                               \
    X("eye", evr_demo_build_eye, 1)                     \
    X("eye-drift", evr_demo_build_eye_drift, 1)         \
    X("square", evr_demo_build_square, 0)               \
    X("disk", evr_demo_build_disk, 0)                   \
    X("cornell", evr_demo_build_cornell, 0)             \
    X("cornell-still", evr_demo_build_cornell_still, 0) \
    X("cornell-bleed", evr_demo_build_cornell_bleed, 0) \
    X("city", evr_demo_build_city, 0)                   \
    X("blink", evr_demo_build_blink, 0)

typedef struct {
    const char *name;
    void (*build)(evr_gltf *g);
    int varies;
} demo_entry;

#define EVR_DEMO_ENTRY(name, build, varies) {name, build, varies},
#define EVR_DEMO_NAME(name, build, varies) name,
static const demo_entry demos[] = {EVR_DEMO_TABLE(EVR_DEMO_ENTRY)};
static const char *const demo_names[] = {EVR_DEMO_TABLE(EVR_DEMO_NAME) NULL};
#define NUM_DEMOS (sizeof demos / sizeof demos[0])

const char *const *evr_demo_names(void) { return demo_names; }

/* The table's entry of the scene called name, or NULL. */
static const demo_entry *find_demo(const char *name)
{
    for (size_t i = 0; name && i < NUM_DEMOS; i++)
        if (strcmp(name, demos[i].name) == 0) return &demos[i];
    return NULL;
}

int evr_demo_has_variants(const char *name)
{
    const demo_entry *d = find_demo(name);
    return d ? d->varies : 0;
}

evr_status evr_demo_glb(const char *name, void **glb, size_t *size, evr_error *err)
{
    return evr_demo_glb_variant(name, 0, glb, size, err);
}

/* err->msg: head, then the table's scenes (those with variants only, or all). */
static void scenes_message(evr_error *err, const char *head, int variants_only)
{
    size_t n = (size_t)snprintf(err->msg, sizeof err->msg, "%s", head);
    for (size_t k = 0; k < NUM_DEMOS && n < sizeof err->msg; k++)
        if (!variants_only || demos[k].varies)
            n += (size_t)snprintf(err->msg + n, sizeof err->msg - n, " %s", demos[k].name);
}

evr_status evr_demo_glb_variant(const char *name, uint64_t seed, void **glb, size_t *size,
                                evr_error *err)
{
    const demo_entry *d = find_demo(name);
    char head[sizeof err->msg];
    evr_gltf *g;
    evr_status st;
    *glb = NULL;
    *size = 0;
    if (!d) {
        snprintf(head, sizeof head,
                 "unknown demo scene \"%s\"; the built-in scenes are:", name ? name : "(null)");
        scenes_message(err, head, 0);
        return EVR_ERR_ARG;
    }
    if (seed && !d->varies) {
        snprintf(head, sizeof head,
                 "demo %s has no variants; the scenes with variants are:", d->name);
        scenes_message(err, head, 1);
        return EVR_ERR_ARG;
    }
    g = evr_gltf_new(d->name);
    if (!g) {
        snprintf(err->msg, sizeof err->msg, "demo %s: out of memory", d->name);
        return EVR_ERR_NOMEM;
    }
    evr_gltf_set_variant(g, seed);
    d->build(g);
    st = evr_gltf_glb(g, glb, size, err);
    evr_gltf_free(g);
    return st;
}

evr_status evr_demo_load(const char *name, evr_scene **out, evr_error *err)
{
    return evr_demo_load_variant(name, 0, out, err);
}

evr_status evr_demo_load_variant(const char *name, uint64_t seed, evr_scene **out, evr_error *err)
{
    void *glb = NULL;
    size_t size = 0;
    evr_status st;
    *out = NULL;
    st = evr_demo_glb_variant(name, seed, &glb, &size, err);
    if (st != EVR_OK) return st;
    st = evr_scene_load_memory(glb, size, "glb", out, err);
    free(glb);
    return st;
}

/* ---- mesh helpers ---- */

static int mesh_reserve(evr_demo_mesh *m, uint32_t nv, uint32_t ni)
{
    if (m->failed) return 0;
    if (m->nv + nv > m->cap_v) {
        uint32_t cap = m->cap_v ? m->cap_v : 1024;
        float *p, *n, *u;
        while (cap < m->nv + nv) cap *= 2;
        p = realloc(m->pos, sizeof(float) * 3 * cap);
        if (p) m->pos = p;
        n = realloc(m->nrm, sizeof(float) * 3 * cap);
        if (n) m->nrm = n;
        u = realloc(m->uv, sizeof(float) * 2 * cap);
        if (u) m->uv = u;
        if (!p || !n || !u) {
            m->failed = 1;
            return 0;
        }
        m->cap_v = cap;
    }
    if (m->ni + ni > m->cap_i) {
        uint32_t cap = m->cap_i ? m->cap_i : 3072;
        uint32_t *q;
        while (cap < m->ni + ni) cap *= 2;
        q = realloc(m->idx, sizeof(uint32_t) * cap);
        if (!q) {
            m->failed = 1;
            return 0;
        }
        m->idx = q;
        m->cap_i = cap;
    }
    return 1;
}

uint32_t evr_demo_mesh_vertex(evr_demo_mesh *m, const double p[3], const double n[3], double u,
                              double v)
{
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    uint32_t i = m->nv;
    int k;
    if (!mesh_reserve(m, 1, 0)) return 0;
    if (!(l > 0.0)) l = 1.0;
    for (k = 0; k < 3; k++) {
        m->pos[3 * i + k] = (float)p[k];
        m->nrm[3 * i + k] = (float)(n[k] / l);
    }
    m->uv[2 * i] = (float)u;
    m->uv[2 * i + 1] = (float)v;
    m->nv++;
    return i;
}

uint32_t evr_demo_mesh_vertex_mm(evr_demo_mesh *m, double x, double y, double z, const double n[3],
                                 double u, double v)
{
    double p[3];
    p[0] = x * 0.001;
    p[1] = y * 0.001;
    p[2] = z * 0.001;
    return evr_demo_mesh_vertex(m, p, n, u, v);
}

void evr_demo_mesh_triangle(evr_demo_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    double e1[3], e2[3], cr[3], ns = 0.0, l1 = 0.0, l2 = 0.0, lc = 0.0;
    int k;
    if (!mesh_reserve(m, 0, 3)) return;
    for (k = 0; k < 3; k++) {
        e1[k] = (double)m->pos[3 * b + k] - m->pos[3 * a + k];
        e2[k] = (double)m->pos[3 * c + k] - m->pos[3 * a + k];
    }
    cr[0] = e1[1] * e2[2] - e1[2] * e2[1];
    cr[1] = e1[2] * e2[0] - e1[0] * e2[2];
    cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
    for (k = 0; k < 3; k++) {
        l1 += e1[k] * e1[k];
        l2 += e2[k] * e2[k];
        lc += cr[k] * cr[k];
        ns += cr[k] * ((double)m->nrm[3 * a + k] + m->nrm[3 * b + k] + m->nrm[3 * c + k]);
    }
    if (!(lc > 1e-12 * l1 * l2)) return; /* degenerate (e.g. at the pole of a sphere) */
    m->idx[m->ni++] = a;
    if (ns >= 0.0) {
        m->idx[m->ni++] = b;
        m->idx[m->ni++] = c;
    } else {
        m->idx[m->ni++] = c;
        m->idx[m->ni++] = b;
    }
}

void evr_demo_mesh_grid(evr_demo_mesh *m, uint32_t first, int cols, int rows)
{
    int i, j;
    uint32_t w = (uint32_t)cols + 1;
    for (j = 0; j < rows; j++) {
        for (i = 0; i < cols; i++) {
            uint32_t a = first + (uint32_t)j * w + (uint32_t)i, b = a + 1, c = a + w, d = c + 1;
            evr_demo_mesh_triangle(m, a, b, d);
            evr_demo_mesh_triangle(m, a, d, c);
        }
    }
}

int evr_demo_mesh_finish(evr_gltf *g, evr_demo_mesh *m, const char *name, int material)
{
    int r = -1;
    if (m->failed) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while generating a demo mesh");
    } else {
        r = evr_gltf_mesh(g, name, m->pos, m->nrm, m->uv, m->nv, m->idx, m->ni, material);
    }
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    free(m->idx);
    memset(m, 0, sizeof *m);
    return r;
}

void evr_demo_look_at(const double eye[3], const double target[3], const double up[3], float q[4])
{
    double z[3], x[3], y[3], l;
    float r[3][3];
    evr_quat qq;
    int k;
    for (k = 0; k < 3; k++) z[k] = eye[k] - target[k]; /* camera +Z points away from the target */
    l = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    for (k = 0; k < 3; k++) z[k] /= l;
    x[0] = up[1] * z[2] - up[2] * z[1];
    x[1] = up[2] * z[0] - up[0] * z[2];
    x[2] = up[0] * z[1] - up[1] * z[0];
    l = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (k = 0; k < 3; k++) x[k] /= l;
    y[0] = z[1] * x[2] - z[2] * x[1];
    y[1] = z[2] * x[0] - z[0] * x[2];
    y[2] = z[0] * x[1] - z[1] * x[0];
    for (k = 0; k < 3; k++) {
        r[k][0] = (float)x[k];
        r[k][1] = (float)y[k];
        r[k][2] = (float)z[k];
    }
    qq = evr_quat_from_m33(r);
    q[0] = qq.x;
    q[1] = qq.y;
    q[2] = qq.z;
    q[3] = qq.w;
}
