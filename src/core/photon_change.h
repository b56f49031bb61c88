/* What changed between two photon buffers and whether it matters to a pixel: cells compared bit
 * for bit, their summed-area table, and the test that a change can move a gather. */
#ifndef EVR_CORE_PHOTON_CHANGE_H
#define EVR_CORE_PHOTON_CHANGE_H

#include <stddef.h>
#include <stdint.h>
#include "core/photon_fixed.h"

/* Whether cell i holds the same photons and the same view in buffers a and b (bit for bit). */
EVR_HD static inline int evr_photon_cell_same(const evr_photon_buffer *a,
                                              const evr_photon_buffer *b, size_t i)
{
    size_t npix = (size_t)a->width * (size_t)a->height;
    uint32_t n = a->count[i] < (uint32_t)a->layers ? a->count[i] : (uint32_t)a->layers, l;
    int k;
    if (a->count[i] != b->count[i]) return 0;
    for (l = 0; l < n; l++) {
        const uint32_t *pa = (const uint32_t *)&a->slots[(size_t)l * npix + i],
                       *pb = (const uint32_t *)&b->slots[(size_t)l * npix + i];
        for (k = 0; k < (int)(sizeof(evr_photon) / 4); k++)
            if (pa[k] != pb[k]) return 0;
    }
    if (a->gbuf && b->gbuf) {
        const uint32_t *ga = (const uint32_t *)(a->gbuf + 8 * i),
                       *gb = (const uint32_t *)(b->gbuf + 8 * i);
        for (k = 0; k < 8; k++)
            if (ga[k] != gb[k]) return 0;
    }
    return 1;
}

/* The changed cells in columns x0 .. x1 - 1 of rows y0 .. y1 - 1 of a w-wide buffer, from its
 * summed-area table (w + 1 entries a row, row 0 and column 0 zero). */
EVR_HD static inline uint32_t evr_sat_count(const uint32_t *sat, int w, int x0, int y0, int x1,
                                            int y1)
{
    const size_t W = (size_t)w + 1;
    return sat[(size_t)y1 * W + (size_t)x1] - sat[(size_t)y0 * W + (size_t)x1] -
           sat[(size_t)y1 * W + (size_t)x0] + sat[(size_t)y0 * W + (size_t)x0];
}

/* Whether any cell the gather of image pixel (x, y) may read (window cells around it) changed:
 * sat is the summed-area table, (w + 1) x (h + 1), of the changed cells of a w x h buffer with
 * the given guard band. */
EVR_HD static inline int evr_photon_window_changed(const uint32_t *sat, int w, int h, int margin,
                                                   int window, int x, int y)
{
    int x0 = x + margin - window, x1 = x + margin + window + 1, y0 = y + margin - window,
        y1 = y + margin + window + 1;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > w) x1 = w;
    if (y1 > h) y1 = h;
    if (x0 >= x1 || y0 >= y1) return 0;
    return evr_sat_count(sat, w, x0, y0, x1, y1) != 0;
}

/* Whether buffer cell i (of b, or of a buffer of its shape) holds anything a gather at point p
 * (normal n) could take within sqrt(lim2): a photon close enough with a normal within the
 * cosine, or the camera's view of the cell (its weight in the normalization), tested as
 * evr_photon_gather_cell tests them. */
EVR_HD static inline int evr_photon_cell_reaches(const evr_photon_buffer *b, size_t i, evr_v3 p,
                                                 evr_v3 n, float lim2, float normal_cos)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    int l, nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    /* either way of computing the distance and the cosine: evr_photon_gather_cell's (the limited
     * search) or evr_photon_cell_sum's (evr_dot_rn), which may differ in the last bit */
    if (b->gbuf) {
        const float *g = b->gbuf + 8 * i;
        evr_v3 d = evr_v3_make(g[0] - p.x, g[1] - p.y, g[2] - p.z);
        if ((evr_cell_area_reaches(g, evr_v3_dot(d, d), lim2) &&
             g[3] * n.x + g[4] * n.y + g[5] * n.z >= normal_cos) ||
            (evr_cell_area_reaches(g, evr_dot_rn(d.x, d.y, d.z, d.x, d.y, d.z), lim2) &&
             evr_dot_rn(g[3], g[4], g[5], n.x, n.y, n.z) >= normal_cos))
            return 1;
    }
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        evr_v3 d = evr_v3_make(ph->p[0] - p.x, ph->p[1] - p.y, ph->p[2] - p.z);
        if (evr_v3_dot(d, d) <= lim2 &&
            ph->n[0] * n.x + ph->n[1] * n.y + ph->n[2] * n.z >= normal_cos)
            return 1;
        if (evr_dot_rn(d.x, d.y, d.z, d.x, d.y, d.z) <= lim2 &&
            evr_dot_rn(ph->n[0], ph->n[1], ph->n[2], n.x, n.y, n.z) >= normal_cos)
            return 1;
    }
    return 0;
}

/* Whether the change from buffer prev to cur can move the gather at point p (normal n, seen at
 * distance cam_dist through image pixel (px, py)); sat: the summed-area table of the cells that
 * changed. It cannot when no changed cell of the gather's window holds, before or after, anything
 * the gather could take at its full radius r (evr_photon_cell_reaches): every cell it reads
 * then adds the same, the search stops in the same ring, and the estimate is the same bit for
 * bit. (Photons the moving box sends elsewhere change cells all over the image; most windows
 * see such a change and few are reached by it.) */
EVR_HD static inline int evr_photon_gather_moved(const evr_photon_buffer *cur,
                                                 const evr_photon_buffer *prev, const uint32_t *sat,
                                                 const evr_camera_intr *cam,
                                                 const evr_gather_params *gp, int px, int py,
                                                 evr_v3 p, evr_v3 n, float cam_dist)
{
    const evr_gather_window w = evr_photon_gather_window(cur, cam, px, py, cam_dist, gp);
    int x0 = w.cx - w.h, x1 = w.cx + w.h + 1, y0 = w.cy - w.h, y1 = w.cy + w.h + 1, x, y;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > cur->width) x1 = cur->width;
    if (y1 > cur->height) y1 = cur->height;
    for (y = y0; y < y1; y++) {
        /* the row's changed cells, from the table: none, and the row is passed over */
        if (evr_sat_count(sat, cur->width, x0, y, x1, y + 1) == 0) continue;
        for (x = x0; x < x1; x++) {
            if (evr_sat_count(sat, cur->width, x, y, x + 1, y + 1) == 0) continue;
            const size_t i = (size_t)y * (size_t)cur->width + (size_t)x;
            if (evr_photon_cell_reaches(cur, i, p, n, w.r2, gp->normal_cos) ||
                evr_photon_cell_reaches(prev, i, p, n, w.r2, gp->normal_cos))
                return 1;
        }
    }
    return 0;
}

#endif
