/* Surface description at a hit, lights, and the radiance the sensor sees. Monochrome sensor:
 * the result is the Rec. 709 luminance of linear RGB, never clamped. */
#ifndef EVR_CORE_SHADING_H
#define EVR_CORE_SHADING_H

#include "core/material.h"

EVR_HD static inline float evr_srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}
EVR_HD static inline float evr_linear_to_srgb(float c)
{
    return c <= 0.0031308f ? 12.92f * c : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
}
/* Rec. 709 luminance weights (linear RGB) */
#define EVR_LUMA_R 0.2126f
#define EVR_LUMA_G 0.7152f
#define EVR_LUMA_B 0.0722f

EVR_HD static inline float evr_luminance(float r, float g, float b)
{
    return EVR_LUMA_R * r + EVR_LUMA_G * g + EVR_LUMA_B * b;
}

/* The footprint (evr_surface.tex_lod) of a ray along dir whose cone is cone_width wide where it
 * meets triangle (i0, i1, i2) of mesh m of instance inst, as the instance is at time f (xf). */
EVR_HD static inline float evr_surface_tex_lod(const evr_render_scene *rs, int inst,
                                               const evr_mesh_view *m, uint32_t i0, uint32_t i1,
                                               uint32_t i2, const evr_m34 *xf, float f, evr_v3 dir,
                                               float cone_width)
{
    if (!(cone_width > 0.0f) || !m->uvs || !evr_material_textured(&rs->materials[m->material]))
        return EVR_TEX_LOD_SHARPEST;
    const evr_v3 p0 = evr_m34_point(xf, evr_rs_vertex(rs, inst, m, i0, f));
    const evr_v3 p1 = evr_m34_point(xf, evr_rs_vertex(rs, inst, m, i1, f));
    const evr_v3 p2 = evr_m34_point(xf, evr_rs_vertex(rs, inst, m, i2, f));
    const evr_v3 c = evr_v3_cross(evr_v3_sub(p1, p0), evr_v3_sub(p2, p0));
    const float area2 = evr_v3_len(c); /* areas doubled */
    const float *t0 = m->uvs + 2 * i0, *t1 = m->uvs + 2 * i1, *t2 = m->uvs + 2 * i2;
    const float uv2 = fabsf((t1[0] - t0[0]) * (t2[1] - t0[1]) - (t2[0] - t0[0]) * (t1[1] - t0[1]));
    const float cos_theta = area2 > 0.0f ? evr_v3_dot(c, dir) / area2 : 0.0f;
    return evr_texture_lod(cone_width, cos_theta, area2, uv2);
}

/* Fills the surface at barycentrics (u, v) of triangle prim of instance inst, whose transform at
 * the ray's time f is xf; ray_dir is the incoming direction, t_hit the distance along it;
 * cone_width the width of the ray's cone there (world units; 0: the sharpest texture level),
 * which filters the textures (evr_surface_tex_lod). */
