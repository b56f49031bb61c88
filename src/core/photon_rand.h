/* The low-discrepancy numbers of a photon: a pure function of its emitter and number, so every
 * segment traces the same photons. */
#ifndef EVR_CORE_PHOTON_RAND_H
#define EVR_CORE_PHOTON_RAND_H

#include <stdint.h>
#include "core/rng.h"

/* Radical inverse of i in a prime base (Halton), in [0, 1). */
EVR_HD static inline float evr_radical_inverse(uint32_t i, uint32_t base)
{
    float inv = 1.0f / (float)base, f = inv, r = 0.0f;
    while (i > 0) {
        r += (float)(i % base) * f;
        i /= base;
        f *= inv;
    }
    return fminf(r, 0.99999994f);
}

/* Dimension dim of photon j of emitter e: dims 0-4 (the emission) are the Halton sequence
 * (bases 2, 3, 5, 7, 11) at index j + 1, each shifted by a fixed per-emitter offset (Cranley-
 * Patterson rotation) so that lights do not share points; later dims (the bounces) are
 * counter-based hashes of (seed, e, j, dim). Either way a pure function of the photon number:
 * the same photons every segment. */
EVR_HD static inline float evr_photon_rand(uint64_t seed, int e, uint32_t j, int dim)
{
    if (dim < 5) {
        const uint32_t bases[5] = {2, 3, 5, 7, 11};
        float x =
            evr_radical_inverse(j + 1u, bases[dim]) +
            evr_uniform(evr_hash4(seed, (uint64_t)e, 0x73686966ull /* "shif" */, (uint64_t)dim));
        x -= floorf(x);
        return fminf(x, 0.99999994f);
    }
    return evr_uniform(evr_hash4(seed ^ 0x70686f746f6eull /* "photon" */, (uint64_t)e, (uint64_t)j,
                                 (uint64_t)dim));
}

/* Normalized segment time of photon j: f0 + (f1 - f0) * frac(j * golden ratio). */
EVR_HD static inline float evr_photon_time(uint32_t j, float f0, float f1)
{
    float g = (float)j * 0.61803398875f;
    g -= floorf(g);
    return f0 + (f1 - f0) * g;
}

#endif
