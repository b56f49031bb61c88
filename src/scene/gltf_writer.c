/* glTF 2.0 builder and GLB serializer. Objects that nothing refers back to (meshes, materials,
 * skins, cameras, lights, images, accessors, buffer views) are written to their JSON arrays as
 * soon as they are added; nodes and animations are kept as structs because later calls change
 * them (children, skin, weights, channels), and are written by evr_gltf_glb, which first checks
 * what only the whole document shows (a skinned mesh's node has a skin that covers its joints,
 * node weights and weight channels match their mesh's targets). */
#include "scene/gltf_writer.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/png.h"

#define GLTF_FLOAT 5126
#define GLTF_UINT 5125
#define GLTF_UBYTE 5121
#define GLTF_USHORT 5123
#define GLTF_ARRAY_BUFFER 34962
#define GLTF_ELEMENT_ARRAY_BUFFER 34963
#define GLTF_LINEAR 9729
#define GLTF_REPEAT 10497

/* The extensions the writer may use, in the order extensionsUsed lists them. */
enum {
    EXT_LIGHTS,
    EXT_TEXTURE_TRANSFORM,
    EXT_EMISSIVE_STRENGTH,
    EXT_UNLIT,
    EXT_TRANSMISSION,
    EXT_IOR,
    EXT_VOLUME,
    EXT_SPECULAR,
    EXT_COUNT
};
static const char *const ext_names[EXT_COUNT] = {
    "KHR_lights_punctual",  "KHR_texture_transform",      "KHR_materials_emissive_strength",
    "KHR_materials_unlit",  "KHR_materials_transmission", "KHR_materials_ior",
    "KHR_materials_volume", "KHR_materials_specular"};

/* A growing text buffer holding the comma-separated elements of one JSON array. */
typedef struct {
    char *p;
    size_t n, cap;
    int count;
} sbuf;

typedef struct {
    char *name;
    int parent;
    float t[3], r[4], s[3];
    int has_t, has_r, has_s;
    int mesh, camera, light, skin;
    float *weights; /* num_weights morph weights, or NULL */
    int num_weights;
} gnode;

/* What a node's skin, weights and weight channels are checked against. */
typedef struct {
    int num_targets;
    int max_joint; /* largest joint index of a non-zero weight; -1: not skinned */
} gmesh;

typedef struct {
    int node, path;
    int values; /* floats per key */
} gtarget;

typedef struct {
    char *name;
    sbuf channels, samplers;
    gtarget *targets; /* one per channel, to refuse duplicates */
    int num_targets, cap_targets;
} ganim;

struct evr_gltf {
    evr_status status;
    char msg[sizeof(((evr_error *)0)->msg)];
    char *scene_name;
    unsigned char *bin;
    size_t bin_n, bin_cap;
    sbuf accessors, views, meshes, materials, textures, images, cameras, lights, skins;
    int has_sampler;
    unsigned ext_used; /* EXT_* bits: the extensions written so far */
    gmesh *mesh_info;  /* one per mesh */
    int *skin_joints;  /* joint count of each skin */
    int cap_mesh_info; /* (meshes.count and skins.count are the counts) */
    int cap_skin_joints;
    uint64_t variant; /* evr_gltf_set_variant */
    gnode *nodes;
    int num_nodes, cap_nodes;
    ganim *anims;
    int num_anims, cap_anims;
};

