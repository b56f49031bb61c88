/* Image-space photon mapping (issue 5): every per-photon and per-pixel decision, written once
 * for the CPU and for nvcc (EVR_HD, plain C, no allocation). The loops that trace rays live in
 * the backends (src/cpu/photon_pass.c on the CPU); the material's part (glTF metallic/roughness
 * -> t_diffuse, t_specular, the stay / diffuse / mirror decision, the bounce directions) is in
 * core/material.h. This file holds:
 *   - the flux update at a hit,
 *   - the low-discrepancy numbers of a photon (a pure function of emitter and photon number),
 *   - emission from point, spot and directional lights and from emissive triangles,
 *   - the image-space buffer (projection, lock-free insertion),
 *   - the ring search, the Gaussian kernel and the gather estimate.
 *
 * Light transport model. A surface reflects the fraction albedo * (1 - mirror) diffusely
 * (Lambertian, the direct term's model) and albedo * mirror as a mirror, with
 * mirror = (1 - t_specular) / (1 - t_diffuse). A photon arriving with flux F draws xi in [0, 1):
 *   xi <  t_diffuse               stays: stored with flux F / t_diffuse (so the stored photons
 *                                 estimate the incident flux without bias), path ends;
 *   t_diffuse <= xi < t_specular  diffuse bounce (cosine distributed), flux F * albedo / (1 - t_diffuse);
 *   xi >= t_specular              mirror bounce, flux F * albedo / (1 - t_diffuse).
 * A photon from a light (point, spot, directional) never stays at its first hit: that light is
 * the direct term's, already computed exactly with shadow rays; it bounces with flux F * albedo.
 * Photons from emissive surfaces may stay at their first hit (the direct term has no area lights).
 * Units: a light's colour is intensity (point, spot) or irradiance (directional), as in
 * evr_light_incident; flux = intensity * solid angle, so photon flux / area is an irradiance in
 * the units of the direct term's E and the estimate albedo * (1 - mirror) / pi * E adds to
 * evr_surface_intensity's radiance directly (per RGB channel; the sensor takes the luminance). */
#ifndef EVR_CORE_PHOTON_H
#define EVR_CORE_PHOTON_H

#include <stdint.h>
#include "core/rng.h"
#include "core/shading.h"
#include "core/skip.h"

#if defined(__CUDA_ARCH__)   /* nvcc's device pass; its host pass is the host compiler's */
#define EVR_ATOMIC_INC_U32(p) atomicAdd((unsigned int *)(p), 1u)
/* a product that is never fused with an addition (nvcc fuses a * b + c into one rounding where
 * it likes; the C compiler here, ISO C without FMA, never does) */
#define EVR_MUL_RN(a, b) __fmul_rn((a), (b))
#else
#define EVR_ATOMIC_INC_U32(p) __atomic_fetch_add((p), 1u, __ATOMIC_RELAXED)
#define EVR_MUL_RN(a, b) ((a) * (b))
#endif

/* Uniform direction on the sphere. */
EVR_HD static inline evr_v3 evr_sphere_dir(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 6.28318530718f * u2;
    return evr_v3_make(r * cosf(phi), r * sinf(phi), z);
}

/* ---- low-discrepancy numbers of a photon ---- */

/* Radical inverse of i in a prime base (Halton), in [0, 1). */
EVR_HD static inline float evr_radical_inverse(uint32_t i, uint32_t base)
{
    float inv = 1.0f / (float)base, f = inv, r = 0.0f;
    while (i > 0) {
        r += (float)(i % base) * f;
        i /= base;
        f *= inv;
    }
    return fminf(r, 0.99999994f);
}

/* Dimension dim of photon j of emitter e: dims 0-4 (the emission) are the Halton sequence
 * (bases 2, 3, 5, 7, 11) at index j + 1, each shifted by a fixed per-emitter offset (Cranley-
 * Patterson rotation) so that lights do not share points; later dims (the bounces) are
 * counter-based hashes of (seed, e, j, dim). Either way a pure function of the photon number:
 * the same photons every segment. */
EVR_HD static inline float evr_photon_rand(uint64_t seed, int e, uint32_t j, int dim)
{
    if (dim < 5) {
        const uint32_t bases[5] = {2, 3, 5, 7, 11};
        float x = evr_radical_inverse(j + 1u, bases[dim]) +
                  evr_uniform(evr_hash4(seed, (uint64_t)e, 0x73686966ull /* "shif" */, (uint64_t)dim));
        x -= floorf(x);
        return fminf(x, 0.99999994f);
    }
    return evr_uniform(evr_hash4(seed ^ 0x70686f746f6eull /* "photon" */, (uint64_t)e, (uint64_t)j, (uint64_t)dim));
}

/* Normalized segment time of photon j: f0 + (f1 - f0) * frac(j * golden ratio). */
EVR_HD static inline float evr_photon_time(uint32_t j, float f0, float f1)
{
    float g = (float)j * 0.61803398875f;
    g -= floorf(g);
    return f0 + (f1 - f0) * g;
}

/* ---- emission ---- */

typedef struct {
    evr_ray ray;
    float flux[3];
    int from_light;   /* 1: a point, spot or directional light (never stays at the first hit) */
} evr_photon_ray;

/* Emitters of a pass: every light with power, then every instance with an emissive material. */
typedef struct {
    int kind;          /* 0: light, 1: emissive instance */
    int index;         /* light index or instance index */
    float power;       /* luminance flux (what the photons are split by) */
    uint32_t first;    /* photons [first, first + count) of the pass are this emitter's */
    uint32_t count;
    int tri_first;     /* kind 1: triangles' cumulative areas at cdf[tri_first .. tri_first + ntri) */
    int ntri;
    float area;        /* kind 1: total area (world, at the pass's time) */
} evr_photon_emitter;

/* Scene bounds for directional lights: a sphere. */
typedef struct { evr_v3 center; float radius; } evr_photon_bounds;

/* Position and direction of light l at normalized segment time f. */
EVR_HD static inline void evr_photon_light_pose(const evr_render_scene *rs, const evr_light_view *l, float f, evr_v3 *pos,
                                                evr_v3 *dir)
{
    *pos = l->pos;
    *dir = l->dir;
    if (l->track >= 0) {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, l->track), f);
        *pos = evr_m34_point(&xf, *pos);
        *dir = evr_v3_norm(evr_m34_vector(&xf, *dir));
    }
}

/* Cosine of the half angle of the cone from point p that holds the bounding sphere; -1 when p is
 * inside the sphere (every direction). */
EVR_HD static inline float evr_photon_sphere_cos(evr_v3 p, evr_photon_bounds bb)
{
    evr_v3 to = evr_v3_sub(bb.center, p);
    float d2 = evr_v3_dot(to, to), r2 = bb.radius * bb.radius;
    if (!(bb.radius > 0.0f) || d2 <= r2 * 1.0001f) return -1.0f;
    return sqrtf(fmaxf(0.0f, 1.0f - r2 / d2));
}

/* Total flux (RGB) of light l towards the scene at time f: a point light outside the scene's
 * bounding sphere 2 pi (1 - cos) I over the cone that holds the sphere (nothing outside it can
 * hit anything), else 4 pi I; spot 2 pi (1 - cos_outer) I times the mean smooth falloff
 * (approximate, for the split only: the photons carry the exact falloff); directional E pi R^2
 * over a disk of the scene's bounding radius. */
