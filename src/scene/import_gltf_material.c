/* glTF materials read from the JSON, not through Assimp. Assimp 5.2 drops
 * KHR_materials_emissive_strength, _specular and the texture transform's texCoord, rewrites
 * KHR_texture_transform for its own flipped v, and fails on a texture index out of range without
 * naming the material (docs/assimp-quirks.md). Every property is read here:
 * metallic-roughness factors and textures, normal (scale), occlusion (strength), emissive (times
 * KHR_materials_emissive_strength), alpha mode and cutoff, double-sidedness, KHR_materials_unlit,
 * _transmission, _ior, _volume, _specular, KHR_texture_transform, and the photon extras.
 *
 * One function reads a material twice: before Assimp reads the file (evr_gltf_material_check: bad
 * values are one error naming the material) and after (evr_gltf_materials_read: textures loaded
 * from the images the JSON names, warnings for what evray does not render). Assimp's material i is
 * the JSON's material i; Assimp's default material comes after them (import_material.c). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/photon.h"
#include "scene/import_internal.h"

/* Material extensions evray renders (the others are warned about, one line each). */
static const char *const rendered_ext[] = {"KHR_materials_emissive_strength",
                                           "KHR_materials_transmission",
                                           "KHR_materials_ior",
                                           "KHR_materials_volume",
                                           "KHR_materials_specular",
                                           "KHR_materials_unlit",
                                           "KHR_materials_pbrSpecularGlossiness"};
/* Extensions of the file (extensionsUsed) that evray or Assimp reads besides those. */
static const char *const read_ext[] = {"KHR_texture_transform", "KHR_lights_punctual",
                                       "KHR_mesh_quantization", "EXT_mesh_gpu_instancing",
                                       "KHR_draco_mesh_compression"};

typedef struct {
    const evr_jdoc *d;
    int num_textures, num_images, num_samplers;
    int *tex_v, *img_v, *smp_v; /* the JSON value of each texture, image and sampler */
    const char *name;           /* the material's, for messages */
    evr_error *err;
    importer *im;  /* NULL: checking only (no textures loaded, no warnings) */
    gltf_data *gd; /* the buffers, for images in buffer views */
    int uv[EVR_TEX_COUNT];
} reader;