static void fail(evr_gltf *g, evr_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void fail(evr_gltf *g, evr_status st, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (g->status != EVR_OK) return; /* keep the first failure */
    g->status = st;
    n = snprintf(g->msg, sizeof g->msg, "gltf: ");
    va_start(ap, fmt);
    vsnprintf(g->msg + n, sizeof g->msg - (size_t)n, fmt, ap);
    va_end(ap);
}

static int grow(evr_gltf *g, void **p, size_t elem, size_t need, size_t *cap)
{
    size_t c;
    void *q;
    if (need <= *cap) return 1;
    c = *cap ? *cap : 16;
    while (c < need) c *= 2;
    q = realloc(*p, c * elem);
    if (!q) {
        fail(g, EVR_ERR_NOMEM, "out of memory");
        return 0;
    }
    *p = q;
    *cap = c;
    return 1;
}

static int grow_int(evr_gltf *g, void **p, size_t elem, int need, int *cap)
{
    size_t c = (size_t)*cap;
    if (!grow(g, p, elem, (size_t)need, &c)) return 0;
    *cap = (int)c;
    return 1;
}

static char *dup_str(evr_gltf *g, const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (!d) {
        fail(g, EVR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    memcpy(d, s, n);
    return d;
}

/* ---- JSON text ---- */

static void sb_cat_n(evr_gltf *g, sbuf *b, const char *s, size_t n)
{
    if (g->status != EVR_OK) return;
    if (!grow(g, (void **)&b->p, 1, b->n + n + 1, &b->cap)) return;
    memcpy(b->p + b->n, s, n);
    b->n += n;
    b->p[b->n] = 0;
}

static void sb_cat(evr_gltf *g, sbuf *b, const char *s) { sb_cat_n(g, b, s, strlen(s)); }

static void sb_printf(evr_gltf *g, sbuf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void sb_printf(evr_gltf *g, sbuf *b, const char *fmt, ...)
{
    char tmp[256];
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof tmp) {
        fail(g, EVR_ERR_ARG, "internal: formatted text too long");
        return;
    }
    sb_cat_n(g, b, tmp, (size_t)n);
}

/* A number as JSON: 9 significant digits round-trip a float exactly. The decimal separator is
 * forced to '.' whatever the C locale says. */
static void sb_num(evr_gltf *g, sbuf *b, double v)
{
    char tmp[40];
    char *c;
    if (!isfinite(v)) {
        fail(g, EVR_ERR_ARG, "non-finite number");
        v = 0.0;
    }
    snprintf(tmp, sizeof tmp, "%.9g", v);
    for (c = tmp; *c; c++)
        if (*c == ',') *c = '.';
    sb_cat(g, b, tmp);
}

static void sb_nums(evr_gltf *g, sbuf *b, const float *v, int n)
{
    int i;
    sb_cat(g, b, "[");
    for (i = 0; i < n; i++) {
        if (i) sb_cat(g, b, ",");
        sb_num(g, b, v[i]);
    }
    sb_cat(g, b, "]");
}

static void sb_str(evr_gltf *g, sbuf *b, const char *s)
{
    sb_cat(g, b, "\"");
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') {
            char e[3] = {'\\', (char)c, 0};
            sb_cat(g, b, e);
        } else if (c < 0x20) {
            sb_printf(g, b, "\\u%04x", c);
        } else {
            sb_cat_n(g, b, (const char *)&c, 1);
        }
    }
    sb_cat(g, b, "\"");
}

/* Starts the next element of an array; returns its index. */
static int sb_elem(evr_gltf *g, sbuf *b)
{
    if (b->count) sb_cat(g, b, ",");
    return b->count++;
}

static void sb_free(sbuf *b) { free(b->p); }

/* ---- binary data ---- */

static int host_is_little_endian(void)
{
    const uint16_t probe = 1;
    return *(const unsigned char *)&probe == 1;
}

/* Appends n bytes (as 4-byte words swapped to little-endian when word is set) in a new
 * 4-byte-aligned buffer view; returns the view index. */
static int add_view(evr_gltf *g, const void *data, size_t n, int word, int target)
{
    size_t off = (g->bin_n + 3) & ~(size_t)3;
    int v;
    if (g->status != EVR_OK) return -1;
    if (off + n > 0x7fffffffu) {
        fail(g, EVR_ERR_ARG, "binary data larger than 2 GiB");
        return -1;
    }
    if (!grow(g, (void **)&g->bin, 1, off + n + 4, &g->bin_cap)) return -1;
    memset(g->bin + g->bin_n, 0, off - g->bin_n);
    memcpy(g->bin + off, data, n);
    if (word && !host_is_little_endian()) {
        size_t i;
        for (i = 0; i + 4 <= n; i += 4) {
            unsigned char *w = g->bin + off + i, t0 = w[0], t1 = w[1];
            w[0] = w[3];
            w[1] = w[2];
            w[2] = t1;
            w[3] = t0;
        }
    }
    g->bin_n = off + n;
    v = sb_elem(g, &g->views);
    sb_printf(g, &g->views, "{\"buffer\":0,\"byteOffset\":%lu,\"byteLength\":%lu",
              (unsigned long)off, (unsigned long)n);
    if (target) sb_printf(g, &g->views, ",\"target\":%d", target);
    sb_cat(g, &g->views, "}");
    return g->status == EVR_OK ? v : -1;
}

/* An accessor over a whole view of count elements of type ("SCALAR", "VEC3", ...);
 * min/max (ncomp values each) or NULL. */
static int add_accessor(evr_gltf *g, int view, int component, uint32_t count, const char *type,
                        const float *min, const float *max, int ncomp)
{
    int a;
    if (view < 0) return -1;
    a = sb_elem(g, &g->accessors);
    sb_printf(g, &g->accessors,
              "{\"bufferView\":%d,\"componentType\":%d,\"count\":%lu,\"type\":\"%s\"", view,
              component, (unsigned long)count, type);
    if (min && max) {
        sb_cat(g, &g->accessors, ",\"min\":");
        sb_nums(g, &g->accessors, min, ncomp);
        sb_cat(g, &g->accessors, ",\"max\":");
        sb_nums(g, &g->accessors, max, ncomp);
    }
    sb_cat(g, &g->accessors, "}");
    return g->status == EVR_OK ? a : -1;
}

/* ncomp 1 to 4 (SCALAR to VEC4) or 16 (MAT4). */
static int float_accessor(evr_gltf *g, const float *v, uint32_t count, int ncomp, int target,
                          int with_bounds)
{
    static const char *const types[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    float mn[16] = {0}, mx[16] = {0};
    uint32_t i;
    int c;
    for (i = 0; i < count; i++) {
        for (c = 0; c < ncomp; c++) {
            float x = v[(size_t)i * (size_t)ncomp + (size_t)c];
            if (!isfinite(x)) {
                fail(g, EVR_ERR_ARG, "non-finite value in vertex or key data");
                return -1;
            }
            if (i == 0 || x < mn[c]) mn[c] = x;
            if (i == 0 || x > mx[c]) mx[c] = x;
        }
    }
    return add_accessor(g, add_view(g, v, (size_t)count * (size_t)ncomp * sizeof(float), 1, target),
                        GLTF_FLOAT, count, ncomp == 16 ? "MAT4" : types[ncomp],
                        with_bounds ? mn : NULL, with_bounds ? mx : NULL, ncomp);
}

/* ---- public API ---- */

evr_gltf *evr_gltf_new(const char *scene_name)
{
    evr_gltf *g = calloc(1, sizeof *g);
    if (!g) return NULL;
    g->status = EVR_OK;
    if (scene_name && *scene_name) {
        g->scene_name = dup_str(g, scene_name);
        if (!g->scene_name) {
            free(g);
            return NULL;
        }
    }
    return g;
}

void evr_gltf_free(evr_gltf *g)
{
    int i;
    if (!g) return;
    free(g->scene_name);
    free(g->bin);
    sb_free(&g->accessors);
    sb_free(&g->views);
    sb_free(&g->meshes);
    sb_free(&g->materials);
    sb_free(&g->textures);
    sb_free(&g->images);
    sb_free(&g->cameras);
    sb_free(&g->lights);
    sb_free(&g->skins);
    free(g->mesh_info);
    free(g->skin_joints);
    for (i = 0; i < g->num_nodes; i++) {
        free(g->nodes[i].name);
        free(g->nodes[i].weights);
    }
    free(g->nodes);
    for (i = 0; i < g->num_anims; i++) {
        free(g->anims[i].name);
        sb_free(&g->anims[i].channels);
        sb_free(&g->anims[i].samplers);
        free(g->anims[i].targets);
    }
    free(g->anims);
    free(g);
}

void evr_gltf_fail(evr_gltf *g, evr_status status, const char *msg)
{
    fail(g, status == EVR_OK ? EVR_ERR_ARG : status, "%s", msg ? msg : "failed");
}

evr_status evr_gltf_status(const evr_gltf *g, evr_error *err)
{
    if (err && g->status != EVR_OK) snprintf(err->msg, sizeof err->msg, "%s", g->msg);
    return g->status;
}

static int check_name(evr_gltf *g, const char *what, const char *name)
{
    if (g->status != EVR_OK) return 0;
    if (!name || !*name) {
        fail(g, EVR_ERR_ARG, "every %s needs a name", what);
        return 0;
    }
    return 1;
}

int evr_gltf_texture_png(evr_gltf *g, const char *name, const uint8_t *pixels, int width,
                         int height, int channels)
{
    void *png = NULL;
    size_t png_n = 0;
    evr_error e;
    evr_status st;
    int view, img, tex;
    if (!check_name(g, "texture", name)) return -1;
    if (!pixels || (channels != 3 && channels != 4) || width <= 0 || height <= 0) {
        fail(g, EVR_ERR_ARG, "texture \"%s\": bad image %dx%d with %d channels", name, width,
             height, channels);
        return -1;
    }
    e.msg[0] = 0;
    st = evr_png_encode(pixels, width, height, channels, 8, &png, &png_n, &e);
    if (st != EVR_OK) {
        fail(g, st, "texture \"%s\": %s", name, e.msg);
        return -1;
    }
    view = add_view(g, png, png_n, 0, 0);
    free(png);
    if (view < 0) return -1;
    g->has_sampler = 1;
    img = sb_elem(g, &g->images);
    sb_cat(g, &g->images, "{\"name\":");
    sb_str(g, &g->images, name);
    sb_printf(g, &g->images, ",\"mimeType\":\"image/png\",\"bufferView\":%d}", view);
    tex = sb_elem(g, &g->textures);
    sb_cat(g, &g->textures, "{\"name\":");
    sb_str(g, &g->textures, name);
    sb_printf(g, &g->textures, ",\"sampler\":0,\"source\":%d}", img);
    return g->status == EVR_OK ? tex : -1;
}

static void slot_none(evr_gltf_texture_slot *t)
{
    t->index = -1;
    t->offset[0] = t->offset[1] = 0.0f;
    t->rotation = 0.0f;
    t->scale[0] = t->scale[1] = 1.0f;
}

void evr_gltf_material_init(evr_gltf_material *m, const char *name)
{
    memset(m, 0, sizeof *m);
    m->name = name;
    m->base_color[0] = m->base_color[1] = m->base_color[2] = m->base_color[3] = 1.0f;
    slot_none(&m->base_texture);
    slot_none(&m->metallic_roughness_texture);
    slot_none(&m->normal_texture);
    slot_none(&m->occlusion_texture);
    slot_none(&m->emissive_texture);
    slot_none(&m->transmission_texture);
    m->metallic = 0.0f;
    m->roughness = 1.0f;
    m->double_sided = 1;
    m->normal_scale = 1.0f;
    m->occlusion_strength = 1.0f;
    m->emissive_strength = 1.0f;
    m->alpha_mode = EVR_GLTF_OPAQUE;
    m->alpha_cutoff = 0.5f;
    m->ior = 1.5f;
    m->attenuation_distance = INFINITY;
    m->attenuation_color[0] = m->attenuation_color[1] = m->attenuation_color[2] = 1.0f;
    m->specular = 1.0f;
    m->specular_color[0] = m->specular_color[1] = m->specular_color[2] = 1.0f;
}

static int unit_range(const float *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!(v[i] >= 0.0f && v[i] <= 1.0f)) return 0;
    return 1;
}

static int all_finite(const float *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static int slot_identity(const evr_gltf_texture_slot *t)
{
    return t->offset[0] == 0.0f && t->offset[1] == 0.0f && t->rotation == 0.0f &&
           t->scale[0] == 1.0f && t->scale[1] == 1.0f;
}

static int slot_ok(evr_gltf *g, const char *mat, const char *what, const evr_gltf_texture_slot *t)
{
    if (t->index < -1 || t->index >= g->textures.count) {
        fail(g, EVR_ERR_ARG, "material \"%s\": %s: no texture %d", mat, what, t->index);
        return 0;
    }
    if (!all_finite(t->offset, 2) || !isfinite(t->rotation) || !all_finite(t->scale, 2)) {
        fail(g, EVR_ERR_ARG, "material \"%s\": %s: non-finite texture transform", mat, what);
        return 0;
    }
    return 1;
}

/* A textureInfo: ,"key":{"index":i[,"<extra>":v][,"extensions":{"KHR_texture_transform":...}]}
 * when the slot holds a texture; extra names normalTexture's scale or occlusionTexture's
 * strength (NULL: none). */
static void put_slot(evr_gltf *g, sbuf *b, const char *key, const evr_gltf_texture_slot *t,
                     const char *extra, float extra_v)
{
    if (t->index < 0) return;
    sb_printf(g, b, ",\"%s\":{\"index\":%d", key, t->index);
    if (extra && extra_v != 1.0f) {
        sb_printf(g, b, ",\"%s\":", extra);
        sb_num(g, b, extra_v);
    }
    if (!slot_identity(t)) {
        g->ext_used |= 1u << EXT_TEXTURE_TRANSFORM;
        sb_cat(g, b, ",\"extensions\":{\"KHR_texture_transform\":{\"offset\":");
        sb_nums(g, b, t->offset, 2);
        sb_cat(g, b, ",\"rotation\":");
        sb_num(g, b, t->rotation);
        sb_cat(g, b, ",\"scale\":");
        sb_nums(g, b, t->scale, 2);
        sb_cat(g, b, "}}");
    }
    sb_cat(g, b, "}");
}

static int material_ok(evr_gltf *g, const evr_gltf_material *m)
{
    const char *n = m->name;
    if (!unit_range(m->base_color, 4) || !unit_range(&m->metallic, 1) ||
        !unit_range(&m->roughness, 1) || !unit_range(m->emissive, 3)) {
        fail(g, EVR_ERR_ARG,
             "material \"%s\": colour, metallic, roughness and emissive factors must lie in [0,1]",
             n);
        return 0;
    }
    if (!(m->emissive_strength >= 0.0f) || !isfinite(m->emissive_strength) ||
        !isfinite(m->normal_scale) || !unit_range(&m->occlusion_strength, 1)) {
        fail(g, EVR_ERR_ARG,
             "material \"%s\": needs emissive strength >= 0, a finite normal scale and occlusion "
             "strength in [0,1]",
             n);
        return 0;
    }
    if ((int)m->alpha_mode < 0 || (int)m->alpha_mode > 2 || !(m->alpha_cutoff >= 0.0f) ||
        !isfinite(m->alpha_cutoff)) {
        fail(g, EVR_ERR_ARG, "material \"%s\": bad alpha mode or cutoff", n);
        return 0;
    }
    if (!unit_range(&m->transmission, 1) || !(m->ior >= 1.0f) || !isfinite(m->ior)) {
        fail(g, EVR_ERR_ARG, "material \"%s\": needs transmission in [0,1] and IOR >= 1", n);
        return 0;
    }
    if (!(m->thickness >= 0.0f) || !isfinite(m->thickness) || !(m->attenuation_distance > 0.0f) ||
        !unit_range(m->attenuation_color, 3)) {
        fail(g, EVR_ERR_ARG,
             "material \"%s\": volume needs thickness >= 0, attenuation distance > 0 and colour in "
             "[0,1]",
             n);
        return 0;
    }
    if (!unit_range(&m->specular, 1) || !all_finite(m->specular_color, 3) ||
        !(m->specular_color[0] >= 0.0f && m->specular_color[1] >= 0.0f &&
          m->specular_color[2] >= 0.0f)) {
        fail(g, EVR_ERR_ARG, "material \"%s\": needs specular in [0,1] and a colour >= 0", n);
        return 0;
    }
    return slot_ok(g, n, "base colour texture", &m->base_texture) &&
           slot_ok(g, n, "metallic-roughness texture", &m->metallic_roughness_texture) &&
           slot_ok(g, n, "normal texture", &m->normal_texture) &&
           slot_ok(g, n, "occlusion texture", &m->occlusion_texture) &&
           slot_ok(g, n, "emissive texture", &m->emissive_texture) &&
           slot_ok(g, n, "transmission texture", &m->transmission_texture);
}

/* The material's "extensions" object, when any differs from its defaults. */
static void put_material_extensions(evr_gltf *g, sbuf *b, const evr_gltf_material *m)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    int first = 1;
#define EXT_OPEN(bit)                                                                     \
    do {                                                                                  \
        sb_printf(g, b, "%s\"%s\":{", first ? ",\"extensions\":{" : ",", ext_names[bit]); \
        g->ext_used |= 1u << (bit);                                                       \
        first = 0;                                                                        \
    } while (0)
    if (m->emissive_strength != 1.0f) {
        EXT_OPEN(EXT_EMISSIVE_STRENGTH);
        sb_cat(g, b, "\"emissiveStrength\":");
        sb_num(g, b, m->emissive_strength);
        sb_cat(g, b, "}");
    }
    if (m->unlit) {
        EXT_OPEN(EXT_UNLIT);
        sb_cat(g, b, "}");
    }
    if (m->transmission > 0.0f || m->transmission_texture.index >= 0) {
        EXT_OPEN(EXT_TRANSMISSION);
        sb_cat(g, b, "\"transmissionFactor\":");
        sb_num(g, b, m->transmission);
        put_slot(g, b, "transmissionTexture", &m->transmission_texture, NULL, 1.0f);
        sb_cat(g, b, "}");
    }
    if (m->ior != 1.5f) {
        EXT_OPEN(EXT_IOR);
        sb_cat(g, b, "\"ior\":");
        sb_num(g, b, m->ior);
        sb_cat(g, b, "}");
    }
    if (m->thickness > 0.0f || isfinite(m->attenuation_distance) ||
        memcmp(m->attenuation_color, white, sizeof white)) {
        EXT_OPEN(EXT_VOLUME);
        sb_cat(g, b, "\"thicknessFactor\":");
        sb_num(g, b, m->thickness);
        if (isfinite(m->attenuation_distance)) {
            sb_cat(g, b, ",\"attenuationDistance\":");
            sb_num(g, b, m->attenuation_distance);
        }
        sb_cat(g, b, ",\"attenuationColor\":");
        sb_nums(g, b, m->attenuation_color, 3);
        sb_cat(g, b, "}");
    }
    if (m->specular != 1.0f || memcmp(m->specular_color, white, sizeof white)) {
        EXT_OPEN(EXT_SPECULAR);
        sb_cat(g, b, "\"specularFactor\":");
        sb_num(g, b, m->specular);
        sb_cat(g, b, ",\"specularColorFactor\":");
        sb_nums(g, b, m->specular_color, 3);
        sb_cat(g, b, "}");
    }
#undef EXT_OPEN
    if (!first) sb_cat(g, b, "}");
}

int evr_gltf_add_material(evr_gltf *g, const evr_gltf_material *m)
{
    static const char *const modes[3] = {"OPAQUE", "MASK", "BLEND"};
    sbuf *b = &g->materials;
    int idx;
    if (!check_name(g, "material", m->name)) return -1;
    if (!material_ok(g, m)) return -1;
    idx = sb_elem(g, b);
    sb_cat(g, b, "{\"name\":");
    sb_str(g, b, m->name);
    sb_cat(g, b, ",\"pbrMetallicRoughness\":{\"baseColorFactor\":");
    sb_nums(g, b, m->base_color, 4);
    put_slot(g, b, "baseColorTexture", &m->base_texture, NULL, 1.0f);
    sb_cat(g, b, ",\"metallicFactor\":");
    sb_num(g, b, m->metallic);
    sb_cat(g, b, ",\"roughnessFactor\":");
    sb_num(g, b, m->roughness);
    put_slot(g, b, "metallicRoughnessTexture", &m->metallic_roughness_texture, NULL, 1.0f);
    sb_cat(g, b, "}");
    put_slot(g, b, "normalTexture", &m->normal_texture, "scale", m->normal_scale);
    put_slot(g, b, "occlusionTexture", &m->occlusion_texture, "strength", m->occlusion_strength);
    put_slot(g, b, "emissiveTexture", &m->emissive_texture, NULL, 1.0f);
    if (m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f) {
        sb_cat(g, b, ",\"emissiveFactor\":");
        sb_nums(g, b, m->emissive, 3);
    }
    if (m->alpha_mode != EVR_GLTF_OPAQUE)
        sb_printf(g, b, ",\"alphaMode\":\"%s\"", modes[m->alpha_mode]);
    if (m->alpha_mode == EVR_GLTF_MASK && m->alpha_cutoff != 0.5f) {
        sb_cat(g, b, ",\"alphaCutoff\":");
        sb_num(g, b, m->alpha_cutoff);
    }
    if (m->double_sided) sb_cat(g, b, ",\"doubleSided\":true");
    put_material_extensions(g, b, m);
    sb_cat(g, b, "}");
    return g->status == EVR_OK ? idx : -1;
}

int evr_gltf_mesh(evr_gltf *g, const char *name, const float *positions, const float *normals,
                  const float *texcoords, uint32_t num_vertices, const uint32_t *indices,
                  uint32_t num_indices, int material)
{
    evr_gltf_mesh_desc d;
    evr_gltf_mesh_desc_init(&d, name);
    d.positions = positions;
    d.normals = normals;
    d.texcoords = texcoords;
    d.num_vertices = num_vertices;
    d.indices = indices;
    d.num_indices = num_indices;
    d.material = material;
    return evr_gltf_add_mesh(g, &d);
}

void evr_gltf_mesh_desc_init(evr_gltf_mesh_desc *d, const char *name)
{
    memset(d, 0, sizeof *d);
    d->name = name;
    d->material = -1;
}

/* Checks JOINTS_0 / WEIGHTS_0 as glTF requires them and finds the largest joint index that
 * carries weight. */
static int check_skin_attributes(evr_gltf *g, const evr_gltf_mesh_desc *d, int *max_joint)
{
    uint32_t v;
    int k, j;
    *max_joint = -1;
    for (v = 0; v < d->num_vertices; v++) {
        const uint16_t *jv = d->joints + 4 * (size_t)v;
        const float *wv = d->weights + 4 * (size_t)v;
        double sum = 0.0;
        for (k = 0; k < 4; k++) {
            if (!(wv[k] >= 0.0f) || !isfinite(wv[k])) {
                fail(g, EVR_ERR_ARG, "mesh \"%s\": vertex %lu has a negative or non-finite weight",
                     d->name, (unsigned long)v);
                return 0;
            }
            if (wv[k] == 0.0f) continue;
            sum += wv[k];
            for (j = 0; j < k; j++) {
                if (jv[j] == jv[k] && wv[j] > 0.0f) {
                    fail(g, EVR_ERR_ARG, "mesh \"%s\": vertex %lu gives joint %u two weights",
                         d->name, (unsigned long)v, (unsigned)jv[k]);
                    return 0;
                }
            }
            if (jv[k] > *max_joint) *max_joint = jv[k];
        }
        if (!(fabs(sum - 1.0) <= 1e-5)) {
            fail(g, EVR_ERR_ARG, "mesh \"%s\": the weights of vertex %lu sum to %g, not 1", d->name,
                 (unsigned long)v, sum);
            return 0;
        }
    }
    return 1;
}

/* JOINTS_0: unsigned bytes or little-endian unsigned shorts, 0 where the weight is 0. */
static int joints_accessor(evr_gltf *g, const evr_gltf_mesh_desc *d, int max_joint)
{
    const int wide = max_joint > 255;
    const size_t n = 4 * (size_t)d->num_vertices, size = n * (wide ? 2 : 1);
    unsigned char *bytes = malloc(size);
    size_t i;
    int a;
    if (!bytes) {
        fail(g, EVR_ERR_NOMEM, "out of memory");
        return -1;
    }
    for (i = 0; i < n; i++) {
        unsigned j = d->weights[i] > 0.0f ? d->joints[i] : 0u;
        if (wide) {
            bytes[2 * i] = (unsigned char)(j & 0xff);
            bytes[2 * i + 1] = (unsigned char)(j >> 8);
        } else {
            bytes[i] = (unsigned char)j;
        }
    }
    a = add_accessor(g, add_view(g, bytes, size, 0, GLTF_ARRAY_BUFFER),
                     wide ? GLTF_USHORT : GLTF_UBYTE, d->num_vertices, "VEC4", NULL, NULL, 4);
    free(bytes);
    return a;
}

int evr_gltf_add_mesh(evr_gltf *g, const evr_gltf_mesh_desc *d)
{
    const char *name = d->name;
    sbuf *b = &g->meshes;
    const uint32_t nv = d->num_vertices;
    const size_t tstride = 3 * (size_t)nv;
    int apos, anrm = -1, auv = -1, atan = -1, aidx, ajoints = -1, aweights = -1, idx,
              max_joint = -1, t;
    int *acc_t = NULL; /* per target: POSITION accessor, then NORMAL accessor (or -1) */
    uint32_t i;
    if (!check_name(g, "mesh", name)) return -1;
    if (!d->positions || !d->indices || nv == 0 || d->num_indices == 0 || d->num_indices % 3 != 0) {
        fail(g, EVR_ERR_ARG, "mesh \"%s\": needs positions and a multiple of 3 indices", name);
        return -1;
    }
    if (d->material < -1 || d->material >= g->materials.count) {
        fail(g, EVR_ERR_ARG, "mesh \"%s\": no material %d", name, d->material);
        return -1;
    }
    for (i = 0; i < d->num_indices; i++) {
        if (d->indices[i] >= nv) {
            fail(g, EVR_ERR_ARG, "mesh \"%s\": index %lu out of range", name,
                 (unsigned long)d->indices[i]);
            return -1;
        }
    }
    if (d->tangents && !d->normals) {
        fail(g, EVR_ERR_ARG, "mesh \"%s\": tangents need normals", name);
        return -1;
    }
    for (i = 0; d->tangents && i < nv; i++) {
        const float *tv = d->tangents + 4 * (size_t)i;
        if (!all_finite(tv, 3) || (tv[3] != 1.0f && tv[3] != -1.0f)) {
            fail(g, EVR_ERR_ARG, "mesh \"%s\": tangent %lu is not finite with w = +-1", name,
                 (unsigned long)i);
            return -1;
        }
    }
    if (!d->joints != !d->weights) {
        fail(g, EVR_ERR_ARG, "mesh \"%s\": a skin needs both joints and weights", name);
        return -1;
    }
    if (d->joints && !check_skin_attributes(g, d, &max_joint)) return -1;
    if (d->num_targets < 0 || (d->num_targets > 0 && !d->target_positions) ||
        (d->num_targets == 0 &&
         (d->target_positions || d->target_normals || d->default_weights || d->target_names))) {
        fail(g, EVR_ERR_ARG, "mesh \"%s\": morph targets need num_targets and target_positions",
             name);
        return -1;
    }
    for (t = 0; t < d->num_targets; t++) {
        if ((d->default_weights && !isfinite(d->default_weights[t])) ||
            (d->target_names && !check_name(g, "morph target", d->target_names[t]))) {
            fail(g, EVR_ERR_ARG, "mesh \"%s\": bad default weight or name of target %d", name, t);
            return -1;
        }
    }
    if (!grow_int(g, (void **)&g->mesh_info, sizeof *g->mesh_info, b->count + 1, &g->cap_mesh_info))
        return -1;
    if (d->num_targets > 0 && !(acc_t = malloc(sizeof(int) * 2 * (size_t)d->num_targets))) {
        fail(g, EVR_ERR_NOMEM, "out of memory");
        return -1;
    }

    apos = float_accessor(g, d->positions, nv, 3, GLTF_ARRAY_BUFFER, 1);
    if (d->normals) anrm = float_accessor(g, d->normals, nv, 3, GLTF_ARRAY_BUFFER, 0);
    if (d->texcoords) auv = float_accessor(g, d->texcoords, nv, 2, GLTF_ARRAY_BUFFER, 0);
    if (d->tangents) atan = float_accessor(g, d->tangents, nv, 4, GLTF_ARRAY_BUFFER, 0);
    if (d->joints) {
        ajoints = joints_accessor(g, d, max_joint);
        aweights = float_accessor(g, d->weights, nv, 4, GLTF_ARRAY_BUFFER, 0);
    }
    for (t = 0; t < d->num_targets; t++) { /* a target's POSITION needs min and max */
        acc_t[2 * t] = float_accessor(g, d->target_positions + (size_t)t * tstride, nv, 3,
                                      GLTF_ARRAY_BUFFER, 1);
        acc_t[2 * t + 1] = d->target_normals
                               ? float_accessor(g, d->target_normals + (size_t)t * tstride, nv, 3,
                                                GLTF_ARRAY_BUFFER, 0)
                               : -1;
    }
    aidx = add_accessor(g,
                        add_view(g, d->indices, (size_t)d->num_indices * sizeof(uint32_t), 1,
                                 GLTF_ELEMENT_ARRAY_BUFFER),
                        GLTF_UINT, d->num_indices, "SCALAR", NULL, NULL, 1);
    if (g->status != EVR_OK) {
        free(acc_t);
        return -1;
    }
    idx = sb_elem(g, b);
    sb_cat(g, b, "{\"name\":");
    sb_str(g, b, name);
    sb_printf(g, b, ",\"primitives\":[{\"attributes\":{\"POSITION\":%d", apos);
    if (anrm >= 0) sb_printf(g, b, ",\"NORMAL\":%d", anrm);
    if (auv >= 0) sb_printf(g, b, ",\"TEXCOORD_0\":%d", auv);
    if (atan >= 0) sb_printf(g, b, ",\"TANGENT\":%d", atan);
    if (ajoints >= 0) sb_printf(g, b, ",\"JOINTS_0\":%d,\"WEIGHTS_0\":%d", ajoints, aweights);
    sb_printf(g, b, "},\"indices\":%d", aidx);
    if (d->material >= 0) sb_printf(g, b, ",\"material\":%d", d->material);
    sb_cat(g, b, ",\"mode\":4");
    for (t = 0; t < d->num_targets; t++) {
        sb_printf(g, b, "%s{\"POSITION\":%d", t ? "," : ",\"targets\":[", acc_t[2 * t]);
        if (acc_t[2 * t + 1] >= 0) sb_printf(g, b, ",\"NORMAL\":%d", acc_t[2 * t + 1]);
        sb_cat(g, b, t + 1 == d->num_targets ? "}]" : "}");
    }
    sb_cat(g, b, "}]");
    if (d->default_weights) {
        sb_cat(g, b, ",\"weights\":");
        sb_nums(g, b, d->default_weights, d->num_targets);
    }
    for (t = 0; d->target_names && t < d->num_targets; t++) {
        sb_cat(g, b, t ? "," : ",\"extras\":{\"targetNames\":[");
        sb_str(g, b, d->target_names[t]);
        if (t + 1 == d->num_targets) sb_cat(g, b, "]}");
    }
    sb_cat(g, b, "}");
    free(acc_t);
    if (g->status != EVR_OK) return -1;
    g->mesh_info[idx].num_targets = d->num_targets;
    g->mesh_info[idx].max_joint = d->joints ? max_joint : -1;
    return idx;
}

/* Whether node a is node n or one of its ancestors. */
static int is_ancestor_or_self(const evr_gltf *g, int a, int n)
{
    for (; n >= 0; n = g->nodes[n].parent)
        if (n == a) return 1;
    return 0;
}

int evr_gltf_skin(evr_gltf *g, const char *name, const int *joints, int num_joints,
                  const float *inverse_bind, int skeleton)
{
    sbuf *b = &g->skins;
    int i, k, root, aibm = -1, idx;
    if (!check_name(g, "skin", name)) return -1;
    if (!joints || num_joints < 1 || skeleton < -1 || skeleton >= g->num_nodes) {
        fail(g, EVR_ERR_ARG, "skin \"%s\": needs joints (and skeleton -1 or a node)", name);
        return -1;
    }
    for (i = 0; i < num_joints; i++) {
        if (joints[i] < 0 || joints[i] >= g->num_nodes) {
            fail(g, EVR_ERR_ARG, "skin \"%s\": joint %d is no node", name, i);
            return -1;
        }
        for (k = 0; k < i; k++) {
            if (joints[k] == joints[i]) {
                fail(g, EVR_ERR_ARG, "skin \"%s\": node \"%s\" is two joints", name,
                     g->nodes[joints[i]].name);
                return -1;
            }
        }
    }
    /* the closest common root: the nearest ancestor-or-self of the first joint above them all */
    for (root = joints[0]; root >= 0; root = g->nodes[root].parent) {
        for (i = 1; i < num_joints && is_ancestor_or_self(g, root, joints[i]); i++) continue;
        if (i == num_joints) break;
    }
    if (root < 0) {
        fail(g, EVR_ERR_ARG, "skin \"%s\": the joints have no common root node", name);
        return -1;
    }
    if (skeleton >= 0 && !is_ancestor_or_self(g, skeleton, root)) {
        fail(g, EVR_ERR_ARG, "skin \"%s\": skeleton \"%s\" is not above the joints' common root",
             name, g->nodes[skeleton].name);
        return -1;
    }
    for (i = 0; inverse_bind && i < num_joints; i++) {
        const float *m = inverse_bind + 16 * (size_t)i; /* column-major: row 3 at 3, 7, 11, 15 */
        if (m[3] != 0.0f || m[7] != 0.0f || m[11] != 0.0f || m[15] != 1.0f) {
            fail(g, EVR_ERR_ARG, "skin \"%s\": inverse bind matrix %d: last row is not 0 0 0 1",
                 name, i);
            return -1;
        }
    }
    if (!grow_int(g, (void **)&g->skin_joints, sizeof *g->skin_joints, b->count + 1,
                  &g->cap_skin_joints))
        return -1;
    if (inverse_bind) aibm = float_accessor(g, inverse_bind, (uint32_t)num_joints, 16, 0, 0);
    if (g->status != EVR_OK) return -1;
    idx = sb_elem(g, b);
    sb_cat(g, b, "{\"name\":");
    sb_str(g, b, name);
    if (aibm >= 0) sb_printf(g, b, ",\"inverseBindMatrices\":%d", aibm);
    for (i = 0; i < num_joints; i++) sb_printf(g, b, i ? ",%d" : ",\"joints\":[%d", joints[i]);
    sb_cat(g, b, "]");
    if (skeleton >= 0) sb_printf(g, b, ",\"skeleton\":%d", skeleton);
    sb_cat(g, b, "}");
    if (g->status != EVR_OK) return -1;
    g->skin_joints[idx] = num_joints;
    return idx;
}

int evr_gltf_camera(evr_gltf *g, const char *name, float yfov, float aspect, float znear,
                    float zfar)
{
    sbuf *b = &g->cameras;
    int idx;
    if (!check_name(g, "camera", name)) return -1;
    if (!(yfov > 0.0f && yfov < 3.14159265f) || !(znear > 0.0f) || !isfinite(aspect) ||
        (zfar > 0.0f && !(zfar > znear))) {
        fail(g, EVR_ERR_ARG, "camera \"%s\": needs 0 < yfov < pi, znear > 0, zfar > znear", name);
        return -1;
    }
    idx = sb_elem(g, b);
    sb_cat(g, b, "{\"name\":");
    sb_str(g, b, name);
    sb_cat(g, b, ",\"type\":\"perspective\",\"perspective\":{\"yfov\":");
    sb_num(g, b, yfov);
    if (aspect > 0.0f) {
        sb_cat(g, b, ",\"aspectRatio\":");
        sb_num(g, b, aspect);
    }
    sb_cat(g, b, ",\"znear\":");
    sb_num(g, b, znear);
    if (zfar > 0.0f) {
        sb_cat(g, b, ",\"zfar\":");
        sb_num(g, b, zfar);
    }
    sb_cat(g, b, "}}");
    return g->status == EVR_OK ? idx : -1;
}

void evr_gltf_light_desc_init(evr_gltf_light_desc *d, const char *name, evr_gltf_light_type type)
{
    memset(d, 0, sizeof *d);
    d->name = name;
    d->type = type;
    d->color[0] = d->color[1] = d->color[2] = 1.0f;
    d->intensity = 1.0f;
    d->outer_cone = 0.78539816f;
}

int evr_gltf_light(evr_gltf *g, const char *name, evr_gltf_light_type type, const float color[3],
                   float intensity, float inner_cone, float outer_cone)
{
    evr_gltf_light_desc d;
    evr_gltf_light_desc_init(&d, name, type);
    if (color) memcpy(d.color, color, sizeof d.color);
    d.intensity = intensity;
    d.inner_cone = inner_cone;
    d.outer_cone = outer_cone;
    return evr_gltf_add_light(g, &d);
}

int evr_gltf_add_light(evr_gltf *g, const evr_gltf_light_desc *d)
{
    static const char *const types[3] = {"point", "spot", "directional"};
    sbuf *b = &g->lights;
    const char *name = d->name;
    const evr_gltf_light_type type = d->type;
    int idx;
    if (!check_name(g, "light", name)) return -1;
    if ((int)type < 0 || (int)type > 2 || !(d->intensity >= 0.0f) || !isfinite(d->intensity) ||
        !unit_range(d->color, 3)) {
        fail(g, EVR_ERR_ARG, "light \"%s\": bad type, colour or intensity", name);
        return -1;
    }
    if (type == EVR_GLTF_SPOT &&
        !(d->inner_cone >= 0.0f && d->inner_cone < d->outer_cone && d->outer_cone <= 1.5707964f)) {
        fail(g, EVR_ERR_ARG, "light \"%s\": spot cone angles need 0 <= inner < outer <= pi/2",
             name);
        return -1;
    }
    if (!(d->radius >= 0.0f) || !isfinite(d->radius) ||
        (d->radius > 0.0f && type == EVR_GLTF_DIRECTIONAL)) {
        fail(g, EVR_ERR_ARG, "light \"%s\": a radius must be >= 0, and 0 for a directional light",
             name);
        return -1;
    }
    idx = sb_elem(g, b);
    sb_cat(g, b, "{\"name\":");
    sb_str(g, b, name);
    sb_printf(g, b, ",\"type\":\"%s\",\"color\":", types[type]);
    sb_nums(g, b, d->color, 3);
    sb_cat(g, b, ",\"intensity\":");
    sb_num(g, b, d->intensity);
    if (type == EVR_GLTF_SPOT) {
        sb_cat(g, b, ",\"spot\":{\"innerConeAngle\":");
        sb_num(g, b, d->inner_cone);
        sb_cat(g, b, ",\"outerConeAngle\":");
        sb_num(g, b, d->outer_cone);
        sb_cat(g, b, "}");
    }
    if (d->radius > 0.0f) {
        sb_cat(g, b, ",\"extras\":{\"radius\":");
        sb_num(g, b, d->radius);
        sb_cat(g, b, "}");
    }
    sb_cat(g, b, "}");
    if (g->status != EVR_OK) return -1;
    g->ext_used |= 1u << EXT_LIGHTS;
    return idx;
}

int evr_gltf_node(evr_gltf *g, const char *name, int parent)
{
    gnode *n;
    if (!check_name(g, "node", name)) return -1;
    if (parent < -1 || parent >= g->num_nodes) {
        fail(g, EVR_ERR_ARG, "node \"%s\": no parent node %d", name, parent);
        return -1;
    }
    if (!grow_int(g, (void **)&g->nodes, sizeof *g->nodes, g->num_nodes + 1, &g->cap_nodes))
        return -1;
    n = &g->nodes[g->num_nodes];
    memset(n, 0, sizeof *n);
    n->name = dup_str(g, name);
    if (!n->name) return -1;
    n->parent = parent;
    n->mesh = n->camera = n->light = n->skin = -1;
    n->r[3] = 1.0f;
    n->s[0] = n->s[1] = n->s[2] = 1.0f;
    return g->num_nodes++;
}

static gnode *node_ref(evr_gltf *g, int node)
{
    if (g->status != EVR_OK) return NULL;
    if (node < 0 || node >= g->num_nodes) {
        fail(g, EVR_ERR_ARG, "no node %d", node);
        return NULL;
    }
    return &g->nodes[node];
}

void evr_gltf_node_translation(evr_gltf *g, int node, float x, float y, float z)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    n->t[0] = x;
    n->t[1] = y;
    n->t[2] = z;
    n->has_t = 1;
}

