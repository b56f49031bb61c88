/* The event pipeline's estimate without a limit, in fixed point (max_photons 0).
 *
 * Every photon of the window within r whose normal is within the cosine adds its Gaussian-
 * weighted flux, every view of a cell its weighted area, as the limited search does; but each
 * term is rounded to an integer (evr_fix) and the terms are summed modulo 2^64. Such a sum does
 * not depend on the order of its terms, and a term depends only on the cell and the gather
 * point. So the sum over a segment's end buffer is the sum over its start buffer plus the terms
 * of the cells that changed minus their old terms, bit for bit (evr_photon_gather_delta): a
 * pixel whose surface point stays updates its indirect light from the cells the moving objects
 * changed instead of walking its whole window again, and gets exactly what a fresh gather gets
 * (brute force and change-driven sampling stay identical). The flux is summed as the luminance
 * of the light the point sends back (its weights c = the luminance's coefficients times the
 * point's diffuse weight k, per RGB channel): one sum, what the pixel model takes. Dot products
 * and distances are written with products no compiler fuses with the sums (evr_dot_rn), so that
 * the terms are the same bits wherever they are computed (and on the CPU and GPU alike). */
#ifndef EVR_CORE_PHOTON_FIXED_H
#define EVR_CORE_PHOTON_FIXED_H

#include <stddef.h>
#include <stdint.h>
#include "core/photon_gather.h"

typedef struct {
    uint64_t a; /* weighted luminance flux, in units of 1 / flux_scale */
    uint64_t w; /* the view's weighted area, in units of sigma^2 / 2^32 */
} evr_gather_sum;

/* Fixed-point quanta per unit of flux for a pass of `photons` photons carrying total_power
 * (luminance flux): 2^40 quanta for the mean photon, whose flux is total_power / photons (the
 * photons are split by power), so a window of thousands of photons a few hundred times brighter
 * than the mean stays far below 2^64, and a photon 10^-6 of the mean still counts. The scale is
 * the run's, from its first pass: a term is clamped at 2^52 quanta (evr_fix), so a photon over
 * about 4000 times that pass's mean photon (lights that brighten that much later) would count
 * for less than it carries. */
EVR_HD static inline float evr_gather_flux_scale(float total_power, uint32_t photons)
{
    float mean = photons > 0u ? total_power / (float)photons : 0.0f;
    return mean > 0.0f && mean < 1e30f ? 1099511627776.0f / mean : 1.0f;
}

/* A term in fixed point: rounded to the nearest integer, at most 2^52 (a window of 4096 such
 * terms still fits), 0 for anything not positive (or NaN). Through int64_t: one instruction on
 * x86-64, where a float to uint64_t conversion is a branch and two. */
EVR_HD static inline uint64_t evr_fix(float v)
{
    return v > 0.0f
               ? (uint64_t)(int64_t)((v < 4503599627370496.0f ? v : 4503599627370496.0f) + 0.5f)
               : 0u;
}

/* a.b, rounded the same by every compiler: three products, two additions, left to right */
EVR_HD static inline float evr_dot_rn(float ax, float ay, float az, float bx, float by, float bz)
{
    return EVR_MUL_RN(ax, bx) + EVR_MUL_RN(ay, by) + EVR_MUL_RN(az, bz);
}

/* A gather's query: the point, its normal, the luminance weights of the flux (c), the distance
 * filter r^2, the normal cosine, the flux scale and the kernel's constants. */
typedef struct {
    evr_v3 p, n, c;
    float r2, normal_cos, flux_scale;
    float e, area_scale; /* -1 / (2 sigma^2), 2^32 / sigma^2 */
    float s2;            /* sigma^2 */
} evr_sum_query;

/* Adds cell i's terms for query q to s (sub: subtracts them). Returns the photons taken. */
EVR_HD static inline int evr_photon_cell_sum(const evr_photon_buffer *b, size_t i,
                                             const evr_sum_query *q, evr_gather_sum *s, int sub)
{
    const size_t npix = (size_t)b->width * (size_t)b->height;
    const float e = q->e, area_scale = q->area_scale;
    const evr_v3 p = q->p, n = q->n;
    uint64_t a = 0, aw = 0;
    int l, nl, used = 0;
    if (b->gbuf) {
        const float *g = b->gbuf + 8 * i;
        float dx = g[0] - p.x, dy = g[1] - p.y, dz = g[2] - p.z;
        float d2 = evr_dot_rn(dx, dy, dz, dx, dy, dz),
              c = evr_dot_rn(g[3], g[4], g[5], n.x, n.y, n.z);
        if (evr_cell_area_reaches(g, d2, q->r2) && c >= q->normal_cos)
            aw = evr_fix(EVR_MUL_RN(evr_cell_area_weight(g, d2, q->s2), area_scale));
    }
    nl = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers;
    for (l = 0; l < nl; l++) {
        const evr_photon *ph = &b->slots[(size_t)l * npix + i];
        float dx = ph->p[0] - p.x, dy = ph->p[1] - p.y, dz = ph->p[2] - p.z;
        float d2 = evr_dot_rn(dx, dy, dz, dx, dy, dz),
              c = evr_dot_rn(ph->n[0], ph->n[1], ph->n[2], n.x, n.y, n.z);
        if (d2 > q->r2 || c < q->normal_cos) continue;
        const float lum = evr_dot_rn(ph->flux[0], ph->flux[1], ph->flux[2], q->c.x, q->c.y, q->c.z);
        a += evr_fix(EVR_MUL_RN(EVR_MUL_RN(expf(EVR_MUL_RN(d2, e)), q->flux_scale), lum));
        used++;
    }
    if (sub) {
        s->a -= a;
        s->w -= aw;
    } else {
        s->a += a;
        s->w += aw;
    }
    return used;
}