EVR_HD static inline void evr_photon_light_flux(const evr_render_scene *rs, const evr_light_view *l, float f,
                                                evr_photon_bounds bb, float out[3])
{
    float k;
    if (l->type == 2) k = EVR_PI * bb.radius * bb.radius;
    else if (l->type == 1) k = 2.0f * EVR_PI * (1.0f - l->cos_outer) * 0.5f;
    else {
        evr_v3 lp, ld;
        evr_photon_light_pose(rs, l, f, &lp, &ld);
        k = 2.0f * EVR_PI * (1.0f - evr_photon_sphere_cos(lp, bb));
    }
    out[0] = l->color[0] * k;
    out[1] = l->color[1] * k;
    out[2] = l->color[2] * k;
}

/* Photon number j (of count) of light l at normalized segment time f, from the numbers u[0..3]. */
EVR_HD static inline int evr_photon_emit_light(const evr_render_scene *rs, const evr_light_view *l, float f,
                                               evr_photon_bounds bb, const float u[4], uint32_t count,
                                               evr_photon_ray *out)
{
    evr_v3 lp, ld;
    float k;
    evr_photon_light_pose(rs, l, f, &lp, &ld);
    out->from_light = 1;
    if (l->type == 2) {   /* directional: a disk across the scene's bounding sphere, upstream */
        evr_v3 t, b;
        float r = bb.radius * sqrtf(u[0]), phi = 6.28318530718f * u[1];
        evr_onb(ld, &t, &b);
        out->ray.org = evr_v3_add(evr_v3_sub(bb.center, evr_v3_scale(ld, 1.01f * bb.radius)),
                                  evr_v3_add(evr_v3_scale(t, r * cosf(phi)), evr_v3_scale(b, r * sinf(phi))));
        out->ray.dir = ld;
        k = EVR_PI * bb.radius * bb.radius;
    } else if (l->type == 1) {   /* spot: uniform in the outer cone, weighted by the falloff */
        evr_v3 t, b;
        float cz = 1.0f - u[0] * (1.0f - l->cos_outer), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
        float phi = 6.28318530718f * u[1];
        float a = (cz - l->cos_outer) / fmaxf(l->cos_inner - l->cos_outer, 1e-4f);
        a = fminf(fmaxf(a, 0.0f), 1.0f);
        evr_onb(ld, &t, &b);
        out->ray.org = lp;
        out->ray.dir = evr_v3_norm(evr_v3_add(evr_v3_add(evr_v3_scale(t, sz * cosf(phi)), evr_v3_scale(b, sz * sinf(phi))),
                                              evr_v3_scale(ld, cz)));
        k = 2.0f * EVR_PI * (1.0f - l->cos_outer) * a * a;
    } else {   /* point: every direction, or only those towards the scene's sphere from outside it */
        float cmax = evr_photon_sphere_cos(lp, bb);
        out->ray.org = lp;
        if (cmax > -1.0f) {
            evr_v3 axis = evr_v3_norm(evr_v3_sub(bb.center, lp)), t, b;
            float cz = 1.0f - u[0] * (1.0f - cmax), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
            float phi = 6.28318530718f * u[1];
            evr_onb(axis, &t, &b);
            out->ray.dir = evr_v3_norm(evr_v3_add(evr_v3_add(evr_v3_scale(t, sz * cosf(phi)), evr_v3_scale(b, sz * sinf(phi))),
                                                  evr_v3_scale(axis, cz)));
            k = 2.0f * EVR_PI * (1.0f - cmax);
        } else {
            out->ray.dir = evr_sphere_dir(u[0], u[1]);
            k = 4.0f * EVR_PI;
        }
    }
    k /= (float)(count ? count : 1u);
    out->flux[0] = l->color[0] * k;
    out->flux[1] = l->color[1] * k;
    out->flux[2] = l->color[2] * k;
    return k > 0.0f;
}

/* Photon number j (of count) of an emissive instance: a triangle by area (u[0], which also picks
 * the side: both sides emit, as evr_surface_at's emission is two-sided), a point on it (u[1],
 * u[2]), a cosine-distributed direction (u[3], u[4]); flux = 2 pi Le * area / count.
 * cdf: the instance's cumulative world-space triangle areas (cdf[ntri - 1] == area). */
EVR_HD static inline int evr_photon_emit_surface(const evr_render_scene *rs, const evr_photon_emitter *em,
                                                 const float *cdf, const evr_m34 *xf, const float u[5],
                                                 evr_photon_ray *out)
{
    const evr_mesh_view *m = &rs->meshes[rs->instances[em->index].mesh];
    const evr_material_view *mat = &rs->materials[m->material];
    const float *c = cdf + em->tri_first;
    float side = u[0] < 0.5f ? 1.0f : -1.0f, x = (u[0] < 0.5f ? u[0] * 2.0f : u[0] * 2.0f - 1.0f) * em->area;
    int lo = 0, hi = em->ntri - 1;
    while (lo < hi) {   /* first triangle whose cumulative area exceeds x */
        int mid = (lo + hi) / 2;
        if (c[mid] > x) hi = mid;
        else lo = mid + 1;
    }
    uint32_t i0 = m->indices[3 * lo], i1 = m->indices[3 * lo + 1], i2 = m->indices[3 * lo + 2];
    evr_v3 p0 = evr_m34_point(xf, evr_v3_make(m->positions[3 * i0], m->positions[3 * i0 + 1], m->positions[3 * i0 + 2]));
    evr_v3 p1 = evr_m34_point(xf, evr_v3_make(m->positions[3 * i1], m->positions[3 * i1 + 1], m->positions[3 * i1 + 2]));
    evr_v3 p2 = evr_m34_point(xf, evr_v3_make(m->positions[3 * i2], m->positions[3 * i2 + 1], m->positions[3 * i2 + 2]));
    float su = sqrtf(u[1]), b1 = 1.0f - su, b2 = u[2] * su;
    evr_v3 e1 = evr_v3_sub(p1, p0), e2 = evr_v3_sub(p2, p0);
    evr_v3 n = evr_v3_scale(evr_v3_norm(evr_v3_cross(e1, e2)), side);
    float k = 2.0f * EVR_PI * em->area / (float)(em->count ? em->count : 1u);
    out->from_light = 0;
    out->ray.org = evr_v3_add(p0, evr_v3_add(evr_v3_scale(e1, b1), evr_v3_scale(e2, b2)));
    out->ray.dir = evr_cosine_dir(n, u[3], u[4]);
    out->flux[0] = mat->emissive[0] * k;
    out->flux[1] = mat->emissive[1] * k;
    out->flux[2] = mat->emissive[2] * k;
    return k > 0.0f;
}

/* ---- a photon's path (the loop that traces it is the backend's) ---- */

/* What a pass traces with (the CPU's and the GPU's). */
typedef struct {
    int max_bounces;               /* indirect bounces: a light photon has at most max_bounces + 1 hits */
    float f0, f1;                  /* photon j is traced at time evr_photon_time(j, f0, f1) */
    uint64_t seed;
    int threads;                   /* CPU: <= 0 all cores */
    evr_photon_bounds bounds;      /* the scene's bounding sphere (directional lights) */
    float ray_eps;                 /* secondary-ray offset (rs->ray_eps) */
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
    evr_photon_ray pr;             /* the ray to trace next and the flux it carries */
    float tnear;                   /* where the next ray starts */
    float f;                       /* normalized segment time of the photon */
    uint32_t i, j;                 /* photon number in the pass, in its emitter */
    int ei;                        /* emitter */
    int bounce, max_hits;          /* hits so far; the path ends at max_hits ("capped") */
} evr_photon_path;

