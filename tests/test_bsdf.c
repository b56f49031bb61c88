/* The metallic-roughness BSDF (src/core/material.h, core/bsdf.h): the white furnace (a white
 * surface reflects all the light it receives: the specular lobe's energy compensation and the
 * diffuse base's albedo scaling), the albedo table against direct integration, reciprocity of
 * the specular lobe, the glTF spec's limits (metal reflects its base colour at normal
 * incidence, a dielectric about 4%), and a light's radius widening the lobe with its energy
 * kept. */
#include "check.h"
#include "bsdf_env.h"

#include <stdlib.h>
#include <string.h>

/* Directional albedo of s seen along wo: the integral of BSDF * cos over the hemisphere (unit
 * irradiance from every direction), on a grid in (cos theta, phi) refined near the normal. */
static double albedo(const evr_surface *s, evr_v3 wo, float spread, int n_mu, int n_phi)
{
    double sum = 0.0;
    for (int i = 0; i < n_mu; i++) {
        /* cos theta = 1 - u^2: denser towards the normal and the mirror direction */
        const double u0 = (double)i / n_mu, u1 = (double)(i + 1) / n_mu, um = 0.5 * (u0 + u1);
        const double c = 1.0 - um * um, dc = (1.0 - u0 * u0) - (1.0 - u1 * u1);
        const double st = sqrt(fmax(0.0, 1.0 - c * c));
        for (int j = 0; j < n_phi; j++) {
            const double phi = 2.0 * 3.14159265358979 * (j + 0.5) / n_phi;
            const evr_v3 wi = evr_v3_make((float)(st * cos(phi)), (float)(st * sin(phi)), (float)c);
            float acc[3] = {0.0f, 0.0f, 0.0f};
            const float e[3] = {1.0f, 1.0f, 1.0f};
            evr_material_add_light(s, wo, wi, e, spread, acc);
            /* solid angle of the cell: dc dphi; acc already holds BSDF * cos */
            sum += (double)evr_luminance(acc[0], acc[1], acc[2]) * dc *
                   (2.0 * 3.14159265358979 / n_phi);
        }
    }
    return sum;
}

static void test_white_furnace(void)
{
    static bsdf_env e;
    const float mus[4] = {1.0f, 0.7f, 0.4f, 0.2f}, roughs[4] = {0.3f, 0.5f, 0.8f, 1.0f};
    env_init(&e);
    for (int metal = 0; metal < 2; metal++)
        for (int r = 0; r < 4; r++)
            for (int m = 0; m < 4; m++) {
                e.mat.metallic = (float)metal;
                e.mat.roughness = roughs[r];
                const evr_v3 wo = view(mus[m]);
                const evr_surface s = surface(&e, wo);
                const double a = albedo(&s, wo, 0.0f, 1500, 360);
                if (fabs(a - 1.0) > 0.01)
                    fprintf(stderr, "furnace: metal %d rough %.2f mu %.2f: %.4f\n", metal,
                            (double)roughs[r], (double)mus[m], a);
                CHECK(fabs(a - 1.0) <= 0.01);
                /* what the ambient term and the traced rays use: the same energy */
                const double table_a =
                    evr_luminance(s.spec_albedo[0], s.spec_albedo[1], s.spec_albedo[2]) +
                    evr_luminance(s.diffuse[0], s.diffuse[1], s.diffuse[2]);
                CHECK(fabs(table_a - 1.0) <= 0.01);
            }
}

static void test_table_matches_integral(void)
{
    static bsdf_env e;
    env_init(&e);
    e.mat.metallic = 1.0f;
    e.mat.base_color[0] = 0.9f, e.mat.base_color[1] = 0.6f, e.mat.base_color[2] = 0.3f;
    for (float r = 0.3f; r <= 1.0f; r += 0.35f) {
        e.mat.roughness = r;
        const evr_v3 wo = view(0.6f);
        const evr_surface s = surface(&e, wo);
        const double a = albedo(&s, wo, 0.0f, 1500, 360);
        const double t = evr_luminance(s.spec_albedo[0], s.spec_albedo[1], s.spec_albedo[2]);
        CHECK(fabs(a - t) <= 0.01 * t);
    }
}

