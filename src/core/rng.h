/* Counter-based random numbers: a value is a pure function of (seed, a, b, counter), so results
 * do not depend on thread count, tile order or backend. The mixer is SplitMix64's finalizer. */
#ifndef EVR_CORE_RNG_H
#define EVR_CORE_RNG_H

#include <math.h>
#include <stdint.h>
#include "core/hd.h"

EVR_HD static inline uint64_t evr_mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

EVR_HD static inline uint64_t evr_hash4(uint64_t seed, uint64_t a, uint64_t b, uint64_t counter)
{
    return evr_mix64(evr_mix64(evr_mix64(evr_mix64(seed) ^ a) ^ b) ^ counter);
}

/* Uniform in [0, 1) with 24 random bits (exact in float). */
EVR_HD static inline float evr_uniform(uint64_t h)
{
    return (float)(h >> 40) * (1.0f / 16777216.0f);
}

/* Uniform in (0, 1]: never 0, for logarithms. */
EVR_HD static inline float evr_uniform_pos(uint64_t h)
{
    return ((float)(h >> 40) + 1.0f) * (1.0f / 16777216.0f);
}

/* Two independent standard normal values from one hash (Box-Muller on its two 24-bit halves). */
EVR_HD static inline void evr_gauss2(uint64_t h, float *z0, float *z1)
{
    float r = sqrtf(-2.0f * logf(evr_uniform_pos(h)));
    float a = 6.28318530718f * (float)((h >> 16) & 0xffffffu) * (1.0f / 16777216.0f);
    *z0 = r * cosf(a);
    *z1 = r * sinf(a);
}

/* The per-pixel offset of its sample times within a sample interval, in [0, 1). */
EVR_HD static inline float evr_pixel_phase(uint64_t seed, int x, int y)
{
    return evr_uniform(evr_hash4(seed, (uint64_t)x, (uint64_t)y, 0x7068617365ull /* "phase" */));
}

#endif