/* Starts photon i of a pass over emitters e[0..n) (cdf: the emissive instances' cumulative
 * areas): its time, its first ray and flux. 0 when there is no such photon or it carries nothing. */
EVR_HD static inline int evr_photon_path_start(const evr_render_scene *rs, const evr_photon_emitter *e, int n,
                                               const float *cdf, const evr_photon_params *pp, uint32_t i,
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
        if (!evr_photon_emit_light(rs, &rs->lights[em->index], p->f, pp->bounds, u, em->count, &p->pr)) return 0;
    } else {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[em->index].track), p->f);
        if (!evr_photon_emit_surface(rs, em, cdf, &xf, u, &p->pr)) return 0;
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
EVR_HD static inline int evr_photon_path_hit(evr_photon_path *p, const evr_photon_params *pp, const evr_surface *s,
                                             const evr_material_view *mat, float stored[3], float absorbed[3],
                                             uint32_t *key)
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
    if (first_light)   /* the direct term's light: the part the surface absorbs */
        for (c = 0; c < 3; c++) absorbed[c] = p->pr.flux[c] * (1.0f - s->albedo[c]);
    if (ev == EVR_PHOTON_ABSORB) return ev;
    for (c = 0; c < 3; c++) p->pr.flux[c] *= s->albedo[c] * w;
    if (ev == EVR_PHOTON_DIFFUSE)
        p->pr.ray.dir = evr_cosine_dir(s->n, evr_photon_rand(pp->seed, p->ei, p->j, 6 + 3 * p->bounce),
                                       evr_photon_rand(pp->seed, p->ei, p->j, 7 + 3 * p->bounce));
    else
        p->pr.ray.dir = evr_v3_norm(evr_mirror_dir(p->pr.ray.dir, s->n));
    p->pr.ray.org = s->p;
    p->tnear = evr_shadow_tnear(s, p->pr.ray.dir, pp->ray_eps);
    p->bounce++;
    return ev;
}

/* ---- the image-space buffer ---- */

typedef struct {
    float p[3], n[3];     /* world position, normal on the side the photon came from */
    float flux[3];        /* incident flux the photon stands for (RGB) */
    uint32_t key;         /* photon number * 16 + bounce: a canonical order */
} evr_photon;

/* The image plus a guard band of `margin` pixels on every side (so that pixels near the image's
 * border have photons all round them): width x height cells, width = image width + 2 margin,
 * of `layers` photons each. Image pixel (x, y), -margin <= x < image width + margin, is cell
 * i = (y + margin) * width + x + margin; layer k of cell i is slots[k * width * height + i];
 * count[i] is how many photons arrived at cell i (those beyond `layers` were dropped and counted
 * in *collisions). Host or device pointers; the owner zeroes count and *collisions. */
typedef struct {
    int width, height, layers, margin;
    evr_photon *slots;
    uint32_t *count;
    uint32_t *collisions;
    /* Optional (NULL: none): what the camera sees through each cell's centre, 8 floats per cell:
     * position (3), normal facing the camera (3), the surface area the cell covers there, 0; a
     * cell that sees nothing has area 0. evr_photon_gather then normalizes its kernel over the
     * part of the disk that lies on surfaces like the query's, not the whole disk (no darkening
     * at creases and silhouettes). */
    float *gbuf;
} evr_photon_buffer;

/* Image pixel of world point p for the camera (world_to_cam = inverse pose), which may lie up
 * to margin pixels outside the image; 0 when behind the camera or farther out. */
EVR_HD static inline int evr_photon_pixel(const evr_camera_intr *c, const evr_m34 *world_to_cam, evr_v3 p, int margin,
                                          int *x, int *y)
{
    float px = -1e9f, py = -1e9f, m = (float)margin;
    if (!evr_camera_project(c, world_to_cam, p, &px, &py)) return 0;
    if (!(px >= -m && py >= -m && px < (float)c->width + m && py < (float)c->height + m)) return 0;
    *x = (int)floorf(px);
    *y = (int)floorf(py);
    if (*x >= c->width + margin) *x = c->width + margin - 1;
    if (*y >= c->height + margin) *y = c->height + margin - 1;
    return 1;
}

/* A photon that stays at s at time f is kept where the camera sees it: the cell (x, y) it
 * lands in, and the ray r from s towards the camera that must be free over [*tnear, *tfar).
 * 0 when the camera is behind the surface or the point projects outside the image and its band. */
EVR_HD static inline int evr_photon_view_ray(const evr_render_scene *rs, const evr_surface *s, float f, int margin,
                                             float eps, int *x, int *y, evr_ray *r, float *tnear, float *tfar)
{
    evr_m34 pose = evr_rs_camera_pose(rs, f), inv = evr_m34_inverse(&pose);
    evr_v3 cam = evr_v3_make(pose.m[0][3], pose.m[1][3], pose.m[2][3]);
    evr_v3 d = evr_v3_sub(cam, s->p);
    float dist = evr_v3_len(d);
    if (!(dist > 0.0f) || evr_v3_dot(d, s->n) <= 0.0f) return 0;
    if (!evr_photon_pixel(&rs->camera, &inv, s->p, margin, x, y)) return 0;
    r->org = s->p;
    r->dir = evr_v3_scale(d, 1.0f / dist);
    *tnear = evr_shadow_tnear(s, r->dir, eps);
    *tfar = dist * (1.0f - 1e-4f);
    return 1;
}

/* The buffer's record of a photon stored at s. */
EVR_HD static inline evr_photon evr_photon_make(const evr_surface *s, const float flux[3], uint32_t key)
{
    evr_photon ph;
    ph.p[0] = s->p.x; ph.p[1] = s->p.y; ph.p[2] = s->p.z;
    ph.n[0] = s->n.x; ph.n[1] = s->n.y; ph.n[2] = s->n.z;
    ph.flux[0] = flux[0]; ph.flux[1] = flux[1]; ph.flux[2] = flux[2];
    ph.key = key;
    return ph;
}

/* ---- a photon's trail: its path kept for the next pass ----
 *
 * A pass that traces photon i records the rays its path traced (origin, direction, length: the
 * hit's distance, 1e30 for a ray that met nothing, the whole ray for the camera's occlusion test)
 * and what it stored: the photon and its cell, or nothing. The trail is clean when none of those
 * rays met the swept bounds of what moves in that segment (the change-driven sampling plan,
 * core/skip.h): the path met static triangles only. A later pass, with the camera, the lights and
 * the emitters unchanged (the plan's reuse and the same emitter table), takes a clean trail's
 * outcome instead of tracing it again when its rays meet none of its own segment's moving
 * bounds: the same rays would meet the same static triangles, and the outcome would be the same
 * bit for bit. As with pixels, a photon a moving object touches is traced again. */
#define EVR_TRAIL_NONE 0xffffffffu

typedef struct {
    evr_photon ph;         /* what the path stored */
    uint32_t cell;         /* its buffer cell; EVR_TRAIL_NONE: nothing stored (or no trail yet) */
    uint16_t n;            /* rays recorded */
    uint8_t clean, started;   /* clean: see above; started: the path had a start (evr_photon_path_start) */
} evr_photon_trail;

typedef struct {
    float org[3], dir[3], tmax;
} evr_trail_ray;

/* Rays a trail holds at most: one per hit (max_bounces + 1 for a light's photon) and the
 * camera's occlusion test. */
EVR_HD static inline int evr_photon_trail_len(const evr_photon_params *pp)
{
    return pp->max_bounces + 2;
}

