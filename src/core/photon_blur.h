/* The blurred estimate (--gi-blur): once per photon pass, the irradiance at every buffer cell's
 * view (what the camera sees through its centre): the flux of the photons on the cell's footprint
 * and the footprint's area, each blurred over that surface alone (the same instance, a like
 * normal, a Gaussian of the distance), their ratio; a sample takes the estimate of its
 * pixel's cell, blended in time between the passes around it (evr_gi_lerp).
 *
 * A gather at each sample counts the few photons of a small disk, and as soon as anything moves
 * some of those photons are drawn anew every pass: the estimate flickers, and the flicker makes
 * events no camera would see, on the moving object and on every still surface its photons reach.
 * Irradiance varies slowly over a surface, so a wide blur on that surface removes the flicker
 * without the cost of a wide gather at every sample: one pass over the cells serves every sample
 * of the segments the pass bounds. */
#ifndef EVR_CORE_PHOTON_BLUR_H
#define EVR_CORE_PHOTON_BLUR_H

#include "core/photon_indirect.h"

/* cells whose normals differ more (cosine below) are not the same surface */
#define EVR_BLUR_NORMAL_COS 0.9f
/* the blur's a-trous steps at most (steps 1, 2, ..., 128 cells) */
#define EVR_BLUR_MAX_STEPS 8

/* A cell's working values while it is blurred: the flux of its photons (RGB) and the area of
 * surface its view covers; the estimate is their ratio (evr_blur_cell_finish), so a blurred
 * cell is every tap's flux over every tap's area: a density over the surface, whatever the
 * cells' footprints. */
#define EVR_BLUR_CH 4

/* Buffer cell i's flux and area (w, EVR_BLUR_CH floats) from the view b->gbuf: the photons it
 * holds that lie on the surface the view sees (a like normal, off its plane by at most twice the
 * footprint's width and at most the gather radius). A photon is stored in the cell the camera
 * sees it through, so the cell's photons are those on its footprint; the blur then spreads them
 * over the surface as a gather's disk would, at one cell's cost. */
EVR_HD static inline void evr_blur_cell_splat(const evr_photon_buffer *b,
                                              const evr_gather_params *gp, size_t i, float w[4])
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    const float *g = b->gbuf + 8 * i;
    const float tol = fminf(gp->radius, 2.0f * sqrtf(g[6]));
    const int nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    w[0] = w[1] = w[2] = 0.0f;
    w[3] = g[6];
    for (int l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        const float off =
            (ph->p[0] - g[0]) * g[3] + (ph->p[1] - g[1]) * g[4] + (ph->p[2] - g[2]) * g[5];
        if (!(fabsf(off) <= tol) ||
            ph->n[0] * g[3] + ph->n[1] * g[4] + ph->n[2] * g[5] < gp->normal_cos)
            continue;
        w[0] += ph->flux[0];
        w[1] += ph->flux[1];
        w[2] += ph->flux[2];
    }
}

/* The a-trous steps a blur of sigma (world units) takes where a cell spans pix: steps 1, 2, 4,
 * ... while the taps (2 step cells out) stay within 2 sigma, at least one. */
EVR_HD static inline int evr_blur_steps(float sigma, float pix)
{
    int n = 1;
    while (n < EVR_BLUR_MAX_STEPS && 2.0f * (float)(1 << n) * pix <= 2.0f * sigma) n++;
    return n;
}

/* Step k (0, 1, ...) of the blur at cell (cx, cy) that sees a surface (b->view_inst >= 0), from
 * src into dst (EVR_BLUR_CH floats a cell): an a-trous B3 spline of 5 x 5 taps 2^k cells apart
 * over src's values of the taps on the same instance with a like normal, each weighted by a Gaussian of its distance
 * (sigma); a cell whose own steps (evr_blur_steps at its distance from the camera at cam_org)
 * are done keeps its value. */