void evr_gltf_node_rotation(evr_gltf *g, int node, float x, float y, float z, float w)
{
    gnode *n = node_ref(g, node);
    float l = sqrtf(x * x + y * y + z * z + w * w);
    if (!n) return;
    if (!(fabsf(l - 1.0f) < 1e-3f)) {
        fail(g, EVR_ERR_ARG, "node \"%s\": rotation is not a unit quaternion", n->name);
        return;
    }
    n->r[0] = x / l;
    n->r[1] = y / l;
    n->r[2] = z / l;
    n->r[3] = w / l;
    n->has_r = 1;
}

void evr_gltf_node_scale(evr_gltf *g, int node, float x, float y, float z)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    n->s[0] = x;
    n->s[1] = y;
    n->s[2] = z;
    n->has_s = 1;
}

void evr_gltf_node_mesh(evr_gltf *g, int node, int mesh)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    if (mesh < 0 || mesh >= g->meshes.count)
        fail(g, EVR_ERR_ARG, "node \"%s\": no mesh %d", n->name, mesh);
    else n->mesh = mesh;
}

void evr_gltf_node_camera(evr_gltf *g, int node, int camera)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    if (camera < 0 || camera >= g->cameras.count)
        fail(g, EVR_ERR_ARG, "node \"%s\": no camera %d", n->name, camera);
    else n->camera = camera;
}

