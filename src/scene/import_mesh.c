/* Materials (metallic-roughness factors, emission, the photon thresholds, the base colour
 * texture, alpha mode and cutoff, double-sidedness) and triangle meshes (positions, unit normals, the material's UV channel). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>
#include <assimp/material.h>
#include <assimp/GltfMaterial.h>

#include "core/photon.h"
#include "scene/import_internal.h"

evr_status evr_import_materials(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    int n = ai->mNumMaterials ? (int)ai->mNumMaterials : 1; /* at least a default one */

    s->materials = calloc((size_t)n, sizeof *s->materials);
    im->mat_uv = calloc((size_t)n, sizeof *im->mat_uv);
    if (!s->materials || !im->mat_uv)
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading materials");
    s->num_materials = n;
    for (i = 0; i < (unsigned)n; i++) {
        evr_material_defaults(&s->materials[i].p);
    }
    for (i = 0; i < ai->mNumMaterials; i++) {
        const struct aiMaterial *am = ai->mMaterials[i];
        evr_material *m = &s->materials[i];
        struct aiString str;
        struct aiColor4D c;
        ai_real f;
        unsigned int one = 1, uv = 0;
        int tt;
        static const enum aiTextureType kinds[2] = {aiTextureType_BASE_COLOR,
                                                    aiTextureType_DIFFUSE};

        if (aiGetMaterialString(am, AI_MATKEY_NAME, &str) == aiReturn_SUCCESS)
            evr_import_copy_name(m->name, sizeof m->name, str.data);
        else snprintf(m->name, sizeof m->name, "material%u", i);
        if (aiGetMaterialColor(am, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS ||
            aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS) {
            m->p.base_color[0] = c.r;
            m->p.base_color[1] = c.g;
            m->p.base_color[2] = c.b;
            m->p.base_color[3] = c.a;
        }
        if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS) {
            float k = 1.0f;
            one = 1;
            if (aiGetMaterialFloatArray(am, AI_MATKEY_EMISSIVE_INTENSITY, &f, &one) ==
                aiReturn_SUCCESS)
                k = (float)f;
            else if (im->have_side && (int)i < im->side.num_materials)
                k = im->side.emissive_strength[i];
            m->p.emissive[0] = c.r * k;
            m->p.emissive[1] = c.g * k;
            m->p.emissive[2] = c.b * k;
        }
        one = 1;
        if (aiGetMaterialFloatArray(am, AI_MATKEY_METALLIC_FACTOR, &f, &one) == aiReturn_SUCCESS)
            m->p.metallic = (float)f;
        one = 1;
        if (aiGetMaterialFloatArray(am, AI_MATKEY_ROUGHNESS_FACTOR, &f, &one) == aiReturn_SUCCESS)
            m->p.roughness = (float)f;
        evr_photon_material_map(m->p.base_color, m->p.metallic, m->p.roughness, &m->p.t_diffuse,
                                &m->p.t_specular);
        { /* glTF alphaMode, alphaCutoff, doubleSided (Assimp's keys for them) */
            int two = 0;
            one = 1;
            if (aiGetMaterialIntegerArray(am, AI_MATKEY_TWOSIDED, &two, &one) == aiReturn_SUCCESS)
                m->p.double_sided = two != 0;
            if (aiGetMaterialString(am, AI_MATKEY_GLTF_ALPHAMODE, &str) == aiReturn_SUCCESS)
                m->p.alpha_mode = !strcmp(str.data, "MASK")    ? EVR_ALPHA_MASK
                                  : !strcmp(str.data, "BLEND") ? EVR_ALPHA_BLEND
                                                               : EVR_ALPHA_OPAQUE;
            one = 1;
            if (aiGetMaterialFloatArray(am, AI_MATKEY_GLTF_ALPHACUTOFF, &f, &one) ==
                aiReturn_SUCCESS)
                m->p.alpha_cutoff = (float)f;
        }
        if (im->have_side && (int)i < im->side.num_materials &&
            (im->side.t_extras[2 * i] != T_ABSENT || im->side.t_extras[2 * i + 1] != T_ABSENT)) {
            float td = im->side.t_extras[2 * i], ts = im->side.t_extras[2 * i + 1];
            if (td == T_ABSENT) td = m->p.t_diffuse;
            if (ts == T_ABSENT) ts = td > m->p.t_specular ? td : m->p.t_specular;
            if (!(td >= 0.0f && td <= ts && ts <= 1.0f))
                return evr_import_fail(
                    im->err, EVR_ERR_FORMAT,
                    "material '%s': extras need 0 <= t_diffuse <= t_specular <= 1 (got %g, %g)",
                    m->name, (double)td, (double)ts);
            m->p.t_diffuse = td;
            m->p.t_specular = ts;
        }

        for (tt = 0; tt < 2; tt++) {
            if (aiGetMaterialTextureCount(am, kinds[tt]) == 0) continue;
            uv = 0;
            if (aiGetMaterialTexture(am, kinds[tt], 0, &str, NULL, &uv, NULL, NULL, NULL, NULL) !=
                    aiReturn_SUCCESS ||
                !str.data[0])
                continue;
            {
                evr_status st =
                    evr_import_texture(im, str.data, m->name, &m->p.tex[EVR_TEX_BASE].index);
                if (st != EVR_OK) return st;
            }
            im->mat_uv[i] = (int)uv;
            break;
        }
    }
    if (!ai->mNumMaterials) strcpy(s->materials[0].name, "default");
    return EVR_OK;
}