/* A trail for a pass of plan pl: clean only if the plan may cache (camera and lights still). */
EVR_HD static inline void evr_photon_trail_begin(evr_photon_trail *t, const evr_skip_plan *pl)
{
    t->cell = EVR_TRAIL_NONE;
    t->n = 0;
    t->clean = (uint8_t)(pl != NULL && pl->cache);
    t->started = 0;
}

/* Records a ray of the path (len: the trail's capacity; a ray beyond it leaves the trail unclean). */
EVR_HD static inline void evr_photon_trail_ray(evr_photon_trail *t, evr_trail_ray *rays, int len, const evr_skip_plan *pl,
                                               evr_ray r, float tmax)
{
    if (!t->clean) return;   /* never reused: nothing more to keep */
    if (t->n >= len || evr_skip_ray_meets_any(pl, r.org, r.dir, tmax)) {
        t->clean = 0;
        return;
    }
    evr_trail_ray *k = &rays[t->n++];
    k->org[0] = r.org.x; k->org[1] = r.org.y; k->org[2] = r.org.z;
    k->dir[0] = r.dir.x; k->dir[1] = r.dir.y; k->dir[2] = r.dir.z;
    k->tmax = tmax;
}

/* Whether a pass of plan pl may take the trail's outcome: clean, and none of its rays meets
 * what moves in the segment. The caller checks that the camera, lights and emitters are those
 * of the pass that recorded it. */
EVR_HD static inline int evr_photon_trail_reusable(const evr_photon_trail *t, const evr_trail_ray *rays, const evr_skip_plan *pl)
{
    int k;
    if (!t->clean || !pl->reuse) return 0;
    for (k = 0; k < (int)t->n; k++) {
        const evr_trail_ray *r = &rays[k];
        if (evr_skip_ray_meets_any(pl, evr_v3_make(r->org[0], r->org[1], r->org[2]), evr_v3_make(r->dir[0], r->dir[1], r->dir[2]),
                                   r->tmax))
            return 0;
    }
    return 1;
}

/* The camera's ray (pose) through the centre of buffer cell (cx, cy), guard band included. */
EVR_HD static inline evr_ray evr_photon_cell_ray(const evr_render_scene *rs, const evr_m34 *pose, const evr_photon_buffer *b,
                                                 int cx, int cy)
{
    return evr_camera_ray(&rs->camera, pose, (float)(cx - b->margin) + 0.5f, (float)(cy - b->margin) + 0.5f);
}

/* A cell's view (gbuf, 8 floats) from the surface s met at distance t along its ray; fwd: the
 * camera's forward axis. The area is the pixel's at unit distance * depth^2 * cos(off-axis
 * angle) / |cos of the incidence| (the cosine at least 0.1). */
EVR_HD static inline void evr_photon_cell_view(const evr_render_scene *rs, evr_v3 fwd, const evr_surface *s, evr_ray ray,
                                               float t, float g[8])
{
    const float a = 4.0f * rs->camera.tan_half_y * rs->camera.tan_half_y / ((float)rs->camera.height * (float)rs->camera.height);
    float ca = evr_v3_dot(ray.dir, fwd), z = t * ca;
    float ct = fmaxf(fabsf(evr_v3_dot(s->n, ray.dir)), 0.1f);
    g[0] = s->p.x; g[1] = s->p.y; g[2] = s->p.z;
    g[3] = s->n.x; g[4] = s->n.y; g[5] = s->n.z;
    g[6] = a * z * z * ca / ct;
    g[7] = 0.0f;
}

/* Whether cell i holds the same photons and the same view in buffers a and b (bit for bit). */
EVR_HD static inline int evr_photon_cell_same(const evr_photon_buffer *a, const evr_photon_buffer *b, size_t i)
{
    size_t npix = (size_t)a->width * (size_t)a->height;
    uint32_t n = a->count[i] < (uint32_t)a->layers ? a->count[i] : (uint32_t)a->layers, l;
    int k;
    if (a->count[i] != b->count[i]) return 0;
    for (l = 0; l < n; l++) {
        const uint32_t *pa = (const uint32_t *)&a->slots[(size_t)l * npix + i], *pb = (const uint32_t *)&b->slots[(size_t)l * npix + i];
        for (k = 0; k < (int)(sizeof(evr_photon) / 4); k++)
            if (pa[k] != pb[k]) return 0;
    }
    if (a->gbuf && b->gbuf) {
        const uint32_t *ga = (const uint32_t *)(a->gbuf + 8 * i), *gb = (const uint32_t *)(b->gbuf + 8 * i);
        for (k = 0; k < 8; k++)
            if (ga[k] != gb[k]) return 0;
    }
    return 1;
}

/* Whether any cell the gather of image pixel (x, y) may read (window cells around it) changed:
 * sat is the summed-area table, (w + 1) x (h + 1), of the changed cells of a w x h buffer with
 * the given guard band. */
/* The changed cells in columns x0 .. x1 - 1 of rows y0 .. y1 - 1 of a w-wide buffer, from its
 * summed-area table (w + 1 entries a row, row 0 and column 0 zero). */
EVR_HD static inline uint32_t evr_sat_count(const uint32_t *sat, int w, int x0, int y0, int x1, int y1)
{
    const size_t W = (size_t)w + 1;
    return sat[(size_t)y1 * W + (size_t)x1] - sat[(size_t)y0 * W + (size_t)x1] - sat[(size_t)y1 * W + (size_t)x0] +
           sat[(size_t)y0 * W + (size_t)x0];
}

EVR_HD static inline int evr_photon_window_changed(const uint32_t *sat, int w, int h, int margin, int window, int x, int y)
{
    int x0 = x + margin - window, x1 = x + margin + window + 1, y0 = y + margin - window, y1 = y + margin + window + 1;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > w) x1 = w;
    if (y1 > h) y1 = h;
    if (x0 >= x1 || y0 >= y1) return 0;
    return evr_sat_count(sat, w, x0, y0, x1, y1) != 0;
}

/* Lock-free insertion: an atomic increment claims a layer; a photon arriving at a full cell is
 * dropped and counted as a collision. Returns 1 when stored. Threads inserting concurrently
 * store the same set of photons whenever no cell overflows (the order of a cell's layers may
 * differ: evr_photon_buffer_sort_cell restores the canonical order). */
EVR_HD static inline int evr_photon_buffer_insert(evr_photon_buffer *b, int x, int y, const evr_photon *ph)
{
    size_t i = (size_t)(y + b->margin) * (size_t)b->width + (size_t)(x + b->margin);
    uint32_t k = EVR_ATOMIC_INC_U32(&b->count[i]);
    if (k >= (uint32_t)b->layers) {
        EVR_ATOMIC_INC_U32(b->collisions);
        return 0;
    }
    b->slots[(size_t)k * (size_t)b->width * (size_t)b->height + i] = *ph;
    return 1;
}

/* Sorts one cell's layers by key (insertion sort over a handful). */
EVR_HD static inline void evr_photon_buffer_sort_cell(evr_photon_buffer *b, size_t i)
{
    size_t npix = (size_t)b->width * (size_t)b->height;
    int n = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers, a, c;
    for (a = 1; a < n; a++) {
        evr_photon v = b->slots[(size_t)a * npix + i];
        for (c = a; c > 0 && b->slots[(size_t)(c - 1) * npix + i].key > v.key; c--)
            b->slots[(size_t)c * npix + i] = b->slots[(size_t)(c - 1) * npix + i];
        b->slots[(size_t)c * npix + i] = v;
    }
}