void evr_gltf_node_light(evr_gltf *g, int node, int light)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    if (light < 0 || light >= g->lights.count)
        fail(g, EVR_ERR_ARG, "node \"%s\": no light %d", n->name, light);
    else n->light = light;
}

void evr_gltf_node_skin(evr_gltf *g, int node, int skin)
{
    gnode *n = node_ref(g, node);
    if (!n) return;
    if (skin < 0 || skin >= g->skins.count)
        fail(g, EVR_ERR_ARG, "node \"%s\": no skin %d", n->name, skin);
    else n->skin = skin;
}

void evr_gltf_node_weights(evr_gltf *g, int node, const float *weights, int count)
{
    gnode *n = node_ref(g, node);
    float *w;
    int i;
    if (!n) return;
    if (!weights || count < 1) {
        fail(g, EVR_ERR_ARG, "node \"%s\": no weights", n->name);
        return;
    }
    for (i = 0; i < count; i++) {
        if (!isfinite(weights[i])) {
            fail(g, EVR_ERR_ARG, "node \"%s\": non-finite weight", n->name);
            return;
        }
    }
    if (!(w = malloc(sizeof *w * (size_t)count))) {
        fail(g, EVR_ERR_NOMEM, "out of memory");
        return;
    }
    memcpy(w, weights, sizeof *w * (size_t)count);
    free(n->weights);
    n->weights = w;
    n->num_weights = count;
}

