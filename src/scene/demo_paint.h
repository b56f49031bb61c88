/* Deterministic noise and a small painter for the built-in scenes' textures (the eye's parts in
 * demo_eye_parts.c, the blink scene's finger): hashing and a counter-based generator, value noise
 * and its fractal sum, and an 8-bit sRGB image painted with soft strokes and handed to the glTF
 * builder as a PNG. The same numbers on every platform. Internal to the library. */
#ifndef EVR_SCENE_DEMO_PAINT_H
#define EVR_SCENE_DEMO_PAINT_H

#include <stdint.h>
#include "scene/gltf_writer.h"

uint32_t evr_demo_hash_u32(uint32_t x);

/* A generator: uniform numbers from the hash of a counter. */
typedef struct {
    uint32_t s;
} evr_demo_rng;

double evr_demo_rng_uniform(evr_demo_rng *r); /* [0, 1) */
double evr_demo_rng_range(evr_demo_rng *r, double a, double b);

double evr_demo_smooth01(double t); /* 3t^2 - 2t^3 */
double evr_demo_clamp(double x, double lo, double hi);
double evr_demo_smoothstep(double a, double b, double x); /* 0 at a, 1 at b, smooth between */

/* Value noise in [0,1]; period > 0 wraps x with that integer period. */
double evr_demo_vnoise(double x, double y, uint32_t seed, int period);
/* Fractal noise in [0,1] (octaves of vnoise, each twice the frequency and half the weight). */
double evr_demo_fbm(double x, double y, uint32_t seed, int octaves, int period);

/* An 8-bit sRGB image being painted, with a coverage mask for strokes. */
typedef struct {
    int w, h, wrap_x;
    double *rgb; /* 0..255, 3 per pixel */
    float *mask;
} evr_demo_image;

/* 0 when out of memory (free the image all the same). wrap_x: strokes wrap around in x. */
int evr_demo_image_init(evr_demo_image *im, int w, int h, int wrap_x);
void evr_demo_image_free(evr_demo_image *im);
void evr_demo_image_set(evr_demo_image *im, int x, int y, const double c[3]);
/* Adds a stroke from (xa,ya) to (xb,yb), radius r0 -> r1, opacity a0 -> a1, to the coverage mask
 * (the maximum is kept, so that overlapping pieces of one stroke do not build up);
 * evr_demo_image_apply then paints the mask in one colour and clears it. */
void evr_demo_image_stroke(evr_demo_image *im, double xa, double ya, double xb, double yb,
                           double r0, double r1, double a0, double a1);
void evr_demo_image_apply(evr_demo_image *im, const double c[3]);
/* The image as a texture of the builder (its index, -1 on failure, recorded in g). */
int evr_demo_image_texture(evr_gltf *g, evr_demo_image *im, const char *name);
/* The same with an alpha channel: the coverage mask as it stands (strokes not yet applied), for
 * cut-outs (alpha-masked materials). */
int evr_demo_image_texture_masked(evr_gltf *g, evr_demo_image *im, const char *name);

void evr_demo_mix3(double out[3], const double a[3], const double b[3], double t);

#endif
