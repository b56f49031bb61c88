/* The eye scene's anatomy (src/scene/demo_eye_parts.c), loaded through the C API as the
 * simulator loads it, and its glTF as the writer made it:
 *   - the cornea's front surface is a cap of the 7.8 mm corneal sphere protruding from the 12 mm
 *     eyeball, closed behind in the limbus plane; the sclera ends at the limbus;
 *   - the iris lies inside the globe (inside the eyeball's sphere or under the cornea), under the
 *     cornea (at least 0.5 mm behind its front surface), 2.5-3.5 mm behind the apex, rooted at
 *     the limbus, with the pupil's hole of radius 1.8 at its centre;
 *   - the pupil's disc is centred on the gaze axis just behind the iris, and follows the gaze
 *     (yaw 10, pitch 3 degrees in the second fixation);
 *   - materials: the cornea clear (transmission 1, IOR 1.376, smooth, a volume), the pupil unlit
 *     black, the lashes alpha-masked, sclera and skin rough as specified; the IR LED has a radius
 *     of 1.5 mm (in the file and in the imported light);
 *   - the lashes are children of the lids (they move with them);
 *   - the glint (the LED's mirror reflection on the corneal sphere towards the camera) falls on
 *     the cornea at rest gaze; its position is printed for the image-space check. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "evray.h"
#include "io/json_read.h"
#include "scene/demo_eye_parts.h"
#include "scene/scene.h"

#define MM 0.001
#define APEX (EVR_EYE_CORNEA_C + EVR_EYE_CORNEA_R)

static int find_node(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_nodes; i++)
        if (strcmp(s->nodes[i].name, name) == 0) return i;
    return -1;
}

static int find_instance(const evr_scene *s, const char *mesh)
{
    int i;
    for (i = 0; i < s->num_instances; i++)
        if (strcmp(s->meshes[s->instances[i].mesh].name, mesh) == 0) return i;
    return -1;
}

/* Vertex v of the instance's mesh in the eyeball's frame, millimetres (the eye's parts are
 * children of "eyeball", so their node transforms are the identity relative to it). */
static void vertex_mm(const evr_mesh *m, uint32_t v, double p[3])
{
    int k;
    for (k = 0; k < 3; k++) p[k] = m->positions[3 * v + k] / MM;
}