EVR_HD static inline void evr_blur_cell(const evr_photon_buffer *b, const evr_camera_intr *cam,
                                        evr_v3 cam_org, float sigma, const float *src, float *dst,
                                        int cx, int cy, int k)
{
    const float h[5] = {1.0f / 16.0f, 0.25f, 0.375f, 0.25f, 1.0f / 16.0f};
    const size_t i = (size_t)cy * (size_t)b->width + (size_t)cx;
    const int *inst = b->view_inst;
    const float *gi = b->gbuf + 8 * i;
    const float dist = evr_v3_len(evr_v3_sub(evr_v3_make(gi[0], gi[1], gi[2]), cam_org));
    if (k >= evr_blur_steps(sigma, evr_camera_pixel_size(cam, dist))) {
        for (int c = 0; c < EVR_BLUR_CH; c++) dst[EVR_BLUR_CH * i + c] = src[EVR_BLUR_CH * i + c];
        return;
    }
    const int step = 1 << k;
    const float inv2s2 = 0.5f / (sigma * sigma);
    float acc[EVR_BLUR_CH] = {0.0f, 0.0f, 0.0f, 0.0f}, wsum = 0.0f;
    for (int dy = -2; dy <= 2; dy++) {
        const int y = cy + dy * step;
        if (y < 0 || y >= b->height) continue;
        for (int dx = -2; dx <= 2; dx++) {
            const int x = cx + dx * step;
            if (x < 0 || x >= b->width) continue;
            const size_t j = (size_t)y * (size_t)b->width + (size_t)x;
            const float *gj = b->gbuf + 8 * j;
            if (inst[j] != inst[i] ||
                gi[3] * gj[3] + gi[4] * gj[4] + gi[5] * gj[5] < EVR_BLUR_NORMAL_COS)
                continue;
            const float ex = gj[0] - gi[0], ey = gj[1] - gi[1], ez = gj[2] - gi[2];
            const float w = h[dy + 2] * h[dx + 2] * expf(-(ex * ex + ey * ey + ez * ez) * inv2s2);
            for (int c = 0; c < EVR_BLUR_CH; c++) acc[c] += w * src[EVR_BLUR_CH * j + c];
            wsum += w;
        }
    }
    for (int c = 0; c < EVR_BLUR_CH; c++)
        dst[EVR_BLUR_CH * i + c] = acc[c] / wsum; /* the centre itself counts */
}

/* Cell i's blurred estimate (b->blur, RGB irradiance) from its blurred flux and area (src). */
EVR_HD static inline void evr_blur_cell_finish(const evr_photon_buffer *b, const float *src,
                                               size_t i)
{
    const float *w = src + EVR_BLUR_CH * i;
    for (int c = 0; c < 3; c++) b->blur[3 * i + c] = w[3] > 0.0f ? w[c] / w[3] : 0.0f;
}

#define EVR_BLUR_NONE 0 /* no cell around sees a surface */
#define EVR_BLUR_NEAR 1 /* cells around see other surfaces only */
#define EVR_BLUR_LIKE 2 /* a cell around sees the sample's surface */

/* What a sample on instance hit_inst (normal n) seen through image pixel (px, py) takes from a
 * pass's blurred estimates (b->blur): the estimate of its cell where that cell sees the same
 * instance with a like normal, else the mean of such cells among its eight neighbours (an
 * outline: the sample's point lies off its pixel's centre, or the object moved since the pass),
 * EVR_BLUR_LIKE; else the mean of the cells of the nine that see any surface, EVR_BLUR_NEAR;
 * else zero, EVR_BLUR_NONE. It reads nothing but those nine cells' views and estimates. */
