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

#include "core/photon_gather.h"

/* cells whose normals differ more (cosine below) are not the same surface */
#define EVR_BLUR_NORMAL_COS 0.9f

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

/* One step of the blur (an a-trous B3 spline of 5 x 5 taps, `step` cells apart) at cell (cx, cy)
 * that sees a surface (inst[i] >= 0): src's estimates of the taps on the same instance with a
 * like normal, weighted by a Gaussian of their distance (inv2s2 = 1 / (2 sigma^2)), into dst. */
EVR_HD static inline void evr_blur_cell(const evr_photon_buffer *b, const int *inst,
                                        const float *src, float *dst, int cx, int cy, int step,
                                        float inv2s2)
{
    const float h[5] = {1.0f / 16.0f, 0.25f, 0.375f, 0.25f, 1.0f / 16.0f};
    const size_t i = (size_t)cy * (size_t)b->width + (size_t)cx;
    const float *gi = b->gbuf + 8 * i;
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

/* The a-trous steps a blur of sigma (world units) takes where a cell spans pix: steps 1, 2, 4,
 * ... while the taps (2 step cells out) stay within 2 sigma, at least one, at most 8. */
EVR_HD static inline int evr_blur_steps(float sigma, float pix)
{
    int n = 1;
    while (n < 8 && 2.0f * (float)(1 << n) * pix <= 2.0f * sigma) n++;
    return n;
}

/* The estimate a sample on instance hit_inst (normal n) seen through image pixel (px, py) takes
 * from a pass's blurred estimates e: its cell's, where that cell sees the same instance with a
 * like normal, else the mean of such cells among its eight neighbours (an outline: the sample's
 * point lies off its pixel's centre, or the object moved since the pass). Returns 0 when none is
 * such: the sample gathers for itself. */
EVR_HD static inline int evr_blur_lookup(const evr_photon_buffer *b, const int *inst,
                                         const float *e, int px, int py, int hit_inst, evr_v3 n,
                                         float out[3])
{
    const int cx = px + b->margin, cy = py + b->margin;
    int found = 0;
    out[0] = out[1] = out[2] = 0.0f;
    for (int ring = 0; ring <= 1 && !found; ring++)
        for (int dy = -ring; dy <= ring; dy++)
            for (int dx = -ring; dx <= ring; dx++) {
                const int x = cx + dx, y = cy + dy;
                if ((ring && !dx && !dy) || x < 0 || y < 0 || x >= b->width || y >= b->height)
                    continue;
                const size_t j = (size_t)y * (size_t)b->width + (size_t)x;
                const float *g = b->gbuf + 8 * j;
                if (inst[j] != hit_inst ||
                    g[3] * n.x + g[4] * n.y + g[5] * n.z < EVR_BLUR_NORMAL_COS)
                    continue;
                out[0] += e[3 * j];
                out[1] += e[3 * j + 1];
                out[2] += e[3 * j + 2];
                found++;
            }
    if (!found) return 0;
    for (int c = 0; c < 3; c++) out[c] /= (float)found;
    return 1;
}

/* Whether cell i gives every lookup the same in two passes (a and b, with their views' instances
 * and estimates): the same instance, normal and estimate, bit for bit. */
EVR_HD static inline int evr_blur_cell_same(const evr_photon_buffer *a, const int *inst_a,
                                            const float *e_a, const evr_photon_buffer *b,
                                            const int *inst_b, const float *e_b, size_t i)
{
    const uint32_t *ga = (const uint32_t *)(a->gbuf + 8 * i + 3),
                   *gb = (const uint32_t *)(b->gbuf + 8 * i + 3),
                   *ea = (const uint32_t *)(e_a + 3 * i), *eb = (const uint32_t *)(e_b + 3 * i);
    if (inst_a[i] != inst_b[i]) return 0;
    if (inst_a[i] < 0) return 1;
    return ga[0] == gb[0] && ga[1] == gb[1] && ga[2] == gb[2] && ea[0] == eb[0] && ea[1] == eb[1] &&
           ea[2] == eb[2];
}

#endif
