/* Specular paths, written once: a camera ray's hit may reflect (a mirror or near-mirror
 * surface), refract (a transmissive one) and let light through (BLEND coverage below 1), each
 * as one more ray, deterministically (no random choice: it would flicker into events), up to
 * rs->max_bounces deep. The rays form a small tree followed with a stack; what is not traced
 * (too deep, too faint, the stack full) takes the ambient environment's radiance instead.
 *
 * The primary hit and its lights' sum are the backend's (the CPU traces them in packets);
 * evr_path_intensity takes them from there. How a ray finds its closest hit is the backend's
 * too: a file that includes this header defines evr_closest (core/shade_hit.h). */
#ifndef EVR_CORE_PATH_H
#define EVR_CORE_PATH_H

#include "core/shade_hit.h"
#include "core/bsdf_sample.h"
#include "core/skip.h"

/* A ray of a pixel's path still to follow. */
typedef struct {
    evr_ray ray;
    float tnear;
    float w[3]; /* what its radiance is worth at the pixel */
    float cone; /* width of the pixel's ray cone at its origin (texture filtering) */
    int depth;  /* reflections and refractions before it */
    int medium; /* material whose volume it travels in, -1: none */
} evr_path_ray;

#define EVR_PATH_STACK 8
/* A ray worth less than this (luminance) is not traced: its share takes the ambient light. */
#define EVR_PATH_MIN_WEIGHT 1e-3f

typedef struct {
    evr_path_ray r[EVR_PATH_STACK];
    int n;
} evr_path_stack;

/* Pushes a ray from p along dir worth w (when it is worth tracing and there is room); returns
 * 0 when it is not pushed (the caller takes the ambient light for it). */
EVR_HD static inline int evr_path_push(const evr_render_scene *rs, evr_path_stack *st, evr_v3 p,
                                       evr_v3 dir, evr_v3 nv, const float w[3], float cone,
                                       int depth, int medium)
{
    if (depth > rs->max_bounces || st->n >= EVR_PATH_STACK) return 0;
    if (evr_luminance(w[0], w[1], w[2]) < EVR_PATH_MIN_WEIGHT) return 0;
    evr_path_ray *r = &st->r[st->n++];
    r->ray.org = p;
    r->ray.dir = dir;
    r->tnear = rs->ray_eps / fmaxf(fabsf(evr_v3_dot(nv, dir)), 0.05f);
    r->w[0] = w[0], r->w[1] = w[1], r->w[2] = w[2];
    r->cone = cone;
    r->depth = depth;
    r->medium = medium;
    return 1;
}

/* The radiance of surface s, met by ray along d with its path's weight w at depth `depth` in
 * medium `medium` (its ray cone `cone` wide at s), from its lights' sum acc: adds w times what it sends back to out and pushes
 * the rays its coverage, reflection and refraction continue along. */
EVR_HD static inline void evr_path_shade(const evr_render_scene *rs, const evr_surface *s, evr_v3 d,
                                         const float acc[3], const float w[3], float cone,
                                         int depth, int medium, evr_path_stack *st, float out[3])
{
    const evr_material_params *mat = &rs->materials[s->material];
    const float a = s->opacity;
    float wr[3], wt[3], wb[3], rgb[3];
    int c;
    for (c = 0; c < 3; c++) {
        wr[c] = w[c] * a * s->spec_albedo[c];
        wt[c] = w[c] * a * s->transmit[c];
        wb[c] = w[c] * (1.0f - a);
    }
    int refl = 0, trans = 0;
    if (evr_material_transmits(s)) {
        evr_v3 dir = d;
        int med = medium;
        if (mat->thickness > 0.0f) { /* a volume: bends at its faces */
            const float eta = s->front ? s->eta : 1.0f / s->eta;
            med = s->front ? s->material : -1;
            if (!evr_refract_dir(d, s->n, eta, &dir)) { /* all of it reflects */
                for (c = 0; c < 3; c++) wr[c] += wt[c], wt[c] = 0.0f;
            }
        }
        if (wt[0] > 0.0f || wt[1] > 0.0f || wt[2] > 0.0f)
            trans = evr_path_push(rs, st, s->p, dir, s->nv, wt, cone, depth + 1, med);
    }
    if (evr_material_mirror(s)) {
        const evr_v3 r = evr_surface_mirror_dir(s, d);
        refl = evr_path_push(rs, st, s->p, r, s->nv, wr, cone, depth + 1, medium);
    }
    evr_material_radiance(s, evr_v3_scale(d, -1.0f), acc, rs->ambient, refl, trans, rgb);
    for (c = 0; c < 3; c++) out[c] += w[c] * a * rgb[c];
    if (a < 1.0f && !evr_path_push(rs, st, s->p, d, s->nv, wb, cone, depth + 1, medium))
        for (c = 0; c < 3; c++) out[c] += wb[c] * rs->ambient;
}

