/* The blurred estimate (--gi-blur): once per photon pass, the irradiance at every buffer cell's
 * view (what the camera sees through its centre), blurred over that surface alone (the same
 * instance, a like normal, a Gaussian of the distance); a sample takes the estimate of its
 * pixel's cell, blended in time between the passes around it (evr_gi_lerp).
 *
 * A gather at each sample counts the few photons of a small disk, and as soon as anything moves
 * some of those photons are drawn anew every pass: the estimate flickers, and the flicker makes
 * events no camera would see, on the moving object and on every still surface its photons reach.
 * Irradiance varies slowly over a surface, so a wide blur on that surface removes the flicker
 * without the cost of a wide gather at every sample: one gather per cell and pass serves every
 * sample of the segments the pass bounds. */
#ifndef EVR_CORE_PHOTON_BLUR_H
#define EVR_CORE_PHOTON_BLUR_H

#include "core/photon_indirect.h"

/* cells whose normals differ more (cosine below) are not the same surface */
#define EVR_BLUR_NORMAL_COS 0.9f
/* the blur's a-trous steps at most (steps 1, 2, ..., 128 cells) */
#define EVR_BLUR_MAX_STEPS 8

/* The estimate at buffer cell (cx, cy)'s view (b->gbuf): every photon of the gather's disk,
 * irradiance RGB into e. */
EVR_HD static inline void evr_blur_cell_gather(const evr_photon_buffer *b,
                                               const evr_camera_intr *cam, evr_v3 cam_org,
                                               const evr_gather_params *gp, int cx, int cy,
                                               float e[3])
{
    const float *g = b->gbuf + 8 * ((size_t)cy * (size_t)b->width + (size_t)cx);
    const evr_v3 p = evr_v3_make(g[0], g[1], g[2]), n = evr_v3_make(g[3], g[4], g[5]);
    evr_gather_params q = *gp;
    q.max_photons = 0x7fffffff;
    evr_photon_gather(b, cam, cx - b->margin, cy - b->margin, p, n,
                      evr_v3_len(evr_v3_sub(p, cam_org)), &q, e);
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
 * src into dst: an a-trous B3 spline of 5 x 5 taps 2^k cells apart over src's estimates of the
 * taps on the same instance with a like normal, each weighted by a Gaussian of its distance
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
        for (int c = 0; c < 3; c++) dst[3 * i + c] = src[3 * i + c];
        return;
    }
    const int step = 1 << k;
    const float inv2s2 = 0.5f / (sigma * sigma);
    float acc[3] = {0.0f, 0.0f, 0.0f}, wsum = 0.0f;
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
            acc[0] += w * src[3 * j];
            acc[1] += w * src[3 * j + 1];
            acc[2] += w * src[3 * j + 2];
            wsum += w;
        }
    }
    for (int c = 0; c < 3; c++) dst[3 * i + c] = acc[c] / wsum; /* the centre itself counts */
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