static void test_fresnel_limits(void)
{
    static bsdf_env e;
    env_init(&e);
    /* metal: the base colour at normal incidence; dielectric of IOR 1.5: 4% */
    e.mat.metallic = 1.0f;
    e.mat.base_color[0] = 0.9f, e.mat.base_color[1] = 0.5f, e.mat.base_color[2] = 0.2f;
    e.mat.roughness = 0.5f;
    evr_surface s = surface(&e, view(1.0f));
    CHECK_NEAR(s.f0[0], 0.9f, 1e-6);
    CHECK_NEAR(s.f0[2], 0.2f, 1e-6);
    CHECK(s.diffuse[0] == 0.0f && s.transmit[0] == 0.0f);
    e.mat.metallic = 0.0f;
    s = surface(&e, view(1.0f));
    CHECK_NEAR(s.f0[1], 0.04f, 1e-6);
    /* KHR_materials_ior 1.376 (the cornea): f0 = ((n - 1) / (n + 1))^2 */
    e.mat.ior = 1.376f;
    s = surface(&e, view(1.0f));
    CHECK_NEAR(s.f0[0], (0.376f / 2.376f) * (0.376f / 2.376f), 1e-6);
    /* transmission takes the diffuse base's share */
    e.mat.transmission = 1.0f;
    s = surface(&e, view(1.0f));
    CHECK(s.diffuse[0] == 0.0f && s.transmit[1] > 0.9f * 0.5f);
}

static void test_reciprocity_and_spread(void)
{
    static bsdf_env e;
    env_init(&e);
    e.mat.metallic = 1.0f;
    e.mat.roughness = 0.4f;
    /* the specular lobe alone (metal): f(wo, wi) == f(wi, wo) */
    const evr_v3 a = evr_v3_norm(evr_v3_make(0.3f, 0.1f, 0.9f)),
                 b = evr_v3_norm(evr_v3_make(-0.5f, 0.2f, 0.6f));
    const float one[3] = {1.0f, 1.0f, 1.0f};
    float fa[3] = {0, 0, 0}, fb[3] = {0, 0, 0};
    evr_surface sa = surface(&e, a), sb = surface(&e, b);
    /* the single-scattering lobe (the compensation scales it by the view's albedo) */
    for (int c = 0; c < 3; c++) sa.comp[c] = sb.comp[c] = 1.0f;
    evr_material_add_light(&sa, a, b, one, 0.0f, fa);
    evr_material_add_light(&sb, b, a, one, 0.0f, fb);
    CHECK_NEAR(fa[0] / b.z, fb[0] / a.z, 1e-4 * fa[0] / b.z + 1e-7);
    /* a smooth metal lit by a sphere light: the highlight widens, its energy stays */
    e.mat.roughness = 0.05f;
    const evr_v3 wo = view(0.8f);
    const evr_surface s = surface(&e, wo);
    const double e0 = albedo(&s, wo, 0.2f, 6000, 720), e1 = albedo(&s, wo, 0.4f, 6000, 720);
    if (fabs(e0 - e1) > 0.02 * e0) fprintf(stderr, "spread: %.4f vs %.4f\n", e0, e1);
    CHECK(fabs(e0 - e1) <= 0.02 * e0);
}

/* The table filled by rows in parts, in any order (the set-up fills it on a pool), is the whole
 * table's bits. */
static void test_table_by_rows(void)
{
    const size_t n = 2 * EVR_BSDF_MU * EVR_BSDF_ROUGH;
    float *whole = malloc(n * sizeof *whole), *parts = malloc(n * sizeof *parts);
    CHECK(whole && parts);
    if (!whole || !parts) return;
    evr_bsdf_table_fill(whole, 256);
    memset(parts, 0xff, n * sizeof *parts);
    evr_bsdf_table_fill_rows(parts, 256, EVR_BSDF_ROUGH / 2, EVR_BSDF_ROUGH);
    evr_bsdf_table_fill_rows(parts, 256, 3, EVR_BSDF_ROUGH / 2);
    evr_bsdf_table_fill_rows(parts, 256, 0, 3);
    CHECK(!memcmp(whole, parts, n * sizeof *parts));
    free(whole);
    free(parts);
}

int main(void)
{
    test_table_by_rows();
    test_white_furnace();
    test_table_matches_integral();
    test_fresnel_limits();
    test_reciprocity_and_spread();
    return check_report("test_bsdf");
}
