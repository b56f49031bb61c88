/* Sampling the BSDF (src/core/bsdf_sample.h), as the path tracer and the photon pass do: the
 * visible-normal density integrates to 1 and the directions drawn follow it; each lobe's
 * sampled weight f cos / pdf has the lobe's albedo from the table as its mean (a white furnace
 * for the sampling: a white surface's estimate is 1); the lobe choice keeps the total; and the
 * estimate with the leaving direction's factors (a photon's) is the integral direct light's
 * BSDF gives. */
#include "check.h"
#include "bsdf_env.h"
#include "core/bsdf_sample.h"
#include "core/rng.h"

/* The k-th of n points of a Hammersley set in [0, 1)^2. */
static void hammersley(unsigned k, unsigned n, float *u1, float *u2)
{
    unsigned bits = k;
    bits = (bits << 16u) | (bits >> 16u);
    bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
    bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
    bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
    bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
    *u1 = ((float)k + 0.5f) / (float)n;
    *u2 = (float)((double)bits * 2.3283064365386963e-10);
}

/* The visible-normal density of reflected directions integrates to 1 over the sphere: its
 * mean ratio to the density of an independent sampler (half vectors drawn by D(h) nh, the
 * table's) is 1. And the directions evr_ggx_vndf draws fall into cones around the mirror
 * direction as often as the density says. */
static void test_vndf_pdf(void)
{
    const evr_v3 n = evr_v3_make(0.0f, 0.0f, 1.0f);
    const float alphas[4] = {0.04f, 0.1f, 0.36f, 1.0f}, mus[3] = {0.95f, 0.6f, 0.2f};
    const unsigned N = 1u << 18;
    for (int ia = 0; ia < 4; ia++)
        for (int im = 0; im < 3; im++) {
            const float a = alphas[ia], a2 = a * a;
            const evr_v3 v = view(mus[im]);
            double sum = 0.0;
            for (unsigned k = 0; k < N; k++) {
                float u1, u2;
                hammersley(k, N, &u1, &u2);
                const float ch = sqrtf((1.0f - u1) / (1.0f + (a2 - 1.0f) * u1)),
                            sh = sqrtf(fmaxf(0.0f, 1.0f - ch * ch)), phi = 6.28318530718f * u2;
                const evr_v3 h = evr_v3_make(sh * cosf(phi), sh * sinf(phi), ch);
                const float vh = evr_v3_dot(v, h);
                if (!(vh > 0.0f)) continue; /* the VNDF never gives these */
                const evr_v3 l = evr_v3_sub(evr_v3_scale(h, 2.0f * vh), v);
                const double q = (double)evr_ggx_d(a, ch) * ch / (4.0 * vh);
                sum += (double)evr_ggx_vndf_pdf(n, v, l, a) / q;
            }
            sum /= N;
            if (fabs(sum - 1.0) > 0.01)
                fprintf(stderr, "vndf pdf: alpha %.2f mu %.2f integrates to %.4f\n", (double)a,
                        (double)mus[im], sum);
            CHECK(fabs(sum - 1.0) <= 0.01);
            /* the share of drawn directions within angle t of the mirror direction against the
             * density integrated over that cone (by sampling the cone's solid angle uniformly) */
            const evr_v3 r = evr_v3_make(-v.x, -v.y, v.z);
            const float t = fminf(2.5f * a, 0.6f), ct = cosf(t);
            unsigned in = 0;
            for (unsigned k = 0; k < N; k++) {
                float u1, u2;
                hammersley(k, N, &u1, &u2);
                const evr_v3 h = evr_ggx_vndf(n, v, a, u1, u2);
                const evr_v3 l = evr_v3_sub(evr_v3_scale(h, 2.0f * evr_v3_dot(v, h)), v);
                in += evr_v3_dot(l, r) >= ct;
            }
            evr_v3 tr, br;
            evr_onb(r, &tr, &br);
            double cone = 0.0;
            for (unsigned k = 0; k < N; k++) {
                float u1, u2;
                hammersley(k, N, &u1, &u2);
                const float cz = 1.0f - u1 * (1.0f - ct), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz)),
                            phi = 6.28318530718f * u2;
                const evr_v3 l = evr_v3_add(
                    evr_v3_add(evr_v3_scale(tr, sz * cosf(phi)), evr_v3_scale(br, sz * sinf(phi))),
                    evr_v3_scale(r, cz));
                cone += evr_ggx_vndf_pdf(n, v, l, a);
            }
            cone *= 6.283185307179586 * (1.0 - ct) / N;
            const double share = (double)in / N;
            if (fabs(share - cone) > 0.01)
                fprintf(stderr,
                        "vndf: alpha %.2f mu %.2f: %.4f drawn in the cone, %.4f by density\n",
                        (double)a, (double)mus[im], share, cone);
            CHECK(fabs(share - cone) <= 0.01);
        }
}