int evr_gltf_animation(evr_gltf *g, const char *name)
{
    ganim *a;
    if (!check_name(g, "animation", name)) return -1;
    if (!grow_int(g, (void **)&g->anims, sizeof *g->anims, g->num_anims + 1, &g->cap_anims))
        return -1;
    a = &g->anims[g->num_anims];
    memset(a, 0, sizeof *a);
    a->name = dup_str(g, name);
    if (!a->name) return -1;
    return g->num_anims++;
}

void evr_gltf_channel(evr_gltf *g, int animation, int node, evr_gltf_path path, const float *times,
                      const float *values, int count, evr_gltf_interp interp)
{
    static const char *const paths[4] = {"translation", "rotation", "scale", "weights"};
    ganim *a;
    gtarget *tg;
    int ncomp, i, in, out, s;
    if (g->status != EVR_OK) return;
    if (animation < 0 || animation >= g->num_anims || node < 0 || node >= g->num_nodes ||
        (int)path < 0 || (int)path > 3 || (interp != EVR_GLTF_LINEAR && interp != EVR_GLTF_STEP) ||
        !times || !values || count < 1) {
        fail(g, EVR_ERR_ARG, "channel: bad animation, node, path, interpolation or keys");
        return;
    }
    a = &g->anims[animation];
    if (path == EVR_GLTF_WEIGHTS) { /* one value per morph target of the node's mesh */
        const int mesh = g->nodes[node].mesh;
        ncomp = mesh >= 0 ? g->mesh_info[mesh].num_targets : 0;
        if (ncomp < 1) {
            fail(g, EVR_ERR_ARG, "animation \"%s\": node \"%s\" has no mesh with morph targets",
                 a->name, g->nodes[node].name);
            return;
        }
    } else {
        ncomp = path == EVR_GLTF_ROTATION ? 4 : 3;
    }
    for (i = 0; i < a->num_targets; i++) {
        if (a->targets[i].node == node && a->targets[i].path == (int)path) {
            fail(g, EVR_ERR_ARG, "animation \"%s\": node \"%s\" has two %s channels", a->name,
                 g->nodes[node].name, paths[path]);
            return;
        }
    }
    for (i = 0; i < count; i++) {
        if (!(times[i] >= 0.0f) || !isfinite(times[i]) || (i > 0 && !(times[i] > times[i - 1]))) {
            fail(g, EVR_ERR_ARG, "animation \"%s\": key times must be finite, >= 0 and increasing",
                 a->name);
            return;
        }
        if (path == EVR_GLTF_ROTATION) {
            const float *q = values + 4 * (size_t)i;
            float l = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            if (!(fabsf(l - 1.0f) < 1e-3f)) {
                fail(g, EVR_ERR_ARG, "animation \"%s\": rotation key %d is not a unit quaternion",
                     a->name, i);
                return;
            }
        }
    }
    if (!grow_int(g, (void **)&a->targets, sizeof *a->targets, a->num_targets + 1, &a->cap_targets))
        return;
    tg = &a->targets[a->num_targets++];
    tg->node = node;
    tg->path = (int)path;
    tg->values = ncomp;
    in = float_accessor(g, times, (uint32_t)count, 1, 0, 1); /* input needs min/max */
    /* weights: SCALAR, the keys' values end to end (count x targets) */
    out = path == EVR_GLTF_WEIGHTS
              ? float_accessor(g, values, (uint32_t)count * (uint32_t)ncomp, 1, 0, 0)
              : float_accessor(g, values, (uint32_t)count, ncomp, 0, 0);
    if (g->status != EVR_OK) return;
    s = sb_elem(g, &a->samplers);
    sb_printf(g, &a->samplers, "{\"input\":%d,\"output\":%d,\"interpolation\":\"%s\"}", in, out,
              interp == EVR_GLTF_STEP ? "STEP" : "LINEAR");
    sb_elem(g, &a->channels);
    sb_printf(g, &a->channels, "{\"sampler\":%d,\"target\":{\"node\":%d,\"path\":\"%s\"}}", s, node,
              paths[path]);
}