/* ---- gather ---- */

/* Cell k of the ring search: ring 0 is the centre (k = 0), ring r (r >= 1) the 8r cells at
 * Chebyshev distance r, k = (2r-1)^2 .. (2r+1)^2 - 1, starting at (-r, -r) and going round
 * clockwise in image coordinates (right along the top row, down the right column, left along
 * the bottom row, up the left column). Returns the ring. */
EVR_HD static inline int evr_ring_cell(int k, int *dx, int *dy)
{
    if (k <= 0) { *dx = 0; *dy = 0; return 0; }
    int r = (int)((sqrtf((float)k) + 1.0f) * 0.5f);
    while ((2 * r + 1) * (2 * r + 1) <= k) r++;   /* exact whatever sqrtf rounds to */
    while (r > 1 && (2 * r - 1) * (2 * r - 1) > k) r--;
    int j = k - (2 * r - 1) * (2 * r - 1), side = j / (2 * r), o = j % (2 * r);
    switch (side) {
    case 0: *dx = -r + o; *dy = -r; break;
    case 1: *dx = r; *dy = -r + o; break;
    case 2: *dx = r - o; *dy = r; break;
    default: *dx = -r; *dy = r - o; break;
    }
    return r;
}

/* Gaussian kernel truncated at radius r, sigma = r / 2, normalized so that its integral over the
 * disk of radius r is 1: K(d) = exp(-d^2 / (2 sigma^2)) / (2 pi sigma^2 (1 - exp(-r^2 / (2 sigma^2)))). */
EVR_HD static inline float evr_gauss_kernel(float d2, float r)
{
    float s2 = 0.25f * r * r;
    if (!(d2 <= r * r) || !(r > 0.0f)) return 0.0f;
    return expf(-d2 / (2.0f * s2)) / (2.0f * EVR_PI * s2 * (1.0f - expf(-(r * r) / (2.0f * s2))));
}

typedef struct {
    float radius;       /* distance filter r (world units): photons farther away are skipped */
    int max_photons;    /* the search stops growing at this many photons (see evr_photon_gather);
                         * 0: no limit, every photon of the disk (the fixed-point sum below) */
    int max_window;     /* the window's half size in pixels is at most this */
    float normal_cos;   /* photons whose normal differs more (cosine below) are skipped */
    float flux_scale;   /* max_photons 0: fixed-point quanta per unit of flux (evr_gather_flux_scale) */
} evr_gather_params;

/* One cell's share of a gather: the photons of buffer cell (x, y) (anywhere: a cell outside the
 * buffer has none) within sqrt(lim2) of p whose normal is within normal_cos of n add their
 * Gaussian-weighted flux to acc (in layer order); with the camera's view of the cells, the
 * kernel's weight over the surface the cell shows (if it is like the query's) adds to *area_w.
 * Returns the photons taken. */
EVR_HD static inline int evr_photon_gather_cell(const evr_photon_buffer *b, int x, int y, evr_v3 p, evr_v3 n, float lim2,
                                                float normal_cos, float s2, float acc[3], float *area_w)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    int l, nl, used = 0;
    if (x < 0 || y < 0 || x >= b->width || y >= b->height) return 0;
    size_t i = (size_t)y * (size_t)b->width + (size_t)x;
    if (b->gbuf) {   /* the kernel's integral over the surfaces the camera sees here */
        const float *g = b->gbuf + 8 * i;
        evr_v3 d = evr_v3_make(g[0] - p.x, g[1] - p.y, g[2] - p.z);
        float d2 = evr_v3_dot(d, d);
        if (g[6] > 0.0f && d2 <= lim2 && g[3] * n.x + g[4] * n.y + g[5] * n.z >= normal_cos)
            *area_w += expf(-d2 / (2.0f * s2)) * g[6];
    }
    nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        evr_v3 d = evr_v3_make(ph->p[0] - p.x, ph->p[1] - p.y, ph->p[2] - p.z);
        float d2 = evr_v3_dot(d, d);
        if (d2 > lim2) continue;
        if (ph->n[0] * n.x + ph->n[1] * n.y + ph->n[2] * n.z < normal_cos) continue;
        float w = expf(-d2 / (2.0f * s2));
        acc[0] += w * ph->flux[0];
        acc[1] += w * ph->flux[1];
        acc[2] += w * ph->flux[2];
        used++;
    }
    return used;
}

/* The window of a gather at a hit seen at distance cam_dist through image pixel (px, py): its
 * centre cell, its half size h in cells (ceil(r / pixel size at the hit) + 1, at most
 * max_window: nearer points project farther out), the pixel size at the hit, r, r^2, sigma^2. */
typedef struct {
    int cx, cy, h;
    float pix, r, r2, s2;
} evr_gather_window;

EVR_HD static inline evr_gather_window evr_photon_gather_window(const evr_photon_buffer *b, const evr_camera_intr *cam, int px,
                                                                int py, float cam_dist, const evr_gather_params *gp)
{
    evr_gather_window w;
    const float r = gp->radius;
    w.r = r;
    w.r2 = r * r;
    w.s2 = 0.25f * w.r2;
    w.pix = 2.0f * cam->tan_half_y * fmaxf(cam_dist, 1e-6f) / (float)cam->height;
    float hf = ceilf(r / w.pix) + 1.0f;
    w.h = hf > (float)gp->max_window ? gp->max_window : (int)hf;
    w.cx = px + b->margin;
    w.cy = py + b->margin;
    return w;
}

/* After the search stopped at ring stop (max photons reached): the disk the rings searched surely
 * cover (radius stop pixel sizes, at least half a pixel, at most r), returned as its radius^2,
 * and the rings that hold all of it (*rings: p lies anywhere in its pixel, one ring further). */
EVR_HD static inline float evr_photon_gather_shrink(const evr_gather_window *w, int stop, int *rings)
{
    float rho = fminf(w->r, fmaxf((float)stop, 0.5f) * w->pix);
    *rings = stop + 1 < w->h ? stop + 1 : w->h;
    return rho * rho;
}

/* The irradiance from the sums over the disk of radius^2 lim2: the Gaussian's integral over the
 * disk, scaled by the share of the disk on surfaces like the query's where the disk spans enough
 * cells to measure it (the camera's view of the cells). */
EVR_HD static inline void evr_photon_gather_finish(const evr_photon_buffer *b, const evr_gather_window *w, float lim2,
                                                   const float acc[3], float area_w, float e_rgb[3])
{
    float z = 2.0f * EVR_PI * w->s2 * (1.0f - expf(-lim2 / (2.0f * w->s2)));
    if (b->gbuf && lim2 >= 9.0f * w->pix * w->pix) z *= fminf(fmaxf(area_w / z, 0.25f), 1.25f);
    float inv = z > 0.0f ? 1.0f / z : 0.0f;
    e_rgb[0] = acc[0] * inv;
    e_rgb[1] = acc[1] * inv;
    e_rgb[2] = acc[2] * inv;
}