/* The mean of lobe k's sampled weight at s seen along -d, with the leaving direction's factors
 * (adjoint) or s's own; n samples on a Hammersley set. */
static void lobe_mean(const evr_surface *s, const evr_material_params *mat, int k, evr_v3 d,
                      int adjoint, unsigned n, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    for (unsigned j = 0; j < n; j++) {
        float u1, u2, w[3];
        evr_v3 dir;
        hammersley(j, n, &u1, &u2);
        if (!evr_bsdf_sample(s, mat, k, d, u1, u2, adjoint, &dir, w)) continue;
        CHECK(fabsf(evr_v3_len(dir) - 1.0f) < 1e-4f);
        for (int c = 0; c < 3; c++) out[c] += w[c];
    }
    for (int c = 0; c < 3; c++) out[c] /= n;
}

/* Each lobe's mean weight is its albedo (the table's for the specular lobe); a white surface's
 * total is 1 (the furnace); the lobe choice by evr_bsdf_pick, weights over odds, keeps the
 * total. */
static void test_lobe_albedo(void)
{
    static bsdf_env e;
    const float mus[3] = {0.9f, 0.5f, 0.2f}, roughs[3] = {0.25f, 0.5f, 1.0f};
    env_init(&e);
    for (int metal = 0; metal < 2; metal++)
        for (int ir = 0; ir < 3; ir++)
            for (int im = 0; im < 3; im++) {
                e.mat.metallic = (float)metal;
                e.mat.roughness = roughs[ir];
                e.mat.base_color[0] = e.mat.base_color[1] = e.mat.base_color[2] = 1.0f;
                const evr_v3 v = view(mus[im]), d = evr_v3_scale(v, -1.0f);
                evr_surface s = surface(&e, v);
                double wd[3], ws[3];
                lobe_mean(&s, &e.mat, EVR_LOBE_DIFFUSE, d, 0, 1u << 14, wd);
                lobe_mean(&s, &e.mat, EVR_LOBE_SPECULAR, d, 0, 1u << 16, ws);
                for (int c = 0; c < 3; c++) {
                    CHECK_NEAR(wd[c], s.diffuse[c], 1e-5);
                    /* the table's albedo is clamped at 1 */
                    const double want = fmin(s.spec_albedo[c], 1.0);
                    if (fabs(fmin(ws[c], 1.0) - want) > 0.01 * want)
                        fprintf(stderr, "lobe: metal %d rough %.2f mu %.2f: %.4f, table %.4f\n",
                                metal, (double)roughs[ir], (double)mus[im], ws[c], want);
                    CHECK(fabs(fmin(ws[c], 1.0) - want) <= 0.01 * want);
                }
                const double total = wd[1] + ws[1];
                if (fabs(total - 1.0) > 0.015)
                    fprintf(stderr, "sampled furnace: metal %d rough %.2f mu %.2f: %.4f\n", metal,
                            (double)roughs[ir], (double)mus[im], total);
                CHECK(fabs(total - 1.0) <= 0.015);
            }
    /* a coloured dielectric with transmission and coverage: lobes picked by their weights */
    e.mat.metallic = 0.0f;
    e.mat.roughness = 0.6f;
    e.mat.transmission = 0.4f;
    e.mat.base_color[0] = 0.8f, e.mat.base_color[1] = 0.5f, e.mat.base_color[2] = 0.2f;
    const evr_v3 v = view(0.7f), d = evr_v3_scale(v, -1.0f);
    evr_surface s = surface(&e, v);
    s.opacity = 0.75f;
    float w[EVR_LOBES][3];
    double want[3] = {0, 0, 0}, got[3] = {0, 0, 0};
    evr_bsdf_lobe_weights(&s, w);
    for (int k = 0; k < EVR_LOBES; k++)
        for (int c = 0; c < 3; c++) want[c] += w[k][c];
    const unsigned n = 1u << 18;
    for (unsigned j = 0; j < n; j++) {
        const float xi = evr_uniform(evr_hash4(3, j, 0, 0)),
                    u1 = evr_uniform(evr_hash4(3, j, 0, 1)),
                    u2 = evr_uniform(evr_hash4(3, j, 0, 2));
        float p, ws[3];
        evr_v3 dir;
        const int k = evr_bsdf_pick(w, xi, &p);
        CHECK(k >= 0 && p > 0.0f);
        if (k < 0 || !evr_bsdf_sample(&s, &e.mat, k, d, u1, u2, 0, &dir, ws)) continue;
        if (k == EVR_LOBE_TRANSMIT || k == EVR_LOBE_PASS) CHECK(evr_v3_dot(dir, s.n) < 0.0f);
        else CHECK(evr_v3_dot(dir, s.n) > 0.0f);
        for (int c = 0; c < 3; c++) got[c] += ws[c] / p;
    }
    for (int c = 0; c < 3; c++) {
        got[c] /= n;
        if (fabs(got[c] - want[c]) > 0.01 * want[c])
            fprintf(stderr, "lobe choice: channel %d %.4f, weights %.4f\n", c, got[c], want[c]);
        CHECK(fabs(got[c] - want[c]) <= 0.01 * want[c]);
    }
}

