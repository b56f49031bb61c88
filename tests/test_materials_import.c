/* Material import (issue 21) against the ground truth of tests/material_assets.py: every glTF
 * material property, the colour space of each texture slot (a 128 grey data texture reads
 * 128/255, a colour texture sRGB-decoded; one image used both ways is decoded twice), the
 * KHR_texture_transform matrix and its texCoord override, one uv set per mesh, tangents (from the
 * file, generated: unit, orthogonal to the normals, w = -1 on mirrored uvs, along increasing u
 * with the bitangent up the image on a sphere), the `evray info` lines, warnings for what is not
 * rendered, errors for bad values; and the Assimp path of another format (OBJ + MTL). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "io/png.h"
#include "scene/scene.h"

static char dir[] = "/tmp/evray_mat_XXXXXX";

static double srgb(double c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }

static evr_scene *load(const char *name)
{
    char path[256];
    evr_scene *s = NULL;
    evr_error err;
    snprintf(path, sizeof path, "%s/%s.gltf", dir, name);
    if (evr_scene_load(path, &s, &err) != EVR_OK) {
        fprintf(stderr, "%s: %s\n", path, err.msg);
        CHECK(!"asset loads");
        return NULL;
    }
    return s;
}

static const evr_material *material(const evr_scene *s, const char *name)
{
    for (int i = 0; i < s->num_materials; i++)
        if (!strcmp(s->materials[i].name, name)) return &s->materials[i];
    fprintf(stderr, "no material '%s'\n", name);
    CHECK(!"material found");
    return NULL;
}

static const evr_mesh *mesh(const evr_scene *s, const char *name)
{
    for (int i = 0; i < s->num_meshes; i++)
        if (!strcmp(s->meshes[i].name, name)) return &s->meshes[i];
    fprintf(stderr, "no mesh '%s'\n", name);
    CHECK(!"mesh found");
    return NULL;
}

/* Texel (x, y) channel c of the texture in slot of m. */
static float texel(const evr_scene *s, const evr_material *m, int slot, int x, int y, int c)
{
    const evr_texture *t;
    int i = m->p.tex[slot].index;
    CHECK(i >= 0 && i < s->num_textures);
    if (i < 0 || i >= s->num_textures) return -1.0f;
    t = &s->textures[i];
    return t->rgba[4 * ((size_t)y * t->width + x) + c];
}

static int identity_xf(const evr_texture_ref *t)
{
    return t->xf[0] == 1 && t->xf[1] == 0 && t->xf[2] == 0 && t->xf[3] == 0 && t->xf[4] == 1 &&
           t->xf[5] == 0;
}

static void test_slots(void)
{
    evr_scene *s = load("slots");
    const evr_material *m;
    int k;
    if (!s || !(m = material(s, "slots"))) goto done;
    CHECK_NEAR(m->p.base_color[0], 0.9, 1e-6);
    CHECK_NEAR(m->p.base_color[1], 0.8, 1e-6);
    CHECK_NEAR(m->p.base_color[2], 0.7, 1e-6);
    CHECK_NEAR(m->p.base_color[3], 1.0, 1e-6);
    CHECK_NEAR(m->p.metallic, 0.5, 1e-6);
    CHECK_NEAR(m->p.roughness, 0.25, 1e-6);
    CHECK_NEAR(m->p.emissive[0], 2.0, 1e-6); /* (1, 0.5, 0.25) * emissive strength 2 */
    CHECK_NEAR(m->p.emissive[1], 1.0, 1e-6);
    CHECK_NEAR(m->p.emissive[2], 0.5, 1e-6);
    CHECK_NEAR(m->p.transmission, 0.5, 1e-6);
    CHECK_NEAR(m->p.tex[EVR_TEX_NORMAL].scale, 0.5, 1e-6);
    CHECK_NEAR(m->p.tex[EVR_TEX_OCCLUSION].scale, 0.75, 1e-6);
    CHECK(m->p.alpha_mode == EVR_ALPHA_OPAQUE && !m->p.double_sided && !m->p.unlit);
    CHECK_NEAR(m->p.ior, 1.5, 1e-6);
    for (k = 0; k < EVR_TEX_COUNT; k++) {
        CHECK(m->p.tex[k].index >= 0);
        CHECK(identity_xf(&m->p.tex[k]));
    }
    CHECK(s->num_textures == 6);
    if (s->num_textures != 6) goto done;
    /* base colour: sRGB-decoded, row 0 the image's top */
    CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 0, 0, 0), 1.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 0, 0, 1), 0.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 1, 0, 1), 1.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 0, 1, 2), 1.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 1, 1, 0), srgb(128.0 / 255.0), 1e-6);
    /* data slots: the bytes / 255 */
    CHECK_NEAR(texel(s, m, EVR_TEX_METALLIC_ROUGHNESS, 0, 0, 1), 128.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_METALLIC_ROUGHNESS, 1, 1, 2), 64.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_NORMAL, 0, 0, 0), 173.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_NORMAL, 0, 0, 1), 189.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_NORMAL, 0, 0, 2), 230.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_OCCLUSION, 1, 0, 0), 128.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_TRANSMISSION, 0, 1, 0), 200.0 / 255.0, 1e-6);
    /* emissive: sRGB (white 1, black 0), 4x4 checker with the top-left white */
    CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 0, 0, 0), 1.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 1, 0, 0), 0.0, 1e-6);
    CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 1, 1, 2), 1.0, 1e-6);
    /* a normal texture: tangents */
    {
        const evr_mesh *q = mesh(s, "quad");
        CHECK(q && q->tangents != NULL && q->uvs != NULL);
    }
