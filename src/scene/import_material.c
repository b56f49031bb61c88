/* Materials. glTF's are read from the JSON (import_gltf_material.c); every other format's, and
 * Assimp's default material after a glTF's own, as Assimp gives them: base (diffuse) colour and
 * its texture, emissive colour and texture, metallic and roughness factors, opacity below 1 as
 * BLEND, two-sidedness, unlit shading, transmission and IOR, normal maps where Assimp says
 * aiTextureType_NORMALS (a height map is not read as one), ambient occlusion maps; a texture of
 * any other kind is a warning. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>
#include <assimp/material.h>

#include "core/photon.h"
#include "scene/import_internal.h"

/* One texture slot from Assimp: the first texture of the first of `kinds` (n) that has one. */
static evr_status assimp_slot(importer *im, const struct aiMaterial *am, evr_material *m,
                              const enum aiTextureType *kinds, int n, int slot, int *uv)
{
    struct aiString str;
    int k;
    for (k = 0; k < n; k++) {
        unsigned int ch = 0;
        if (aiGetMaterialTextureCount(am, kinds[k]) == 0) continue;
        if (aiGetMaterialTexture(am, kinds[k], 0, &str, NULL, &ch, NULL, NULL, NULL, NULL) !=
                aiReturn_SUCCESS ||
            !str.data[0])
            continue;
        *uv = (int)ch;
        return evr_import_texture(im, str.data, m->name,
                                  slot == EVR_TEX_BASE || slot == EVR_TEX_EMISSIVE,
                                  &m->p.tex[slot].index);
    }
    return EVR_OK;
}

static int get_float(const struct aiMaterial *am, const char *key, unsigned type, unsigned idx,
                     float *out)
{
    ai_real f;
    unsigned int one = 1;
    if (aiGetMaterialFloatArray(am, key, type, idx, &f, &one) != aiReturn_SUCCESS || one != 1)
        return 0;
    *out = (float)f;
    return 1;
}

/* Texture kinds evray does not render, named for the warning. */
static const struct {
    enum aiTextureType type;
    const char *name;
} unrendered[] = {
    {aiTextureType_SPECULAR, "specular"},
    {aiTextureType_AMBIENT, "ambient"},
    {aiTextureType_HEIGHT, "height (bump)"},
    {aiTextureType_SHININESS, "shininess"},
    {aiTextureType_OPACITY, "opacity"},
    {aiTextureType_DISPLACEMENT, "displacement"},
    {aiTextureType_LIGHTMAP, "light map"},
    {aiTextureType_REFLECTION, "reflection"},
    {aiTextureType_METALNESS, "metalness (separate from roughness)"},
    {aiTextureType_DIFFUSE_ROUGHNESS, "roughness (separate from metalness)"},
    {aiTextureType_SHEEN, "sheen"},
    {aiTextureType_CLEARCOAT, "clearcoat"},
};

