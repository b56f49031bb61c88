/* The glTF builder (scene/gltf_writer.c), read back from the GLB's JSON and binary chunks as
 * glTF 2.0 lays them out: a skin (joints, skeleton, MAT4 inverse bind matrices), JOINTS_0 as
 * unsigned bytes or shorts (0 where the weight is 0) and WEIGHTS_0 as floats, morph targets
 * (POSITION with min/max, NORMAL), mesh and node weights, target names, and a "weights" channel
 * with keys x targets scalars; materials with every texture slot, KHR_texture_transform, alpha,
 * double-sidedness and the KHR_materials extensions (only those that differ from their defaults,
 * each listed in extensionsUsed), TANGENT, a light's radius in its extras; and every rule the
 * builder enforces refused with a message. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "io/json_read.h"
#include "scene/gltf_writer.h"

typedef struct {
    unsigned char *glb;
    size_t size;
    const char *json;
    size_t json_len;
    const unsigned char *bin;
    evr_jdoc d;
    int root;
} doc;

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static int open_doc(evr_gltf *g, doc *o)
{
    evr_error err;
    void *glb = NULL;
    memset(o, 0, sizeof *o);
    o->root = -1;
    err.msg[0] = 0;
    if (evr_gltf_glb(g, &glb, &o->size, &err) != EVR_OK) {
        fprintf(stderr, "glb: %s\n", err.msg);
        return 0;
    }
    o->glb = glb;
    o->json_len = rd32(o->glb + 12);
    o->json = (const char *)o->glb + 20;
    o->bin = o->glb + 20 + o->json_len + 8;
    o->root = evr_jdoc_parse(&o->d, o->json, o->json_len);
    return o->root >= 0;
}

static void close_doc(doc *o)
{
    evr_jdoc_free(&o->d);
    free(o->glb);
}

static int nth(const doc *o, int arr, int i)
{
    int v = evr_jdoc_first(&o->d, arr);
    while (v >= 0 && i-- > 0) v = evr_jdoc_next(&o->d, v);
    return v;
}

static int num(const doc *o, int v, const char *key)
{
    return (int)evr_jdoc_number(&o->d, evr_jdoc_get(&o->d, v, key), -1.0);
}

static int str_is(const doc *o, int v, const char *s)
{
    char buf[64];
    return evr_jdoc_string(&o->d, v, buf, sizeof buf) && strcmp(buf, s) == 0;
}

static int accessor(const doc *o, int i)
{
    return nth(o, evr_jdoc_get(&o->d, o->root, "accessors"), i);
}

/* The bytes an accessor (over a whole view) reads. */
static const unsigned char *accessor_data(const doc *o, int i)
{
    int view =
        nth(o, evr_jdoc_get(&o->d, o->root, "bufferViews"), num(o, accessor(o, i), "bufferView"));
    return o->bin + num(o, view, "byteOffset");
}

static float rdf(const unsigned char *p)
{
    uint32_t u = rd32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* A quad: vertices 0, 1 at y = 0, 2, 3 at y = 1. */
static const float quad_pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
static const float quad_nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
static const uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};

static void quad(evr_gltf_mesh_desc *d, const char *name)
{
    evr_gltf_mesh_desc_init(d, name);
    d->positions = quad_pos;
    d->normals = quad_nrm;
    d->num_vertices = 4;
    d->indices = quad_idx;
    d->num_indices = 6;
}

/* joints: a root "rig" with j0 under it and j1 under j0 at (0, 1, 0) */
static void rig(evr_gltf *g, int *j)
{
    int r = evr_gltf_node(g, "rig", -1);
    j[0] = evr_gltf_node(g, "j0", r);
    j[1] = evr_gltf_node(g, "j1", j[0]);
    evr_gltf_node_translation(g, j[1], 0, 1, 0);
}

