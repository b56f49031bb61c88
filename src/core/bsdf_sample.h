/* Sampling the BSDF of core/material.h, written once for both kinds of path that carry indirect
 * light: the photon pass's paths from the lights (core/photon_path.h) and the path tracer's
 * from the camera (src/cpu/still.c).
 *
 * A surface's BSDF is split into lobes, each with its RGB weight (evr_bsdf_lobe_weights): the
 * diffuse base, the specular lobe (GGX, sampled from its visible normals; a mirror below
 * EVR_MIRROR_ROUGHNESS, as core/path.h traces it), the transmitted share (refracted through a
 * volume's faces, straight through a thin wall, as core/path.h traces it) and, for BLEND, the
 * share that passes uncovered. A path picks a lobe with odds proportional to its weight
 * (evr_bsdf_pick), draws a direction from it and is weighted by f cos / pdf of that lobe over
 * the odds (evr_bsdf_sample); the weights' expectations are the lobes' albedos, so a path keeps
 * the energy the BSDF keeps.
 *
 * The model is not reciprocal: the diffuse base's and the lobe's view-dependent factors
 * (what the dielectric layer leaves; the multiple-scattering compensation) are those of the
 * direction the surface is seen from. A camera path sees s from where it came, so its weights
 * are s's own; a photon leaves towards where s would be seen from, so its weights are taken for
 * the direction it leaves in (evr_material_lobes there): the photon pass is then the exact
 * adjoint of the path tracer and of direct light. */
#ifndef EVR_CORE_BSDF_SAMPLE_H
#define EVR_CORE_BSDF_SAMPLE_H

#include "core/material.h"

/* ---- directions ---- */

/* Orthonormal basis around unit n (Duff et al. 2017). */
EVR_HD static inline void evr_onb(evr_v3 n, evr_v3 *t, evr_v3 *b)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z), c = n.x * n.y * a;
    *t = evr_v3_make(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = evr_v3_make(c, s + n.y * n.y * a, -n.y);
}

/* Cosine-distributed direction around unit n from (u1, u2) in [0, 1)^2 (pdf cos / pi). */
EVR_HD static inline evr_v3 evr_cosine_dir(evr_v3 n, float u1, float u2)
{
    evr_v3 t, b;
    float r = sqrtf(u1), phi = 6.28318530718f * u2;
    float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    evr_onb(n, &t, &b);
    return evr_v3_norm(
        evr_v3_add(evr_v3_add(evr_v3_scale(t, x), evr_v3_scale(b, y)), evr_v3_scale(n, z)));
}

/* Mirror direction of incoming d about unit n. */
EVR_HD static inline evr_v3 evr_mirror_dir(evr_v3 d, evr_v3 n)
{
    return evr_v3_sub(d, evr_v3_scale(n, 2.0f * evr_v3_dot(d, n)));
}

/* The mirror reflection of a ray along d off s, as core/path.h traces it: about the shading
 * normal, or about the vertex normal when the shading normal would send it into the surface. */
EVR_HD static inline evr_v3 evr_surface_mirror_dir(const evr_surface *s, evr_v3 d)
{
    evr_v3 r = evr_v3_norm(evr_mirror_dir(d, s->n));
    if (evr_v3_dot(r, s->nv) <= 0.0f) r = evr_v3_norm(evr_mirror_dir(d, s->nv));
    return r;
}

/* Refraction of unit d through a surface with unit normal n (facing d's origin side) and ratio
 * of IORs eta (from / to); 0 on total internal reflection. */
EVR_HD static inline int evr_refract_dir(evr_v3 d, evr_v3 n, float eta, evr_v3 *out)
{
    const float c = -evr_v3_dot(d, n), k = 1.0f - eta * eta * (1.0f - c * c);
    if (k < 0.0f) return 0;
    *out = evr_v3_norm(evr_v3_add(evr_v3_scale(d, eta), evr_v3_scale(n, eta * c - sqrtf(k))));
    return 1;
}

/* A GGX microfacet normal around unit n drawn from those visible from unit v (v.n > 0):
 * evr_ggx_vndf_local in n's frame. */
