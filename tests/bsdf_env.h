/* Test support for the BSDF (core/material.h): a render scene of one material and no geometry,
 * with the albedo table, and the surface of that material at the origin (normal +z) seen from a
 * direction, as evr_material_at makes it. */
#ifndef EVR_TESTS_BSDF_ENV_H
#define EVR_TESTS_BSDF_ENV_H

#include "core/shading.h"

#include <string.h>

typedef struct {
    evr_render_scene rs;
    evr_material_params mat;
    float table[2 * EVR_BSDF_MU * EVR_BSDF_ROUGH];
} bsdf_env;

static void env_init(bsdf_env *e)
{
    memset(&e->rs, 0, sizeof e->rs);
    evr_material_defaults(&e->mat);
    evr_bsdf_table_fill(e->table, 1024);
    e->rs.materials = &e->mat;
    e->rs.bsdf_table = e->table;
}

/* The surface of e's material at the origin, normal +z, seen along wo (front face). */
static evr_surface surface(const bsdf_env *e, evr_v3 wo)
{
    evr_surface s;
    memset(&s, 0, sizeof s);
    s.n = s.nv = evr_v3_make(0.0f, 0.0f, 1.0f);
    s.front = 1;
    s.albedo[0] = e->mat.base_color[0];
    s.albedo[1] = e->mat.base_color[1];
    s.albedo[2] = e->mat.base_color[2];
    s.metallic = e->mat.metallic;
    s.rough = e->mat.roughness;
    s.alpha = fmaxf(s.rough * s.rough, EVR_GGX_ALPHA_MIN);
    s.opacity = s.occlusion = 1.0f;
    s.eta = 1.0f / e->mat.ior;
    evr_material_view(&e->rs, &e->mat, e->mat.transmission, wo, &s);
    return s;
}

/* The unit direction at cos mu from +z in the xz plane. */
static evr_v3 view(float mu) { return evr_v3_make(sqrtf(1.0f - mu * mu), 0.0f, mu); }

#endif