static evr_status bad(reader *r, const char *fmt, ...)
{
    char why[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    return evr_import_fail(r->err, EVR_ERR_FORMAT, "material '%s': %s", r->name, why);
}

static int member(const evr_jdoc *d, int obj, const char *a, const char *b)
{
    return evr_jdoc_get(d, b ? evr_jdoc_get(d, obj, a) : obj, b ? b : a);
}

/* Number `key` of obj into *out (unchanged when absent); an error unless lo <= it <= hi. */
static evr_status number(reader *r, int obj, const char *key, double lo, double hi, float *out)
{
    int v = evr_jdoc_get(r->d, obj, key);
    double x;
    if (v < 0) return EVR_OK;
    x = evr_jdoc_number(r->d, v, NAN);
    if (evr_jdoc_type(r->d, v) != EVR_JDOC_NUMBER) return bad(r, "%s must be a number", key);
    if (!(x >= lo && x <= hi)) {
        if (!isfinite(hi)) return bad(r, "%s must be >= %g (got %g)", key, lo, x);
        return bad(r, "%s must be in [%g, %g] (got %g)", key, lo, hi, x);
    }
    *out = (float)x;
    return EVR_OK;
}

/* Array `key` of n numbers >= 0 (and <= hi) into out (unchanged when absent). */
static evr_status colour(reader *r, int obj, const char *key, int n, double hi, float *out)
{
    int v = evr_jdoc_get(r->d, obj, key), e, k = 0;
    float tmp[4];
    if (v < 0) return EVR_OK;
    if (evr_jdoc_count(r->d, v) != n) return bad(r, "%s must be %d numbers", key, n);
    for (e = evr_jdoc_first(r->d, v); e >= 0; e = evr_jdoc_next(r->d, e), k++) {
        double x = evr_jdoc_number(r->d, e, NAN);
        if (!(x >= 0.0 && x <= hi))
            return bad(r, "%s must hold numbers in [0, %g] (got %g)", key, hi, x);
        tmp[k] = (float)x;
    }
    memcpy(out, tmp, (size_t)n * sizeof *out);
    return EVR_OK;
}

/* The raw name of object member m (extension names have no escapes). */
static void key_of(const evr_jdoc *d, int m, char *out, size_t cap)
{
    size_t n = d->v[m].key_len < cap - 1 ? d->v[m].key_len : cap - 1;
    memcpy(out, d->text + d->v[m].key_off, n);
    out[n] = 0;
}

static void warn(reader *r, const char *fmt, ...)
{
    char line[400];
    va_list ap;
    if (!r->im) return;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    evr_import_warn(r->im, "material '%s': %s", r->name, line);
}

/* KHR_texture_transform of a textureInfo into ref->xf (uv' = T * R * S * uv, the extension's
 * order) and its texCoord override into *uv. */
static evr_status transform(reader *r, int info, evr_texture_ref *ref, int *uv)
{
    const evr_jdoc *d = r->d;
    int x = member(d, info, "extensions", "KHR_texture_transform"), v, e, k;
    float off[2] = {0.0f, 0.0f}, sc[2] = {1.0f, 1.0f}, rot = 0.0f;
    if (x < 0) return EVR_OK;
    for (k = 0; k < 2; k++) {
        float *dst = k ? sc : off;
        const char *key = k ? "scale" : "offset";
        int i = 0;
        v = evr_jdoc_get(d, x, key);
        if (v < 0) continue;
        if (evr_jdoc_count(d, v) != 2)
            return bad(r, "KHR_texture_transform %s needs 2 numbers", key);
        for (e = evr_jdoc_first(d, v); e >= 0; e = evr_jdoc_next(d, e)) {
            double n = evr_jdoc_number(d, e, NAN);
            if (!isfinite(n)) return bad(r, "KHR_texture_transform %s needs 2 numbers", key);
            dst[i++] = (float)n;
        }
    }
    if (number(r, x, "rotation", -INFINITY, INFINITY, &rot) != EVR_OK) return EVR_ERR_FORMAT;
    if ((v = evr_jdoc_get(d, x, "texCoord")) >= 0) {
        if ((*uv = evr_gltf_index(d, v)) < 0)
            return bad(r, "KHR_texture_transform texCoord must be an index");
    }
    {
        float c = cosf(rot), s = sinf(rot);
        ref->xf[0] = c * sc[0], ref->xf[1] = s * sc[1], ref->xf[2] = off[0];
        ref->xf[3] = -s * sc[0], ref->xf[4] = c * sc[1], ref->xf[5] = off[1];
    }
    return EVR_OK;
}

/* Loads the image of texture `index` for slot (sRGB for colour slots) into ref->index. */
static evr_status load(reader *r, int index, int slot, evr_texture_ref *ref)
{
    const evr_jdoc *d = r->d;
    int tv = r->tex_v[index], src = evr_gltf_index(d, evr_jdoc_get(d, tv, "source"));
    int srgb = slot == EVR_TEX_BASE || slot == EVR_TEX_EMISSIVE;
    unsigned char *bytes = NULL;
    size_t n = 0;
    char path[1100], key[1200], what[1300];
    evr_status st;
    if (src < 0) { /* only in an extension's format (KHR_texture_basisu, EXT_texture_webp, ...) */
        int m = evr_jdoc_first(d, evr_jdoc_get(d, tv, "extensions"));
        int img = m >= 0 ? evr_gltf_index(d, evr_jdoc_get(d, m, "source")) : -1;
        char ext[64] = "no image", uri[160] = "";
        if (m >= 0) key_of(d, m, ext, sizeof ext);
        if (img >= 0 && img < r->num_images &&
            !evr_jdoc_string(d, evr_jdoc_get(d, r->img_v[img], "uri"), uri, sizeof uri))
            evr_jdoc_string(d, evr_jdoc_get(d, r->img_v[img], "name"), uri, sizeof uri);
        if (!strcmp(ext, "KHR_texture_basisu"))
            warn(r,
                 "texture %d's image%s%s%s is KTX2 (Basis Universal, KHR_texture_basisu), which "
                 "evray cannot decode (no Debian 12 library does): the slot is empty, the "
                 "material keeps its factors",
                 index, uri[0] ? " '" : "", uri, uri[0] ? "'" : "");
        else
            warn(r,
                 "texture %d has no PNG or JPEG image (%s): the slot is empty, the material "
                 "keeps its factors",
                 index, ext);
        return EVR_OK;
    }
    if (src >= r->num_images)
        return bad(r, "texture %d's image %d does not exist (the file has %d)", index, src,
                   r->num_images);
    if (!r->im) return EVR_OK;
    {
        /* evray's lookups repeat (core/material.h): other wrap modes would be drawn wrong */
        int sm = evr_gltf_index(d, evr_jdoc_get(d, tv, "sampler"));
        int smv = sm >= 0 && sm < r->num_samplers ? r->smp_v[sm] : -1;
        double ws = evr_jdoc_number(d, evr_jdoc_get(d, smv, "wrapS"), 10497);
        double wt = evr_jdoc_number(d, evr_jdoc_get(d, smv, "wrapT"), 10497);
        if (ws != 10497 || wt != 10497)
            warn(r, "texture %d's sampler clamps or mirrors (wrapS %g, wrapT %g): evray repeats",
                 index, ws, wt);
    }
    st = evr_gltf_image_source(r->gd, r->img_v[src], &bytes, &n, path, sizeof path, r->err);
    if (st != EVR_OK) return st;
    if (bytes) {
        snprintf(key, sizeof key, "glTF image %d", src);
        snprintf(what, sizeof what, "image %d of material '%s'", src, r->name);
    } else {
        char uri[1024];
        evr_jdoc_string(d, evr_jdoc_get(d, r->img_v[src], "uri"), uri, sizeof uri);
        snprintf(key, sizeof key, "%s", path);
        snprintf(what, sizeof what, "'%s' of material '%s'", uri, r->name);
    }
    st = evr_import_texture_image(r->im, key, bytes, n, what, srgb, &ref->index);
    free(bytes);
    return st;
}

/* A textureInfo (info: its JSON value, -1 absent) for slot: index, texCoord, transform, and
 * `scale_key` (normalTexture.scale, occlusionTexture.strength) into ref->scale. */
static evr_status texture(reader *r, int info, int slot, const char *what, const char *scale_key,
                          evr_texture_ref *ref)
{
    const evr_jdoc *d = r->d;
    int index, uv = 0, v;
    evr_status st;
    if (info < 0) return EVR_OK;
    index = evr_gltf_index(d, evr_jdoc_get(d, info, "index"));
    if (index < 0 || index >= r->num_textures)
        return bad(r, "%s's index %g is not a texture of the file (it has %d)", what,
                   evr_jdoc_number(d, evr_jdoc_get(d, info, "index"), -1), r->num_textures);
    if ((v = evr_jdoc_get(d, info, "texCoord")) >= 0 && (uv = evr_gltf_index(d, v)) < 0)
        return bad(r, "%s's texCoord must be an index", what);
    if (scale_key) {
        /* occlusion strength in [0, 1]; a normal map's scale may be any number */
        int occ = slot == EVR_TEX_OCCLUSION;
        if (number(r, info, scale_key, occ ? 0.0 : -INFINITY, occ ? 1.0 : INFINITY, &ref->scale) !=
            EVR_OK)
            return EVR_ERR_FORMAT;
    }
    if ((st = transform(r, info, ref, &uv)) != EVR_OK) return st;
    if ((st = load(r, index, slot, ref)) != EVR_OK) return st;
    r->uv[slot] = uv;
    return EVR_OK;
}

/* The extensions of material m: what evray renders into p, a warning for each other one. */
static evr_status extensions(reader *r, int m, evr_material_params *p)
{
    const evr_jdoc *d = r->d;
    int exts = evr_jdoc_get(d, m, "extensions"), e, x;
    float strength = 1.0f;
    evr_status st = EVR_OK;
    for (e = evr_jdoc_first(d, exts); e >= 0 && exts >= 0; e = evr_jdoc_next(d, e)) {
        char name[64];
        size_t k;
        key_of(d, e, name, sizeof name);
        for (k = 0; k < sizeof rendered_ext / sizeof *rendered_ext; k++)
            if (!strcmp(name, rendered_ext[k])) break;
        if (k == sizeof rendered_ext / sizeof *rendered_ext)
            warn(r, "%s is not rendered (ignored)", name);
    }
    x = member(d, m, "extensions", "KHR_materials_emissive_strength");
    if ((st = number(r, x, "emissiveStrength", 0.0, INFINITY, &strength)) != EVR_OK) return st;
    p->emissive[0] *= strength, p->emissive[1] *= strength, p->emissive[2] *= strength;

    x = member(d, m, "extensions", "KHR_materials_transmission");
    if ((st = number(r, x, "transmissionFactor", 0.0, 1.0, &p->transmission)) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, x, "transmissionTexture"), EVR_TEX_TRANSMISSION,
                      "transmissionTexture", NULL, &p->tex[EVR_TEX_TRANSMISSION])) != EVR_OK)
        return st;

    x = member(d, m, "extensions", "KHR_materials_ior");
    if ((st = number(r, x, "ior", 0.0, INFINITY, &p->ior)) != EVR_OK) return st;
    if (p->ior != 0.0f && p->ior < 1.0f) /* 0 is the spec's special case: Fresnel 1 */
        return bad(r, "KHR_materials_ior ior must be 0 or >= 1 (got %g)", (double)p->ior);

    x = member(d, m, "extensions", "KHR_materials_volume");
    if ((st = number(r, x, "thicknessFactor", 0.0, INFINITY, &p->thickness)) != EVR_OK ||
        (st = colour(r, x, "attenuationColor", 3, 1.0, p->attenuation_color)) != EVR_OK)
        return st;
    if (evr_jdoc_get(d, x, "attenuationDistance") >= 0) {
        double a = evr_jdoc_number(d, evr_jdoc_get(d, x, "attenuationDistance"), NAN);
        if (!(a > 0.0)) return bad(r, "KHR_materials_volume attenuationDistance must be > 0");
        p->attenuation_distance = (float)a;
    }
    if (evr_jdoc_get(d, x, "thicknessTexture") >= 0)
        warn(r, "KHR_materials_volume thicknessTexture is not rendered (thicknessFactor is used)");

    x = member(d, m, "extensions", "KHR_materials_specular");
    if ((st = number(r, x, "specularFactor", 0.0, INFINITY, &p->specular)) != EVR_OK ||
        (st = colour(r, x, "specularColorFactor", 3, INFINITY, p->specular_color)) != EVR_OK)
        return st;
    if (evr_jdoc_get(d, x, "specularTexture") >= 0)
        warn(r, "KHR_materials_specular specularTexture is not rendered (the factor is used)");
    if (evr_jdoc_get(d, x, "specularColorTexture") >= 0)
        warn(r, "KHR_materials_specular specularColorTexture is not rendered (the factor is "
                "used)");

    if (member(d, m, "extensions", "KHR_materials_unlit") >= 0) p->unlit = 1;

    /* specular-glossiness (archived): its diffuse as the base colour, roughness from glossiness */
    x = member(d, m, "extensions", "KHR_materials_pbrSpecularGlossiness");
    if (x >= 0 && evr_jdoc_get(d, m, "pbrMetallicRoughness") < 0) {
        float gloss = 1.0f;
        p->metallic = 0.0f;
        if ((st = colour(r, x, "diffuseFactor", 4, 1.0, p->base_color)) != EVR_OK ||
            (st = number(r, x, "glossinessFactor", 0.0, 1.0, &gloss)) != EVR_OK ||
            (st = texture(r, evr_jdoc_get(d, x, "diffuseTexture"), EVR_TEX_BASE, "diffuseTexture",
                          NULL, &p->tex[EVR_TEX_BASE])) != EVR_OK)
            return st;
        p->roughness = 1.0f - gloss;
        warn(r, "KHR_materials_pbrSpecularGlossiness is read as metallic-roughness (diffuse as "
                "base colour, roughness 1 - glossiness)");
    }
    return EVR_OK;
}