done:
    evr_scene_release(s);
}

static void test_colour_spaces(void)
{
    evr_scene *s = load("colour_spaces");
    const evr_material *c, *d;
    if (!s || !(c = material(s, "grey_colour")) || !(d = material(s, "grey_data"))) goto done;
    CHECK(s->num_textures == 2);
    CHECK(c->p.tex[EVR_TEX_BASE].index >= 0 && d->p.tex[EVR_TEX_METALLIC_ROUGHNESS].index >= 0);
    CHECK(c->p.tex[EVR_TEX_BASE].index != d->p.tex[EVR_TEX_METALLIC_ROUGHNESS].index);
    CHECK(c->p.tex[EVR_TEX_METALLIC_ROUGHNESS].index < 0 && d->p.tex[EVR_TEX_BASE].index < 0);
    CHECK_NEAR(texel(s, c, EVR_TEX_BASE, 0, 0, 0), 0.2158605, 1e-6);
    CHECK_NEAR(texel(s, d, EVR_TEX_METALLIC_ROUGHNESS, 0, 0, 1), 128.0 / 255.0, 1e-6);
    CHECK_NEAR(texel(s, d, EVR_TEX_METALLIC_ROUGHNESS, 0, 0, 3), 1.0, 1e-6);
    /* no normal texture: no tangents */
    for (int i = 0; i < s->num_meshes; i++) CHECK(s->meshes[i].tangents == NULL);
    /* glTF without pbrMetallicRoughness factors: the spec's metallic 1, roughness 1 */
    CHECK(c->p.metallic == 1.0f && c->p.roughness == 1.0f);
done:
    evr_scene_release(s);
}