/* ---- the event pipeline's estimate without a limit, in fixed point (max_photons 0) ----
 *
 * Every photon of the window within r whose normal is within the cosine adds its Gaussian-
 * weighted flux, every view of a cell its weighted area, as the limited search does; but each
 * term is rounded to an integer (evr_fix) and the terms are summed modulo 2^64. Such a sum does
 * not depend on the order of its terms, and a term depends only on the cell and the gather
 * point. So the sum over a segment's end buffer is the sum over its start buffer plus the terms
 * of the cells that changed minus their old terms, bit for bit (evr_photon_gather_delta): a
 * pixel whose surface point stays updates its indirect light from the cells the moving objects
 * changed instead of walking its whole window again, and gets exactly what a fresh gather gets
 * (brute force and change-driven sampling stay identical). The flux is summed as the luminance
 * of the light the point sends back (its weights c = the luminance's coefficients times the
 * point's diffuse share k, per RGB channel): one sum, what the pixel model takes. Dot products
 * and distances are written with products no compiler fuses with the sums (evr_dot_rn), so that
 * the terms are the same bits wherever they are computed (and on the CPU and GPU alike). */
typedef struct {
    uint64_t a;      /* weighted luminance flux, in units of 1 / flux_scale */
    uint64_t w;      /* the view's weighted area, in units of sigma^2 / 2^32 */
} evr_gather_sum;

/* Fixed-point quanta per unit of flux for a pass of `photons` photons carrying total_power
 * (luminance flux): 2^40 quanta for the mean photon, whose flux is total_power / photons (the
 * photons are split by power), so a window of thousands of photons a few hundred times brighter
 * than the mean stays far below 2^64, and a photon 10^-6 of the mean still counts. The scale is
 * the run's, from its first pass: a term is clamped at 2^52 quanta (evr_fix), so a photon over
 * about 4000 times that pass's mean photon (lights that brighten that much later) would count
 * for less than it carries. */
EVR_HD static inline float evr_gather_flux_scale(float total_power, uint32_t photons)
{
    float mean = photons > 0u ? total_power / (float)photons : 0.0f;
    return mean > 0.0f && mean < 1e30f ? 1099511627776.0f / mean : 1.0f;
}

/* A term in fixed point: rounded to the nearest integer, at most 2^52 (a window of 4096 such
 * terms still fits), 0 for anything not positive (or NaN). Through int64_t: one instruction on
 * x86-64, where a float to uint64_t conversion is a branch and two. */
EVR_HD static inline uint64_t evr_fix(float v)
{
    return v > 0.0f ? (uint64_t)(int64_t)((v < 4503599627370496.0f ? v : 4503599627370496.0f) + 0.5f) : 0u;
}

/* a.b, rounded the same by every compiler: three products, two additions, left to right */
EVR_HD static inline float evr_dot_rn(float ax, float ay, float az, float bx, float by, float bz)
{
    return EVR_MUL_RN(ax, bx) + EVR_MUL_RN(ay, by) + EVR_MUL_RN(az, bz);
}

/* A gather's query: the point, its normal, the luminance weights of the flux (c), the distance
 * filter r^2, the normal cosine, the flux scale and the kernel's constants. */
typedef struct {
    evr_v3 p, n, c;
    float r2, normal_cos, flux_scale;
    float e, area_scale;   /* -1 / (2 sigma^2), 2^32 / sigma^2 */
} evr_sum_query;

/* Adds cell i's terms for query q to s (sub: subtracts them). Returns the photons taken. */
EVR_HD static inline int evr_photon_cell_sum(const evr_photon_buffer *b, size_t i, const evr_sum_query *q, evr_gather_sum *s,
                                             int sub)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    const float e = q->e, area_scale = q->area_scale;
    const evr_v3 p = q->p, n = q->n;
    uint64_t a = 0, aw = 0;
    int l, nl, used = 0;
    if (b->gbuf) {
        const float *g = b->gbuf + 8 * i;
        float dx = g[0] - p.x, dy = g[1] - p.y, dz = g[2] - p.z;
        float d2 = evr_dot_rn(dx, dy, dz, dx, dy, dz), c = evr_dot_rn(g[3], g[4], g[5], n.x, n.y, n.z);
        if (g[6] > 0.0f && d2 <= q->r2 && c >= q->normal_cos)
            aw = evr_fix(EVR_MUL_RN(EVR_MUL_RN(expf(EVR_MUL_RN(d2, e)), g[6]), area_scale));
    }
    nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        float dx = ph->p[0] - p.x, dy = ph->p[1] - p.y, dz = ph->p[2] - p.z;
        float d2 = evr_dot_rn(dx, dy, dz, dx, dy, dz), c = evr_dot_rn(ph->n[0], ph->n[1], ph->n[2], n.x, n.y, n.z);
        if (d2 > q->r2 || c < q->normal_cos) continue;
        const float lum = evr_dot_rn(ph->flux[0], ph->flux[1], ph->flux[2], q->c.x, q->c.y, q->c.z);
        a += evr_fix(EVR_MUL_RN(EVR_MUL_RN(expf(EVR_MUL_RN(d2, e)), q->flux_scale), lum));
        used++;
    }
    if (sub) {
        s->a -= a;
        s->w -= aw;
    } else {
        s->a += a;
        s->w += aw;
    }
    return used;
}

/* The cells of window w inside buffer b: columns x0 .. x1 - 1 of rows y0 .. y1 - 1. */
EVR_HD static inline void evr_gather_window_cells(const evr_photon_buffer *b, const evr_gather_window *w, int *x0, int *y0,
                                                  int *x1, int *y1)
{
    *x0 = w->cx - w->h > 0 ? w->cx - w->h : 0;
    *y0 = w->cy - w->h > 0 ? w->cy - w->h : 0;
    *x1 = w->cx + w->h + 1 < b->width ? w->cx + w->h + 1 : b->width;
    *y1 = w->cy + w->h + 1 < b->height ? w->cy + w->h + 1 : b->height;
}

/* The fixed-point sums of query q over window w of b. Returns the photons taken. */
EVR_HD static inline int evr_photon_gather_sum(const evr_photon_buffer *b, const evr_gather_window *w, const evr_sum_query *q,
                                               evr_gather_sum *s)
{
    int x0, y0, x1, y1, x, y, used = 0;
    evr_gather_sum acc = {0, 0};   /* a local: kept in registers, not stored back cell by cell */
    evr_gather_window_cells(b, w, &x0, &y0, &x1, &y1);
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++) used += evr_photon_cell_sum(b, (size_t)y * (size_t)b->width + (size_t)x, q, &acc, 0);
    *s = acc;
    return used;
}

/* The luminance from the sums, normalized as evr_photon_gather_finish normalizes its float sums. */
EVR_HD static inline float evr_photon_gather_sum_finish(const evr_photon_buffer *b, const evr_gather_window *w,
                                                        const evr_gather_params *gp, const evr_gather_sum *s)
{
    const float acc[3] = {(float)s->a / gp->flux_scale, 0.0f, 0.0f};
    float e[3];
    evr_photon_gather_finish(b, w, w->r2, acc, (float)s->w * (w->s2 / 4294967296.0f), e);
    return e[0];
}

/* The cells that changed between two buffers, listed row by row: row y's changed cells are
 * entries base[y] .. base[y + 1] - 1 of x (their columns, ascending), and those of them in
 * columns x0 .. x1 - 1 are entries base[y] + before[y (w + 1) + x0] .. base[y] + before[y (w + 1)
 * + x1] - 1, where before[y (w + 1) + x] counts row y's changed cells left of column x (w: the
 * buffer's width). Built per segment by the backends (evr_changed_cells_from_sat on the CPU). */
typedef struct {
    const uint32_t *before;   /* (w + 1) per row */
    const uint32_t *base;     /* h + 1 */
    const uint32_t *x;
} evr_changed_cells;

/* The sums of a gather at p (normal n) over buffer cur, from its sums s over buffer prev (the
 * same point, the same window): the terms of every changed cell of the window (ch: the cells
 * that differ from prev to cur, or more: a listed cell that did not change adds nothing), those
 * of cur added and those of prev taken away. Bit for bit the sums of a fresh gather over cur. */