/* ---- serialization ---- */

static void put_array(evr_gltf *g, sbuf *j, const char *key, const sbuf *arr)
{
    if (!arr->count) return;
    sb_printf(g, j, ",\"%s\":[", key);
    sb_cat_n(g, j, arr->p, arr->n);
    sb_cat(g, j, "]");
}

static void put_node(evr_gltf *g, sbuf *j, int i)
{
    const gnode *n = &g->nodes[i];
    int c, first = 1;
    sb_cat(g, j, "{\"name\":");
    sb_str(g, j, n->name);
    for (c = i + 1; c < g->num_nodes; c++) { /* children always come after their parent */
        if (g->nodes[c].parent != i) continue;
        sb_printf(g, j, first ? ",\"children\":[%d" : ",%d", c);
        first = 0;
    }
    if (!first) sb_cat(g, j, "]");
    if (n->mesh >= 0) sb_printf(g, j, ",\"mesh\":%d", n->mesh);
    if (n->skin >= 0) sb_printf(g, j, ",\"skin\":%d", n->skin);
    if (n->weights) {
        sb_cat(g, j, ",\"weights\":");
        sb_nums(g, j, n->weights, n->num_weights);
    }
    if (n->camera >= 0) sb_printf(g, j, ",\"camera\":%d", n->camera);
    if (n->has_t) {
        sb_cat(g, j, ",\"translation\":");
        sb_nums(g, j, n->t, 3);
    }
    if (n->has_r) {
        sb_cat(g, j, ",\"rotation\":");
        sb_nums(g, j, n->r, 4);
    }
    if (n->has_s) {
        sb_cat(g, j, ",\"scale\":");
        sb_nums(g, j, n->s, 3);
    }
    if (n->light >= 0)
        sb_printf(g, j, ",\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}", n->light);
    sb_cat(g, j, "}");
}

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v & 0xff);
    p[1] = (unsigned char)((v >> 8) & 0xff);
    p[2] = (unsigned char)((v >> 16) & 0xff);
    p[3] = (unsigned char)((v >> 24) & 0xff);
}

