/* The photon pass's material decisions (the light transport model is in core/photon.h): glTF
 * metallic-roughness to the thresholds t_diffuse and t_specular, the stay / diffuse / mirror
 * decision at a hit, and the directions a photon leaves in. */
#ifndef EVR_CORE_PHOTON_SCATTER_H
#define EVR_CORE_PHOTON_SCATTER_H

#include "core/vec.h"

/* glTF metallic-roughness to the photon thresholds: reflectance R = max(base colour) clamped to
 * [0.05, 0.95]; mirror = metallic * (1 - roughness);
 * t_diffuse = 1 - R, t_specular = t_diffuse + R * (1 - mirror). */
EVR_HD static inline void evr_photon_material_map(const float base_color[3], float metallic, float roughness,
                                                  float *t_diffuse, float *t_specular)
{
    float r = fmaxf(base_color[0], fmaxf(base_color[1], base_color[2]));
    float m = fminf(fmaxf(metallic, 0.0f), 1.0f) * (1.0f - fminf(fmaxf(roughness, 0.0f), 1.0f));
    r = fminf(fmaxf(r, 0.05f), 0.95f);
    *t_diffuse = 1.0f - r;
    *t_specular = *t_diffuse + r * (1.0f - m);
}

/* Share of the reflected light that is a mirror reflection. */
EVR_HD static inline float evr_photon_mirror_share(float t_diffuse, float t_specular)
{
    float refl = 1.0f - t_diffuse;
    return refl > 0.0f ? fminf(fmaxf((1.0f - t_specular) / refl, 0.0f), 1.0f) : 0.0f;
}

enum { EVR_PHOTON_STAY = 0, EVR_PHOTON_DIFFUSE = 1, EVR_PHOTON_MIRROR = 2, EVR_PHOTON_ABSORB = 3 };

/* The decision at a hit for random xi in [0, 1). *weight multiplies the flux: stay 1/t_diffuse,
 * bounce 1/(1 - t_diffuse) (times the albedo, which the caller applies), 1 for a bounce when
 * staying is not allowed. ABSORB only when nothing else is possible. */
EVR_HD static inline int evr_photon_scatter(float t_diffuse, float t_specular, float xi, int allow_stay, float *weight)
{
    float td = fminf(fmaxf(t_diffuse, 0.0f), 1.0f), ts = fminf(fmaxf(t_specular, td), 1.0f);
    if (allow_stay) {
        if (xi < td) {
            *weight = 1.0f / td;
            return EVR_PHOTON_STAY;
        }
        if (td >= 1.0f) { *weight = 0.0f; return EVR_PHOTON_ABSORB; }
        *weight = 1.0f / (1.0f - td);
        return xi < ts ? EVR_PHOTON_DIFFUSE : EVR_PHOTON_MIRROR;
    }
    if (td >= 1.0f) { *weight = 0.0f; return EVR_PHOTON_ABSORB; }
    *weight = 1.0f;
    /* xi spread over the bounce options only */
    return td + xi * (1.0f - td) < ts ? EVR_PHOTON_DIFFUSE : EVR_PHOTON_MIRROR;
}

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
    return evr_v3_norm(evr_v3_add(evr_v3_add(evr_v3_scale(t, x), evr_v3_scale(b, y)), evr_v3_scale(n, z)));
}

/* Mirror direction of incoming d about unit n. */
EVR_HD static inline evr_v3 evr_mirror_dir(evr_v3 d, evr_v3 n)
{
    return evr_v3_sub(d, evr_v3_scale(n, 2.0f * evr_v3_dot(d, n)));
}

/* Uniform direction on the sphere. */
EVR_HD static inline evr_v3 evr_sphere_dir(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 6.28318530718f * u2;
    return evr_v3_make(r * cosf(phi), r * sinf(phi), z);
}

#endif