EVR_HD static inline evr_v3 evr_ggx_vndf(evr_v3 n, evr_v3 v, float alpha, float u1, float u2)
{
    evr_v3 t, b;
    float h[3];
    evr_onb(n, &t, &b);
    evr_ggx_vndf_local(evr_v3_dot(v, t), evr_v3_dot(v, b), evr_v3_dot(v, n), alpha, u1, u2, h);
    return evr_v3_norm(evr_v3_add(evr_v3_add(evr_v3_scale(t, h[0]), evr_v3_scale(b, h[1])),
                                  evr_v3_scale(n, h[2])));
}

/* The density of l reflected about a visible normal drawn for v (evr_ggx_vndf): G1(v) D(h) /
 * (4 nv) with h the half vector of v and l; 0 where none could give it. */
EVR_HD static inline float evr_ggx_vndf_pdf(evr_v3 n, evr_v3 v, evr_v3 l, float alpha)
{
    const float nv = evr_v3_dot(n, v);
    const evr_v3 h = evr_v3_norm(evr_v3_add(v, l));
    const float nh = evr_v3_dot(n, h);
    if (!(nv > 0.0f) || !(nh > 0.0f) || !(evr_v3_dot(v, h) > 0.0f)) return 0.0f;
    return evr_smith_g1(alpha, nv) * evr_ggx_d(alpha, nh) / (4.0f * nv);
}

/* ---- the lobes ---- */

enum {
    EVR_LOBE_DIFFUSE = 0,  /* the diffuse base: cosine-distributed */
    EVR_LOBE_SPECULAR = 1, /* the GGX lobe, or a mirror (evr_material_mirror) */
    EVR_LOBE_TRANSMIT = 2, /* the transmitted share: refracted (a volume) or straight (thin) */
    EVR_LOBE_PASS = 3,     /* BLEND: the uncovered share, straight on */
    EVR_LOBES = 4
};

/* The lobes' weights of s as seen (the albedo of each: what it returns of light arriving from
 * the direction s is seen from); an unlit surface reflects nothing. */
EVR_HD static inline void evr_bsdf_lobe_weights(const evr_surface *s, float w[EVR_LOBES][3])
{
    const float a = s->opacity, lit = s->unlit ? 0.0f : a;
    for (int c = 0; c < 3; c++) {
        w[EVR_LOBE_DIFFUSE][c] = lit * s->diffuse[c];
        w[EVR_LOBE_SPECULAR][c] = lit * s->spec_albedo[c];
        w[EVR_LOBE_TRANSMIT][c] = lit * s->transmit[c];
        w[EVR_LOBE_PASS][c] = 1.0f - a;
    }
}

/* Picks a lobe for x in [0, 1) with odds proportional to the sum of its weight's channels;
 * *p gets the odds. -1 when every weight is 0. */
EVR_HD static inline int evr_bsdf_pick(const float w[EVR_LOBES][3], float x, float *p)
{
    float sum[EVR_LOBES], total = 0.0f, acc = 0.0f;
    int k, last = -1;
    for (k = 0; k < EVR_LOBES; k++) {
        sum[k] = fmaxf(w[k][0], 0.0f) + fmaxf(w[k][1], 0.0f) + fmaxf(w[k][2], 0.0f);
        total += sum[k];
    }
    if (!(total > 0.0f)) return -1;
    for (k = 0; k < EVR_LOBES; k++) {
        if (!(sum[k] > 0.0f)) continue;
        last = k;
        acc += sum[k];
        if (x * total < acc) break;
    }
    *p = sum[last] / total;
    return last;
}

/* What a ray that crossed s by transmission did to its medium (the volume it travels in):
 * 1 it entered s's material's volume (a front face of a material with thickness), -1 it left it
 * (a back face), 0 it passed a thin wall and keeps its medium (core/path.h's rule). */
EVR_HD static inline int evr_bsdf_crossing(const evr_surface *s, const evr_material_params *mat)
{
    if (!(mat->thickness > 0.0f)) return 0;
    return s->front ? 1 : -1;
}

/* What passes a distance t through the volume of material m (KHR_materials_volume's Beer-
 * Lambert attenuation, as core/path.h applies it), per channel, multiplied into w. */