/* The texCoord set of the material's textures: the base colour's (else the first slot's); a
 * warning when the slots use different ones (evray keeps one uv set per mesh). */
static int uv_set(reader *r)
{
    int s, uv = r->uv[EVR_TEX_BASE], other = -1;
    for (s = 0; s < EVR_TEX_COUNT; s++) {
        if (r->uv[s] < 0) continue;
        if (uv < 0) uv = r->uv[s];
        if (r->uv[s] != uv) other = r->uv[s];
    }
    if (other >= 0)
        warn(r,
             "its textures use TEXCOORD_%d and TEXCOORD_%d; evray keeps one uv set per mesh: "
             "TEXCOORD_%d (the base colour's)",
             uv, other, uv);
    return uv < 0 ? 0 : uv;
}

/* Reads material value m into p (defaults set by the caller). */
static evr_status read_material(reader *r, int m, evr_material_params *p, int *uv)
{
    const evr_jdoc *d = r->d;
    int pbr = evr_jdoc_get(d, m, "pbrMetallicRoughness"), v, s;
    char mode[16];
    evr_status st;

    for (s = 0; s < EVR_TEX_COUNT; s++) r->uv[s] = -1;
    /* the spec's defaults (Assimp 5.2 reports the same): metallic and roughness 1 */
    p->metallic = 1.0f;
    p->roughness = 1.0f;
    if ((st = colour(r, pbr, "baseColorFactor", 4, 1.0, p->base_color)) != EVR_OK ||
        (st = number(r, pbr, "metallicFactor", 0.0, 1.0, &p->metallic)) != EVR_OK ||
        (st = number(r, pbr, "roughnessFactor", 0.0, 1.0, &p->roughness)) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, pbr, "baseColorTexture"), EVR_TEX_BASE, "baseColorTexture",
                      NULL, &p->tex[EVR_TEX_BASE])) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, pbr, "metallicRoughnessTexture"),
                      EVR_TEX_METALLIC_ROUGHNESS, "metallicRoughnessTexture", NULL,
                      &p->tex[EVR_TEX_METALLIC_ROUGHNESS])) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, m, "normalTexture"), EVR_TEX_NORMAL, "normalTexture",
                      "scale", &p->tex[EVR_TEX_NORMAL])) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, m, "occlusionTexture"), EVR_TEX_OCCLUSION,
                      "occlusionTexture", "strength", &p->tex[EVR_TEX_OCCLUSION])) != EVR_OK ||
        (st = texture(r, evr_jdoc_get(d, m, "emissiveTexture"), EVR_TEX_EMISSIVE, "emissiveTexture",
                      NULL, &p->tex[EVR_TEX_EMISSIVE])) != EVR_OK ||
        (st = colour(r, m, "emissiveFactor", 3, INFINITY, p->emissive)) != EVR_OK ||
        (st = number(r, m, "alphaCutoff", 0.0, INFINITY, &p->alpha_cutoff)) != EVR_OK)
        return st;
    if ((v = evr_jdoc_get(d, m, "alphaMode")) >= 0) {
        evr_jdoc_string(d, v, mode, sizeof mode);
        if (!strcmp(mode, "OPAQUE")) p->alpha_mode = EVR_ALPHA_OPAQUE;
        else if (!strcmp(mode, "MASK")) p->alpha_mode = EVR_ALPHA_MASK;
        else if (!strcmp(mode, "BLEND")) p->alpha_mode = EVR_ALPHA_BLEND;
        else return bad(r, "alphaMode must be OPAQUE, MASK or BLEND");
    }
    if ((v = evr_jdoc_get(d, m, "doubleSided")) >= 0) {
        if (evr_jdoc_type(d, v) != EVR_JDOC_BOOL)
            return bad(r, "doubleSided must be true or false");
        p->double_sided = d->v[v].num != 0.0;
    }
    if ((st = extensions(r, m, p)) != EVR_OK) return st;
    *uv = uv_set(r);

    /* the photon thresholds of evray before its BSDF: photons follow the BSDF now */
    v = evr_jdoc_get(d, m, "extras");
    if (evr_jdoc_get(d, v, "t_diffuse") >= 0 || evr_jdoc_get(d, v, "t_specular") >= 0)
        warn(r, "extras t_diffuse / t_specular are not read (photons follow the BSDF): ignored");
    return EVR_OK;
}