/* Follows the rays on the stack to the end: each one's closest hit shaded with its lights
 * (their shadow rays through evr_shadow_pass) and its own continuations; a ray that meets
 * nothing sees the ambient environment. *rays counts every ray. With a skip plan pl, *deep gains
 * EVR_DEEP_MOVED when a ray, or the segment from its hit to a light, meets anything that moves
 * in the segment (without one it gains it anyway). */
EVR_HD static inline void evr_path_follow(const evr_render_scene *rs, struct evr_occlusion *o,
                                          float f, const evr_skip_plan *pl, evr_path_stack *st,
                                          unsigned *rays, int *deep, float out[3])
{
    if (!pl) *deep |= EVR_DEEP_MOVED;
    while (st->n > 0) {
        const evr_path_ray pr = st->r[--st->n];
        evr_hit h;
        float w[3] = {pr.w[0], pr.w[1], pr.w[2]};
        (*rays)++;
        const int hit = evr_closest(o, pr.ray, pr.tnear, 1e30f, f, &h);
        if (!(*deep & EVR_DEEP_MOVED) && pl->num_boxes > 0 &&
            evr_skip_hit_ray_meets(pl, pr.ray, hit ? h.t : INFINITY))
            *deep |= EVR_DEEP_MOVED;
        if (!hit) {
            for (int c = 0; c < 3; c++) out[c] += w[c] * rs->ambient;
            continue;
        }
        if (pr.medium >= 0) /* Beer-Lambert through the volume it crossed */
            evr_volume_attenuate(&rs->materials[pr.medium], h.t, w);
        const evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), f);
        const float cone = pr.cone + evr_camera_pixel_spread(&rs->camera) * h.t;
        evr_surface s;
        evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, f, pr.ray, h.t, cone, &s);
        if (!(*deep & EVR_DEEP_MOVED) && pl->num_boxes > 0 && evr_skip_lights_meet(rs, pl, s.p))
            *deep |= EVR_DEEP_MOVED;
        float acc[3];
        evr_shade_direct_sum(rs, &s, evr_v3_scale(pr.ray.dir, -1.0f), f, o, rays, acc);
        evr_path_shade(rs, &s, pr.ray.dir, acc, w, cone, pr.depth, pr.medium, st, out);
    }
}

/* The radiance (RGB) of a camera ray along d whose hit s at distance t_hit has the lights' sum
 * acc, with every reflection and refraction its path takes; *deep gets EVR_DEEP_PATH when the
 * path went beyond the primary hit, and EVR_DEEP_MOVED as evr_path_follow says (pl: the
 * segment's skip plan, NULL: none). */
EVR_HD static inline void evr_path_radiance(const evr_render_scene *rs, const evr_surface *s,
                                            evr_v3 d, float t_hit, const float acc[3],
                                            struct evr_occlusion *o, float f,
                                            const evr_skip_plan *pl, unsigned *rays, int *deep,
                                            float out[3])
{
    const float w[3] = {1.0f, 1.0f, 1.0f};
    evr_path_stack st;
    st.n = 0;
    out[0] = out[1] = out[2] = 0.0f;
    evr_path_shade(rs, s, d, acc, w, evr_camera_cone(&rs->camera, t_hit), 0, -1, &st, out);
    if (st.n > 0) {
        *deep |= EVR_DEEP_PATH;
        evr_path_follow(rs, o, f, pl, &st, rays, deep, out);
    }
}

/* The sensor intensity of the same: the luminance of evr_path_radiance. */
EVR_HD static inline float evr_path_intensity(const evr_render_scene *rs, const evr_surface *s,
                                              evr_v3 d, float t_hit, const float acc[3],
                                              struct evr_occlusion *o, float f,
                                              const evr_skip_plan *pl, unsigned *rays, int *deep)
{
    float out[3];
    evr_path_radiance(rs, s, d, t_hit, acc, o, f, pl, rays, deep, out);
    return evr_luminance(out[0], out[1], out[2]);
}

#endif