/* The cells of window w inside buffer b: columns x0 .. x1 - 1 of rows y0 .. y1 - 1. */
EVR_HD static inline void evr_gather_window_cells(const evr_photon_buffer *b,
                                                  const evr_gather_window *w, int *x0, int *y0,
                                                  int *x1, int *y1)
{
    *x0 = w->cx - w->h > 0 ? w->cx - w->h : 0;
    *y0 = w->cy - w->h > 0 ? w->cy - w->h : 0;
    *x1 = w->cx + w->h + 1 < b->width ? w->cx + w->h + 1 : b->width;
    *y1 = w->cy + w->h + 1 < b->height ? w->cy + w->h + 1 : b->height;
}

/* The fixed-point sums of query q over window w of b. Returns the photons taken. */
EVR_HD static inline int evr_photon_gather_sum(const evr_photon_buffer *b,
                                               const evr_gather_window *w, const evr_sum_query *q,
                                               evr_gather_sum *s)
{
    int x0, y0, x1, y1, x, y, used = 0;
    evr_gather_sum acc = {0, 0}; /* a local: kept in registers, not stored back cell by cell */
    evr_gather_window_cells(b, w, &x0, &y0, &x1, &y1);
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++)
            used += evr_photon_cell_sum(b, (size_t)y * (size_t)b->width + (size_t)x, q, &acc, 0);
    *s = acc;
    return used;
}

/* The luminance from the sums, normalized as evr_photon_gather_finish normalizes its float sums. */
EVR_HD static inline float evr_photon_gather_sum_finish(const evr_photon_buffer *b,
                                                        const evr_gather_window *w,
                                                        const evr_gather_params *gp,
                                                        const evr_gather_sum *s)
{
    const float acc[3] = {(float)s->a / gp->flux_scale, 0.0f, 0.0f};
    float e[3];
    evr_photon_gather_finish(b, w, w->r2, acc, (float)s->w * (w->s2 / 4294967296.0f), e);
    return e[0];
}

/* The cells that changed between two buffers, listed row by row: row y's changed cells are
 * entries base[y] .. base[y + 1] - 1 of x (their columns, ascending), and those of them in
 * columns x0 .. x1 - 1 are entries base[y] + before[y (w + 1) + x0] .. base[y] + before[y (w + 1)
 * + x1] - 1, where before[y (w + 1) + x] counts row y's changed cells left of column x (w: the
 * buffer's width). Built per segment by the backends (evr_changed_cells_from_sat on the CPU). */
typedef struct {
    const uint32_t *before; /* (w + 1) per row */
    const uint32_t *base;   /* h + 1 */
    const uint32_t *x;
} evr_changed_cells;

/* The sums of a gather at p (normal n) over buffer cur, from its sums s over buffer prev (the
 * same point, the same window): the terms of every changed cell of the window (ch: the cells
 * that differ from prev to cur, or more: a listed cell that did not change adds nothing), those
 * of cur added and those of prev taken away. Bit for bit the sums of a fresh gather over cur. */
EVR_HD static inline void evr_photon_gather_delta(const evr_photon_buffer *cur,
                                                  const evr_photon_buffer *prev,
                                                  const evr_changed_cells *ch,
                                                  const evr_gather_window *w,
                                                  const evr_sum_query *q, evr_gather_sum *s)
{
    const size_t W = (size_t)cur->width + 1;
    int x0, y0, x1, y1, y;
    evr_gather_sum acc = *s;
    evr_gather_window_cells(cur, w, &x0, &y0, &x1, &y1);
    for (y = y0; y < y1; y++) {
        const uint32_t *row = ch->before + (size_t)y * W, b = ch->base[y], k1 = b + row[x1];
        uint32_t k;
        for (k = b + row[x0]; k < k1; k++) {
            const size_t i = (size_t)y * (size_t)cur->width + (size_t)ch->x[k];
            evr_photon_cell_sum(cur, i, q, &acc, 0);
            evr_photon_cell_sum(prev, i, q, &acc, 1);
        }
    }
    *s = acc;
}

#endif