EVR_HD static inline void evr_photon_gather_delta(const evr_photon_buffer *cur, const evr_photon_buffer *prev,
                                                  const evr_changed_cells *ch, const evr_gather_window *w, const evr_sum_query *q,
                                                  evr_gather_sum *s)
{
    const size_t W = (size_t)cur->width + 1;
    int x0, y0, x1, y1, y;
    evr_gather_sum acc = *s;
    evr_gather_window_cells(cur, w, &x0, &y0, &x1, &y1);
    for (y = y0; y < y1; y++) {
        const uint32_t *row = ch->before + (size_t)y * W, b = ch->base[y], k1 = b + row[x1];
        uint32_t k;
        for (k = b + row[x0]; k < k1; k++) {
            const size_t i = (size_t)y * (size_t)cur->width + (size_t)ch->x[k];
            evr_photon_cell_sum(cur, i, q, &acc, 0);
            evr_photon_cell_sum(prev, i, q, &acc, 1);
        }
    }
    *s = acc;
}

/* Sums the photons of rings 0 .. rings of the window around cell (cx, cy) that lie within
 * sqrt(lim2) of p with a normal within the cosine; stops in the cell where max photons are
 * reached (returns the ring where it stopped in *stop_ring, or -1 when it did not stop). */
EVR_HD static inline int evr_photon_gather_rings(const evr_photon_buffer *b, int cx, int cy, int rings, evr_v3 p,
                                                 evr_v3 n, float lim2, float normal_cos, float s2, int max,
                                                 float acc[3], int *stop_ring, float *area_w)
{
    int r, side, o, used = 0;
    acc[0] = acc[1] = acc[2] = 0.0f;
    *stop_ring = -1;
    *area_w = 0.0f;
    /* the cells in evr_ring_cell's order, walked directly (no square root and division per cell) */
    used += evr_photon_gather_cell(b, cx, cy, p, n, lim2, normal_cos, s2, acc, area_w);
    if (used >= max) {
        *stop_ring = 0;
        return used;
    }
    for (r = 1; r <= rings; r++) {
        for (side = 0; side < 4; side++) {
            for (o = 0; o < 2 * r; o++) {
                int dx = side == 0 ? -r + o : side == 1 ? r : side == 2 ? r - o : -r;
                int dy = side == 0 ? -r : side == 1 ? -r + o : side == 2 ? r : r - o;
                used += evr_photon_gather_cell(b, cx + dx, cy + dy, p, n, lim2, normal_cos, s2, acc, area_w);
                if (used >= max) {
                    *stop_ring = r;
                    return used;
                }
            }
        }
    }
    return used;
}

/* Irradiance at surface point p (normal n, seen at distance cam_dist from the camera through
 * image pixel (px, py)) from the buffer. The window (evr_photon_gather_window) is searched ring
 * by ring from the centre; photons farther than r or whose normal differs more than normal_cos
 * are skipped; weights are the Gaussian kernel (sigma = r / 2) normalized over the disk searched.
 * When max_photons is reached in ring k, the disk shrinks to the one that rings 0 .. k surely
 * cover (evr_photon_gather_shrink) and the estimate is every photon in that disk: on a surface
 * seen at a grazing angle the window reaches far along the surface but not across, and the
 * farthest photon taken would overstate the disk. Returns the photons used. */
EVR_HD static inline int evr_photon_gather(const evr_photon_buffer *b, const evr_camera_intr *cam, int px, int py,
                                           evr_v3 p, evr_v3 n, float cam_dist, const evr_gather_params *gp,
                                           float e_rgb[3])
{
    const evr_gather_window w = evr_photon_gather_window(b, cam, px, py, cam_dist, gp);
    float acc[3], lim2 = w.r2, area_w;
    int stop, used;
    const int max = gp->max_photons > 0 ? gp->max_photons : 0x7fffffff;   /* 0: no limit */
    used = evr_photon_gather_rings(b, w.cx, w.cy, w.h, p, n, lim2, gp->normal_cos, w.s2, max, acc, &stop, &area_w);
    if (stop >= 0) {   /* the limit: the disk the rings searched cover, all of its photons */
        int rings;
        lim2 = evr_photon_gather_shrink(&w, stop, &rings);
        used = evr_photon_gather_rings(b, w.cx, w.cy, rings, p, n, lim2, gp->normal_cos, w.s2, 0x7fffffff, acc, &stop, &area_w);
    }
    evr_photon_gather_finish(b, &w, lim2, acc, area_w, e_rgb);
    return used;
}

/* Whether buffer cell i (of b, or of a buffer of its shape) holds anything a gather at point p
 * (normal n) could take within sqrt(lim2): a photon close enough with a normal within the
 * cosine, or the camera's view of the cell (its weight in the normalization), tested as
 * evr_photon_gather_cell tests them. */
EVR_HD static inline int evr_photon_cell_reaches(const evr_photon_buffer *b, size_t i, evr_v3 p, evr_v3 n, float lim2,
                                                 float normal_cos)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    int l, nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    /* either way of computing the distance and the cosine: evr_photon_gather_cell's (the limited
     * search) or evr_photon_cell_sum's (evr_dot_rn), which may differ in the last bit */
    if (b->gbuf) {
        const float *g = b->gbuf + 8 * i;
        evr_v3 d = evr_v3_make(g[0] - p.x, g[1] - p.y, g[2] - p.z);
        if (g[6] > 0.0f && ((evr_v3_dot(d, d) <= lim2 && g[3] * n.x + g[4] * n.y + g[5] * n.z >= normal_cos) ||
                            (evr_dot_rn(d.x, d.y, d.z, d.x, d.y, d.z) <= lim2 && evr_dot_rn(g[3], g[4], g[5], n.x, n.y, n.z) >= normal_cos)))
            return 1;
    }
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        evr_v3 d = evr_v3_make(ph->p[0] - p.x, ph->p[1] - p.y, ph->p[2] - p.z);
        if (evr_v3_dot(d, d) <= lim2 && ph->n[0] * n.x + ph->n[1] * n.y + ph->n[2] * n.z >= normal_cos) return 1;
        if (evr_dot_rn(d.x, d.y, d.z, d.x, d.y, d.z) <= lim2 && evr_dot_rn(ph->n[0], ph->n[1], ph->n[2], n.x, n.y, n.z) >= normal_cos)
            return 1;
    }
    return 0;
}

/* Whether the change from buffer prev to cur can move the gather at point p (normal n, seen at
 * distance cam_dist through image pixel (px, py)); sat: the summed-area table of the cells that
 * changed. It cannot when no changed cell of the gather's window holds, before or after, anything
 * the gather could take at its full radius r (evr_photon_cell_reaches): every cell it reads
 * then adds the same, the search stops in the same ring, and the estimate is the same bit for
 * bit. (Photons the moving box sends elsewhere change cells all over the image; most windows
 * see such a change and few are reached by it.) */