static void test_transform(void)
{
    evr_scene *s = load("texture_transform");
    const evr_material *m;
    const evr_mesh *q, *mixed;
    double c = cos(0.5), sn = sin(0.5);
    uint32_t v;
    if (!s || !(m = material(s, "xf")) || !(q = mesh(s, "quad")) || !(mixed = mesh(s, "mixed")))
        goto done;
    {
        const float *xf = m->p.tex[EVR_TEX_BASE].xf;
        float tu, tv;
        CHECK_NEAR(xf[0], 2 * c, 1e-6);
        CHECK_NEAR(xf[1], 3 * sn, 1e-6);
        CHECK_NEAR(xf[2], 0.25, 1e-6);
        CHECK_NEAR(xf[3], -2 * sn, 1e-6);
        CHECK_NEAR(xf[4], 3 * c, 1e-6);
        CHECK_NEAR(xf[5], 0.5, 1e-6);
        /* the spec's example point: uv (1, 0) goes to offset + R * (scale.x, 0) */
        evr_texture_uv(&m->p.tex[EVR_TEX_BASE], 1.0f, 0.0f, &tu, &tv);
        CHECK_NEAR(tu, 0.25 + 2 * c, 1e-6);
        CHECK_NEAR(tv, 0.5 - 2 * sn, 1e-6);
    }
    /* the extension's texCoord 1 wins: the mesh keeps TEXCOORD_1 = TEXCOORD_0 / 2 */
    CHECK(q->uvs != NULL);
    for (v = 0; q->uvs && v < q->num_vertices; v++) {
        const float *p = &q->positions[3 * v], *uv = &q->uvs[2 * v];
        CHECK_NEAR(uv[0], (p[0] + 0.5) / 2, 1e-6);
        CHECK_NEAR(uv[1], (0.5 - p[1]) / 2, 1e-6);
    }
    /* mixed texCoords: the base colour's set (0), and one warning naming the material */
    CHECK(mixed->uvs != NULL);
    for (v = 0; mixed->uvs && v < mixed->num_vertices; v++)
        CHECK_NEAR(mixed->uvs[2 * v], (mixed->positions[3 * v] + 1) / 2, 1e-6);
    CHECK(s->num_warnings == 1);
    CHECK(strstr(evr_scene_warnings(s), "material 'mixed_uv'") != NULL);
    CHECK(strstr(evr_scene_warnings(s), "TEXCOORD_1") != NULL);
    CHECK(mixed->tangents != NULL); /* it has a normal texture */
done:
    evr_scene_release(s);
}

static void test_alpha_transmission_emissive(void)
{
    evr_scene *s = load("alpha_mask_card");
    const evr_material *m;
    if (s && (m = material(s, "card"))) {
        CHECK(m->p.alpha_mode == EVR_ALPHA_MASK);
        CHECK_NEAR(m->p.alpha_cutoff, 0.4, 1e-6);
        CHECK(m->p.double_sided == 1);
        CHECK(m->p.metallic == 0.0f);
        CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 3, 5, 3), 0.0, 1e-6); /* the left half: a hole */
        CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 4, 5, 3), 1.0, 1e-6);
        CHECK((m = material(s, "black")) && m->p.alpha_mode == EVR_ALPHA_OPAQUE &&
              !m->p.double_sided && m->p.alpha_cutoff == 0.5f);
    }
    evr_scene_release(s);
    s = load("alpha_blend_card");
    if (s && (m = material(s, "veil"))) {
        CHECK(m->p.alpha_mode == EVR_ALPHA_BLEND);
        CHECK_NEAR(m->p.base_color[3], 0.5, 1e-6);
        CHECK_NEAR(m->p.base_color[2], 0.8, 1e-6);
    }
    evr_scene_release(s);
    s = load("transmission_slab");
    if (s && (m = material(s, "glass"))) {
        CHECK_NEAR(m->p.transmission, 1.0, 1e-6);
        CHECK_NEAR(m->p.ior, 1.5, 1e-6);
        CHECK_NEAR(m->p.thickness, 0.2, 1e-6);
        CHECK_NEAR(m->p.attenuation_distance, 2.0, 1e-6);
        CHECK_NEAR(m->p.attenuation_color[0], 0.9, 1e-6);
        CHECK_NEAR(m->p.attenuation_color[1], 0.8, 1e-6);
        CHECK_NEAR(m->p.attenuation_color[2], 0.7, 1e-6);
        CHECK_NEAR(m->p.specular, 0.5, 1e-6);
        CHECK_NEAR(m->p.specular_color[1], 0.9, 1e-6);
        CHECK_NEAR(m->p.specular_color[2], 0.8, 1e-6);
        CHECK(m->p.roughness == 0.0f && m->p.metallic == 0.0f);
        CHECK(m->p.tex[EVR_TEX_TRANSMISSION].index < 0);
        CHECK((m = material(s, "dark")) && isinf(m->p.attenuation_distance) &&
              m->p.thickness == 0.0f && m->p.transmission == 0.0f && m->p.specular == 1.0f);
        {
            char *d = evr_scene_describe(s);
            CHECK(d && strstr(d, "\"glass\": base (1 1 1), metal 0 rough 0; transmission 1; ior "
                                 "1.5; volume thickness 0.2 attenuation 2 (0.9 0.8 0.7); specular "
                                 "0.5 (1 0.9 0.8)\n"));
            free(d);
        }
    }
    evr_scene_release(s);
    s = load("emissive_texture");
    if (s && (m = material(s, "glow_checker"))) {
        CHECK_NEAR(m->p.emissive[0], 5.0, 1e-6);
        CHECK_NEAR(m->p.emissive[2], 5.0, 1e-6);
        CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 2, 0, 1), 1.0, 1e-6);
        CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 3, 0, 1), 0.0, 1e-6);
        CHECK(m->p.base_color[0] == 0.0f && m->p.tex[EVR_TEX_BASE].index < 0);
    }
    evr_scene_release(s);
}

