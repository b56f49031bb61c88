/* A photon's path: its start (emitter, time, first ray) and what happens at each hit. The loop
 * that traces it is the backend's (src/cpu/photon_pass.c, src/cuda/cuda_gi.cu). */
#ifndef EVR_CORE_PHOTON_PATH_H
#define EVR_CORE_PHOTON_PATH_H

#include <stdint.h>
#include "core/shading.h"
#include "core/photon_emit.h"
#include "core/photon_rand.h"

/* What a pass traces with (the CPU's and the GPU's). */
typedef struct {
    int max_bounces; /* indirect bounces: a light photon has at most max_bounces + 1 hits */
    float f0, f1;    /* photon j is traced at time evr_photon_time(j, f0, f1) */
    uint64_t seed;
    int threads;              /* CPU: <= 0 all cores */
    evr_photon_bounds bounds; /* the scene's bounding sphere (directional lights) */
    float ray_eps;            /* secondary-ray offset (rs->ray_eps) */
} evr_photon_params;

/* Index of the emitter of photon i of a pass: the last emitter whose first <= i. */
EVR_HD static inline int evr_photon_emitter_of(const evr_photon_emitter *e, int n, uint32_t i)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (e[mid].first <= i) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

typedef struct {
    evr_photon_ray pr;    /* the ray to trace next and the flux it carries */
    float tnear;          /* where the next ray starts */
    float f;              /* normalized segment time of the photon */
    uint32_t i, j;        /* photon number in the pass, in its emitter */
    int ei;               /* emitter */
    int bounce, max_hits; /* hits so far; the path ends at max_hits ("capped") */
} evr_photon_path;

/* Starts photon i of a pass over emitters e[0..n) (cdf: the emissive instances' cumulative
 * areas): its time, its first ray and flux. 0 when there is no such photon or it carries nothing. */
EVR_HD static inline int evr_photon_path_start(const evr_render_scene *rs,
                                               const evr_photon_emitter *e, int n, const float *cdf,
                                               const evr_photon_params *pp, uint32_t i,
                                               evr_photon_path *p)
{
    float u[5];
    int k;
    if (n <= 0) return 0;
    p->ei = evr_photon_emitter_of(e, n, i);
    const evr_photon_emitter *em = &e[p->ei];
    p->i = i;
    p->j = i - em->first;
    if (p->j >= em->count) return 0;
    p->f = evr_photon_time(p->j, pp->f0, pp->f1);
    for (k = 0; k < 5; k++) u[k] = evr_photon_rand(pp->seed, p->ei, p->j, k);
    if (em->kind == 0) {
        if (!evr_photon_emit_light(rs, &rs->lights[em->index], p->f, pp->bounds, u, em->count,
                                   &p->pr))
            return 0;
    } else {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[em->index].track), p->f);
        if (!evr_photon_emit_surface(rs, em, cdf, &xf, p->f, u, &p->pr)) return 0;
    }
    p->bounce = 0;
    p->max_hits = p->pr.from_light ? pp->max_bounces + 1 : pp->max_bounces;
    p->tnear = p->pr.from_light ? 0.0f : pp->ray_eps;
    return 1;
}

/* The path meets surface s (material mat). Returns EVR_PHOTON_STAY (stored[] gets the flux the
 * photon stands for, *key its canonical order), EVR_PHOTON_DIFFUSE or EVR_PHOTON_MIRROR (the
 * path's ray is the next one to trace while bounce < max_hits; past that the path is capped) or
 * EVR_PHOTON_ABSORB (the path ends). absorbed[] gets the flux this hit absorbs (bookkeeping). */
EVR_HD static inline int evr_photon_path_hit(evr_photon_path *p, const evr_photon_params *pp,
                                             const evr_surface *s, const evr_material_params *mat,
                                             float stored[3], float absorbed[3], uint32_t *key)
{
    float w;
    const int first_light = p->pr.from_light && p->bounce == 0;
    const float xi = evr_photon_rand(pp->seed, p->ei, p->j, 5 + 3 * p->bounce);
    const int ev = evr_material_photon_event(mat, s, p->pr.ray.dir, xi, !first_light, &w);
    int c;
    for (c = 0; c < 3; c++) absorbed[c] = stored[c] = 0.0f;
    if (ev == EVR_PHOTON_STAY) {
        for (c = 0; c < 3; c++) {
            stored[c] = p->pr.flux[c] * w;
            absorbed[c] = stored[c] * (1.0f - s->albedo[c]);
        }
        *key = p->i * 16u + (uint32_t)(p->bounce < 15 ? p->bounce : 15);
        return ev;
    }
    if (first_light) /* the direct term's light: the part the surface absorbs */
        for (c = 0; c < 3; c++) absorbed[c] = p->pr.flux[c] * (1.0f - s->albedo[c]);
    if (ev == EVR_PHOTON_ABSORB) return ev;
    for (c = 0; c < 3; c++) p->pr.flux[c] *= s->albedo[c] * w;
    if (ev == EVR_PHOTON_DIFFUSE)
        p->pr.ray.dir =
            evr_cosine_dir(s->n, evr_photon_rand(pp->seed, p->ei, p->j, 6 + 3 * p->bounce),
                           evr_photon_rand(pp->seed, p->ei, p->j, 7 + 3 * p->bounce));
    else p->pr.ray.dir = evr_v3_norm(evr_mirror_dir(p->pr.ray.dir, s->n));
    p->pr.ray.org = s->p;
    p->tnear = evr_shadow_tnear(s, p->pr.ray.dir, pp->ray_eps);
    p->bounce++;
    return ev;
}

#endif