/* With the factors of the leaving direction (a photon's), the mean weight is the integral over
 * the leaving direction wo of f(wo, wi) cos(wo), f as direct light evaluates it: the surface
 * seen from wo lit from wi (evr_material_add_light gives f cos(wi)). */
static void test_adjoint(void)
{
    static bsdf_env e;
    env_init(&e);
    const float roughs[2] = {0.3f, 0.7f}, mus[2] = {0.85f, 0.3f};
    for (int metal = 0; metal < 2; metal++)
        for (int ir = 0; ir < 2; ir++)
            for (int im = 0; im < 2; im++) {
                e.mat.metallic = metal ? 0.8f : 0.0f;
                e.mat.roughness = roughs[ir];
                e.mat.base_color[0] = 0.9f, e.mat.base_color[1] = 0.6f, e.mat.base_color[2] = 0.3f;
                const evr_v3 wi = view(mus[im]), d = evr_v3_scale(wi, -1.0f);
                const evr_surface s = surface(&e, wi);
                double wd[3], ws[3], want[3] = {0, 0, 0};
                lobe_mean(&s, &e.mat, EVR_LOBE_DIFFUSE, d, 1, 1u << 16, wd);
                lobe_mean(&s, &e.mat, EVR_LOBE_SPECULAR, d, 1, 1u << 17, ws);
                const int n_mu = 600, n_phi = 360;
                for (int i = 0; i < n_mu; i++) {
                    const double u0 = (double)i / n_mu, u1 = (double)(i + 1) / n_mu,
                                 um = 0.5 * (u0 + u1);
                    const double c = 1.0 - um * um, dc = (1.0 - u0 * u0) - (1.0 - u1 * u1);
                    const double st = sqrt(fmax(0.0, 1.0 - c * c));
                    for (int j = 0; j < n_phi; j++) {
                        const double phi = 6.283185307179586 * (j + 0.5) / n_phi;
                        const evr_v3 wo =
                            evr_v3_make((float)(st * cos(phi)), (float)(st * sin(phi)), (float)c);
                        const evr_surface so = surface(&e, wo);
                        const float one[3] = {1.0f, 1.0f, 1.0f};
                        float acc[3] = {0.0f, 0.0f, 0.0f};
                        evr_material_add_light(&so, wo, wi, one, 0.0f, acc);
                        for (int k = 0; k < 3; k++)
                            want[k] += (double)acc[k] / wi.z * c * dc * 6.283185307179586 / n_phi;
                    }
                }
                for (int k = 0; k < 3; k++) {
                    const double got = wd[k] + ws[k];
                    if (fabs(got - want[k]) > 0.015 * want[k])
                        fprintf(stderr,
                                "adjoint: metallic %.1f rough %.2f mu %.2f channel %d: %.4f, "
                                "integral %.4f\n",
                                (double)e.mat.metallic, (double)roughs[ir], (double)mus[im], k, got,
                                want[k]);
                    CHECK(fabs(got - want[k]) <= 0.015 * want[k]);
                }
            }
}

int main(void)
{
    test_vndf_pdf();
    test_lobe_albedo();
    test_adjoint();
    return check_report("test_bsdf_sample");
}