/* Every vertex of mesh `name` in asset has tangent (tx, ty, tz, w). */
static void check_plane_tangents(const char *asset, float tx, float w)
{
    evr_scene *s = load(asset);
    const evr_mesh *q;
    if (s && (q = mesh(s, "quad"))) {
        CHECK(q->tangents != NULL);
        for (uint32_t v = 0; q->tangents && v < q->num_vertices; v++) {
            CHECK_NEAR(q->tangents[4 * v], tx, 1e-6);
            CHECK_NEAR(q->tangents[4 * v + 1], 0.0, 1e-6);
            CHECK_NEAR(q->tangents[4 * v + 2], 0.0, 1e-6);
            CHECK(q->tangents[4 * v + 3] == w);
        }
        if (s->num_warnings) fprintf(stderr, "%s: %s", asset, evr_scene_warnings(s));
        CHECK(s->num_warnings == 0);
    }
    evr_scene_release(s);
}

static void test_tangents(void)
{
    evr_scene *s;
    const evr_mesh *b;
    int checked = 0;
    check_plane_tangents("normal_plane_tangents", 1.0f, 1.0f);
    check_plane_tangents("normal_plane", 1.0f, 1.0f);
    check_plane_tangents("normal_plane_mirrored", -1.0f, -1.0f);
    check_plane_tangents("normal_plane_mirrored_tangents", -1.0f, -1.0f);
    /* the sphere: unit, orthogonal to the normal, along increasing u (longitude), the bitangent
     * cross(n, t) * w towards the north pole (up the image: decreasing v) */
    s = load("normal_sphere");
    if (s && (b = mesh(s, "ball"))) {
        CHECK(b->tangents != NULL);
        for (uint32_t v = 0; b->tangents && v < b->num_vertices; v++) {
            const float *t = &b->tangents[4 * v], *n = &b->normals[3 * v];
            evr_v3 tv = evr_v3_make(t[0], t[1], t[2]), nv = evr_v3_make(n[0], n[1], n[2]);
            int seam;
            evr_v3 bt = evr_v3_scale(evr_v3_cross(nv, tv), t[3]);
            double phi = atan2(n[0], n[2]), th = acos(n[1] < -1 ? -1 : n[1] > 1 ? 1 : n[1]);
            evr_v3 east = evr_v3_make((float)cos(phi), 0, (float)-sin(phi));
            evr_v3 north = evr_v3_make((float)(-cos(th) * sin(phi)), (float)sin(th),
                                       (float)(-cos(th) * cos(phi)));
            CHECK_NEAR(evr_v3_len(tv), 1.0, 1e-5);
            CHECK_NEAR(evr_v3_dot(tv, nv), 0.0, 1e-5);
            CHECK(t[3] == 1.0f);
            if (fabs(n[1]) > 0.99) continue; /* at the poles u has no direction */
            /* the seam's vertices (u = 0 and 1 apart) see one side's triangles only: their
             * tangent is a chord's, off by up to half a segment (7.5 degrees) */
            seam = fabs(n[0]) < 1e-6 && n[2] > 0;
            CHECK(evr_v3_dot(tv, east) > (seam ? 0.99f : 0.9999f));
            CHECK(evr_v3_dot(bt, north) > (seam ? 0.99f : 0.9999f));
            checked++;
        }
        CHECK(checked > 200);
    }
    evr_scene_release(s);
}