/* Material i as Assimp gives it (m: its name and defaults set). */
static evr_status assimp_material(importer *im, const struct aiMaterial *am, evr_material *m,
                                  int *mat_uv)
{
    static const enum aiTextureType base[2] = {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE};
    static const enum aiTextureType emis[2] = {aiTextureType_EMISSIVE,
                                               aiTextureType_EMISSION_COLOR};
    static const enum aiTextureType normal[1] = {aiTextureType_NORMALS};
    static const enum aiTextureType occl[1] = {aiTextureType_AMBIENT_OCCLUSION};
    static const enum aiTextureType trans[1] = {aiTextureType_TRANSMISSION};
    struct aiColor4D c;
    float f, k = 1.0f;
    int uv[EVR_TEX_COUNT], s, two = 0, shading = 0, chosen;
    unsigned int one = 1;
    size_t t;
    evr_status st;

    if (aiGetMaterialColor(am, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS ||
        aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS) {
        m->p.base_color[0] = c.r;
        m->p.base_color[1] = c.g;
        m->p.base_color[2] = c.b;
        m->p.base_color[3] = c.a;
    }
    if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS) {
        get_float(am, AI_MATKEY_EMISSIVE_INTENSITY, &k);
        m->p.emissive[0] = c.r * k;
        m->p.emissive[1] = c.g * k;
        m->p.emissive[2] = c.b * k;
    }
    get_float(am, AI_MATKEY_METALLIC_FACTOR, &m->p.metallic);
    get_float(am, AI_MATKEY_ROUGHNESS_FACTOR, &m->p.roughness);
    if (get_float(am, AI_MATKEY_OPACITY, &f) && f >= 0.0f && f < 1.0f) {
        m->p.base_color[3] = f;
        m->p.alpha_mode = EVR_ALPHA_BLEND;
    }
    /* formats other than glTF have no rule that one side is invisible: both sides show unless
     * the file says the material is one-sided */
    m->p.double_sided = 1;
    if (aiGetMaterialIntegerArray(am, AI_MATKEY_TWOSIDED, &two, &one) == aiReturn_SUCCESS)
        m->p.double_sided = two != 0;
    one = 1;
    if (aiGetMaterialIntegerArray(am, AI_MATKEY_SHADING_MODEL, &shading, &one) ==
            aiReturn_SUCCESS &&
        shading == aiShadingMode_Unlit)
        m->p.unlit = 1;
    if (get_float(am, AI_MATKEY_TRANSMISSION_FACTOR, &f) && f > 0.0f && f <= 1.0f) {
        m->p.transmission = f;
        if (get_float(am, AI_MATKEY_REFRACTI, &f) && f >= 1.0f) m->p.ior = f;
    }

    for (s = 0; s < EVR_TEX_COUNT; s++) uv[s] = -1;
    if ((st = assimp_slot(im, am, m, base, 2, EVR_TEX_BASE, &uv[EVR_TEX_BASE])) != EVR_OK ||
        (st = assimp_slot(im, am, m, emis, 2, EVR_TEX_EMISSIVE, &uv[EVR_TEX_EMISSIVE])) != EVR_OK ||
        (st = assimp_slot(im, am, m, normal, 1, EVR_TEX_NORMAL, &uv[EVR_TEX_NORMAL])) != EVR_OK ||
        (st = assimp_slot(im, am, m, occl, 1, EVR_TEX_OCCLUSION, &uv[EVR_TEX_OCCLUSION])) !=
            EVR_OK ||
        (st = assimp_slot(im, am, m, trans, 1, EVR_TEX_TRANSMISSION, &uv[EVR_TEX_TRANSMISSION])) !=
            EVR_OK)
        return st;
    chosen = uv[EVR_TEX_BASE];
    for (s = 0; s < EVR_TEX_COUNT; s++) {
        if (uv[s] < 0) continue;
        if (chosen < 0) chosen = uv[s];
        if (uv[s] != chosen)
            evr_import_warn(im,
                            "material '%s': its textures use uv channels %d and %d; evray keeps "
                            "one per mesh: %d (the base colour's)",
                            m->name, chosen, uv[s], chosen);
    }
    *mat_uv = chosen < 0 ? 0 : chosen;
    for (t = 0; t < sizeof unrendered / sizeof *unrendered; t++)
        if (aiGetMaterialTextureCount(am, unrendered[t].type) > 0)
            evr_import_warn(im, "material '%s': its %s texture is not rendered (ignored)", m->name,
                            unrendered[t].name);
    return EVR_OK;
}

evr_status evr_import_materials(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    int n = ai->mNumMaterials ? (int)ai->mNumMaterials : 1; /* at least a default one */
    int from_json = 0;
    evr_status st;

    s->materials = calloc((size_t)n, sizeof *s->materials);
    im->mat_uv = calloc((size_t)n, sizeof *im->mat_uv);
    if (!s->materials || !im->mat_uv)
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading materials");
    s->num_materials = n;
    for (i = 0; i < (unsigned)n; i++) evr_material_defaults(&s->materials[i].p);
    for (i = 0; i < ai->mNumMaterials; i++) {
        struct aiString str;
        evr_material *m = &s->materials[i];
        if (aiGetMaterialString(ai->mMaterials[i], AI_MATKEY_NAME, &str) == aiReturn_SUCCESS)
            evr_import_copy_name(m->name, sizeof m->name, str.data);
        else snprintf(m->name, sizeof m->name, "material%u", i);
    }
    /* glTF: the JSON's materials (as many of Assimp's, matched by name: evr_gltf_materials_read);
     * Assimp's own default material, when it added one, is the last */
    if (im->gltf && im->have_side && im->src.bytes &&
        (st = evr_gltf_materials_read(im, &from_json)) != EVR_OK)
        return st;
    for (i = (unsigned)from_json; i < ai->mNumMaterials; i++)
        if ((st = assimp_material(im, ai->mMaterials[i], &s->materials[i], &im->mat_uv[i])) !=
            EVR_OK)
            return st;
    if (!ai->mNumMaterials) strcpy(s->materials[0].name, "default");
    return EVR_OK;
}
