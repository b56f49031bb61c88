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
        if (evr_occluded(o, lr.ray, lr.tnear, lr.tfar, f)) continue;
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
