/* Mip pyramids (texture_mips.h): a box filter with exact area weights, so that odd sizes neither
 * drop a row nor weigh one twice. */
#include <stdio.h>
#include <stdlib.h>

#include "core/render_scene.h"
#include "scene/texture_mips.h"

/* The taps of one axis from n source texels to m = evr_mip_size(n, 1) texels: destination i
 * covers [i n / m, (i+1) n / m) in source texels; scaled by m, source j covers [j m, (j+1) m) and
 * the overlap is an integer, the weight overlap / n. At most three taps (n = 2m + 1). */
typedef struct {
    int first, count;
    float w[3];
} axis_taps;

static void make_taps(int n, int m, axis_taps *taps)
{
    for (int i = 0; i < m; i++) {
        long lo = (long)i * n, hi = (long)(i + 1) * n;
        int j = (int)(lo / m);
        taps[i].first = j;
        taps[i].count = 0;
        for (; (long)j * m < hi && taps[i].count < 3; j++) {
            long a = (long)j * m > lo ? (long)j * m : lo;
            long b = (long)(j + 1) * m < hi ? (long)(j + 1) * m : hi;
            taps[i].w[taps[i].count++] = (float)((double)(b - a) / (double)n);
        }
    }
}

/* One level from the one before: src (sw texels wide) into dst (dw x dh). */
static void downsample(const float *src, int sw, float *dst, int dw, int dh, const axis_taps *tx,
                       const axis_taps *ty)
{
    for (int y = 0; y < dh; y++) {
        for (int x = 0; x < dw; x++) {
            float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            for (int b = 0; b < ty[y].count; b++) {
                const float *row = src + 4 * (size_t)(ty[y].first + b) * (size_t)sw;
                for (int a = 0; a < tx[x].count; a++) {
                    const float *p = row + 4 * (size_t)(tx[x].first + a);
                    const float wt = ty[y].w[b] * tx[x].w[a];
                    for (int c = 0; c < 4; c++) acc[c] += wt * p[c];
                }
            }
            for (int c = 0; c < 4; c++) dst[4 * ((size_t)y * (size_t)dw + (size_t)x) + c] = acc[c];
        }
    }
}

evr_status evr_texture_build_mips(evr_texture *t, evr_error *err)
{
    int levels = 1;
    size_t total = 0;
    while (evr_mip_size(t->width, levels - 1) > 1 || evr_mip_size(t->height, levels - 1) > 1)
        levels++;
    for (int k = 0; k < levels; k++)
        total += (size_t)evr_mip_size(t->width, k) * (size_t)evr_mip_size(t->height, k);
    float *rgba = realloc(t->rgba, total * 4 * sizeof(float));
    axis_taps *tx = malloc((size_t)evr_mip_size(t->width, 1) * sizeof *tx);
    axis_taps *ty = malloc((size_t)evr_mip_size(t->height, 1) * sizeof *ty);
    if (rgba) t->rgba = rgba; /* level 0 kept either way */
    if (!rgba || !tx || !ty) {
        free(tx);
        free(ty);
        snprintf(err->msg, sizeof err->msg, "out of memory building a %d x %d texture's mip levels",
                 t->width, t->height);
        return EVR_ERR_NOMEM;
    }
    float *src = t->rgba;
    for (int k = 0; k + 1 < levels; k++) {
        const int sw = evr_mip_size(t->width, k), sh = evr_mip_size(t->height, k);
        const int dw = evr_mip_size(t->width, k + 1), dh = evr_mip_size(t->height, k + 1);
        float *dst = src + 4 * (size_t)sw * (size_t)sh;
        make_taps(sw, dw, tx);
        make_taps(sh, dh, ty);
        downsample(src, sw, dst, dw, dh, tx, ty);
        src = dst;
    }
    free(tx);
    free(ty);
    t->levels = levels;
    return EVR_OK;
}
