/* The photon pass's emitter table, for both backends (see photon_emitters.h). */
#include "prep/photon_emitters.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int emitter_push(evr_photon_emitters *em, const evr_photon_emitter *e)
{
    if (em->n == em->cap) {
        int nc = em->cap ? 2 * em->cap : 16;
        evr_photon_emitter *p = realloc(em->e, (size_t)nc * sizeof *p);
        if (!p) return 0;
        em->e = p;
        em->cap = nc;
    }
    em->e[em->n++] = *e;
    return 1;
}

evr_status evr_photon_emitters_build(const evr_render_scene *rs, float f, evr_photon_bounds bb,
                                     uint32_t photons, evr_photon_emitters *em, evr_error *err)
{
    int i;
    uint32_t next = 0;
    em->n = 0;
    em->cdf_n = 0;
    em->total_power = 0.0f;
    for (i = 0; i < rs->num_lights; i++) {
        evr_photon_emitter e;
        float flux[3];
        memset(&e, 0, sizeof e);
        evr_photon_light_flux(rs, &rs->lights[i], f, bb, flux);
        e.kind = 0;
        e.index = i;
        e.power = evr_luminance(flux[0], flux[1], flux[2]);
        if (!(e.power > 0.0f)) continue;
        if (!emitter_push(em, &e)) goto nomem;
    }
    for (i = 0; i < rs->num_instances; i++) {
        const evr_mesh_view *m = &rs->meshes[rs->instances[i].mesh];
        const evr_material_params *mat = &rs->materials[m->material];
        float le = evr_luminance(mat->emissive[0], mat->emissive[1], mat->emissive[2]);
        evr_photon_emitter e;
        uint32_t t;
        double area = 0.0;
        if (!(le > 0.0f) || m->num_triangles == 0) continue;
        if (em->cdf_n + (int)m->num_triangles > em->cdf_cap) {
            int nc = em->cdf_cap ? em->cdf_cap : 64;
            while (nc < em->cdf_n + (int)m->num_triangles) nc *= 2;
            float *p = realloc(em->cdf, (size_t)nc * sizeof *p);
            if (!p) goto nomem;
            em->cdf = p;
            em->cdf_cap = nc;
        }
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[i].track), f);
        for (t = 0; t < m->num_triangles; t++) {
            uint32_t i0 = m->indices[3 * t], i1 = m->indices[3 * t + 1], i2 = m->indices[3 * t + 2];
            evr_v3 p0 = evr_m34_point(&xf, evr_rs_vertex(rs, i, m, i0, f));
            evr_v3 p1 = evr_m34_point(&xf, evr_rs_vertex(rs, i, m, i1, f));
            evr_v3 p2 = evr_m34_point(&xf, evr_rs_vertex(rs, i, m, i2, f));
            area += 0.5 * (double)evr_v3_len(evr_v3_cross(evr_v3_sub(p1, p0), evr_v3_sub(p2, p0)));
            em->cdf[em->cdf_n + (int)t] = (float)area;
        }
        if (!(area > 0.0)) continue;
        memset(&e, 0, sizeof e);
        e.kind = 1;
        e.index = i;
        e.tri_first = em->cdf_n;
        e.ntri = (int)m->num_triangles;
        e.area = (float)area;
        e.power = (float)(2.0 * EVR_PI * area) * le; /* both sides */
        em->cdf_n += (int)m->num_triangles;
        if (!emitter_push(em, &e)) goto nomem;
    }
    for (i = 0; i < em->n; i++) em->total_power += em->e[i].power;
    for (i = 0; i < em->n; i++) {
        double share = (double)em->e[i].power / (double)em->total_power * (double)photons;
        uint32_t c = (uint32_t)floor(share + 0.5);
        if (c == 0 && photons > 0) c = 1;
        em->e[i].first = next;
        em->e[i].count = c;
        next += c;
    }
    em->photons = next;
    return EVR_OK;
nomem:
    snprintf(err->msg, sizeof err->msg, "out of memory for the photon emitters");
    return EVR_ERR_NOMEM;
}

int evr_photon_emitters_copy(evr_photon_emitters *dst, const evr_photon_emitters *src)
{
    if (dst->cap < src->n) {
        evr_photon_emitter *p = realloc(dst->e, (size_t)src->n * sizeof *p);
        if (!p) return 0;
        dst->e = p;
        dst->cap = src->n;
    }
    if (dst->cdf_cap < src->cdf_n) {
        float *c = realloc(dst->cdf, (size_t)src->cdf_n * sizeof *c);
        if (!c) return 0;
        dst->cdf = c;
        dst->cdf_cap = src->cdf_n;
    }
    if (src->n) memcpy(dst->e, src->e, (size_t)src->n * sizeof *src->e);
    if (src->cdf_n) memcpy(dst->cdf, src->cdf, (size_t)src->cdf_n * sizeof *src->cdf);
    dst->n = src->n;
    dst->cdf_n = src->cdf_n;
    dst->total_power = src->total_power;
    dst->photons = src->photons;
    return 1;
}

int evr_photon_emitters_same(const evr_photon_emitters *a, const evr_photon_emitters *b)
{
    return a->n == b->n && a->cdf_n == b->cdf_n && a->photons == b->photons &&
           (a->n == 0 || !memcmp(a->e, b->e, (size_t)a->n * sizeof *a->e)) &&
           (a->cdf_n == 0 || !memcmp(a->cdf, b->cdf, (size_t)a->cdf_n * sizeof *a->cdf));
}

void evr_photon_emitters_free(evr_photon_emitters *em)
{
    free(em->e);
    free(em->cdf);
    memset(em, 0, sizeof *em);
}

int evr_photon_trails_pass(evr_photon_emitters *recorded, int *valid, const evr_photon_emitters *em)
{
    const int reuse = *valid && evr_photon_emitters_same(recorded, em);
    /* this pass records every photon's trail: valid for the next, with these emitters */
    *valid = evr_photon_emitters_copy(recorded, em);
    return reuse;
}
