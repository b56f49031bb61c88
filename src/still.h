/* One image of a scene at one time (evray still): direct light only, direct plus photon-mapped
 * indirect light (the image-space photon buffer of src/core/photon.h), or direct plus a
 * brute-force path-traced indirect term, the reference for the photon estimate. The direct term
 * is the event pipeline's shading (src/core/shading.h) through the pixel centre; the indirect
 * term is added in linear RGB. Implementation: src/cpu/still.c (Embree, all cores). */
#ifndef EVR_STILL_H
#define EVR_STILL_H

#include <stdint.h>
#include "evray.h"
#include "cpu/photon_pass.h"

typedef enum { EVR_GI_NONE = 0, EVR_GI_PHOTON = 1, EVR_GI_PATH = 2 } evr_gi_mode;

typedef struct {
    int width, height;
    double time;                   /* seconds into the animation */
    const char *camera;            /* NULL: the first */
    evr_gi_mode gi;
    int spp;                       /* path: paths per pixel */
    uint32_t photons;              /* photon: photons per pass (0: 8 per pixel) */
    float gather_radius;           /* photon: distance filter r, world units (<= 0: 2% of the scene's diagonal) */
    int gather_max;                /* photon: photons per estimate at most */
    int gather_window;             /* photon: the window's half size at most, pixels */
    float gather_normal_cos;       /* photon: normals must agree to this cosine */
    int photon_layers;             /* photon: photons per pixel of the buffer */
    int gather_area;               /* photon: normalize over the surface the camera sees (evr_photon_gbuffer) */
    int auto_layers;               /* photon: double the layers (up to 64) while > 3% of the photons collide */
    int max_bounces;               /* indirect bounces (both methods) */
    float ambient;
    uint64_t seed;
    int threads;                   /* 0: all cores */
} evr_still_params;

void evr_still_defaults(evr_still_params *p);

typedef struct {
    int width, height;
    float *rgb;                    /* width * height * 3 linear radiance, rows top to bottom */
    float *direct;                 /* the direct term alone (same layout) */
    int *instance;                 /* scene instance seen at each pixel's centre, -1: none */
    evr_photon_stats photon;       /* photon mode: the pass */
    float gather_radius;           /* the radius used */
    int photon_layers;             /* the layers used */
    double photons_per_estimate;   /* mean photons per gather over hit pixels */
    double seconds_setup, seconds_photons, seconds_shading;
    int threads;
} evr_still_result;

evr_status evr_still_render(const evr_scene *s, const evr_still_params *p, evr_still_result *out, evr_error *err);
void evr_still_result_free(evr_still_result *r);

#endif