static const uint16_t quad_joints[16] = {0, 1, 0, 0, 0, 7, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
static const float quad_weights[16] = {0.75f, 0.25f, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
/* column-major: the inverse of a translation by (0, y, 0) */
static void ibm_translate_y(float *m, float y)
{
    memset(m, 0, 16 * sizeof *m);
    m[0] = m[5] = m[10] = m[15] = 1.0f;
    m[13] = -y;
}

static void test_document(void)
{
    evr_gltf *g = evr_gltf_new("deform");
    evr_gltf_mesh_desc d;
    const char *names[2] = {"up", "wide"};
    float ibm[32], tp[24] = {0}, tn[24] = {0}, dw[2] = {0.0f, 0.25f}, nw[2] = {0.5f, 0.0f};
    const float times[3] = {0.0f, 0.5f, 1.0f}, wv[6] = {0, 0, 1, 0.5f, 0, 1};
    const float rot[8] = {0, 0, 0, 1, 0, 0, 0.70710678f, 0.70710678f}, rt[2] = {0.0f, 1.0f};
    int j[2], skin, arm, blob, n_arm, n_blob, anim, v, k;
    doc o;
    rig(g, j);
    quad(&d, "arm");
    d.joints = quad_joints;
    d.weights = quad_weights;
    arm = evr_gltf_add_mesh(g, &d);
    ibm_translate_y(ibm, 0.0f);
    ibm_translate_y(ibm + 16, 1.0f);
    skin = evr_gltf_skin(g, "arm_skin", j, 2, ibm, 0);
    n_arm = evr_gltf_node(g, "arm", -1);
    evr_gltf_node_mesh(g, n_arm, arm);
    evr_gltf_node_skin(g, n_arm, skin);

    for (v = 2; v < 4; v++) tp[3 * v + 1] = 1.0f;  /* target 0 lifts the top edge */
    for (v = 0; v < 4; v++) tp[12 + 3 * v] = 0.5f; /* target 1 moves everything along +x */
    tn[2] = -0.5f;
    quad(&d, "blob");
    d.num_targets = 2;
    d.target_positions = tp;
    d.target_normals = tn;
    d.default_weights = dw;
    d.target_names = names;
    blob = evr_gltf_add_mesh(g, &d);
    n_blob = evr_gltf_node(g, "blob", -1);
    evr_gltf_node_mesh(g, n_blob, blob);
    evr_gltf_node_weights(g, n_blob, nw, 2);

    anim = evr_gltf_animation(g, "move");
    evr_gltf_channel(g, anim, n_blob, EVR_GLTF_WEIGHTS, times, wv, 3, EVR_GLTF_LINEAR);
    evr_gltf_channel(g, anim, j[1], EVR_GLTF_ROTATION, rt, rot, 2, EVR_GLTF_LINEAR);
    CHECK(skin == 0 && arm == 0 && blob == 1);
    CHECK(open_doc(g, &o));
    if (o.root >= 0) {
        const evr_jdoc *jd = &o.d;
        int sk = nth(&o, evr_jdoc_get(jd, o.root, "skins"), 0);
        int nodes = evr_jdoc_get(jd, o.root, "nodes"), meshes = evr_jdoc_get(jd, o.root, "meshes");
        int prim, attrs, targets, a, ch, smp;
        const unsigned char *p;
        /* the skin */
        CHECK(evr_jdoc_count(jd, evr_jdoc_get(jd, o.root, "skins")) == 1);
        CHECK(str_is(&o, evr_jdoc_get(jd, sk, "name"), "arm_skin"));
        CHECK(evr_jdoc_count(jd, evr_jdoc_get(jd, sk, "joints")) == 2);
        CHECK(evr_jdoc_number(jd, nth(&o, evr_jdoc_get(jd, sk, "joints"), 0), -1) == j[0]);
        CHECK(evr_jdoc_number(jd, nth(&o, evr_jdoc_get(jd, sk, "joints"), 1), -1) == j[1]);
        CHECK(num(&o, sk, "skeleton") == 0);
        a = num(&o, sk, "inverseBindMatrices");
        CHECK(str_is(&o, evr_jdoc_get(jd, accessor(&o, a), "type"), "MAT4"));
        CHECK(num(&o, accessor(&o, a), "componentType") == 5126 &&
              num(&o, accessor(&o, a), "count") == 2);
        p = accessor_data(&o, a);
        CHECK(rdf(p + 4 * 13) == 0.0f && rdf(p + 64 + 4 * 13) == -1.0f &&
              rdf(p + 64 + 4 * 15) == 1.0f);
        CHECK(num(&o, nth(&o, nodes, n_arm), "skin") == 0 &&
              num(&o, nth(&o, nodes, n_arm), "mesh") == 0);
        /* JOINTS_0: unsigned bytes, the joint of a zero weight written as 0; WEIGHTS_0: floats */
        prim = nth(&o, evr_jdoc_get(jd, nth(&o, meshes, 0), "primitives"), 0);
        attrs = evr_jdoc_get(jd, prim, "attributes");
        a = num(&o, attrs, "JOINTS_0");
        CHECK(num(&o, accessor(&o, a), "componentType") == 5121);
        CHECK(str_is(&o, evr_jdoc_get(jd, accessor(&o, a), "type"), "VEC4") &&
              num(&o, accessor(&o, a), "count") == 4);
        p = accessor_data(&o, a);
        CHECK(p[0] == 0 && p[1] == 1 && p[4] == 0 && p[5] == 0 && p[8] == 1 && p[12] == 1);
        a = num(&o, attrs, "WEIGHTS_0");
        CHECK(num(&o, accessor(&o, a), "componentType") == 5126);
        CHECK(rdf(accessor_data(&o, a)) == 0.75f && rdf(accessor_data(&o, a) + 4) == 0.25f);
        CHECK(evr_jdoc_get(jd, prim, "targets") < 0);
        /* morph targets */
        prim = nth(&o, evr_jdoc_get(jd, nth(&o, meshes, 1), "primitives"), 0);
        targets = evr_jdoc_get(jd, prim, "targets");
        CHECK(evr_jdoc_count(jd, targets) == 2);
        for (k = 0; k < 2; k++) {
            int t = nth(&o, targets, k), pa = accessor(&o, num(&o, t, "POSITION"));
            CHECK(evr_jdoc_count(jd, evr_jdoc_get(jd, pa, "min")) == 3);
            CHECK(evr_jdoc_count(jd, evr_jdoc_get(jd, pa, "max")) == 3);
            CHECK(num(&o, pa, "count") == 4 && num(&o, t, "NORMAL") >= 0);
        }
        a = num(&o, nth(&o, targets, 0), "POSITION");
        CHECK(rdf(accessor_data(&o, a) + 4 * 7) == 1.0f); /* vertex 2's y */
        CHECK(evr_jdoc_number(jd, nth(&o, evr_jdoc_get(jd, accessor(&o, a), "max"), 1), 0) == 1.0);
        CHECK(evr_jdoc_number(jd, nth(&o, evr_jdoc_get(jd, nth(&o, meshes, 1), "weights"), 1), 0) ==
              0.25);
        CHECK(str_is(
            &o,
            nth(&o, evr_jdoc_get(jd, evr_jdoc_get(jd, nth(&o, meshes, 1), "extras"), "targetNames"),
                1),
            "wide"));
        CHECK(evr_jdoc_number(jd, nth(&o, evr_jdoc_get(jd, nth(&o, nodes, n_blob), "weights"), 0),
                              0) == 0.5);
        /* the weights channel: 3 keys x 2 targets, one scalar each */
        ch = nth(&o,
                 evr_jdoc_get(jd, nth(&o, evr_jdoc_get(jd, o.root, "animations"), 0), "channels"),
                 0);
        CHECK(str_is(&o, evr_jdoc_get(jd, evr_jdoc_get(jd, ch, "target"), "path"), "weights"));
        CHECK(num(&o, evr_jdoc_get(jd, ch, "target"), "node") == n_blob);
        smp = nth(&o,
                  evr_jdoc_get(jd, nth(&o, evr_jdoc_get(jd, o.root, "animations"), 0), "samplers"),
                  num(&o, ch, "sampler"));
        a = num(&o, smp, "output");
        CHECK(str_is(&o, evr_jdoc_get(jd, accessor(&o, a), "type"), "SCALAR"));
        CHECK(num(&o, accessor(&o, a), "count") == 6 &&
              num(&o, accessor(&o, num(&o, smp, "input")), "count") == 3);
        CHECK(rdf(accessor_data(&o, a) + 4 * 3) == 0.5f);
    }
    close_doc(&o);
    evr_gltf_free(g);
}

/* Joint indices past 255 are written as little-endian unsigned shorts. */
static void test_wide_joints(void)
{
    enum { N = 300 };
    evr_gltf *g = evr_gltf_new(NULL);
    evr_gltf_mesh_desc d;
    uint16_t jv[16] = {0};
    float wv[16] = {0};
    int joints[N], i, n;
    doc o;
    char name[16];
    joints[0] = evr_gltf_node(g, "bone0", -1);
    for (i = 1; i < N; i++) {
        snprintf(name, sizeof name, "bone%d", i);
        joints[i] = evr_gltf_node(g, name, joints[i - 1]);
    }
    for (i = 0; i < 4; i++) wv[4 * i] = 1.0f;
    jv[0] = 299;
    jv[4] = 256;
    quad(&d, "long");
    d.joints = jv;
    d.weights = wv;
    n = evr_gltf_node(g, "long", -1);
    evr_gltf_node_mesh(g, n, evr_gltf_add_mesh(g, &d));
    evr_gltf_node_skin(g, n, evr_gltf_skin(g, "long_skin", joints, N, NULL, -1));
    CHECK(open_doc(g, &o));
    if (o.root >= 0) {
        int prim = nth(
            &o, evr_jdoc_get(&o.d, nth(&o, evr_jdoc_get(&o.d, o.root, "meshes"), 0), "primitives"),
            0);
        int a = num(&o, evr_jdoc_get(&o.d, prim, "attributes"), "JOINTS_0");
        const unsigned char *p = accessor_data(&o, a);
        int sk = nth(&o, evr_jdoc_get(&o.d, o.root, "skins"), 0);
        CHECK(num(&o, accessor(&o, a), "componentType") == 5123);
        CHECK(p[0] == (299 & 0xff) && p[1] == 1 && p[8] == 0 && p[9] == 1);
        CHECK(evr_jdoc_get(&o.d, sk, "inverseBindMatrices") < 0 &&
              evr_jdoc_get(&o.d, sk, "skeleton") < 0);
    }
    close_doc(&o);
    evr_gltf_free(g);
}

static double numf(const doc *o, int v, const char *key, double def)
{
    return evr_jdoc_number(&o->d, evr_jdoc_get(&o->d, v, key), def);
}

static double elem(const doc *o, int arr, int i)
{
    return evr_jdoc_number(&o->d, nth(o, arr, i), -1);
}

static int list_has(const doc *o, int arr, const char *s)
{
    int v;
    for (v = evr_jdoc_first(&o->d, arr); v >= 0; v = evr_jdoc_next(&o->d, v))
        if (str_is(o, v, s)) return 1;
    return 0;
}

/* Materials: one with everything, one with the defaults; a mesh with tangents; lights with and
 * without a radius. */
static void test_materials(void)
{
    static const uint8_t px[4 * 4] = {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 9, 9, 9, 9};
    static const float tangents[16] = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, -1, 1, 0, 0, 1};
    evr_gltf *g = evr_gltf_new("materials");
    evr_gltf_material m;
    evr_gltf_mesh_desc d;
    evr_gltf_light_desc ld;
    int tex[3], full, plain, node, k;
    doc o;
    for (k = 0; k < 3; k++) {
        char name[8];
        snprintf(name, sizeof name, "t%d", k);
        tex[k] = evr_gltf_texture_png(g, name, px, 2, 2, k == 0 ? 4 : 3);
    }
    evr_gltf_material_init(&m, "plain");
    CHECK(m.double_sided == 1 && m.ior == 1.5f && m.alpha_cutoff == 0.5f && m.specular == 1.0f &&
          m.base_texture.index == -1 && m.normal_texture.scale[1] == 1.0f);
    plain = evr_gltf_add_material(g, &m);
    evr_gltf_material_init(&m, "full");
    m.base_texture.index = tex[0];
    m.base_texture.offset[0] = 0.25f;
    m.base_texture.rotation = 0.5f;
    m.base_texture.scale[1] = 2.0f;
    m.metallic_roughness_texture.index = tex[1];
    m.normal_texture.index = tex[2];
    m.normal_scale = 0.75f;
    m.occlusion_texture.index = tex[1];
    m.occlusion_strength = 0.5f;
    m.emissive_texture.index = tex[0];
    m.emissive[0] = 1.0f;
    m.emissive_strength = 4.0f;
    m.alpha_mode = EVR_GLTF_MASK;
    m.alpha_cutoff = 0.25f;
    m.double_sided = 0;
    m.unlit = 1;
    m.transmission = 1.0f;
    m.transmission_texture.index = tex[2];
    m.ior = 1.376f;
    m.thickness = 0.5f;
    m.attenuation_distance = 2.0f;
    m.attenuation_color[1] = 0.5f;
    m.specular = 0.5f;
    m.specular_color[2] = 2.0f;
    full = evr_gltf_add_material(g, &m);
    quad(&d, "tangent_quad");
    d.tangents = tangents;
    d.material = full;
    node = evr_gltf_node(g, "tangent_quad", -1);
    evr_gltf_node_mesh(g, node, evr_gltf_add_mesh(g, &d));
    evr_gltf_light_desc_init(&ld, "led", EVR_GLTF_POINT);
    ld.radius = 0.0015f;
    ld.intensity = 2e-3f;
    evr_gltf_node_light(g, evr_gltf_node(g, "led", -1), evr_gltf_add_light(g, &ld));
    evr_gltf_node_light(g, evr_gltf_node(g, "spot", -1),
                        evr_gltf_light(g, "spot", EVR_GLTF_SPOT, NULL, 1.0f, 0.1f, 0.2f));
    CHECK(plain == 0 && full == 1);
    CHECK(open_doc(g, &o));
    if (o.root >= 0) {
        const evr_jdoc *jd = &o.d;
        int mats = evr_jdoc_get(jd, o.root, "materials"),
            used = evr_jdoc_get(jd, o.root, "extensionsUsed");
        int p0 = nth(&o, mats, 0), p1 = nth(&o, mats, 1), pbr, t, x, e, prim, lights, a;
        static const char *const exts[] = {
            "KHR_lights_punctual",  "KHR_texture_transform",      "KHR_materials_emissive_strength",
            "KHR_materials_unlit",  "KHR_materials_transmission", "KHR_materials_ior",
            "KHR_materials_volume", "KHR_materials_specular"};
        CHECK(evr_jdoc_count(jd, used) == 8);
        for (k = 0; k < 8; k++) CHECK(list_has(&o, used, exts[k]));
        /* the defaults: nothing but the core, two-sided */
        CHECK(evr_jdoc_get(jd, p0, "extensions") < 0 && evr_jdoc_get(jd, p0, "alphaMode") < 0 &&
              evr_jdoc_get(jd, p0, "normalTexture") < 0);
        CHECK(evr_jdoc_type(jd, evr_jdoc_get(jd, p0, "doubleSided")) == EVR_JDOC_BOOL &&
              jd->v[evr_jdoc_get(jd, p0, "doubleSided")].num == 1.0);
        CHECK(evr_jdoc_get(jd, evr_jdoc_get(jd, p0, "pbrMetallicRoughness"), "baseColorTexture") <
              0);
        /* everything */
        pbr = evr_jdoc_get(jd, p1, "pbrMetallicRoughness");
        t = evr_jdoc_get(jd, pbr, "baseColorTexture");
        CHECK(num(&o, t, "index") == tex[0]);
        x = evr_jdoc_get(jd, evr_jdoc_get(jd, t, "extensions"), "KHR_texture_transform");
        CHECK(elem(&o, evr_jdoc_get(jd, x, "offset"), 0) == 0.25 &&
              elem(&o, evr_jdoc_get(jd, x, "offset"), 1) == 0.0);
        CHECK(numf(&o, x, "rotation", -1) == 0.5);
        CHECK(elem(&o, evr_jdoc_get(jd, x, "scale"), 0) == 1.0 &&
              elem(&o, evr_jdoc_get(jd, x, "scale"), 1) == 2.0);
        CHECK(num(&o, evr_jdoc_get(jd, pbr, "metallicRoughnessTexture"), "index") == tex[1]);
        CHECK(evr_jdoc_get(jd, evr_jdoc_get(jd, pbr, "metallicRoughnessTexture"), "extensions") <
              0);
        t = evr_jdoc_get(jd, p1, "normalTexture");
        CHECK(num(&o, t, "index") == tex[2] && numf(&o, t, "scale", -1) == 0.75);
        t = evr_jdoc_get(jd, p1, "occlusionTexture");
        CHECK(num(&o, t, "index") == tex[1] && numf(&o, t, "strength", -1) == 0.5);
        CHECK(num(&o, evr_jdoc_get(jd, p1, "emissiveTexture"), "index") == tex[0]);
        CHECK(elem(&o, evr_jdoc_get(jd, p1, "emissiveFactor"), 0) == 1.0);
        CHECK(str_is(&o, evr_jdoc_get(jd, p1, "alphaMode"), "MASK") &&
              numf(&o, p1, "alphaCutoff", -1) == 0.25);
        CHECK(evr_jdoc_get(jd, p1, "doubleSided") < 0);
        e = evr_jdoc_get(jd, p1, "extensions");
        CHECK(evr_jdoc_count(jd, e) == 0 && evr_jdoc_type(jd, e) == EVR_JDOC_OBJECT);
        CHECK(numf(&o, evr_jdoc_get(jd, e, "KHR_materials_emissive_strength"), "emissiveStrength",
                   -1) == 4.0);
        CHECK(evr_jdoc_type(jd, evr_jdoc_get(jd, e, "KHR_materials_unlit")) == EVR_JDOC_OBJECT);
        x = evr_jdoc_get(jd, e, "KHR_materials_transmission");
        CHECK(numf(&o, x, "transmissionFactor", -1) == 1.0 &&
              num(&o, evr_jdoc_get(jd, x, "transmissionTexture"), "index") == tex[2]);
        CHECK((float)numf(&o, evr_jdoc_get(jd, e, "KHR_materials_ior"), "ior", -1) == 1.376f);
        x = evr_jdoc_get(jd, e, "KHR_materials_volume");
        CHECK(numf(&o, x, "thicknessFactor", -1) == 0.5 &&
              numf(&o, x, "attenuationDistance", -1) == 2.0 &&
              elem(&o, evr_jdoc_get(jd, x, "attenuationColor"), 1) == 0.5);
        x = evr_jdoc_get(jd, e, "KHR_materials_specular");
        CHECK(numf(&o, x, "specularFactor", -1) == 0.5 &&
              elem(&o, evr_jdoc_get(jd, x, "specularColorFactor"), 2) == 2.0);
        /* TANGENT: VEC4 floats as given */
        prim = nth(
            &o, evr_jdoc_get(jd, nth(&o, evr_jdoc_get(jd, o.root, "meshes"), 0), "primitives"), 0);
        a = num(&o, evr_jdoc_get(jd, prim, "attributes"), "TANGENT");
        CHECK(a >= 0 && str_is(&o, evr_jdoc_get(jd, accessor(&o, a), "type"), "VEC4") &&
              num(&o, accessor(&o, a), "count") == 4);
        if (a >= 0) CHECK(rdf(accessor_data(&o, a) + 4 * 11) == -1.0f);
        /* the radius in the light's extras, none on the spot */
        lights = evr_jdoc_get(
            jd, evr_jdoc_get(jd, evr_jdoc_get(jd, o.root, "extensions"), "KHR_lights_punctual"),
            "lights");
        CHECK(evr_jdoc_count(jd, lights) == 2);
        CHECK((float)numf(&o, evr_jdoc_get(jd, nth(&o, lights, 0), "extras"), "radius", -1) ==
              0.0015f);
        CHECK(evr_jdoc_get(jd, nth(&o, lights, 1), "extras") < 0);
    }
    close_doc(&o);
    evr_gltf_free(g);
}

/* Materials, tangents and lights the builder refuses, each with a message containing `what`. */
static void test_bad_material(int which)
{
    static const char *const what[] = {"IOR >= 1",
                                       "no texture 7",
                                       "texture transform",
                                       "alpha mode",
                                       "attenuation distance",
                                       "tangents need normals",
                                       "w = +-1",
                                       "radius",
                                       "emissive strength",
                                       "specular in [0,1]"};
    static const float tangents[16] = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 0.5f, 1, 0, 0, 1};
    evr_gltf *g = evr_gltf_new(NULL);
    evr_gltf_material m;
    evr_gltf_mesh_desc d;
    evr_gltf_light_desc ld;
    evr_error err;
    void *glb = NULL;
    size_t size = 0;
    evr_gltf_material_init(&m, "m");
    if (which == 0) m.ior = 0.9f;
    if (which == 1) m.occlusion_texture.index = 7;
    if (which == 2) m.normal_texture.rotation = NAN;
    if (which == 3) m.alpha_mode = (evr_gltf_alpha_mode)3;
    if (which == 4) m.attenuation_distance = 0.0f;
    if (which == 8) m.emissive_strength = -1.0f;
    if (which == 9) m.specular = 1.5f;
    evr_gltf_add_material(g, &m);
    quad(&d, "q");
    if (which == 5) {
        d.normals = NULL;
        d.tangents = tangents;
    }
    if (which == 6) d.tangents = tangents;
    evr_gltf_add_mesh(g, &d);
    evr_gltf_light_desc_init(&ld, "sun", EVR_GLTF_DIRECTIONAL);
    if (which == 7) ld.radius = 0.01f;
    evr_gltf_add_light(g, &ld);
    err.msg[0] = 0;
    CHECK(evr_gltf_glb(g, &glb, &size, &err) == EVR_ERR_ARG && glb == NULL);
    if (!strstr(err.msg, what[which]))
        fprintf(stderr, "material case %d: \"%s\" lacks \"%s\"\n", which, err.msg, what[which]);
    CHECK(strstr(err.msg, what[which]) != NULL);
    free(glb);
    evr_gltf_free(g);
}

