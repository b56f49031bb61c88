/* Photon emission: from point, spot and directional lights (their flux towards the scene) and
 * from emissive triangles; the emitter table a pass splits its photons by. */
#ifndef EVR_CORE_PHOTON_EMIT_H
#define EVR_CORE_PHOTON_EMIT_H

#include <stdint.h>
#include "core/shading.h"
#include "core/bsdf_sample.h"

/* Uniform direction on the sphere. */
EVR_HD static inline evr_v3 evr_sphere_dir(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 6.28318530718f * u2;
    return evr_v3_make(r * cosf(phi), r * sinf(phi), z);
}

typedef struct {
    evr_ray ray;
    float flux[3];
    int from_light; /* 1: a point, spot or directional light (never stays at the first hit) */
} evr_photon_ray;

/* Emitters of a pass: every light with power, then every instance with an emissive material. */
typedef struct {
    int kind;       /* 0: light, 1: emissive instance */
    int index;      /* light index or instance index */
    float power;    /* luminance flux (what the photons are split by) */
    uint32_t first; /* photons [first, first + count) of the pass are this emitter's */
    uint32_t count;
    int tri_first; /* kind 1: triangles' cumulative areas at cdf[tri_first .. tri_first + ntri) */
    int ntri;
    float area; /* kind 1: total area (world, at the pass's time) */
} evr_photon_emitter;

/* Scene bounds for directional lights: a sphere. */
typedef struct {
    evr_v3 center;
    float radius;
} evr_photon_bounds;

/* Position and direction of light l at normalized segment time f. */
EVR_HD static inline void evr_photon_light_pose(const evr_render_scene *rs, const evr_light_view *l,
                                                float f, evr_v3 *pos, evr_v3 *dir)
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
EVR_HD static inline void evr_photon_light_flux(const evr_render_scene *rs, const evr_light_view *l,
                                                float f, evr_photon_bounds bb, float out[3])
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
EVR_HD static inline int evr_photon_emit_light(const evr_render_scene *rs, const evr_light_view *l,
                                               float f, evr_photon_bounds bb, const float u[4],
                                               uint32_t count, evr_photon_ray *out)
{
    evr_v3 lp, ld;
    float k;
    evr_photon_light_pose(rs, l, f, &lp, &ld);
    out->from_light = 1;
    if (l->type == 2) { /* directional: a disk across the scene's bounding sphere, upstream */
        evr_v3 t, b;
        float r = bb.radius * sqrtf(u[0]), phi = 6.28318530718f * u[1];
        evr_onb(ld, &t, &b);
        out->ray.org =
            evr_v3_add(evr_v3_sub(bb.center, evr_v3_scale(ld, 1.01f * bb.radius)),
                       evr_v3_add(evr_v3_scale(t, r * cosf(phi)), evr_v3_scale(b, r * sinf(phi))));
        out->ray.dir = ld;
        k = EVR_PI * bb.radius * bb.radius;
    } else if (l->type == 1) { /* spot: uniform in the outer cone, weighted by the falloff */
        evr_v3 t, b;
        float cz = 1.0f - u[0] * (1.0f - l->cos_outer), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
        float phi = 6.28318530718f * u[1];
        float a = (cz - l->cos_outer) / fmaxf(l->cos_inner - l->cos_outer, 1e-4f);
        a = fminf(fmaxf(a, 0.0f), 1.0f);
        evr_onb(ld, &t, &b);
        out->ray.org = lp;
        out->ray.dir = evr_v3_norm(
            evr_v3_add(evr_v3_add(evr_v3_scale(t, sz * cosf(phi)), evr_v3_scale(b, sz * sinf(phi))),
                       evr_v3_scale(ld, cz)));
        k = 2.0f * EVR_PI * (1.0f - l->cos_outer) * a * a;
    } else { /* point: every direction, or only those towards the scene's sphere from outside it */
        float cmax = evr_photon_sphere_cos(lp, bb);
        out->ray.org = lp;
        if (cmax > -1.0f) {
            evr_v3 axis = evr_v3_norm(evr_v3_sub(bb.center, lp)), t, b;
            float cz = 1.0f - u[0] * (1.0f - cmax), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
            float phi = 6.28318530718f * u[1];
            evr_onb(axis, &t, &b);
            out->ray.dir = evr_v3_norm(evr_v3_add(
                evr_v3_add(evr_v3_scale(t, sz * cosf(phi)), evr_v3_scale(b, sz * sinf(phi))),
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
 * u[2]), a cosine-distributed direction (u[3], u[4]); flux = 2 pi Le * area / count. xf is the
 * instance's transform at the photon's time f.
 * cdf: the instance's cumulative world-space triangle areas (cdf[ntri - 1] == area). */
EVR_HD static inline int evr_photon_emit_surface(const evr_render_scene *rs,
                                                 const evr_photon_emitter *em, const float *cdf,
                                                 const evr_m34 *xf, float f, const float u[5],
                                                 evr_photon_ray *out)
{
    const evr_mesh_view *m = &rs->meshes[rs->instances[em->index].mesh];
    const evr_material_params *mat = &rs->materials[m->material];
    const float *c = cdf + em->tri_first;
    float side = u[0] < 0.5f ? 1.0f : -1.0f,
          x = (u[0] < 0.5f ? u[0] * 2.0f : u[0] * 2.0f - 1.0f) * em->area;
    int lo = 0, hi = em->ntri - 1;
    while (lo < hi) { /* first triangle whose cumulative area exceeds x */
        int mid = (lo + hi) / 2;
        if (c[mid] > x) hi = mid;
        else lo = mid + 1;
    }
    uint32_t i0 = m->indices[3 * lo], i1 = m->indices[3 * lo + 1], i2 = m->indices[3 * lo + 2];
    evr_v3 p0 = evr_m34_point(xf, evr_rs_vertex(rs, em->index, m, i0, f));
    evr_v3 p1 = evr_m34_point(xf, evr_rs_vertex(rs, em->index, m, i1, f));
    evr_v3 p2 = evr_m34_point(xf, evr_rs_vertex(rs, em->index, m, i2, f));
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

#endif