/* What only the whole document shows: skins, node weights and weight channels against the meshes
 * their nodes place. */
static void check_deform(evr_gltf *g)
{
    int i, k;
    for (i = 0; i < g->num_nodes && g->status == EVR_OK; i++) {
        const gnode *n = &g->nodes[i];
        const gmesh *m = n->mesh >= 0 ? &g->mesh_info[n->mesh] : NULL;
        if (n->skin >= 0 && (!m || m->max_joint < 0))
            fail(g, EVR_ERR_ARG, "node \"%s\" has a skin but no skinned mesh", n->name);
        else if (n->skin < 0 && m && m->max_joint >= 0)
            fail(g, EVR_ERR_ARG, "node \"%s\": its mesh is skinned, the node needs a skin",
                 n->name);
        else if (n->skin >= 0 && m->max_joint >= g->skin_joints[n->skin])
            fail(g, EVR_ERR_ARG, "node \"%s\": its mesh uses joint %d, its skin has %d", n->name,
                 m->max_joint, g->skin_joints[n->skin]);
        else if (n->weights && (!m || m->num_targets != n->num_weights))
            fail(g, EVR_ERR_ARG, "node \"%s\": %d weights for %d morph targets", n->name,
                 n->num_weights, m ? m->num_targets : 0);
    }
    for (i = 0; i < g->num_anims && g->status == EVR_OK; i++) {
        for (k = 0; k < g->anims[i].num_targets; k++) {
            const gtarget *t = &g->anims[i].targets[k];
            const gnode *n = &g->nodes[t->node];
            if (t->path == EVR_GLTF_WEIGHTS && g->mesh_info[n->mesh].num_targets != t->values)
                fail(g, EVR_ERR_ARG,
                     "animation \"%s\": node \"%s\" changed its mesh after its weights channel",
                     g->anims[i].name, n->name);
        }
    }
}