static double len3(const double p[3]) { return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

/* The distance from the corneal sphere's centre. */
static double cornea_dist(const double p[3])
{
    double q[3] = {p[0], p[1], p[2] - EVR_EYE_CORNEA_C};
    return len3(q);
}

static void check_geometry(const evr_scene *s)
{
    const int iris = find_instance(s, "iris"), pupil = find_instance(s, "pupil"),
              cornea = find_instance(s, "cornea"), sclera = find_instance(s, "sclera");
    const double zl = (EVR_EYE_R * EVR_EYE_R - EVR_EYE_CORNEA_R * EVR_EYE_CORNEA_R +
                       EVR_EYE_CORNEA_C * EVR_EYE_CORNEA_C) /
                      (2.0 * EVR_EYE_CORNEA_C);
    const double rl = sqrt(EVR_EYE_R * EVR_EYE_R - zl * zl);
    double rmin = 1e9, rmax = 0.0, zmax = -1e9, zmin = 1e9, c[3], lo[3], hi[3], p[3];
    const evr_mesh *m;
    uint32_t v;
    int eyeball = find_node(s, "eyeball"), cap = 0, back = 0;
    CHECK(iris >= 0 && pupil >= 0 && cornea >= 0 && sclera >= 0 && eyeball >= 0);
    if (iris < 0 || pupil < 0 || cornea < 0 || sclera < 0 || eyeball < 0) return;
    CHECK(s->nodes[s->instances[iris].node].parent == eyeball &&
          s->nodes[s->instances[pupil].node].parent == eyeball &&
          s->nodes[s->instances[cornea].node].parent == eyeball);

    /* the cornea: its front on the corneal sphere in front of the limbus, its back the disc in
     * the limbus plane */
    m = &s->meshes[s->instances[cornea].mesh];
    for (v = 0; v < m->num_vertices; v++) {
        vertex_mm(m, v, p);
        int on_cap = fabs(cornea_dist(p) - EVR_EYE_CORNEA_R) < 1e-3 && p[2] >= zl - 1e-3;
        int on_back = fabs(p[2] - zl) < 1e-3 && hypot(p[0], p[1]) <= rl + 1e-3;
        cap += on_cap;
        back += on_back;
        CHECK(on_cap || on_back);
        if (p[2] > zmax) zmax = p[2];
    }
    CHECK(cap > 1000 && back > 32);
    CHECK_NEAR(zmax, APEX, 1e-3);
    CHECK(APEX > EVR_EYE_R + 2.0); /* protruding */
    /* the sclera: on the eyeball's sphere, behind the limbus */
    m = &s->meshes[s->instances[sclera].mesh];
    for (v = 0; v < m->num_vertices; v++) {
        vertex_mm(m, v, p);
        CHECK(fabs(len3(p) - EVR_EYE_R) < 1e-3 && p[2] <= zl + 1e-3);
    }

    /* the iris: inside the globe, under the cornea, behind the apex, from the pupil to the
     * limbus */
    m = &s->meshes[s->instances[iris].mesh];
    zmax = -1e9;
    for (v = 0; v < m->num_vertices; v++) {
        double r, zc;
        vertex_mm(m, v, p);
        r = hypot(p[0], p[1]);
        zc = EVR_EYE_CORNEA_C + sqrt(EVR_EYE_CORNEA_R * EVR_EYE_CORNEA_R - r * r);
        CHECK(len3(p) <= EVR_EYE_R + 1e-3 || cornea_dist(p) <= EVR_EYE_CORNEA_R + 1e-3);
        CHECK(p[2] >= zl - 1e-3);
        if (r < rl - 1e-3) CHECK(p[2] <= zc - 0.5 || r > EVR_EYE_IRIS_R + 0.01);
        if (r < rmin) rmin = r;
        if (r > rmax) rmax = r;
        if (p[2] > zmax) zmax = p[2];
        if (p[2] < zmin) zmin = p[2];
    }
    printf("iris: radius %.3f to %.3f mm, z %.3f to %.3f (apex %.2f, limbus z %.3f r %.3f)\n", rmin,
           rmax, zmin, zmax, APEX, zl, rl);
    CHECK_NEAR(rmin, EVR_EYE_PUPIL_R, 1e-3);
    CHECK_NEAR(rmax, rl, 1e-3);
    CHECK(APEX - zmax >= 2.5 && APEX - zmax <= 3.5);
    CHECK_NEAR(zmin, zl, 1e-3);

    /* the pupil: a disc on the gaze axis just behind the iris's inner edge, covering the hole */
    m = &s->meshes[s->instances[pupil].mesh];
    rmax = 0.0;
    lo[0] = lo[1] = lo[2] = 1e9;
    hi[0] = hi[1] = hi[2] = -1e9;
    for (v = 0; v < m->num_vertices; v++) {
        int k;
        vertex_mm(m, v, p);
        for (k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], p[k]);
            hi[k] = fmax(hi[k], p[k]);
        }
        if (hypot(p[0], p[1]) > rmax) rmax = hypot(p[0], p[1]);
    }
    for (v = 0; v < 3; v++) c[v] = 0.5 * (lo[v] + hi[v]); /* the disc's centre */
    CHECK(fabs(c[0]) < 1e-4 && fabs(c[1]) < 1e-4);
    CHECK(c[2] < EVR_EYE_PUPIL_Z && c[2] > EVR_EYE_PUPIL_Z - 0.2);
    CHECK(rmax > EVR_EYE_PUPIL_R && rmax < EVR_EYE_PUPIL_R + 0.2);

    /* the pupil follows the gaze: at 0.45 s the eye holds its second fixation, yaw 10 (towards
     * +X) and pitch 3 (up) degrees */
    {
        evr_m34 w = evr_node_world_at(s, s->instances[pupil].node, 0.45);
        evr_v3 q = evr_m34_point(
            &w, evr_v3_make((float)(c[0] * MM), (float)(c[1] * MM), (float)(c[2] * MM)));
        double yaw = atan2(q.x, q.z) * 180.0 / 3.14159265358979,
               pitch = atan2(q.y, hypot(q.x, q.z)) * 180.0 / 3.14159265358979;
        printf("pupil at 0.45 s: yaw %.3f, pitch %.3f deg\n", yaw, pitch);
        CHECK_NEAR(yaw, 10.0, 1e-3);
        CHECK_NEAR(pitch, 3.0, 1e-3);
    }

    /* the lashes ride on the lids */
    CHECK(find_instance(s, "upper_lashes") >= 0 && find_instance(s, "lower_lashes") >= 0);
    if (find_instance(s, "upper_lashes") >= 0 && find_instance(s, "lower_lashes") >= 0) {
        CHECK(s->nodes[s->instances[find_instance(s, "upper_lashes")].node].parent ==
              find_node(s, "upper_lid"));
        CHECK(s->nodes[s->instances[find_instance(s, "lower_lashes")].node].parent ==
              find_node(s, "lower_lid"));
    }
}

