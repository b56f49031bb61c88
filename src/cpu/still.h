/* One image of a scene at one time (evray still): direct light only, direct plus photon-mapped
 * indirect light (the image-space photon buffer of src/core/photon.h), or direct plus a
 * brute-force path-traced indirect term, the reference for the photon estimate. The direct term
 * is the event pipeline's shading (src/core/shading.h) through the pixel centre; the indirect
 * term is added in linear RGB. Implementation: src/cpu/still.c (Embree, all cores). */
#ifndef EVR_CPU_STILL_H
#define EVR_CPU_STILL_H

#include <stdint.h>
#include "evray.h"
#include "evray_experimental.h"
#include "cpu/photon_pass.h"

/* evr_gi_mode, evr_still_params and evr_still_defaults are in evray_experimental.h, with the
 * program's view of a result (evr_still_image_render). */

typedef struct {
    int width, height;
    float *rgb;                  /* width * height * 3 linear radiance, rows top to bottom */
    float *direct;               /* the direct term alone (same layout) */
    int *instance;               /* scene instance seen at each pixel's centre, -1: none */
    evr_photon_stats photon;     /* photon mode: the pass */
    float gather_radius;         /* the radius used */
    int photon_layers;           /* the layers used */
    double photons_per_estimate; /* mean photons per gather over hit pixels */
    double seconds_setup, seconds_photons, seconds_shading;
    int threads;
} evr_still_result;

evr_status evr_still_render(const evr_scene *s, const evr_still_params *p, evr_still_result *out,
                            evr_error *err);
void evr_still_result_free(evr_still_result *r);

#endif