EVR_HD static inline void evr_volume_attenuate(const evr_material_params *m, float t, float w[3])
{
    if (!(m->attenuation_distance < 1e30f)) return;
    for (int c = 0; c < 3; c++)
        w[c] *= powf(fmaxf(m->attenuation_color[c], 1e-6f), t / m->attenuation_distance);
}

/* Draws a direction from lobe `lobe` of s (material mat) for a path that arrived along unit d,
 * from (u1, u2) in [0, 1)^2: *dir, and w = f cos / pdf of the lobe (its weight's expectation is
 * the lobe's weight in evr_bsdf_lobe_weights; divide by the pick's odds). `adjoint` 0: a path
 * from the camera (s is seen along -d; s's own view-dependent factors); 1: a photon (the factors
 * of the direction it leaves in). Returns 0 when the sample carries nothing (a direction into
 * the surface). A transmitted direction that total internal reflection turns back reflects, as
 * core/path.h's does. */
EVR_HD static inline int evr_bsdf_sample(const evr_surface *s, const evr_material_params *mat,
                                         int lobe, evr_v3 d, float u1, float u2, int adjoint,
                                         evr_v3 *dir, float w[3])
{
    const float a = s->opacity;
    const evr_v3 v = evr_v3_scale(d, -1.0f);
    float f0[3], f90, comp[3], diffuse[3], transmit[3], spec[3];
    const float *vd = s->diffuse, *vt = s->transmit, *vc = s->comp;
    evr_v3 l;
    int c;
    if (lobe == EVR_LOBE_PASS) {
        *dir = d;
        w[0] = w[1] = w[2] = 1.0f - a;
        return 1;
    }
    if (lobe == EVR_LOBE_DIFFUSE) l = evr_cosine_dir(s->n, u1, u2);
    else if (lobe == EVR_LOBE_TRANSMIT) {
        l = d;
        if (mat->thickness > 0.0f &&
            !evr_refract_dir(d, s->n, s->front ? s->eta : 1.0f / s->eta, &l))
            l = evr_surface_mirror_dir(s, d);
    } else if (evr_material_mirror(s)) l = evr_surface_mirror_dir(s, d);
    else {
        if (!(evr_v3_dot(s->n, v) > 0.0f)) return 0;
        const evr_v3 h = evr_ggx_vndf(s->n, v, s->alpha, u1, u2);
        l = evr_v3_norm(evr_v3_sub(evr_v3_scale(h, 2.0f * evr_v3_dot(v, h)), v));
    }
    const float nl = evr_v3_dot(s->n, l);
    if (lobe != EVR_LOBE_TRANSMIT && (!(nl > 0.0f) || !(evr_v3_dot(s->nv, l) > 0.0f))) return 0;
    if (adjoint) { /* the view-dependent factors of the direction the photon leaves in */
        evr_material_lobes(s->bsdf_table, mat, s->albedo, s->metallic, s->rough, s->transmission,
                           fmaxf(fabsf(nl), 1e-4f), f0, &f90, comp, diffuse, transmit, spec);
        vd = diffuse, vt = transmit, vc = comp;
    }
    *dir = l;
    if (lobe == EVR_LOBE_DIFFUSE)
        for (c = 0; c < 3; c++) w[c] = a * vd[c];
    else if (lobe == EVR_LOBE_TRANSMIT)
        for (c = 0; c < 3; c++) w[c] = a * vt[c];
    else if (evr_material_mirror(s)) /* a mirror leaves at the angle it is met: s's own */
        for (c = 0; c < 3; c++) w[c] = a * s->spec_albedo[c];
    else { /* visible-normal sampling: f cos / pdf = F comp G2 / G1(v) */
        const float nv = fmaxf(evr_v3_dot(s->n, v), 1e-4f);
        const evr_v3 h = evr_v3_norm(evr_v3_add(v, l));
        const float fw = evr_schlick_w(fmaxf(evr_v3_dot(v, h), 0.0f));
        const float g = 4.0f * evr_smith_v(s->alpha, nl, nv) * nl * nv / evr_smith_g1(s->alpha, nv);
        for (c = 0; c < 3; c++) w[c] = a * (s->f0[c] + (s->f90 - s->f0[c]) * fw) * vc[c] * g;
    }
    return 1;
}

#endif