EVR_HD static inline void evr_surface_at(const evr_render_scene *rs, int inst, unsigned prim,
                                         float u, float v, const evr_m34 *xf, float f, evr_ray ray,
                                         float t_hit, float cone_width, evr_surface *s)
{
    const evr_mesh_view *m = &rs->meshes[rs->instances[inst].mesh];
    uint32_t i0 = m->indices[3 * prim], i1 = m->indices[3 * prim + 1],
             i2 = m->indices[3 * prim + 2];
    float w = 1.0f - u - v;
    evr_v3 n0 = evr_rs_normal(rs, inst, m, i0, f);
    evr_v3 n1 = evr_rs_normal(rs, inst, m, i1, f);
    evr_v3 n2 = evr_rs_normal(rs, inst, m, i2, f);
    evr_v3 n =
        evr_v3_add(evr_v3_add(evr_v3_scale(n0, w), evr_v3_scale(n1, u)), evr_v3_scale(n2, v));
    n = evr_m34_normal(xf, n);
    s->front = evr_v3_dot(n, ray.dir) <= 0.0f;
    if (!s->front) n = evr_v3_scale(n, -1.0f); /* two-sided */
    s->nv = n;
    s->p = evr_v3_add(ray.org, evr_v3_scale(ray.dir, t_hit));
    evr_v3 tw = evr_v3_make(0.0f, 0.0f, 0.0f);
    float tsign = 1.0f;
    if (m->tangents) {
        const float *t0 = m->tangents + 4 * i0, *t1 = m->tangents + 4 * i1,
                    *t2 = m->tangents + 4 * i2;
        tw = evr_m34_vector(xf, evr_v3_make(w * t0[0] + u * t1[0] + v * t2[0],
                                            w * t0[1] + u * t1[1] + v * t2[1],
                                            w * t0[2] + u * t1[2] + v * t2[2]));
        tsign = t0[3] < 0.0f ? -1.0f : 1.0f;
    }
    s->tex_lod = evr_surface_tex_lod(rs, inst, m, i0, i1, i2, xf, f, ray.dir, cone_width);
    evr_material_at(rs, m, i0, i1, i2, w, u, v, tw, tsign, evr_v3_scale(ray.dir, -1.0f), s);
}

/* Light arriving at p from light l at normalized segment time f: direction towards the light,
 * distance to it (for the shadow ray; huge for directional) and irradiance on a surface facing
 * it. Returns 0 when no light arrives (outside a spot cone, zero power). */
EVR_HD static inline int evr_light_incident(const evr_render_scene *rs, const evr_light_view *l,
                                            float f, evr_v3 p, evr_v3 *wi, float *dist,
                                            float e_rgb[3])
{
    evr_v3 lp = l->pos, ld = l->dir;
    float scale = 1.0f;
    if (l->track >= 0) {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, l->track), f);
        lp = evr_m34_point(&xf, lp);
        ld = evr_v3_norm(evr_m34_vector(&xf, ld));
    }
    if (l->type == 2) { /* directional */
        *wi = evr_v3_scale(ld, -1.0f);
        *dist = 1e30f;
    } else {
        evr_v3 d = evr_v3_sub(lp, p);
        float d2 = evr_v3_dot(d, d);
        if (d2 <= 0.0f) return 0;
        *dist = sqrtf(d2);
        *wi = evr_v3_scale(d, 1.0f / *dist);
        scale = 1.0f / d2;
        if (l->type == 1) { /* spot: glTF's recommended smooth falloff */
            float cd = -evr_v3_dot(*wi, ld);
            float a = (cd - l->cos_outer) / fmaxf(l->cos_inner - l->cos_outer, 1e-4f);
            a = fminf(fmaxf(a, 0.0f), 1.0f);
            scale *= a * a;
        }
    }
    e_rgb[0] = l->color[0] * scale;
    e_rgb[1] = l->color[1] * scale;
    e_rgb[2] = l->color[2] * scale;
    return scale > 0.0f && (e_rgb[0] > 0.0f || e_rgb[1] > 0.0f || e_rgb[2] > 0.0f);
}

/* Sensor intensity of s seen along wo: the luminance of its radiance (evr_material_radiance)
 * from the lights' sum acc (evr_material_add_light), with no reflection or refraction traced. */
EVR_HD static inline float evr_surface_intensity(const evr_surface *s, evr_v3 wo,
                                                 const float acc[3], float ambient)
{
    float rgb[3];
    evr_material_radiance(s, wo, acc, ambient, 0, 0, rgb);
    return evr_luminance(rgb[0], rgb[1], rgb[2]);
}

/* Where a shadow ray along wi starts, as a distance from the hit point: far enough that the
 * point is eps above the surface. The ray stays on the exact line from the hit to the light (an
 * offset along the normal would shift that line sideways and misjudge shadows near edges). */
EVR_HD static inline float evr_shadow_tnear(const evr_surface *s, evr_v3 wi, float eps)
{
    return eps / fmaxf(evr_v3_dot(s->nv, wi), 0.05f);
}

#endif