evr_status evr_gltf_glb(evr_gltf *g, void **glb, size_t *size, evr_error *err)
{
    sbuf j = {NULL, 0, 0, 0};
    size_t json_len, bin_len, total;
    unsigned char *out, *p;
    int i, first;
    *glb = NULL;
    *size = 0;
    for (i = 0; i < g->num_anims && g->status == EVR_OK; i++)
        if (!g->anims[i].channels.count)
            fail(g, EVR_ERR_ARG, "animation \"%s\" has no channels", g->anims[i].name);
    check_deform(g);
    if (g->status != EVR_OK) return evr_gltf_status(g, err);

    sb_cat(g, &j, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"evray gltf_writer\"}");
    for (i = 0, first = 1; i < EXT_COUNT; i++) {
        if (!(g->ext_used & (1u << i))) continue;
        sb_printf(g, &j, "%s\"%s\"", first ? ",\"extensionsUsed\":[" : ",", ext_names[i]);
        first = 0;
    }
    if (!first) sb_cat(g, &j, "]");
    if (g->lights.count) {
        sb_cat(g, &j, ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[");
        sb_cat_n(g, &j, g->lights.p, g->lights.n);
        sb_cat(g, &j, "]}}");
    }
    sb_cat(g, &j, ",\"scene\":0,\"scenes\":[{");
    if (g->scene_name) {
        sb_cat(g, &j, "\"name\":");
        sb_str(g, &j, g->scene_name);
    }
    for (i = 0, first = 1; i < g->num_nodes; i++) {
        if (g->nodes[i].parent >= 0) continue;
        if (first) sb_printf(g, &j, "%s\"nodes\":[%d", g->scene_name ? "," : "", i);
        else sb_printf(g, &j, ",%d", i);
        first = 0;
    }
    sb_cat(g, &j, first ? "}]" : "]}]");
    if (g->num_nodes) {
        sb_cat(g, &j, ",\"nodes\":[");
        for (i = 0; i < g->num_nodes; i++) {
            if (i) sb_cat(g, &j, ",");
            put_node(g, &j, i);
        }
        sb_cat(g, &j, "]");
    }
    put_array(g, &j, "meshes", &g->meshes);
    put_array(g, &j, "skins", &g->skins);
    put_array(g, &j, "materials", &g->materials);
    put_array(g, &j, "textures", &g->textures);
    put_array(g, &j, "images", &g->images);
    if (g->has_sampler)
        sb_printf(g, &j,
                  ",\"samplers\":[{\"magFilter\":%d,\"minFilter\":%d,\"wrapS\":%d,\"wrapT\":%d}]",
                  GLTF_LINEAR, GLTF_LINEAR, GLTF_REPEAT, GLTF_REPEAT);
    put_array(g, &j, "cameras", &g->cameras);
    if (g->num_anims) {
        sb_cat(g, &j, ",\"animations\":[");
        for (i = 0; i < g->num_anims; i++) {
            const ganim *a = &g->anims[i];
            if (i) sb_cat(g, &j, ",");
            sb_cat(g, &j, "{\"name\":");
            sb_str(g, &j, a->name);
            sb_cat(g, &j, ",\"channels\":[");
            sb_cat_n(g, &j, a->channels.p, a->channels.n);
            sb_cat(g, &j, "],\"samplers\":[");
            sb_cat_n(g, &j, a->samplers.p, a->samplers.n);
            sb_cat(g, &j, "]}");
        }
        sb_cat(g, &j, "]");
    }
    put_array(g, &j, "accessors", &g->accessors);
    put_array(g, &j, "bufferViews", &g->views);
    bin_len = (g->bin_n + 3) & ~(size_t)3;
    if (bin_len) sb_printf(g, &j, ",\"buffers\":[{\"byteLength\":%lu}]", (unsigned long)bin_len);
    sb_cat(g, &j, "}");
    if (g->status != EVR_OK) {
        sb_free(&j);
        return evr_gltf_status(g, err);
    }

    json_len = (j.n + 3) & ~(size_t)3;
    total = 12 + 8 + json_len + (bin_len ? 8 + bin_len : 0);
    if (total > 0xffffffffu) {
        sb_free(&j);
        fail(g, EVR_ERR_ARG, "scene larger than 4 GiB");
        return evr_gltf_status(g, err);
    }
    out = malloc(total);
    if (!out) {
        sb_free(&j);
        if (err) snprintf(err->msg, sizeof err->msg, "gltf: out of memory");
        return EVR_ERR_NOMEM;
    }
    p = out;
    memcpy(p, "glTF", 4);
    put_u32(p + 4, 2);
    put_u32(p + 8, (uint32_t)total);
    p += 12;
    put_u32(p, (uint32_t)json_len);
    memcpy(p + 4, "JSON", 4);
    memcpy(p + 8, j.p, j.n);
    memset(p + 8 + j.n, ' ', json_len - j.n);
    p += 8 + json_len;
    if (bin_len) {
        put_u32(p, (uint32_t)bin_len);
        memcpy(p + 4, "BIN\0", 4);
        memcpy(p + 8, g->bin, g->bin_n);
        memset(p + 8 + g->bin_n, 0, bin_len - g->bin_n);
    }
    sb_free(&j);
    *glb = out;
    *size = total;
    return EVR_OK;
}

void evr_gltf_set_variant(evr_gltf *g, uint64_t seed) { g->variant = seed; }

uint64_t evr_gltf_variant(const evr_gltf *g) { return g->variant; }
