/* Deterministic noise and painting for the built-in scenes' textures (demo_paint.h). */
#include <math.h>
#include <stdlib.h>

#include "scene/demo_paint.h"

uint32_t evr_demo_hash_u32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

double evr_demo_rng_uniform(evr_demo_rng *r)
{
    r->s += 0x9e3779b9u;
    return evr_demo_hash_u32(r->s) / 4294967296.0;
}

double evr_demo_rng_range(evr_demo_rng *r, double a, double b)
{
    return a + (b - a) * evr_demo_rng_uniform(r);
}

static double lattice(int ix, int iy, uint32_t seed)
{
    return evr_demo_hash_u32((uint32_t)ix * 0x8da6b343u ^
                             evr_demo_hash_u32((uint32_t)iy * 0xd8163841u ^ seed * 0xcb1ab31fu)) /
           4294967295.0;
}

double evr_demo_smooth01(double t) { return t * t * (3.0 - 2.0 * t); }

double evr_demo_clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

double evr_demo_smoothstep(double a, double b, double x)
{
    return evr_demo_smooth01(evr_demo_clamp((x - a) / (b - a), 0.0, 1.0));
}

double evr_demo_vnoise(double x, double y, uint32_t seed, int period)
{
    double fx = floor(x), fy = floor(y);
    int ix = (int)fx, iy = (int)fy, ix1;
    double tx = evr_demo_smooth01(x - fx), ty = evr_demo_smooth01(y - fy);
    double a, b, c, d;
    if (period > 0) {
        ix %= period;
        if (ix < 0) ix += period;
        ix1 = (ix + 1) % period;
    } else {
        ix1 = ix + 1;
    }
    a = lattice(ix, iy, seed);
    b = lattice(ix1, iy, seed);
    c = lattice(ix, iy + 1, seed);
    d = lattice(ix1, iy + 1, seed);
    return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

double evr_demo_fbm(double x, double y, uint32_t seed, int octaves, int period)
{
    double sum = 0.0, amp = 1.0, norm = 0.0;
    int k;
    for (k = 0; k < octaves; k++) {
        sum += amp * evr_demo_vnoise(x, y, seed + (uint32_t)k * 101u, period);
        norm += amp;
        amp *= 0.5;
        x *= 2.0;
        y *= 2.0;
        if (period > 0) period *= 2;
    }
    return sum / norm;
}

int evr_demo_image_init(evr_demo_image *im, int w, int h, int wrap_x)
{
    im->w = w;
    im->h = h;
    im->wrap_x = wrap_x;
    im->rgb = malloc(sizeof(double) * 3 * (size_t)w * (size_t)h);
    im->mask = calloc((size_t)w * (size_t)h, sizeof(float));
    return im->rgb && im->mask;
}

void evr_demo_image_free(evr_demo_image *im)
{
    free(im->rgb);
    free(im->mask);
}

void evr_demo_image_set(evr_demo_image *im, int x, int y, const double c[3])
{
    double *p = im->rgb + 3 * ((size_t)y * (size_t)im->w + (size_t)x);
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
}

void evr_demo_image_stroke(evr_demo_image *im, double xa, double ya, double xb, double yb,
                           double r0, double r1, double a0, double a1)
{
    double len = hypot(xb - xa, yb - ya), rmax = r0 > r1 ? r0 : r1;
    int xmin = (int)floor((xa < xb ? xa : xb) - rmax - 2),
        xmax = (int)ceil((xa > xb ? xa : xb) + rmax + 2);
    int ymin = (int)floor((ya < yb ? ya : yb) - rmax - 2),
        ymax = (int)ceil((ya > yb ? ya : yb) + rmax + 2);
    int x, y;
    if (ymin < 0) ymin = 0;
    if (ymax > im->h - 1) ymax = im->h - 1;
    if (!im->wrap_x) {
        if (xmin < 0) xmin = 0;
        if (xmax > im->w - 1) xmax = im->w - 1;
    }
    for (y = ymin; y <= ymax; y++) {
        for (x = xmin; x <= xmax; x++) {
            double px = x + 0.5, py = y + 0.5, t = 0.0, d, r, a, cov;
            int wx = im->wrap_x ? ((x % im->w) + im->w) % im->w : x;
            float *m;
            if (len > 0.0)
                t = evr_demo_clamp(((px - xa) * (xb - xa) + (py - ya) * (yb - ya)) / (len * len),
                                   0.0, 1.0);
            d = hypot(px - (xa + t * (xb - xa)), py - (ya + t * (yb - ya)));
            r = r0 + (r1 - r0) * t;
            a = a0 + (a1 - a0) * t;
            cov = evr_demo_clamp(r + 0.5 - d, 0.0, 1.0) * a;
            m = &im->mask[(size_t)y * (size_t)im->w + (size_t)wx];
            if (cov > *m) *m = (float)cov;
        }
    }
}

void evr_demo_image_apply(evr_demo_image *im, const double c[3])
{
    size_t i, n = (size_t)im->w * (size_t)im->h;
    int k;
    for (i = 0; i < n; i++) {
        double a = im->mask[i];
        if (a <= 0.0) continue;
        for (k = 0; k < 3; k++) im->rgb[3 * i + k] += (c[k] - im->rgb[3 * i + k]) * a;
        im->mask[i] = 0.0f;
    }
}

/* The image as 8-bit pixels (with the mask as alpha when alpha is set), then a texture. */
static int image_texture(evr_gltf *g, evr_demo_image *im, const char *name, int alpha)
{
    const int ch = alpha ? 4 : 3;
    size_t i, n = (size_t)im->w * (size_t)im->h;
    uint8_t *px = malloc(n * (size_t)ch);
    int k, tex;
    if (!px) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (i = 0; i < n; i++) {
        for (k = 0; k < 3; k++)
            px[ch * i + k] = (uint8_t)evr_demo_clamp(floor(im->rgb[3 * i + k] + 0.5), 0.0, 255.0);
        if (alpha)
            px[ch * i + 3] = (uint8_t)evr_demo_clamp(floor(255.0 * im->mask[i] + 0.5), 0.0, 255.0);
    }
    tex = evr_gltf_texture_png(g, name, px, im->w, im->h, ch);
    free(px);
    return tex;
}

int evr_demo_image_texture(evr_gltf *g, evr_demo_image *im, const char *name)
{
    return image_texture(g, im, name, 0);
}

int evr_demo_image_texture_masked(evr_gltf *g, evr_demo_image *im, const char *name)
{
    return image_texture(g, im, name, 1);
}

void evr_demo_mix3(double out[3], const double a[3], const double b[3], double t)
{
    int k;
    for (k = 0; k < 3; k++) out[k] = a[k] + (b[k] - a[k]) * t;
}
