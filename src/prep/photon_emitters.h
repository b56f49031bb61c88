/* The emitters of a photon pass (lights and emissive instances at one time of the segment) and
 * how the photons are split among them: made on the host before every pass, for the CPU's pass
 * and the GPU's alike, and the bookkeeping that lets a pass reuse the previous pass's trails. */
#ifndef EVR_PREP_PHOTON_EMITTERS_H
#define EVR_PREP_PHOTON_EMITTERS_H

#include <stdint.h>
#include "evray.h"
#include "core/photon.h"

/* The emitters of one pass and how the photons are split among them (by power). */
typedef struct {
    evr_photon_emitter *e;
    int n, cap;
    float *cdf; /* cumulative triangle areas of the emissive instances */
    int cdf_n, cdf_cap;
    float total_power; /* luminance flux of all emitters */
    uint32_t
        photons; /* sum of the emitters' counts (== the photons asked for, give or take rounding) */
} evr_photon_emitters;

/* Emitters at normalized segment time f (light positions and emissive areas; bb: a sphere
 * holding the scene at every time of the segment): every light with non-zero power, every instance whose
 * material is emissive (its triangles' world areas at f); photons split by luminance power,
 * each emitter's count fixed by (powers, photons) alone, so a static scene gets the same photons
 * every segment. Reuses em's arrays (zero-initialize em before the first call). */
evr_status evr_photon_emitters_build(const evr_render_scene *rs, float f, evr_photon_bounds bb,
                                     uint32_t photons, evr_photon_emitters *em, evr_error *err);
void evr_photon_emitters_free(evr_photon_emitters *em);
/* dst becomes a copy of src (dst's arrays reused); 0: out of memory (dst unchanged in size). */
int evr_photon_emitters_copy(evr_photon_emitters *dst, const evr_photon_emitters *src);
/* Whether two tables send the same photons: the same emitters, counts and areas. */
int evr_photon_emitters_same(const evr_photon_emitters *a, const evr_photon_emitters *b);

/* The bookkeeping of a pass that records every photon's trail, for the CPU's trails and the GPU's:
 * whether the recorded trails (*valid, made with emitter table *recorded) may be reused by a pass
 * with emitters em; then *recorded and *valid describe this pass's trails. */
int evr_photon_trails_pass(evr_photon_emitters *recorded, int *valid,
                           const evr_photon_emitters *em);

#endif