/* Each case builds a small document with one mistake; the builder must refuse it with a message
 * that contains `what`. */
enum {
    BAD_SUM,
    BAD_NEGATIVE,
    BAD_TWICE,
    BAD_ONLY_JOINTS,
    BAD_IBM_ROW,
    BAD_NO_COMMON_ROOT,
    BAD_SKELETON,
    BAD_DUPLICATE_JOINT,
    BAD_SKIN_ON_PLAIN,
    BAD_NO_SKIN,
    BAD_JOINT_RANGE,
    BAD_NODE_WEIGHTS,
    BAD_CHANNEL_NO_TARGETS,
    BAD_CHANNEL_TWICE,
    BAD_TARGETS_NO_DATA,
    NUM_BAD
};

static const char *const bad_what[NUM_BAD] = {
    "sum to",
    "negative",
    "two weights",
    "both joints and weights",
    "last row",
    "no common root",
    "not above",
    "two joints",
    "no skinned mesh",
    "needs a skin",
    "uses joint",
    "2 weights for 0",
    "no mesh with morph targets",
    "two weights channels",
    "morph targets need",
};

static void test_bad(int which)
{
    evr_gltf *g = evr_gltf_new(NULL);
    evr_gltf_mesh_desc d;
    uint16_t jv[16];
    float wv[16], ibm[32], w2[2] = {0, 0}, tp[12] = {0};
    const float times[1] = {0.0f}, vals[2] = {0, 0};
    int j[2], node, mesh, skin, anim, twin[2];
    void *glb = NULL;
    size_t size = 0;
    evr_error err;
    memcpy(jv, quad_joints, sizeof jv);
    memcpy(wv, quad_weights, sizeof wv);
    ibm_translate_y(ibm, 0.0f);
    ibm_translate_y(ibm + 16, 1.0f);
    rig(g, j);
    twin[0] = j[0];
    twin[1] = j[1];
    if (which == BAD_SUM) wv[1] = 0.3f;
    if (which == BAD_NEGATIVE) wv[2] = -0.1f;
    if (which == BAD_TWICE) jv[1] = 0;
    if (which == BAD_IBM_ROW) ibm[16 + 7] = 0.5f;
    if (which == BAD_JOINT_RANGE) jv[8] = 2;
    if (which == BAD_NO_COMMON_ROOT) twin[1] = evr_gltf_node(g, "loose", -1);
    if (which == BAD_DUPLICATE_JOINT) twin[1] = j[0];
    quad(&d, "arm");
    if (which != BAD_SKIN_ON_PLAIN) {
        d.joints = jv;
        d.weights = which == BAD_ONLY_JOINTS ? NULL : wv;
    }
    if (which == BAD_TARGETS_NO_DATA) d.num_targets = 1;
    mesh = evr_gltf_add_mesh(g, &d);
    skin = evr_gltf_skin(g, "skin", twin, 2, ibm, which == BAD_SKELETON ? j[1] : -1);
    node = evr_gltf_node(g, "arm", -1);
    evr_gltf_node_mesh(g, node, mesh);
    if (which != BAD_NO_SKIN) evr_gltf_node_skin(g, node, skin);
    if (which == BAD_NODE_WEIGHTS) evr_gltf_node_weights(g, node, w2, 2);
    anim = evr_gltf_animation(g, "anim");
    if (which == BAD_CHANNEL_NO_TARGETS) {
        evr_gltf_channel(g, anim, node, EVR_GLTF_WEIGHTS, times, vals, 1, EVR_GLTF_LINEAR);
    } else if (which == BAD_CHANNEL_TWICE) {
        quad(&d, "morph");
        d.num_targets = 1;
        d.target_positions = tp;
        mesh = evr_gltf_add_mesh(g, &d);
        node = evr_gltf_node(g, "morph", -1);
        evr_gltf_node_mesh(g, node, mesh);
        evr_gltf_channel(g, anim, node, EVR_GLTF_WEIGHTS, times, vals, 1, EVR_GLTF_LINEAR);
        evr_gltf_channel(g, anim, node, EVR_GLTF_WEIGHTS, times, vals, 1, EVR_GLTF_STEP);
    } else {
        evr_gltf_channel(g, anim, j[1], EVR_GLTF_TRANSLATION, times, tp, 1, EVR_GLTF_LINEAR);
    }
    err.msg[0] = 0;
    CHECK(evr_gltf_glb(g, &glb, &size, &err) == EVR_ERR_ARG && glb == NULL);
    if (!strstr(err.msg, bad_what[which]))
        fprintf(stderr, "case %d: \"%s\" lacks \"%s\"\n", which, err.msg, bad_what[which]);
    CHECK(strstr(err.msg, bad_what[which]) != NULL);
    free(glb);
    evr_gltf_free(g);
}

int main(void)
{
    int k;
    test_document();
    test_wide_joints();
    for (k = 0; k < NUM_BAD; k++) test_bad(k);
    test_materials();
    for (k = 0; k < 10; k++) test_bad_material(k);
    return check_report("test_gltf_writer");
}