/* The LED's reflection on the corneal sphere towards the camera at rest gaze: the point whose
 * normal bisects the directions to the camera and to the LED (fixed-point iteration). */
static void check_glint(const evr_scene *s)
{
    int led = -1, i, k;
    double cam[3], lp[3], n[3] = {0, 0, 1}, x[3];
    evr_m34 cw;
    evr_v3 cp;
    for (i = 0; i < s->num_lights; i++)
        if (strcmp(s->lights[i].name, "ir_led") == 0) led = i;
    CHECK(led >= 0);
    if (led < 0) return;
    CHECK_NEAR(s->lights[led].radius, 1.5e-3, 1e-9);
    cw = evr_node_world_at(s, s->cameras[0].node, 0.0);
    cp = evr_m34_point(&cw, evr_m34_point(&s->cameras[0].local, evr_v3_make(0, 0, 0)));
    {
        evr_m34 lw = evr_node_world_at(s, s->lights[led].node, 0.0);
        evr_v3 l = evr_m34_point(&lw, s->lights[led].position);
        lp[0] = l.x / MM, lp[1] = l.y / MM, lp[2] = l.z / MM;
    }
    cam[0] = cp.x / MM, cam[1] = cp.y / MM, cam[2] = cp.z / MM;
    printf("camera at (%.3f %.3f %.3f) mm, LED at (%.3f %.3f %.3f) mm\n", cam[0], cam[1], cam[2],
           lp[0], lp[1], lp[2]);
    CHECK(fabs(cam[1] + 10.0) < 1e-3 && fabs(cam[2] - 40.0) < 1e-3);
    for (i = 0; i < 100; i++) {
        double a[3], b[3], la, lb, h[3], lh;
        for (k = 0; k < 3; k++) x[k] = (k == 2 ? EVR_EYE_CORNEA_C : 0.0) + EVR_EYE_CORNEA_R * n[k];
        for (k = 0; k < 3; k++) a[k] = cam[k] - x[k], b[k] = lp[k] - x[k];
        la = len3(a);
        lb = len3(b);
        for (k = 0; k < 3; k++) h[k] = a[k] / la + b[k] / lb;
        lh = len3(h);
        for (k = 0; k < 3; k++) n[k] = h[k] / lh;
    }
    printf("glint at rest gaze: (%.4f %.4f %.4f) mm, %.2f deg from the corneal axis\n", x[0], x[1],
           x[2], acos(n[2]) * 180.0 / 3.14159265358979);
    /* on the cornea's cap, well inside the limbus */
    CHECK(acos(n[2]) < 30.0 * 3.14159265358979 / 180.0);
    CHECK(fabs(x[0] - 0.5557) < 1e-3 && fabs(x[1] + 2.2377) < 1e-3 && fabs(x[2] - 14.1514) < 1e-3);
}

/* The materials and the light as the writer put them in the glTF. */
static const char *json_of(const unsigned char *glb, size_t n, size_t *len)
{
    if (n < 20) return NULL;
    *len = (size_t)glb[12] | (size_t)glb[13] << 8 | (size_t)glb[14] << 16 | (size_t)glb[15] << 24;
    return *len + 20 <= n ? (const char *)glb + 20 : NULL;
}

