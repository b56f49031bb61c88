/* The gather: the ring search over the buffer's cells around a pixel, the Gaussian kernel, the
 * window a hit's disk covers, and the limited estimate (at most max_photons photons). */
#ifndef EVR_CORE_PHOTON_GATHER_H
#define EVR_CORE_PHOTON_GATHER_H

#include <stddef.h>
#include <stdint.h>
#include "core/photon_buffer.h"

/* Cell k of the ring search: ring 0 is the centre (k = 0), ring r (r >= 1) the 8r cells at
 * Chebyshev distance r, k = (2r-1)^2 .. (2r+1)^2 - 1, starting at (-r, -r) and going round
 * clockwise in image coordinates (right along the top row, down the right column, left along
 * the bottom row, up the left column). Returns the ring. */
EVR_HD static inline int evr_ring_cell(int k, int *dx, int *dy)
{
    if (k <= 0) {
        *dx = 0;
        *dy = 0;
        return 0;
    }
    int r = (int)((sqrtf((float)k) + 1.0f) * 0.5f);
    while ((2 * r + 1) * (2 * r + 1) <= k) r++; /* exact whatever sqrtf rounds to */
    while (r > 1 && (2 * r - 1) * (2 * r - 1) > k) r--;
    int j = k - (2 * r - 1) * (2 * r - 1), side = j / (2 * r), o = j % (2 * r);
    switch (side) {
    case 0:
        *dx = -r + o;
        *dy = -r;
        break;
    case 1:
        *dx = r;
        *dy = -r + o;
        break;
    case 2:
        *dx = r - o;
        *dy = r;
        break;
    default:
        *dx = -r;
        *dy = r - o;
        break;
    }
    return r;
}

/* Gaussian kernel truncated at radius r, sigma = r / 2, normalized so that its integral over the
 * disk of radius r is 1: K(d) = exp(-d^2 / (2 sigma^2)) / (2 pi sigma^2 (1 - exp(-r^2 / (2 sigma^2)))). */
EVR_HD static inline float evr_gauss_kernel(float d2, float r)
{
    float s2 = 0.25f * r * r;
    if (!(d2 <= r * r) || !(r > 0.0f)) return 0.0f;
    return expf(-d2 / (2.0f * s2)) / (2.0f * EVR_PI * s2 * (1.0f - expf(-(r * r) / (2.0f * s2))));
}

typedef struct {
    float radius;     /* distance filter r (world units): photons farther away are skipped */
    int max_photons;  /* the search stops growing at this many photons (see evr_photon_gather);
                         * 0: no limit, every photon of the disk (the fixed-point sum below) */
    int max_window;   /* the window's half size in pixels is at most this */
    float normal_cos; /* photons whose normal differs more (cosine below) are skipped */
    float
        flux_scale; /* max_photons 0: fixed-point quanta per unit of flux (evr_gather_flux_scale) */
} evr_gather_params;

/* One cell's share of a gather: the photons of buffer cell (x, y) (anywhere: a cell outside the
 * buffer has none) within sqrt(lim2) of p whose normal is within normal_cos of n add their
 * Gaussian-weighted flux to acc (in layer order); with the camera's view of the cells, the
 * kernel's weight over the surface the cell shows (if it is like the query's) adds to *area_w.
 * Returns the photons taken. */
EVR_HD static inline int evr_photon_gather_cell(const evr_photon_buffer *b, int x, int y, evr_v3 p,
                                                evr_v3 n, float lim2, float normal_cos, float s2,
                                                float acc[3], float *area_w)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    int l, nl, used = 0;
    if (x < 0 || y < 0 || x >= b->width || y >= b->height) return 0;
    size_t i = (size_t)y * (size_t)b->width + (size_t)x;
    if (b->gbuf) { /* the kernel's integral over the surfaces the camera sees here */
        const float *g = b->gbuf + 8 * i;
        evr_v3 d = evr_v3_make(g[0] - p.x, g[1] - p.y, g[2] - p.z);
        float d2 = evr_v3_dot(d, d);
        if (evr_cell_area_reaches(g, d2, lim2) &&
            g[3] * n.x + g[4] * n.y + g[5] * n.z >= normal_cos)
            *area_w += evr_cell_area_weight(g, d2, s2);
    }
    nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        evr_v3 d = evr_v3_make(ph->p[0] - p.x, ph->p[1] - p.y, ph->p[2] - p.z);
        float d2 = evr_v3_dot(d, d);
        if (d2 > lim2) continue;
        if (ph->n[0] * n.x + ph->n[1] * n.y + ph->n[2] * n.z < normal_cos) continue;
        float w = expf(-d2 / (2.0f * s2));
        acc[0] += w * ph->flux[0];
        acc[1] += w * ph->flux[1];
        acc[2] += w * ph->flux[2];
        used++;
    }
    return used;
}

/* The window of a gather at a hit seen at distance cam_dist through image pixel (px, py): its
 * centre cell, its half size h in cells (ceil(r / pixel size at the hit) + 1, at most
 * max_window: nearer points project farther out), the pixel size at the hit, r, r^2, sigma^2. */
typedef struct {
    int cx, cy, h;
    float pix, r, r2, s2;
} evr_gather_window;

