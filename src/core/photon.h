/* Image-space photon mapping: every per-photon and per-pixel decision, written once
 * for the CPU and for nvcc (EVR_HD, plain C, no allocation). The loops that trace rays live in
 * the backends (src/cpu/photon_pass.c on the CPU); the material's part (glTF metallic/roughness
 * -> t_diffuse, t_specular, the stay / diffuse / mirror decision, the bounce directions) is in
 * core/material.h. This header includes them all:
 *   photon_rand.h      the low-discrepancy numbers of a photon (a pure function of emitter and number)
 *   photon_emit.h      emission from point, spot and directional lights and from emissive triangles
 *   photon_path.h      a photon's path: its start and the flux update at each hit
 *   photon_buffer.h    the image-space buffer (projection, lock-free insertion, the cells' view)
 *   photon_trail.h     a photon's trail: its path kept for the next pass
 *   photon_gather.h    the ring search, the Gaussian kernel and the limited gather estimate
 *   photon_fixed.h     the estimate without a limit in fixed point, updated from changed cells
 *   photon_change.h    what changed between two buffers and whether it can move a gather
 *   photon_indirect.h  the indirect light of a surface point from the buffers
 *
 * Light transport model. A surface reflects the fraction albedo * (1 - mirror) diffusely
 * (Lambertian, the direct term's model) and albedo * mirror as a mirror, with
 * mirror = (1 - t_specular) / (1 - t_diffuse). A photon arriving with flux F draws xi in [0, 1):
 *   xi <  t_diffuse               stays: stored with flux F / t_diffuse (so the stored photons
 *                                 estimate the incident flux without bias), path ends;
 *   t_diffuse <= xi < t_specular  diffuse bounce (cosine distributed), flux F * albedo / (1 - t_diffuse);
 *   xi >= t_specular              mirror bounce, flux F * albedo / (1 - t_diffuse).
 * A photon from a light (point, spot, directional) never stays at its first hit: that light is
 * the direct term's, already computed exactly with shadow rays; it bounces with flux F * albedo.
 * Photons from emissive surfaces may stay at their first hit (the direct term has no area lights).
 * Units: a light's colour is intensity (point, spot) or irradiance (directional), as in
 * evr_light_incident; flux = intensity * solid angle, so photon flux / area is an irradiance in
 * the units of the direct term's E and the estimate albedo * (1 - mirror) / pi * E adds to
 * evr_surface_intensity's radiance directly (per RGB channel; the sensor takes the luminance). */
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

#endif
