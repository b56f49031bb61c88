/* The microfacet pieces of the glTF 2.0 metallic-roughness BSDF (the spec's Appendix B): the
 * GGX normal distribution, the height-correlated Smith visibility, Schlick's Fresnel, and the
 * table of the GGX lobe's directional albedo that makes the lobe keep its energy (multiple
 * scattering compensated, Turquin 2019) and lets the diffuse base take exactly what the
 * specular layer leaves (albedo scaling, as OpenPBR layers). core/material.h combines them. */
#ifndef EVR_CORE_BSDF_H
#define EVR_CORE_BSDF_H

#include "core/vec.h"

/* The smallest GGX alpha shaded as a lobe: a smoother surface is a mirror for traced rays, and
 * its highlight of a point light would be a spike no pixel sees. */
#define EVR_GGX_ALPHA_MIN 1e-3f

/* GGX (Trowbridge-Reitz) normal distribution at cos(theta_h) = nh, alpha = roughness^2. */
EVR_HD static inline float evr_ggx_d(float alpha, float nh)
{
    const float a2 = alpha * alpha, d = nh * nh * (a2 - 1.0f) + 1.0f;
    return a2 / (3.14159265358979f * d * d);
}

/* Height-correlated Smith visibility V = G / (4 nl nv) (Heitz 2014), as glTF's Appendix B. */
EVR_HD static inline float evr_smith_v(float alpha, float nl, float nv)
{
    const float a2 = alpha * alpha;
    const float gv = nl * sqrtf(nv * nv * (1.0f - a2) + a2);
    const float gl = nv * sqrtf(nl * nl * (1.0f - a2) + a2);
    const float s = gv + gl;
    return s > 0.0f ? 0.5f / s : 0.0f;
}

/* Smith's masking G1 of the GGX lobe seen at cos nv; with evr_smith_v, the weight of a
 * direction sampled from the visible normals: G2 / G1(v) = 4 V nl nv / G1(v). */
EVR_HD static inline float evr_smith_g1(float alpha, float nv)
{
    const float a2 = alpha * alpha;
    return 2.0f * nv / (nv + sqrtf(nv * nv * (1.0f - a2) + a2));
}

/* A GGX microfacet normal drawn from the normals visible from v (their distribution
 * D_v(h) = G1(v) max(v.h, 0) D(h) / nv), in the frame where the macro normal is +z and v.z > 0:
 * stretch v to the alpha = 1 configuration, draw a point on the spherical cap of the unit sphere
 * that v sees (Dupuy and Benyoub, "Sampling Visible GGX Normals with Spherical Caps", 2023),
 * offset it by v, and unstretch. (u1, u2) in [0, 1)^2. The reflected direction
 * l = 2 (v.h) h - v then has the density G1(v) D(h) / (4 nv). */
EVR_HD static inline void evr_ggx_vndf_local(float vx, float vy, float vz, float alpha, float u1,
                                             float u2, float h[3])
{
    float sx = alpha * vx, sy = alpha * vy, sz = vz;
    const float inv = 1.0f / sqrtf(sx * sx + sy * sy + sz * sz);
    sx *= inv, sy *= inv, sz *= inv;
    const float phi = 6.28318530718f * u1;
    const float z = (1.0f - u2) * (1.0f + sz) - sz; /* uniform over the cap z >= -sz */
    const float st = sqrtf(fminf(fmaxf(1.0f - z * z, 0.0f), 1.0f));
    const float hx = alpha * (st * cosf(phi) + sx), hy = alpha * (st * sinf(phi) + sy),
                hz = fmaxf(z + sz, 0.0f);
    const float hl = sqrtf(hx * hx + hy * hy + hz * hz);
    if (!(hl > 0.0f)) { /* v at the horizon and a sample at its rim: the normal itself */
        h[0] = h[1] = 0.0f, h[2] = 1.0f;
        return;
    }
    h[0] = hx / hl, h[1] = hy / hl, h[2] = hz / hl;
}

/* Schlick's Fresnel weight (1 - c)^5 at cos c. */
EVR_HD static inline float evr_schlick_w(float c)
{
    const float m = fminf(fmaxf(1.0f - c, 0.0f), 1.0f), m2 = m * m;
    return m2 * m2 * m;
}

/* ---- the directional albedo table ---- */

/* The table: for cos(theta_o) = mu and perceptual roughness r, both on uniform grids over
 * [0, 1] of EVR_BSDF_MU x EVR_BSDF_ROUGH points, the two parts (A, B) of the GGX lobe's
 * directional albedo with Schlick's Fresnel: E(mu, r; f0, f90) = f0 A + f90 B. A + B is the
 * albedo without Fresnel (E1 < 1: the energy single scattering loses). Filled on the host once
 * (src/prep/bsdf_table.c), read by both backends. */
