/* Triangle meshes: positions, unit normals, the material's uv channel, and tangents for a
 * material with a normal texture (the file's, else generated: tangents.c). Materials are read
 * before (import_material.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>
#include <assimp/material.h>

#include "host_clock.h"
#include "scene/import_internal.h"

/* Tangents for a mesh whose material has a normal texture: the file's (Assimp's mTangents and
 * mBitangents; w is the sign of the bitangent against cross(normal, tangent)), made orthogonal to
 * the normal, else generated from the uvs. A skinned or morphed mesh keeps its rest tangents (the
 * shading makes them orthogonal to the deformed normal). Without uvs: none, and a warning. */
static evr_status mesh_tangents(importer *im, const struct aiMesh *am, evr_mesh *m)
{
    uint32_t v;
    int usable = am->mTangents && am->mBitangents;
    if (!m->uvs) {
        evr_import_warn(im, "mesh '%s': its material's normal texture needs uvs (not rendered)",
                        m->name);
        return EVR_OK;
    }
    if (usable) {
        m->tangents = malloc((size_t)m->num_vertices * 4 * sizeof(float) + 1);
        if (!m->tangents)
            return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading tangents");
        for (v = 0; v < m->num_vertices && usable; v++) {
            evr_v3 n = evr_v3_make(m->normals[3 * v], m->normals[3 * v + 1], m->normals[3 * v + 2]);
            evr_v3 t = evr_v3_make(am->mTangents[v].x, am->mTangents[v].y, am->mTangents[v].z);
            evr_v3 b =
                evr_v3_make(am->mBitangents[v].x, am->mBitangents[v].y, am->mBitangents[v].z);
            float l;
            t = evr_v3_sub(t, evr_v3_scale(n, evr_v3_dot(n, t)));
            l = evr_v3_len(t);
            if (!(l > 1e-12f) || !isfinite(l)) {
                usable = 0; /* a degenerate tangent: generate them all instead */
                break;
            }
            t = evr_v3_scale(t, 1.0f / l);
            m->tangents[4 * v] = t.x;
            m->tangents[4 * v + 1] = t.y;
            m->tangents[4 * v + 2] = t.z;
            m->tangents[4 * v + 3] = evr_v3_dot(evr_v3_cross(n, t), b) < 0.0f ? -1.0f : 1.0f;
        }
        if (usable) return EVR_OK;
        free(m->tangents);
        m->tangents = NULL;
    }
    const double t = evr_host_seconds();
    const int made = evr_mesh_generate_tangents(m);
    im->s->times.tangents += evr_host_seconds() - t;
    if (!made) return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory generating tangents");
    return EVR_OK;
}

evr_status evr_import_meshes(importer *im, uint64_t *total_tris)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i, coloured = 0;
    const char *first_coloured = NULL;
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
        if (s->materials[m->material].p.tex[EVR_TEX_NORMAL].index >= 0) {
            evr_status st = mesh_tangents(im, am, m);
            if (st != EVR_OK) return st;
        }
        if (am->mColors[0] && !coloured++) first_coloured = m->name;
        *total_tris += ntri;
    }
    /* glTF's COLOR_0 multiplies the base colour, other formats' paint the surface: neither is
     * rendered, one line says so */
    if (coloured)
        evr_import_warn(
            im, "%u mesh%s (the first '%s') %s vertex colours, which evray does not render",
            coloured, coloured == 1 ? "" : "es", first_coloured, coloured == 1 ? "has" : "have");
    return EVR_OK;
}