/* The extensions of extensionsUsed that neither evray nor Assimp reads and that no material
 * names (a material's own are warned about with it): one warning each. */
static void warn_file_extensions(importer *im, const evr_jdoc *d, int root)
{
    int e, m, mats = evr_jdoc_get(d, root, "materials"), texs = evr_jdoc_get(d, root, "textures");
    for (e = evr_jdoc_first(d, evr_jdoc_get(d, root, "extensionsUsed")); e >= 0;
         e = evr_jdoc_next(d, e)) {
        char name[64];
        size_t k;
        int named = 0;
        if (!evr_jdoc_string(d, e, name, sizeof name)) continue;
        for (k = 0; k < sizeof rendered_ext / sizeof *rendered_ext; k++)
            if (!strcmp(name, rendered_ext[k])) named = 1;
        for (k = 0; k < sizeof read_ext / sizeof *read_ext; k++)
            if (!strcmp(name, read_ext[k])) named = 1;
        for (m = evr_jdoc_first(d, mats); m >= 0 && !named; m = evr_jdoc_next(d, m))
            named = member(d, m, "extensions", name) >= 0;
        /* a texture's (KHR_texture_basisu, EXT_texture_webp): warned about with its material */
        for (m = evr_jdoc_first(d, texs); m >= 0 && !named; m = evr_jdoc_next(d, m))
            named = member(d, m, "extensions", name) >= 0;
        if (!named)
            evr_import_warn(im, "the file uses %s, which evray does not read (ignored)", name);
    }
}

