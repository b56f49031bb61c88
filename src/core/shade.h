/* Shading a hit, written once: one light's share with its shadow ray, the BSDF for it
 * (core/material.h), and the intensity the sensor sees with ambient and emission. The loop over
 * the lights with the shadow ray's query is core/shade_hit.h's evr_shade_hit; the CPU backend,
 * which traces eight hits' shadow rays per light as one Embree packet, runs these same steps
 * light by light (evr_shade_light_ray; evr_shade_add_light for the visible; evr_shade_intensity). */
#ifndef EVR_CORE_SHADE_H
#define EVR_CORE_SHADE_H

#include "core/shading.h"

/* One light's share at a hit: where it comes from and what it brings, and its shadow ray. */
typedef struct {
    evr_v3 wi;    /* towards the light */
    float e[3];   /* irradiance on a surface facing it */
    float spread; /* the light's angular radius seen from the surface (0: a point) */
    evr_ray ray;  /* the shadow ray, free over [tnear, tfar) when the light is visible */
    float tnear, tfar;
} evr_light_ray;

/* Light l's share at surface s at time f: 0 when it sends nothing there (no shadow ray needed). */
EVR_HD static inline int evr_shade_light_ray(const evr_render_scene *rs, int l, float f,
                                             const evr_surface *s, evr_light_ray *lr)
{
    float dist;
    lr->spread = 0.0f;
    if (s->unlit) return 0;
    if (!evr_light_incident(rs, &rs->lights[l], f, s->p, &lr->wi, &dist, lr->e)) return 0;
    if (evr_v3_dot(lr->wi, s->n) <= 0.0f || evr_v3_dot(lr->wi, s->nv) <= 0.0f) return 0;
    lr->spread = rs->lights[l].radius > 0.0f ? fminf(rs->lights[l].radius / dist, 1.0f) : 0.0f;
    lr->ray.org = s->p;
    lr->ray.dir = lr->wi;
    lr->tnear = evr_shadow_tnear(s, lr->wi, rs->ray_eps);
    lr->tfar = dist * (1.0f - 1e-4f);
    return 1;
}

/* Adds a visible light's share (evr_shade_light_ray) to acc, s seen along wo. */
EVR_HD static inline void evr_shade_add_light(const evr_surface *s, evr_v3 wo,
                                              const evr_light_ray *lr, float acc[3])
{
    evr_material_add_light(s, wo, lr->wi, lr->e, lr->spread, acc);
}

/* Sensor intensity of s seen along wo from the lights' sum acc, plus ambient and emission. */
EVR_HD static inline float evr_shade_intensity(const evr_render_scene *rs, const evr_surface *s,
                                               evr_v3 wo, const float acc[3])
{
    return evr_surface_intensity(s, wo, acc, rs->ambient);
}

#endif