#define EVR_BSDF_MU 64
#define EVR_BSDF_ROUGH 32

/* Bilinear lookup of (A, B) at mu and perceptual roughness r. */
EVR_HD static inline void evr_bsdf_table_ab(const float *table, float mu, float r, float *a,
                                            float *b)
{
    float x = fminf(fmaxf(mu, 0.0f), 1.0f) * (float)(EVR_BSDF_MU - 1);
    float y = fminf(fmaxf(r, 0.0f), 1.0f) * (float)(EVR_BSDF_ROUGH - 1);
    int x0 = (int)x, y0 = (int)y;
    if (x0 > EVR_BSDF_MU - 2) x0 = EVR_BSDF_MU - 2;
    if (y0 > EVR_BSDF_ROUGH - 2) y0 = EVR_BSDF_ROUGH - 2;
    const float fx = x - (float)x0, fy = y - (float)y0;
    const float *p00 = table + 2 * (y0 * EVR_BSDF_MU + x0), *p10 = p00 + 2;
    const float *p01 = p00 + 2 * EVR_BSDF_MU, *p11 = p01 + 2;
    *a = (p00[0] * (1 - fx) + p10[0] * fx) * (1 - fy) + (p01[0] * (1 - fx) + p11[0] * fx) * fy;
    *b = (p00[1] * (1 - fx) + p10[1] * fx) * (1 - fy) + (p01[1] * (1 - fx) + p11[1] * fx) * fy;
}

/* Fills the table's roughness rows [j0, j1) (of EVR_BSDF_ROUGH; each row EVR_BSDF_MU entries of
 * 2 floats) by integrating the lobe over GGX-distributed half vectors on a Hammersley set of n
 * points per entry; rows are independent, so parts of the table can be filled at once. Host
 * code. */
static inline void evr_bsdf_table_fill_rows(float *table, int n, int j0, int j1)
{
    for (int j = j0; j < j1; j++) {
        const float r = (float)j / (float)(EVR_BSDF_ROUGH - 1);
        float alpha = r * r;
        if (alpha < EVR_GGX_ALPHA_MIN) alpha = EVR_GGX_ALPHA_MIN;
        for (int i = 0; i < EVR_BSDF_MU; i++) {
            /* mu = 0 is grazing: its albedo is the limit, taken a little inside */
            double mu = (double)i / (double)(EVR_BSDF_MU - 1);
            if (mu < 1e-3) mu = 1e-3;
            const double vx = sqrt(1.0 - mu * mu), vz = mu;
            double sa = 0.0, sb = 0.0;
            for (int k = 0; k < n; k++) {
                /* Hammersley point (k / n, radical inverse of k) */
                unsigned bits = (unsigned)k;
                bits = (bits << 16u) | (bits >> 16u);
                bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
                bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
                bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
                bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
                const double u1 = ((double)k + 0.5) / (double)n,
                             u2 = (double)bits * 2.3283064365386963e-10;
                /* GGX half vector: pdf(h) = D(h) nh */
                const double a2 = (double)alpha * alpha;
                const double ch = sqrt((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)),
                             sh = sqrt(1.0 - ch * ch), phi = 6.283185307179586 * u2;
                const double hx = sh * cos(phi), hz = ch; /* v lies in the xz plane */
                const double vh = vx * hx + vz * hz;
                if (vh <= 0.0) continue;
                const double lz = 2.0 * vh * hz - vz; /* l = 2 (v.h) h - v, its z */
                if (lz <= 0.0) continue;
                /* f cos / pdf(l) with pdf(l) = D nh / (4 vh): V * 4 * vh * lz / nh */
                const double gv = lz * sqrt(mu * mu * (1.0 - a2) + a2),
                             gl = mu * sqrt(lz * lz * (1.0 - a2) + a2);
                const double w = (0.5 / (gv + gl)) * 4.0 * vh * lz / hz;
                const double fc = pow(1.0 - vh, 5.0);
                sa += w * (1.0 - fc);
                sb += w * fc;
            }
            table[2 * (j * EVR_BSDF_MU + i)] = (float)(sa / n);
            table[2 * (j * EVR_BSDF_MU + i) + 1] = (float)(sb / n);
        }
    }
}

/* The whole table (2 * EVR_BSDF_MU * EVR_BSDF_ROUGH floats). */
static inline void evr_bsdf_table_fill(float *table, int n)
{
    evr_bsdf_table_fill_rows(table, n, 0, EVR_BSDF_ROUGH);
}

#endif
