/* Mip pyramids of textures, built once at import so that lookups can be filtered by the ray's
 * footprint (core/material.h's evr_texture_sample). */
#ifndef EVR_SCENE_TEXTURE_MIPS_H
#define EVR_SCENE_TEXTURE_MIPS_H

#include "scene/scene.h"

/* Appends to t's level 0 (t->rgba, t->width x t->height) every further level down to 1 x 1 in
 * core/render_scene.h's evr_texture_view layout and sets t->levels. Level k+1 is
 * evr_mip_size(w, k+1) x evr_mip_size(h, k+1); each of its texels is the area-weighted mean of
 * the level-k texels its footprint covers (a 2 x 2 box for even sizes; for odd sizes each texel
 * covers 2 + 1/n source texels per axis, the end ones partly), all four channels alike, in the
 * linear values held (so the mean of every level is level 0's). On failure (out of memory) t is
 * unchanged, err says why. */
evr_status evr_texture_build_mips(evr_texture *t, evr_error *err);

#endif