evr_status evr_import_meshes(importer *im, uint64_t *total_tris)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    *total_tris = 0;
    s->meshes = calloc((size_t)ai->mNumMeshes + 1, sizeof *s->meshes);
    if (!s->meshes) return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
    s->num_meshes = (int)ai->mNumMeshes;
    for (i = 0; i < ai->mNumMeshes; i++) {
        const struct aiMesh *am = ai->mMeshes[i];
        evr_mesh *m = &s->meshes[i];
        unsigned f, v, ntri = 0;
        int uvch;
        if (am->mName.length) evr_import_copy_name(m->name, sizeof m->name, am->mName.data);
        else snprintf(m->name, sizeof m->name, "mesh%u", i);
        m->material =
            (am->mMaterialIndex < (unsigned)s->num_materials) ? (int)am->mMaterialIndex : 0;
        for (f = 0; f < am->mNumFaces; f++)
            if (am->mFaces[f].mNumIndices == 3) ntri++;
        m->num_vertices = am->mNumVertices;
        m->num_triangles = ntri;
        m->positions = malloc((size_t)am->mNumVertices * 3 * sizeof(float) + 1);
        m->normals = malloc((size_t)am->mNumVertices * 3 * sizeof(float) + 1);
        m->indices = malloc((size_t)ntri * 3 * sizeof(uint32_t) + 1);
        if (!m->positions || !m->normals || !m->indices)
            return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
        m->bounds_min = evr_v3_make(INFINITY, INFINITY, INFINITY);
        m->bounds_max = evr_v3_make(-INFINITY, -INFINITY, -INFINITY);
        for (v = 0; v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            m->positions[3 * v] = p->x;
            m->positions[3 * v + 1] = p->y;
            m->positions[3 * v + 2] = p->z;
            m->bounds_min = evr_v3_make(fminf(m->bounds_min.x, p->x), fminf(m->bounds_min.y, p->y),
                                        fminf(m->bounds_min.z, p->z));
            m->bounds_max = evr_v3_make(fmaxf(m->bounds_max.x, p->x), fmaxf(m->bounds_max.y, p->y),
                                        fmaxf(m->bounds_max.z, p->z));
        }
        if (!am->mNumVertices) m->bounds_min = m->bounds_max = evr_v3_make(0, 0, 0);
        ntri = 0;
        for (f = 0; f < am->mNumFaces; f++) {
            const struct aiFace *fc = &am->mFaces[f];
            if (fc->mNumIndices != 3) continue;
            if (fc->mIndices[0] >= am->mNumVertices || fc->mIndices[1] >= am->mNumVertices ||
                fc->mIndices[2] >= am->mNumVertices)
                return evr_import_fail(im->err, EVR_ERR_FORMAT,
                                       "mesh '%s': a triangle refers to a missing vertex", m->name);
            m->indices[3 * ntri] = fc->mIndices[0];
            m->indices[3 * ntri + 1] = fc->mIndices[1];
            m->indices[3 * ntri + 2] = fc->mIndices[2];
            ntri++;
        }
        /* Normals: Assimp's (GenSmoothNormals makes them where the file has none), made unit;
         * area-weighted face normals for any vertex still without a usable one. */
        {
            unsigned char *fix = calloc((size_t)am->mNumVertices + 1, 1);
            int any_fix = 0;
            if (!fix)
                return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
            for (v = 0; v < am->mNumVertices; v++) {
                float *nv = &m->normals[3 * v];
                if (am->mNormals) {
                    nv[0] = am->mNormals[v].x;
                    nv[1] = am->mNormals[v].y;
                    nv[2] = am->mNormals[v].z;
                }
                if (!am->mNormals || !isfinite(nv[0] + nv[1] + nv[2]) ||
                    (nv[0] == 0.0f && nv[1] == 0.0f && nv[2] == 0.0f)) {
                    nv[0] = nv[1] = nv[2] = 0.0f;
                    fix[v] = 1;
                    any_fix = 1;
                }
            }
            for (f = 0; f < ntri && any_fix; f++) {
                const uint32_t *t = &m->indices[3 * f];
                evr_v3 a = evr_v3_make(m->positions[3 * t[0]], m->positions[3 * t[0] + 1],
                                       m->positions[3 * t[0] + 2]);
                evr_v3 b = evr_v3_make(m->positions[3 * t[1]], m->positions[3 * t[1] + 1],
                                       m->positions[3 * t[1] + 2]);
                evr_v3 c = evr_v3_make(m->positions[3 * t[2]], m->positions[3 * t[2] + 1],
                                       m->positions[3 * t[2] + 2]);
                evr_v3 fn = evr_v3_cross(evr_v3_sub(b, a), evr_v3_sub(c, a));
                int k;
                for (k = 0; k < 3; k++) {
                    float *nv = &m->normals[3 * t[k]];
                    if (!fix[t[k]]) continue;
                    nv[0] += fn.x;
                    nv[1] += fn.y;
                    nv[2] += fn.z;
                }
            }
            free(fix);
        }
        for (v = 0; v < am->mNumVertices; v++) {
            float *nv = &m->normals[3 * v];
            float l = sqrtf(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
            if (l > 0.0f && isfinite(l)) {
                nv[0] /= l;
                nv[1] /= l;
                nv[2] /= l;
            } else {
                nv[0] = 0.0f;
                nv[1] = 0.0f;
                nv[2] = 1.0f;
            }
        }
        uvch = im->mat_uv[m->material];
        if (uvch < 0 || uvch >= AI_MAX_NUMBER_OF_TEXTURECOORDS || !am->mTextureCoords[uvch])
            uvch = 0;
        if (am->mTextureCoords[uvch]) {
            m->uvs = malloc((size_t)am->mNumVertices * 2 * sizeof(float) + 1);
            if (!m->uvs)
                return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
            for (v = 0; v < am->mNumVertices; v++) {
                m->uvs[2 * v] = am->mTextureCoords[uvch][v].x;
                m->uvs[2 * v + 1] = am->mTextureCoords[uvch][v].y;
            }
        }
        *total_tris += ntri;
    }
    return EVR_OK;
}