EVR_HD static inline int evr_photon_gather_moved(const evr_photon_buffer *cur, const evr_photon_buffer *prev, const uint32_t *sat,
                                                 const evr_camera_intr *cam, const evr_gather_params *gp, int px, int py,
                                                 evr_v3 p, evr_v3 n, float cam_dist)
{
    const evr_gather_window w = evr_photon_gather_window(cur, cam, px, py, cam_dist, gp);
    int x0 = w.cx - w.h, x1 = w.cx + w.h + 1, y0 = w.cy - w.h, y1 = w.cy + w.h + 1, x, y;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > cur->width) x1 = cur->width;
    if (y1 > cur->height) y1 = cur->height;
    for (y = y0; y < y1; y++) {
        /* the row's changed cells, from the table: none, and the row is passed over */
        if (evr_sat_count(sat, cur->width, x0, y, x1, y + 1) == 0) continue;
        for (x = x0; x < x1; x++) {
            if (evr_sat_count(sat, cur->width, x, y, x + 1, y + 1) == 0) continue;
            const size_t i = (size_t)y * (size_t)cur->width + (size_t)x;
            if (evr_photon_cell_reaches(cur, i, p, n, w.r2, gp->normal_cos) || evr_photon_cell_reaches(prev, i, p, n, w.r2, gp->normal_cos))
                return 1;
        }
    }
    return 0;
}

/* What multiplies the irradiance (RGB) for the indirect radiance leaving surface s of material
 * mat: the diffuse share of the albedo over pi. */
EVR_HD static inline void evr_photon_indirect_k(const evr_surface *s, const evr_material_view *mat, float k_rgb[3])
{
    float k = evr_material_diffuse_k(mat);
    k_rgb[0] = s->albedo[0] * k;
    k_rgb[1] = s->albedo[1] * k;
    k_rgb[2] = s->albedo[2] * k;
}

/* Indirect radiance leaving surface s (material mat) from an irradiance estimate: the diffuse
 * share of the albedo over pi, per RGB channel (add its luminance to evr_surface_intensity). */
EVR_HD static inline void evr_photon_indirect(const evr_surface *s, const evr_material_view *mat, const float e_rgb[3],
                                              float out_rgb[3])
{
    float k[3];
    evr_photon_indirect_k(s, mat, k);
    out_rgb[0] = k[0] * e_rgb[0];
    out_rgb[1] = k[1] * e_rgb[1];
    out_rgb[2] = k[2] * e_rgb[2];
}

/* What a gather needs of a surface point: position, normal, distance from the camera and the
 * diffuse share of the albedo over pi (evr_photon_indirect_k). Made where the ray meets the
 * surface; the gather itself may run later (the GPU defers it to a kernel of its own). */
typedef struct evr_gather_point {
    evr_v3 p, n;
    float dist;
    float k[3];
} evr_gather_point;

EVR_HD static inline void evr_gather_point_at(const evr_surface *s, const evr_material_view *mat, evr_v3 cam_org,
                                              evr_gather_point *g)
{
    g->p = s->p;
    g->n = s->n;
    g->dist = evr_v3_len(evr_v3_sub(s->p, cam_org));
    evr_photon_indirect_k(s, mat, g->k);
}

/* max_photons 0: gather point g's query and window in b (pixel (x, y)). */
EVR_HD static inline evr_gather_window evr_gather_point_query(const evr_photon_buffer *b, const evr_camera_intr *cam,
                                                              const evr_gather_params *gp, const evr_gather_point *g, int x, int y,
                                                              evr_sum_query *q)
{
    const evr_gather_window w = evr_photon_gather_window(b, cam, x, y, g->dist, gp);
    q->p = g->p;
    q->n = g->n;
    q->c = evr_v3_make(EVR_LUMA_R * g->k[0], EVR_LUMA_G * g->k[1], EVR_LUMA_B * g->k[2]);
    q->r2 = w.r2;
    q->normal_cos = gp->normal_cos;
    q->flux_scale = gp->flux_scale;
    q->e = -0.5f / w.s2;
    q->area_scale = 4294967296.0f / w.s2;
    return w;
}

/* max_photons 0: the luminance of the indirect light leaving gather point g (pixel (x, y)) from
 * its fixed-point sums s over buffer b (any buffer of b's shape: only its shape is read). */
EVR_HD static inline float evr_gather_sum_lum(const evr_photon_buffer *b, const evr_camera_intr *cam, const evr_gather_params *gp,
                                              const evr_gather_point *g, int x, int y, const evr_gather_sum *s)
{
    const evr_gather_window w = evr_photon_gather_window(b, cam, x, y, g->dist, gp);
    return evr_photon_gather_sum_finish(b, &w, gp, s);
}

/* max_photons 0: the sums of gather point g's window in b (pixel (x, y)). */
EVR_HD static inline void evr_gather_point_sum(const evr_photon_buffer *b, const evr_camera_intr *cam, const evr_gather_params *gp,
                                               const evr_gather_point *g, int x, int y, evr_gather_sum *s)
{
    evr_sum_query q;
    const evr_gather_window w = evr_gather_point_query(b, cam, gp, g, x, y, &q);
    evr_photon_gather_sum(b, &w, &q, s);
}

/* max_photons 0: s, gather point g's sums over prev, becomes its sums over cur (ch: the cells
 * that changed from prev to cur). */
EVR_HD static inline void evr_gather_point_delta(const evr_photon_buffer *cur, const evr_photon_buffer *prev,
                                                 const evr_changed_cells *ch, const evr_camera_intr *cam, const evr_gather_params *gp,
                                                 const evr_gather_point *g, int x, int y, evr_gather_sum *s)
{
    evr_sum_query q;
    const evr_gather_window w = evr_gather_point_query(cur, cam, gp, g, x, y, &q);
    evr_photon_gather_delta(cur, prev, ch, &w, &q, s);
}

/* Luminance of the indirect light leaving gather point g seen through image pixel (x, y): the
 * limited search, or with max_photons 0 the fixed-point sums. */
EVR_HD static inline float evr_gather_point_lum(const evr_photon_buffer *b, const evr_camera_intr *cam,
                                                const evr_gather_params *gp, const evr_gather_point *g, int x, int y)
{
    float e[3];
    if (gp->max_photons <= 0) {
        evr_gather_sum s;
        evr_gather_point_sum(b, cam, gp, g, x, y, &s);
        return evr_gather_sum_lum(b, cam, gp, g, x, y, &s);
    }
    evr_photon_gather(b, cam, x, y, g->p, g->n, g->dist, gp, e);
    return evr_luminance(g->k[0] * e[0], g->k[1] * e[1], g->k[2] * e[2]);
}

/* The indirect light of a sample at normalized segment time f, from the gathers in the photon
 * buffers of the segment's start (ls) and end (le). The event pipeline's photon passes are
 * samples in time at the segment boundaries; between them the indirect light is linear, so that
 * a still surface lit by a moving object brightens smoothly and its events fall at the times
 * the light crosses their thresholds, not at the boundaries (one buffer per segment made each
 * segment's indirect light a step: 60% of GI events within a tenth of a segment of a boundary).
 * fmaf: the same rounding on every backend and in every kernel, and exactly ls where le == ls
 * (still windows keep their light bit for bit). */
EVR_HD static inline float evr_gi_lerp(float ls, float le, float f)
{
    return fmaf(f, le - ls, ls);
}

/* Luminance of the indirect light leaving surface s (material mat) seen from cam_org through
 * image pixel (x, y): the gather and the diffuse share. */
EVR_HD static inline float evr_photon_indirect_lum(const evr_photon_buffer *b, const evr_camera_intr *cam,
                                                   const evr_gather_params *gp, const evr_material_view *mat,
                                                   const evr_surface *s, evr_v3 cam_org, int x, int y)
{
    evr_gather_point g;
    evr_gather_point_at(s, mat, cam_org, &g);
    return evr_gather_point_lum(b, cam, gp, &g, x, y);
}

#endif