static int material(const evr_jdoc *d, int root, const char *name)
{
    int m;
    char buf[64];
    for (m = evr_jdoc_first(d, evr_jdoc_get(d, root, "materials")); m >= 0; m = evr_jdoc_next(d, m))
        if (evr_jdoc_string(d, evr_jdoc_get(d, m, "name"), buf, sizeof buf) && !strcmp(buf, name))
            return m;
    return -1;
}

static double roughness(const evr_jdoc *d, int m)
{
    return evr_jdoc_number(
        d, evr_jdoc_get(d, evr_jdoc_get(d, m, "pbrMetallicRoughness"), "roughnessFactor"), -1.0);
}

static void check_file(void)
{
    void *glb = NULL;
    size_t size = 0, len = 0;
    evr_error err;
    const char *json;
    evr_jdoc d;
    int root, m, e, l;
    char buf[16];
    err.msg[0] = 0;
    CHECK_OK(evr_demo_glb("eye", &glb, &size, &err));
    json = glb ? json_of(glb, size, &len) : NULL;
    CHECK(json != NULL);
    if (!json) {
        free(glb);
        return;
    }
    root = evr_jdoc_parse(&d, json, len);
    CHECK(root >= 0);
    m = material(&d, root, "cornea");
    e = evr_jdoc_get(&d, m, "extensions");
    CHECK(evr_jdoc_number(&d,
                          evr_jdoc_get(&d, evr_jdoc_get(&d, e, "KHR_materials_transmission"),
                                       "transmissionFactor"),
                          0) == 1.0);
    CHECK((float)evr_jdoc_number(&d,
                                 evr_jdoc_get(&d, evr_jdoc_get(&d, e, "KHR_materials_ior"), "ior"),
                                 0) == EVR_EYE_CORNEA_IOR);
    CHECK(evr_jdoc_number(
              &d, evr_jdoc_get(&d, evr_jdoc_get(&d, e, "KHR_materials_volume"), "thicknessFactor"),
              0) > 0.0);
    CHECK(roughness(&d, m) >= 0.02 && roughness(&d, m) <= 0.05);
    m = material(&d, root, "pupil");
    CHECK(evr_jdoc_get(&d, evr_jdoc_get(&d, m, "extensions"), "KHR_materials_unlit") >= 0);
    CHECK(evr_jdoc_number(
              &d,
              evr_jdoc_first(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, m, "pbrMetallicRoughness"),
                                              "baseColorFactor")),
              1) == 0.0);
    for (l = 0; l < 2; l++) {
        m = material(&d, root, l ? "upper_lashes" : "lower_lashes");
        CHECK(evr_jdoc_string(&d, evr_jdoc_get(&d, m, "alphaMode"), buf, sizeof buf) &&
              !strcmp(buf, "MASK"));
        CHECK(evr_jdoc_get(&d, evr_jdoc_get(&d, m, "pbrMetallicRoughness"), "baseColorTexture") >=
              0);
    }
    m = material(&d, root, "sclera");
    CHECK(roughness(&d, m) >= 0.2 && roughness(&d, m) <= 0.3);
    m = material(&d, root, "skin");
    CHECK(roughness(&d, m) >= 0.5 && roughness(&d, m) <= 0.6);
    l = evr_jdoc_first(&d, evr_jdoc_get(&d,
                                        evr_jdoc_get(&d, evr_jdoc_get(&d, root, "extensions"),
                                                     "KHR_lights_punctual"),
                                        "lights"));
    CHECK((float)evr_jdoc_number(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, l, "extras"), "radius"),
                                 0) == 1.5e-3f);
    evr_jdoc_free(&d);
    free(glb);
}

int main(void)
{
    evr_scene *s = NULL;
    evr_error err;
    err.msg[0] = 0;
    CHECK_OK(evr_demo_load("eye", &s, &err));
    if (!s) {
        fprintf(stderr, "eye: %s\n", err.msg);
        return check_report("test_eye_anatomy");
    }
    check_geometry(s);
    check_glint(s);
    check_file();
    evr_scene_release(s);
    return check_report("test_eye_anatomy");
}