/* Parses src's JSON; *root -1 when it is not glTF 2.0 JSON (nothing to read). */
static evr_status parse(const gltf_source *src, evr_jdoc *d, int *root, reader *r, evr_error *err)
{
    const char *json;
    size_t jlen;
    char version[16];
    memset(r, 0, sizeof *r);
    memset(d, 0, sizeof *d);
    *root = -1;
    if (!evr_gltf_json_span(src->bytes, src->nbytes, &json, &jlen)) return EVR_OK;
    *root = evr_jdoc_parse(d, json, jlen);
    if (*root < 0 || evr_jdoc_type(d, *root) != EVR_JDOC_OBJECT ||
        !evr_jdoc_string(d, member(d, *root, "asset", "version"), version, sizeof version) ||
        version[0] != '2') {
        *root = -1;
        return d->failed
                   ? evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
                   : EVR_OK;
    }
    r->d = d;
    r->err = err;
    r->num_textures = evr_jdoc_count(d, evr_jdoc_get(d, *root, "textures"));
    r->num_images = evr_jdoc_count(d, evr_jdoc_get(d, *root, "images"));
    r->tex_v = evr_jdoc_elements(d, evr_jdoc_get(d, *root, "textures"));
    r->img_v = evr_jdoc_elements(d, evr_jdoc_get(d, *root, "images"));
    r->num_samplers = evr_jdoc_count(d, evr_jdoc_get(d, *root, "samplers"));
    r->smp_v = evr_jdoc_elements(d, evr_jdoc_get(d, *root, "samplers"));
    if (!r->tex_v || !r->img_v || !r->smp_v)
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON");
    return EVR_OK;
}

