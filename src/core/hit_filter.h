/* Hits a material says are not there, skipped by the ray traversal itself (Embree's filter
 * functions and the deforming user geometry on the CPU, src/cuda/gpu_traverse.h on the GPU), so
 * that a ray goes on to what lies behind, deterministically (no random transparency: it would
 * flicker into events):
 *   - alpha MASK: a hit where alpha = base_color[3] times the base texture's alpha (its
 *     KHR_texture_transform applied, bilinear at level 0) is below alpha_cutoff is no hit, for
 *     every ray (camera, secondary and shadow rays: the holes of a cut-out let light through);
 *   - single-sided (double_sided 0): a hit on the back face is no hit for camera and secondary
 *     rays. Shadow rays still see both faces, as a rasterizer's shadow map and Blender do: a
 *     single-sided plane seen from behind is invisible but still casts its shadow.
 * The front face is the glTF one: counter-clockwise in world space, i.e. the triangle's vertices
 * mapped to world space (a mirroring transform flips the winding, as the glTF spec says) give a
 * geometric normal ng = (p1 - p0) x (p2 - p0) with dot(ng, ray direction) < 0; edge-on (0) counts
 * as front. The test reads the triangle at the ray's time (evr_rs_vertex: a deforming instance's
 * vertices at that time), not its shading normals. A mesh needs the test only when its
 * evr_mesh_view.filter says so (evr_material_filter): the traversals test that first, so scenes
 * without such materials trace exactly as before. */
#ifndef EVR_CORE_HIT_FILTER_H
#define EVR_CORE_HIT_FILTER_H

#include "core/material.h"

#define EVR_FILTER_MASK 1 /* alpha MASK: holes where alpha < alpha_cutoff */
#define EVR_FILTER_CULL 2 /* single-sided: back faces culled (not for shadow rays) */

/* The tests a mesh of material mat needs (evr_mesh_view.filter): MASK when alpha can fall below
 * the cutoff (a base texture on a mesh with uvs, or a base alpha below it), CULL when the
 * material is single-sided and not a volume (KHR_materials_volume: a ray that entered it must
 * meet its inner faces to leave it). */
static inline int evr_material_filter(const evr_material_params *mat, int has_uvs)
{
    int bits = 0;
    if (mat->alpha_mode == EVR_ALPHA_MASK &&
        ((mat->tex[EVR_TEX_BASE].index >= 0 && has_uvs) || mat->base_color[3] < mat->alpha_cutoff))
        bits |= EVR_FILTER_MASK;
    if (!mat->double_sided && !(mat->transmission > 0.0f && mat->thickness > 0.0f))
        bits |= EVR_FILTER_CULL;
    return bits;
}

/* Whether the alpha MASK of mesh m's material cuts the hit at barycentrics (u, v) of its
 * triangle prim. */
EVR_HD static inline int evr_hit_alpha_cut(const evr_render_scene *rs, const evr_mesh_view *m,
                                           uint32_t prim, float u, float v)
{
    const evr_material_params *mat = &rs->materials[m->material];
    float alpha = mat->base_color[3];
    const evr_texture_ref *t = &mat->tex[EVR_TEX_BASE];
    if (t->index >= 0 && m->uvs) {
        const uint32_t i0 = m->indices[3 * prim], i1 = m->indices[3 * prim + 1],
                       i2 = m->indices[3 * prim + 2];
        const float w = 1.0f - u - v;
        float tu = w * m->uvs[2 * i0] + u * m->uvs[2 * i1] + v * m->uvs[2 * i2];
        float tv = w * m->uvs[2 * i0 + 1] + u * m->uvs[2 * i1 + 1] + v * m->uvs[2 * i2 + 1];
        float xu, xv, texel[4];
        evr_texture_uv(t, tu, tv, &xu, &xv);
        evr_texture_bilinear(&rs->textures[t->index], xu, xv, texel);
        alpha *= texel[3];
    }
    return alpha < mat->alpha_cutoff;
}

/* Whether a ray along dir meets triangle prim of instance inst (mesh m) at time f from behind.
 * dir is in world space, or with dir_local in the instance's own space (that of evr_rs_vertex:
 * what Embree hands an instanced geometry's filter). */
EVR_HD static inline int evr_hit_back_face(const evr_render_scene *rs, int inst,
                                           const evr_mesh_view *m, uint32_t prim, evr_v3 dir,
                                           int dir_local, float f)
{
    const evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[inst].track), f);
    const evr_v3 p0 = evr_rs_vertex(rs, inst, m, m->indices[3 * prim], f);
    const evr_v3 p1 = evr_rs_vertex(rs, inst, m, m->indices[3 * prim + 1], f);
    const evr_v3 p2 = evr_rs_vertex(rs, inst, m, m->indices[3 * prim + 2], f);
    const evr_v3 e1 = evr_m34_vector(&xf, evr_v3_sub(p1, p0));
    const evr_v3 e2 = evr_m34_vector(&xf, evr_v3_sub(p2, p0));
    const evr_v3 d = dir_local ? evr_m34_vector(&xf, dir) : dir;
    return evr_v3_dot(evr_v3_cross(e1, e2), d) > 0.0f;
}

/* 1 when the hit at barycentrics (u, v) of triangle prim of instance inst, met at time f by a
 * ray along dir (world space, or the instance's own with dir_local), is to be ignored; shadow:
 * the ray only asks whether anything is in the way (back faces count). */
EVR_HD static inline int evr_hit_filtered(const evr_render_scene *rs, int inst, uint32_t prim,
                                          float u, float v, evr_v3 dir, int dir_local, float f,
                                          int shadow)
{
    const evr_mesh_view *m = &rs->meshes[rs->instances[inst].mesh];
    if ((m->filter & EVR_FILTER_MASK) && evr_hit_alpha_cut(rs, m, prim, u, v)) return 1;
    return !shadow && (m->filter & EVR_FILTER_CULL) &&
           evr_hit_back_face(rs, inst, m, prim, dir, dir_local, f);
}

#endif
