/* evr_shade_hit: the direct light of a hit from every light with its shadow ray, plus ambient and
 * emission (core/shade.h's steps), for a backend that traces one shadow ray at a time.
 *
 * How a shadow ray finds triangles is the backend's: a file that includes this header defines
 * `struct evr_occlusion` and evr_occluded below (Embree one ray at a time for evray still, the
 * GPU's traversal for the CUDA kernels), so the loop is inlined with it and no function pointer. */
#ifndef EVR_CORE_SHADE_HIT_H
#define EVR_CORE_SHADE_HIT_H

#include "core/shade.h"

struct evr_occlusion;

/* 1 when something blocks ray r over [tnear, tfar) at normalized segment time f. */
EVR_HD static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar,
                                      float f);
/* 1 when ray r meets something over [tnear, tfar) at time f; *h the closest hit. */
EVR_HD static inline int evr_closest(struct evr_occlusion *o, evr_ray r, float tnear, float tfar,
                                     float f, evr_hit *h);

/* Most layers a shadow ray passes through before it counts as blocked. */
#define EVR_SHADOW_LAYERS 8

/* What reaches the end of shadow ray r over [tnear, tfar) at time f: 0 when blocked, else 1
 * with T the share of each colour that passes. Where some material transmits or blends
 * (rs->translucent), the ray passes such surfaces, each letting through its uncovered share and
 * its transmitted share (straight: light through glass is not bent, so caustics are not made);
 * elsewhere any hit blocks it. */
EVR_HD static inline int evr_shadow_pass(const evr_render_scene *rs, struct evr_occlusion *o,
                                         evr_ray r, float tnear, float tfar, float f, float T[3])
{
    T[0] = T[1] = T[2] = 1.0f;
    if (!rs->translucent) return !evr_occluded(o, r, tnear, tfar, f);
    for (int k = 0; k < EVR_SHADOW_LAYERS; k++) {
        evr_hit h;
        if (!evr_closest(o, r, tnear, tfar, f, &h)) return 1;
        const evr_material_params *mat =
            &rs->materials[rs->meshes[rs->instances[h.inst].mesh].material];
        if (!(mat->transmission > 0.0f) && mat->alpha_mode != EVR_ALPHA_BLEND) return 0;
        const evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), f);
        evr_surface s;
        evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, f, r, h.t, 0.0f, &s);
        for (int c = 0; c < 3; c++) T[c] *= (1.0f - s.opacity) + s.opacity * s.transmit[c];
        if (!(fmaxf(T[0], fmaxf(T[1], T[2])) > 1e-4f)) return 0;
        tnear = h.t + rs->ray_eps;
    }
    return 0;
}

/* The lights' sum acc at s (irradiance times the BSDF's cosine, core/material.h) at time f,
 * each light's shadow ray through evr_occluded; *rays counts the shadow rays. */
EVR_HD static inline void evr_shade_direct_sum(const evr_render_scene *rs, const evr_surface *s,
                                               evr_v3 wo, float f, struct evr_occlusion *o,
                                               unsigned *rays, float acc[3])
{
    acc[0] = acc[1] = acc[2] = 0.0f;
    for (int l = 0; l < rs->num_lights; l++) {
        evr_light_ray lr;
        if (!evr_shade_light_ray(rs, l, f, s, &lr)) continue;
        (*rays)++;
        float T[3];
        if (!evr_shadow_pass(rs, o, lr.ray, lr.tnear, lr.tfar, f, T)) continue;
        lr.e[0] *= T[0], lr.e[1] *= T[1], lr.e[2] *= T[2];
        evr_shade_add_light(s, wo, &lr, acc);
    }
}

/* The direct light of a hit as the sensor sees it: surface s seen along wo at time f. */
EVR_HD static inline float evr_shade_hit(const evr_render_scene *rs, const evr_surface *s,
                                         evr_v3 wo, float f, struct evr_occlusion *o,
                                         unsigned *rays)
{
    float acc[3];
    evr_shade_direct_sum(rs, s, wo, f, o, rays, acc);
    return evr_shade_intensity(rs, s, wo, acc);
}

#endif