static void test_warnings_and_errors(void)
{
    static const char *bad[] = {"bad_ior", "bad_factor", "bad_cutoff", "bad_texture"};
    static const char *why[] = {"ior must be 0 or >= 1 (got 0.5)",
                                "metallicFactor must be in [0, 1] (got -0.5)",
                                "alphaCutoff must be >= 0 (got -0.1)",
                                "baseColorTexture's index 7 is not a texture of the file"};
    evr_scene *s = load("unsupported");
    if (s) {
        const char *w = evr_scene_warnings(s);
        CHECK(s->num_warnings == 7);
        CHECK(strstr(w, "material 'clamped': texture 2's sampler clamps or mirrors (wrapS 33071, "
                        "wrapT 33071): evray repeats") != NULL);
        CHECK(strstr(w, "material 'coated': KHR_materials_clearcoat is not rendered") != NULL);
        CHECK(strstr(w, "material 'coated': KHR_materials_sheen is not rendered") != NULL);
        CHECK(strstr(w, "material 'volume_tex': KHR_materials_volume thicknessTexture") != NULL);
        CHECK(strstr(w, "material 'volume_tex': KHR_materials_specular specularTexture") != NULL);
        CHECK(strstr(w, "material 'volume_tex': KHR_materials_specular specularColorTexture") !=
              NULL);
        CHECK(strstr(w, "KHR_materials_iridescence") != NULL);
        CHECK(strstr(w, "KHR_texture_transform") == NULL && strstr(w, "lights_punctual") == NULL);
        {
            const evr_material *m = material(s, "volume_tex");
            CHECK(m && m->p.thickness == 0.1f && m->p.transmission == 1.0f);
        }
    }
    evr_scene_release(s);
    for (int i = 0; i < 4; i++) {
        char path[256];
        evr_error err;
        evr_status st;
        s = NULL;
        snprintf(path, sizeof path, "%s/%s.gltf", dir, bad[i]);
        st = evr_scene_load(path, &s, &err);
        CHECK(st == EVR_ERR_FORMAT && s == NULL);
        CHECK(strchr(err.msg, '\n') == NULL);
        CHECK(strncmp(err.msg, "material '", 10) == 0 && strstr(err.msg, bad[i]) != NULL);
        CHECK(strstr(err.msg, why[i]) != NULL);
        if (st != EVR_ERR_FORMAT || !strstr(err.msg, why[i]))
            fprintf(stderr, "  %s: %d '%s'\n", bad[i], (int)st, err.msg);
        evr_scene_release(s);
    }
}