static void reader_free(reader *r, evr_jdoc *d)
{
    free(r->tex_v);
    free(r->img_v);
    free(r->smp_v);
    evr_jdoc_free(d);
}

/* The name of material value m as messages give it: its name, else Assimp's. */
static void material_name(const evr_jdoc *d, int m, int i, char *out, size_t cap)
{
    if (!evr_jdoc_string(d, evr_jdoc_get(d, m, "name"), out, cap) || !out[0])
        snprintf(out, cap, "materials[%d]", i);
}

evr_status evr_gltf_material_check(const gltf_source *src, evr_error *err)
{
    evr_jdoc d;
    reader r;
    int root, m, i = 0, uv;
    char name[128];
    evr_status st = parse(src, &d, &root, &r, err);
    for (m = st == EVR_OK && root >= 0 ? evr_jdoc_first(&d, evr_jdoc_get(&d, root, "materials"))
                                       : -1;
         m >= 0 && st == EVR_OK; m = evr_jdoc_next(&d, m), i++) {
        evr_material_params p;
        evr_material_defaults(&p);
        material_name(&d, m, i, name, sizeof name);
        r.name = name;
        st = read_material(&r, m, &p, &uv);
    }
    reader_free(&r, &d);
    return st;
}

/* The Assimp material that JSON material j (named `name`) became: Assimp 5.2 lists a glTF's
 * materials in the order meshes first use them, not the file's, and keeps their names; a name
 * that no untaken Assimp material has (an unnamed material) takes the first untaken one from j
 * on. -1: none left. */
