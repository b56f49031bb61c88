/* The indirect light a pixel gets from the buffers: a surface point's diffuse weight, its gather
 * (limited, or the fixed-point sums and their update), and the blend between a segment's start
 * and end buffers. */
#ifndef EVR_CORE_PHOTON_INDIRECT_H
#define EVR_CORE_PHOTON_INDIRECT_H

#include "core/shading.h"
#include "core/photon_gather.h"
#include "core/photon_fixed.h"

/* What multiplies the irradiance (RGB) for the indirect radiance leaving surface s towards the
 * direction it is seen from: its diffuse weight (evr_surface.diffuse, the direct term's diffuse
 * base) over pi, times its coverage; nothing for an unlit surface. The stored photons estimate
 * the irradiance; what the specular lobe makes of it is not in the buffer (core/photon_path.h). */
EVR_HD static inline void evr_photon_indirect_k(const evr_surface *s, float k_rgb[3])
{
    const float k = s->unlit ? 0.0f : s->opacity * (1.0f / EVR_PI);
    k_rgb[0] = s->diffuse[0] * k;
    k_rgb[1] = s->diffuse[1] * k;
    k_rgb[2] = s->diffuse[2] * k;
}

/* Indirect radiance leaving surface s from an irradiance estimate (evr_photon_indirect_k per
 * RGB channel; add its luminance to evr_surface_intensity). */
EVR_HD static inline void evr_photon_indirect(const evr_surface *s, const float e_rgb[3],
                                              float out_rgb[3])
{
    float k[3];
    evr_photon_indirect_k(s, k);
    out_rgb[0] = k[0] * e_rgb[0];
    out_rgb[1] = k[1] * e_rgb[1];
    out_rgb[2] = k[2] * e_rgb[2];
}

/* What a gather needs of a surface point: position, normal, distance from the camera and what
 * turns irradiance into radiance (evr_photon_indirect_k). Made where the ray meets the
 * surface; the gather itself may run later (the GPU defers it to a kernel of its own). */
typedef struct evr_gather_point {
    evr_v3 p, n;
    float dist;
    float k[3];
    int inst; /* the scene instance (the blurred estimate looks it up) */
} evr_gather_point;

EVR_HD static inline void evr_gather_point_at(const evr_surface *s, int inst, evr_v3 cam_org,
                                              evr_gather_point *g)
{
    g->inst = inst;
    g->p = s->p;
    g->n = s->n;
    g->dist = evr_v3_len(evr_v3_sub(s->p, cam_org));
    evr_photon_indirect_k(s, g->k);
}

/* max_photons 0: gather point g's query and window in b (pixel (x, y)). */
EVR_HD static inline evr_gather_window evr_gather_point_query(const evr_photon_buffer *b,
                                                              const evr_camera_intr *cam,
                                                              const evr_gather_params *gp,
                                                              const evr_gather_point *g, int x,
                                                              int y, evr_sum_query *q)
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
    q->s2 = w.s2;
    return w;
}

/* max_photons 0: the luminance of the indirect light leaving gather point g (pixel (x, y)) from
 * its fixed-point sums s over buffer b (any buffer of b's shape: only its shape is read). */
EVR_HD static inline float evr_gather_sum_lum(const evr_photon_buffer *b,
                                              const evr_camera_intr *cam,
                                              const evr_gather_params *gp,
                                              const evr_gather_point *g, int x, int y,
                                              const evr_gather_sum *s)
{
    const evr_gather_window w = evr_photon_gather_window(b, cam, x, y, g->dist, gp);
    return evr_photon_gather_sum_finish(b, &w, gp, s);
}

/* max_photons 0: the sums of gather point g's window in b (pixel (x, y)). */
EVR_HD static inline void evr_gather_point_sum(const evr_photon_buffer *b,
                                               const evr_camera_intr *cam,
                                               const evr_gather_params *gp,
                                               const evr_gather_point *g, int x, int y,
                                               evr_gather_sum *s)
{
    evr_sum_query q;
    const evr_gather_window w = evr_gather_point_query(b, cam, gp, g, x, y, &q);
    evr_photon_gather_sum(b, &w, &q, s);
}

/* max_photons 0: s, gather point g's sums over prev, becomes its sums over cur (ch: the cells
 * that changed from prev to cur). */
EVR_HD static inline void
evr_gather_point_delta(const evr_photon_buffer *cur, const evr_photon_buffer *prev,
                       const evr_changed_cells *ch, const evr_camera_intr *cam,
                       const evr_gather_params *gp, const evr_gather_point *g, int x, int y,
                       evr_gather_sum *s)
{
    evr_sum_query q;
    const evr_gather_window w = evr_gather_point_query(cur, cam, gp, g, x, y, &q);
    evr_photon_gather_delta(cur, prev, ch, &w, &q, s);
}

/* Luminance of the indirect light leaving gather point g seen through image pixel (x, y): the
 * limited search, or with max_photons 0 the fixed-point sums. */
EVR_HD static inline float evr_gather_point_lum(const evr_photon_buffer *b,
                                                const evr_camera_intr *cam,
                                                const evr_gather_params *gp,
                                                const evr_gather_point *g, int x, int y)
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
EVR_HD static inline float evr_gi_lerp(float ls, float le, float f) { return fmaf(f, le - ls, ls); }

#endif