/* The same file from memory: data: URI images, the same materials. */
static void test_memory(void)
{
    char path[256];
    FILE *f;
    long n;
    char *buf;
    evr_scene *s = NULL;
    evr_error err;
    snprintf(path, sizeof path, "%s/slots.gltf", dir);
    f = fopen(path, "rb");
    CHECK(f != NULL);
    if (!f) return;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = malloc((size_t)n);
    CHECK(buf && fread(buf, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    if (buf && evr_scene_load_memory(buf, (size_t)n, "gltf", &s, &err) == EVR_OK) {
        const evr_material *m = material(s, "slots");
        CHECK(s->num_textures == 6);
        CHECK(m && m->p.tex[EVR_TEX_NORMAL].scale == 0.5f);
        if (m) CHECK_NEAR(texel(s, m, EVR_TEX_OCCLUSION, 0, 0, 0), 128.0 / 255.0, 1e-6);
    } else {
        CHECK(!"slots.gltf loads from memory");
    }
    evr_scene_release(s);
    free(buf);
}

static int write_png(const char *name, const unsigned char *px, int w, int h)
{
    char path[256];
    void *png = NULL;
    size_t n = 0;
    evr_error err;
    FILE *f;
    int ok;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (evr_png_encode(px, w, h, 3, 8, &png, &n, &err) != EVR_OK) return 0;
    f = fopen(path, "wb");
    ok = f && fwrite(png, 1, n, f) == n;
    if (f) ok = fclose(f) == 0 && ok;
    free(png);
    return ok;
}

/* Another format through Assimp: an OBJ whose MTL gives a diffuse map (sRGB), a normal map
 * (`norm`: aiTextureType_NORMALS, data), a bump map (a height map: not a normal map, a warning),
 * an emissive colour and map, and dissolve 0.5 (BLEND). */
static void test_obj(void)
{
    static const unsigned char grey[12] = {128, 128, 128, 128, 128, 128,
                                           128, 128, 128, 128, 128, 128};
    static const char *obj = "mtllib m.mtl\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nvt 0 0\nvt 1 0\n"
                             "vt 1 1\nvn 0 0 1\nusemtl panel\nf 1/1/1 2/2/1 3/3/1\n";
    static const char *mtl = "newmtl panel\nKd 0.5 0.5 0.5\nKe 1 1 1\nd 0.5\nmap_Kd grey.png\n"
                             "norm grey.png\nmap_bump grey.png\nmap_Ke grey.png\n";
    char path[256];
    FILE *f;
    evr_scene *s = NULL;
    evr_error err;
    const evr_material *m;
    CHECK(write_png("grey.png", grey, 2, 2));
    snprintf(path, sizeof path, "%s/m.mtl", dir);
    CHECK((f = fopen(path, "w")) && fputs(mtl, f) >= 0 && fclose(f) == 0);
    snprintf(path, sizeof path, "%s/m.obj", dir);
    CHECK((f = fopen(path, "w")) && fputs(obj, f) >= 0 && fclose(f) == 0);
    if (evr_scene_load(path, &s, &err) != EVR_OK) {
        fprintf(stderr, "m.obj: %s\n", err.msg);
        CHECK(!"m.obj loads");
        return;
    }
    if ((m = material(s, "panel"))) {
        CHECK_NEAR(m->p.base_color[0], 0.5, 1e-6);
        CHECK(m->p.alpha_mode == EVR_ALPHA_BLEND);
        CHECK_NEAR(m->p.base_color[3], 0.5, 1e-6);
        CHECK_NEAR(m->p.emissive[0], 1.0, 1e-6);
        CHECK(m->p.metallic == 0.0f); /* no metallic factor: evray's default 0 */
        CHECK_NEAR(texel(s, m, EVR_TEX_BASE, 0, 0, 0), srgb(128.0 / 255.0), 1e-6);
        CHECK_NEAR(texel(s, m, EVR_TEX_EMISSIVE, 0, 0, 0), srgb(128.0 / 255.0), 1e-6);
        CHECK_NEAR(texel(s, m, EVR_TEX_NORMAL, 0, 0, 0), 128.0 / 255.0, 1e-6);
        CHECK(m->p.tex[EVR_TEX_BASE].index == m->p.tex[EVR_TEX_EMISSIVE].index);
        CHECK(m->p.tex[EVR_TEX_BASE].index != m->p.tex[EVR_TEX_NORMAL].index);
        CHECK(s->num_textures == 2);
        CHECK(strstr(evr_scene_warnings(s), "material 'panel': its height (bump) texture") != NULL);
        CHECK(s->meshes[0].tangents != NULL);
    }
    evr_scene_release(s);
}

static void test_describe(void)
{
    evr_scene *s = load("slots");
    char *d = s ? evr_scene_describe(s) : NULL;
    CHECK(d && strstr(d, "  [0] \"slots\": base (0.9 0.8 0.7), metal 0.5 rough 0.25, textures: "
                         "base, metallic-roughness, normal 0.5, occlusion 0.75, emissive, "
                         "transmission; emissive (2 1 0.5); transmission 0.5; ior 1.5\n"));
    if (d && !strstr(d, "\"slots\": base")) fprintf(stderr, "%s", d);
    free(d);
    evr_scene_release(s);
    s = load("alpha_mask_card");
    d = s ? evr_scene_describe(s) : NULL;
    CHECK(d && strstr(d, "\"card\": base (1 1 1), metal 0 rough 1, textures: base; alpha mask 0.4; "
                         "double-sided\n"));
    free(d);
    evr_scene_release(s);
}

int main(void)
{
    char cmd[512];
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s/../material_assets.py %s >/dev/null",
             EVR_TEST_DATA, dir);
    CHECK(system(cmd) == 0);
    if (check_failures) return check_report("test_materials_import");
    test_slots();
    test_colour_spaces();
    test_transform();
    test_alpha_transmission_emissive();
    test_tangents();
    test_warnings_and_errors();
    test_memory();
    test_obj();
    test_describe();
    if (!check_failures) {
        snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
        CHECK(system(cmd) == 0);
    }
    return check_report("test_materials_import");
}