EVR_HD static inline evr_gather_window evr_photon_gather_window(const evr_photon_buffer *b,
                                                                const evr_camera_intr *cam, int px,
                                                                int py, float cam_dist,
                                                                const evr_gather_params *gp)
{
    evr_gather_window w;
    const float r = gp->radius;
    w.r = r;
    w.r2 = r * r;
    w.s2 = 0.25f * w.r2;
    w.pix = evr_camera_pixel_size(cam, cam_dist);
    float hf = ceilf(r / w.pix) + 1.0f;
    w.h = hf > (float)gp->max_window ? gp->max_window : (int)hf;
    w.cx = px + b->margin;
    w.cy = py + b->margin;
    return w;
}

/* After the search stopped at ring stop (max photons reached): the disk the rings searched surely
 * cover (radius stop pixel sizes, at least half a pixel, at most r), returned as its radius^2,
 * and the rings that hold all of it (*rings: p lies anywhere in its pixel, one ring further). */
EVR_HD static inline float evr_photon_gather_shrink(const evr_gather_window *w, int stop,
                                                    int *rings)
{
    float rho = fminf(w->r, fmaxf((float)stop, 0.5f) * w->pix);
    *rings = stop + 1 < w->h ? stop + 1 : w->h;
    return rho * rho;
}

/* The irradiance from the sums over the disk of radius^2 lim2: the Gaussian's integral over the
 * disk, scaled by the share of the disk on surfaces like the query's where the disk spans enough
 * cells to measure it (the camera's view of the cells). */
EVR_HD static inline void evr_photon_gather_finish(const evr_photon_buffer *b,
                                                   const evr_gather_window *w, float lim2,
                                                   const float acc[3], float area_w, float e_rgb[3])
{
    float z = 2.0f * EVR_PI * w->s2 * (1.0f - expf(-lim2 / (2.0f * w->s2)));
    if (b->gbuf && lim2 >= 9.0f * w->pix * w->pix) z *= fminf(fmaxf(area_w / z, 0.25f), 1.25f);
    float inv = z > 0.0f ? 1.0f / z : 0.0f;
    e_rgb[0] = acc[0] * inv;
    e_rgb[1] = acc[1] * inv;
    e_rgb[2] = acc[2] * inv;
}

/* Sums the photons of rings 0 .. rings of the window around cell (cx, cy) that lie within
 * sqrt(lim2) of p with a normal within the cosine; stops in the cell where max photons are
 * reached (returns the ring where it stopped in *stop_ring, or -1 when it did not stop). */
EVR_HD static inline int evr_photon_gather_rings(const evr_photon_buffer *b, int cx, int cy,
                                                 int rings, evr_v3 p, evr_v3 n, float lim2,
                                                 float normal_cos, float s2, int max, float acc[3],
                                                 int *stop_ring, float *area_w)
{
    int r, side, o, used = 0;
    acc[0] = acc[1] = acc[2] = 0.0f;
    *stop_ring = -1;
    *area_w = 0.0f;
    /* the cells in evr_ring_cell's order, walked directly (no square root and division per cell) */
    used += evr_photon_gather_cell(b, cx, cy, p, n, lim2, normal_cos, s2, acc, area_w);
    if (used >= max) {
        *stop_ring = 0;
        return used;
    }
    for (r = 1; r <= rings; r++) {
        for (side = 0; side < 4; side++) {
            for (o = 0; o < 2 * r; o++) {
                int dx = side == 0 ? -r + o : side == 1 ? r : side == 2 ? r - o : -r;
                int dy = side == 0 ? -r : side == 1 ? -r + o : side == 2 ? r : r - o;
                used += evr_photon_gather_cell(b, cx + dx, cy + dy, p, n, lim2, normal_cos, s2, acc,
                                               area_w);
                if (used >= max) {
                    *stop_ring = r;
                    return used;
                }
            }
        }
    }
    return used;
}

/* Irradiance at surface point p (normal n, seen at distance cam_dist from the camera through
 * image pixel (px, py)) from the buffer. The window (evr_photon_gather_window) is searched ring
 * by ring from the centre; photons farther than r or whose normal differs more than normal_cos
 * are skipped; weights are the Gaussian kernel (sigma = r / 2) normalized over the disk searched.
 * When max_photons is reached in ring k, the disk shrinks to the one that rings 0 .. k surely
 * cover (evr_photon_gather_shrink) and the estimate is every photon in that disk: on a surface
 * seen at a grazing angle the window reaches far along the surface but not across, and the
 * farthest photon taken would overstate the disk. Returns the photons used. */
EVR_HD static inline int evr_photon_gather(const evr_photon_buffer *b, const evr_camera_intr *cam,
                                           int px, int py, evr_v3 p, evr_v3 n, float cam_dist,
                                           const evr_gather_params *gp, float e_rgb[3])
{
    const evr_gather_window w = evr_photon_gather_window(b, cam, px, py, cam_dist, gp);
    float acc[3], lim2 = w.r2, area_w;
    int stop, used;
    const int max = gp->max_photons > 0 ? gp->max_photons : 0x7fffffff; /* 0: no limit */
    used = evr_photon_gather_rings(b, w.cx, w.cy, w.h, p, n, lim2, gp->normal_cos, w.s2, max, acc,
                                   &stop, &area_w);
    if (stop >= 0) { /* the limit: the disk the rings searched cover, all of its photons */
        int rings;
        lim2 = evr_photon_gather_shrink(&w, stop, &rings);
        used = evr_photon_gather_rings(b, w.cx, w.cy, rings, p, n, lim2, gp->normal_cos, w.s2,
                                       0x7fffffff, acc, &stop, &area_w);
    }
    evr_photon_gather_finish(b, &w, lim2, acc, area_w, e_rgb);
    return used;
}

#endif