static int assimp_index(const importer *im, const char *name, int j, const char *taken)
{
    const int n = im->s->num_materials;
    if (name[0])
        for (int i = 0; i < n; i++)
            if (!taken[i] && !strcmp(im->s->materials[i].name, name)) return i;
    for (int k = 0; k < n; k++) {
        const int i = (j + k) % n;
        if (!taken[i]) return i;
    }
    return -1;
}

evr_status evr_gltf_materials_read(importer *im, int *count)
{
    evr_jdoc d;
    reader r;
    gltf_data gd;
    int root, m, j = 0, done = 0;
    char *taken = calloc((size_t)im->s->num_materials + 1, 1);
    evr_status st = taken ? parse(&im->src, &d, &root, &r, im->err)
                          : evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory");
    if (!taken) return st;
    memset(&gd, 0, sizeof gd);
    if (st == EVR_OK && root >= 0) st = evr_gltf_data_init(&gd, &d, root, &im->src, im->err);
    r.im = im;
    r.gd = &gd;
    for (m = st == EVR_OK && root >= 0 ? evr_jdoc_first(&d, evr_jdoc_get(&d, root, "materials"))
                                       : -1;
         m >= 0 && st == EVR_OK && done < im->s->num_materials; m = evr_jdoc_next(&d, m), j++) {
        char name[64] = "";
        if (!evr_jdoc_string(&d, evr_jdoc_get(&d, m, "name"), name, sizeof name)) name[0] = 0;
        const int i = assimp_index(im, name, j, taken);
        if (i < 0) break;
        taken[i] = 1;
        done++;
        evr_material *mat = &im->s->materials[i];
        r.name = mat->name;
        st = read_material(&r, m, &mat->p, &im->mat_uv[i]);
    }
    *count = done;
    if (st == EVR_OK && root >= 0) warn_file_extensions(im, &d, root);
    if (root >= 0) evr_gltf_data_free(&gd);
    reader_free(&r, &d);
    free(taken);
    return st;
}
