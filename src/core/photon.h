/* Image-space photon mapping: every per-photon and per-pixel decision, written once
 * for the CPU and for nvcc (EVR_HD, plain C, no allocation). The loops that trace rays live in
 * the backends (src/cpu/photon_pass.c on the CPU); the material's part (the BSDF's lobes, their
 * sampling and weights) is core/bsdf_sample.h over core/material.h. This header includes them all:
 *   photon_rand.h      the low-discrepancy numbers of a photon (a pure function of emitter and number)
 *   photon_emit.h      emission from point, spot and directional lights and from emissive triangles
 *   photon_path.h      a photon's path: its start and the decision and flux update at each hit
 *   photon_buffer.h    the image-space buffer (projection, lock-free insertion, the cells' view)
 *   photon_trail.h     a photon's trail: its path kept for the next pass
 *   photon_gather.h    the ring search, the Gaussian kernel and the limited gather estimate
 *   photon_fixed.h     the estimate without a limit in fixed point, updated from changed cells
 *   photon_change.h    what changed between two buffers and whether it can move a gather
 *   photon_indirect.h  the indirect light of a surface point from the buffers
 *
 * Light transport model: the glTF metallic-roughness BSDF of the direct term (core/material.h).
 * At each hit a photon stays (is stored: its flux over the odds of staying estimates the
 * incident flux), bounces off one of the BSDF's lobes (diffuse, glossy or mirror, transmitted,
 * BLEND's uncovered share: a direction from the lobe, the flux times f cos / pdf over the odds)
 * or is absorbed (Russian roulette by the albedo): evr_photon_path_hit. Photons stay only on
 * surfaces with a diffuse part, and a light's photon not before it has bounced off something
 * (before that, its light is the direct term's, computed exactly with shadow rays, which pass
 * transmissive and BLEND surfaces as the photon does). Photons from emissive surfaces may stay
 * at their first hit (the direct term has no area lights).
 * The gather turns the stored photons' irradiance E into radiance with the diffuse weight:
 * diffuse / pi * E (evr_photon_indirect_k); what the specular lobe reflects of indirect light
 * is not estimated (`evray still --gi path` has it).
 * Units: a light's colour is intensity (point, spot) or irradiance (directional), as in
 * evr_light_incident; flux = intensity * solid angle, so photon flux / area is an irradiance in
 * the units of the direct term's E, and the estimate adds to evr_surface_intensity's radiance
 * directly (per RGB channel; the sensor takes the luminance). */
#ifndef EVR_CORE_PHOTON_H
#define EVR_CORE_PHOTON_H

#include <stdint.h>
#include "core/rng.h"
#include "core/shading.h"
#include "core/skip.h"

#include "core/photon_rand.h"
#include "core/photon_emit.h"
#include "core/photon_path.h"
#include "core/photon_buffer.h"
#include "core/photon_trail.h"
#include "core/photon_gather.h"
#include "core/photon_fixed.h"
#include "core/photon_change.h"
#include "core/photon_indirect.h"
#include "core/photon_blur.h"

#endif