EVR_HD static inline int evr_blur_lookup(const evr_photon_buffer *b, int px, int py, int hit_inst,
                                         evr_v3 n, float out[3])
{
    const int cx = px + b->margin, cy = py + b->margin;
    float near[3] = {0.0f, 0.0f, 0.0f};
    int like = 0, seen = 0;
    out[0] = out[1] = out[2] = 0.0f;
    for (int ring = 0; ring <= 1 && !like; ring++)
        for (int dy = -ring; dy <= ring; dy++)
            for (int dx = -ring; dx <= ring; dx++) {
                const int x = cx + dx, y = cy + dy;
                if ((ring && !dx && !dy) || x < 0 || y < 0 || x >= b->width || y >= b->height)
                    continue;
                const size_t j = (size_t)y * (size_t)b->width + (size_t)x;
                const float *g = b->gbuf + 8 * j, *e = b->blur + 3 * j;
                if (b->view_inst[j] < 0) continue;
                near[0] += e[0];
                near[1] += e[1];
                near[2] += e[2];
                seen++;
                if (b->view_inst[j] != hit_inst ||
                    g[3] * n.x + g[4] * n.y + g[5] * n.z < EVR_BLUR_NORMAL_COS)
                    continue;
                out[0] += e[0];
                out[1] += e[1];
                out[2] += e[2];
                like++;
            }
    if (like) {
        for (int c = 0; c < 3; c++) out[c] /= (float)like;
        return EVR_BLUR_LIKE;
    }
    if (!seen) return EVR_BLUR_NONE;
    for (int c = 0; c < 3; c++) out[c] = near[c] / (float)seen;
    return EVR_BLUR_NEAR;
}

/* A sample's irradiance at the passes of its segment's start (s) and end (e) from their blurred
 * estimates: where its surface is seen around its pixel at one pass only (it came into view, or
 * went out of it, as something moved), that pass's estimate for both. */
EVR_HD static inline void evr_blur_ends(const evr_photon_buffer *s, const evr_photon_buffer *e,
                                        int px, int py, int hit_inst, evr_v3 n, float es[3],
                                        float ee[3])
{
    const int ks = evr_blur_lookup(s, px, py, hit_inst, n, es),
              ke = evr_blur_lookup(e, px, py, hit_inst, n, ee);
    if (ks == EVR_BLUR_LIKE && ke != EVR_BLUR_LIKE)
        for (int c = 0; c < 3; c++) ee[c] = es[c];
    else if (ke == EVR_BLUR_LIKE && ks != EVR_BLUR_LIKE)
        for (int c = 0; c < 3; c++) es[c] = ee[c];
}

/* The luminance of the indirect light leaving gather point g (image pixel (x, y)) at the passes
 * of its segment's start (s) and end (e), from their blurred estimates (evr_blur_ends). */
EVR_HD static inline void evr_blur_point_lum(const evr_photon_buffer *s, const evr_photon_buffer *e,
                                             const evr_gather_point *g, int x, int y, float *ls,
                                             float *le)
{
    float es[3], ee[3];
    evr_blur_ends(s, e, x, y, g->inst, g->n, es, ee);
    *ls = evr_luminance(g->k[0] * es[0], g->k[1] * es[1], g->k[2] * es[2]);
    *le = evr_luminance(g->k[0] * ee[0], g->k[1] * ee[1], g->k[2] * ee[2]);
}

/* Whether cell i gives every lookup the same in passes a and b: the same instance, and where it
 * sees one the same normal and estimate, bit for bit. */
EVR_HD static inline int evr_blur_cell_same(const evr_photon_buffer *a, const evr_photon_buffer *b,
                                            size_t i)
{
    const uint32_t *ga = (const uint32_t *)(a->gbuf + 8 * i + 3),
                   *gb = (const uint32_t *)(b->gbuf + 8 * i + 3),
                   *ea = (const uint32_t *)(a->blur + 3 * i),
                   *eb = (const uint32_t *)(b->blur + 3 * i);
    if (a->view_inst[i] != b->view_inst[i]) return 0;
    if (a->view_inst[i] < 0) return 1;
    return ga[0] == gb[0] && ga[1] == gb[1] && ga[2] == gb[2] && ea[0] == eb[0] && ea[1] == eb[1] &&
           ea[2] == eb[2];
}

#endif
