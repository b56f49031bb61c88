/* A photon's path: its start (emitter, time, first ray) and what happens at each hit. The loop
 * that traces it is the backend's (src/cpu/photon_pass.c, src/cuda/cuda_gi.cu). */
#ifndef EVR_CORE_PHOTON_PATH_H
#define EVR_CORE_PHOTON_PATH_H

#include <stddef.h>
#include <stdint.h>
#include "core/shading.h"
#include "core/photon_emit.h"
#include "core/photon_rand.h"
#include "core/bsdf_sample.h"

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
    /* 1 while the photon is a light's (point, spot, directional) and has only passed straight
     * on through surfaces that shadow rays pass too (transmission, BLEND's uncovered share):
     * the light it carries is still the direct term's, so it may not stay */
    int direct;
    const evr_material_params *medium; /* the volume the photon travels in, NULL: none */
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
    p->direct = p->pr.from_light;
    p->medium = NULL;
    p->max_hits = p->pr.from_light ? pp->max_bounces + 1 : pp->max_bounces;
    p->tnear = p->pr.from_light ? 0.0f : pp->ray_eps;
    return 1;
}

enum { EVR_PHOTON_STAY = 0, EVR_PHOTON_BOUNCE = 1, EVR_PHOTON_ABSORB = 2 };

/* The most a photon keeps going with at a hit where it may stay (Russian roulette's odds): a
 * little is always left to stay, and a white surface does not keep a photon forever. */
#define EVR_PHOTON_KEEP_MAX 0.95f

/* The path meets surface s (material mat) and the BSDF decides (core/bsdf_sample.h). Where the
 * photon may stay (a surface with a diffuse part, the photon not `direct`), with A the largest
 * channel of s's albedo (all lobes, as seen from the photon's side) and q = A clamped to
 * [0.05, 0.95], one number xi decides:
 *   - xi < 1 - q: the photon stays, stored[] = its flux / (1 - q): the stored photons estimate
 *     the incident flux without bias (the gather turns it into radiance with the diffuse
 *     weight), and the path ends;
 *   - else a lobe by its weight (the rest of xi spread over the lobes, evr_bsdf_pick), a
 *     direction from it, and the flux times f cos / pdf over q and the odds of the choice: the
 *     flux goes on at about its size (Russian roulette by the albedo).
 * Where it may not stay, it bounces (q = 1; all of xi picks the lobe) with its flux times the
 * lobe's weight over the odds, as a light's photon at its first hit did before the BSDF: no
 * photon is lost there (absorbing a share of them at a light's first hit, with the others' flux
 * raised to match, made the Cornell box's walls 15% noisier at one photon per pixel).
 * Returns EVR_PHOTON_STAY (stored[] and *key, its canonical order, set), EVR_PHOTON_BOUNCE (the
 * path's ray is the next one to trace while bounce < max_hits; past that the path is capped) or
 * EVR_PHOTON_ABSORB (the path ends). absorbed[] gets the flux the hit absorbs in expectation,
 * flux * (1 - albedo) (bookkeeping: over many photons emitted = absorbed + escaped + capped). */
EVR_HD static inline int evr_photon_path_hit(evr_photon_path *p, const evr_photon_params *pp,
                                             const evr_surface *s, const evr_material_params *mat,
                                             float stored[3], float absorbed[3], uint32_t *key)
{
    float w[EVR_LOBES][3], wt[3], pick;
    int c, k;
    for (c = 0; c < 3; c++) absorbed[c] = stored[c] = 0.0f;
    if (p->medium) /* Beer-Lambert through the volume it crossed */
        evr_volume_attenuate(p->medium, evr_v3_len(evr_v3_sub(s->p, p->pr.ray.org)), p->pr.flux);
    evr_bsdf_lobe_weights(s, w);
    float amax = 0.0f;
    for (c = 0; c < 3; c++) {
        float a = 0.0f;
        for (k = 0; k < EVR_LOBES; k++) a += w[k][c];
        absorbed[c] = p->pr.flux[c] * fmaxf(1.0f - a, 0.0f);
        amax = fmaxf(amax, a);
    }
    const int can_stay = !p->direct && !s->unlit &&
                         (w[EVR_LOBE_DIFFUSE][0] > 0.0f || w[EVR_LOBE_DIFFUSE][1] > 0.0f ||
                          w[EVR_LOBE_DIFFUSE][2] > 0.0f);
    const float q = can_stay ? fminf(fmaxf(amax, 1.0f - EVR_PHOTON_KEEP_MAX), EVR_PHOTON_KEEP_MAX)
                             : (amax > 0.0f ? 1.0f : 0.0f);
    const float xi = evr_photon_rand(pp->seed, p->ei, p->j, 5 + 3 * p->bounce);
    if (xi < 1.0f - q) {
        if (!can_stay) return EVR_PHOTON_ABSORB;
        for (c = 0; c < 3; c++) stored[c] = p->pr.flux[c] / (1.0f - q);
        *key = p->i * 16u + (uint32_t)(p->bounce < 15 ? p->bounce : 15);
        return EVR_PHOTON_STAY;
    }
    const float x = fminf((xi - (1.0f - q)) / q, 0.99999994f);
    const int lobe = evr_bsdf_pick(w, x, &pick);
    if (lobe < 0) return EVR_PHOTON_ABSORB;
    const evr_v3 d = p->pr.ray.dir;
    if (!evr_bsdf_sample(s, mat, lobe, d, evr_photon_rand(pp->seed, p->ei, p->j, 6 + 3 * p->bounce),
                         evr_photon_rand(pp->seed, p->ei, p->j, 7 + 3 * p->bounce), 1,
                         &p->pr.ray.dir, wt))
        return EVR_PHOTON_ABSORB;
    for (c = 0; c < 3; c++) p->pr.flux[c] *= wt[c] / (q * pick);
    p->direct = p->direct && (lobe == EVR_LOBE_TRANSMIT || lobe == EVR_LOBE_PASS);
    if (lobe == EVR_LOBE_TRANSMIT && evr_v3_dot(p->pr.ray.dir, s->nv) < 0.0f) {
        const int cross = evr_bsdf_crossing(s, mat);
        if (cross) p->medium = cross > 0 ? mat : NULL;
    }
    p->pr.ray.org = s->p;
    p->tnear = pp->ray_eps / fmaxf(fabsf(evr_v3_dot(s->nv, p->pr.ray.dir)), 0.05f);
    p->bounce++;
    return EVR_PHOTON_BOUNCE;
}

#endif
