/* Global illumination in the CPU event pipeline: one photon pass per segment through the
 * backend's motion-blurred Embree scene (src/cpu/photon_pass.c, src/core/photon.h), the gather
 * per traced sample, and which buffer cells changed since the previous segment (a pixel whose
 * gather window saw no change may keep its intensity: change-driven sampling stays exact). */
#ifndef EVR_CPU_GI_H
#define EVR_CPU_GI_H

#include <embree3/rtcore.h>
#include "backend.h"
#include "cpu/photon_pass.h"

typedef struct {
    RTCScene top;                  /* the backend's top-level scene */
    const int *members, *group_first;   /* (instance, geometry) of a hit -> scene instance */
} evr_cpu_trace_ctx;

typedef struct {
    evr_cpu_trace_ctx tc;
    evr_tracer tr;
    evr_photon_buffer buf, prev;   /* this segment's buffer and the previous segment's */
    evr_photon_emitters em;
    evr_photon_trails trails;      /* the photons' paths, reused where nothing moving meets them */
    int trails_off;                /* EVR_NO_PHOTON_REUSE set: none (tests, measurement) */
    evr_gather_params gp;
    evr_photon_params pp;
    uint32_t photons;
    uint32_t *sat;                 /* summed-area table of the cells that changed, (w + 1) x (h + 1) */
    int have_prev;
    int window;                    /* cells around a pixel a gather may read */
    /* per pixel, the last gather: the same point, normal and distance with no change in the
     * window since give the same estimate bit for bit (most samples of a still surface) */
    struct evr_gi_memo { float key[7]; int inst, valid; float lum; } *memo;   /* key: point, normal, distance */
    int image_width;
    int memo_off;                  /* EVR_GI_NO_MEMO set: no memo (tests) */
} evr_cpu_gi;

/* One ray through an Embree scene at normalized time f (the photon pass's evr_tracer calls, the
 * still renderer's too): the closest hit (0 when nothing is hit), or whether anything lies along
 * it. The hit's scene instance: members[group_first[instance] + geometry] with a mapping (the
 * backend's grouped scene), else the geometry itself (a scene of one geometry per instance). */
int evr_embree_closest1(RTCScene sc, const int *members, const int *group_first, evr_ray ray, float tnear, float tfar,
                        float f, evr_trace_hit *hit);
int evr_embree_occluded1(RTCScene sc, evr_ray ray, float tnear, float tfar, float f);

evr_status evr_cpu_gi_init(evr_cpu_gi *g, const evr_cpu_trace_ctx *tc, const evr_run_setup *setup, const evr_scene *s,
                           evr_error *err);
/* The photon pass of a segment (rs holds its keys, plan its change-driven sampling plan). When
 * nothing moved in this segment or since the previous one (camera, lights and instances) the
 * photons are those of the previous segment: the pass is not run and no cell changed. Else the
 * photons whose trails meet nothing that moves keep their outcome (evr_photon_pass). */
evr_status evr_cpu_gi_segment(evr_cpu_gi *g, const evr_render_scene *rs, const evr_skip_plan *plan, int threads,
                              evr_backend *stats, evr_error *err);
/* Whether pixel (x, y)'s gather may change in this segment: a cell of its window changed and the
 * change reaches its last gather's point (evr_photon_gather_moved); if so, forgets that gather.
 * The thread that renders the pixel calls it before the pixel's samples. */
int evr_cpu_gi_pixel_begin(evr_cpu_gi *g, const evr_camera_intr *cam, int x, int y);
/* Luminance of the indirect light leaving surface s of scene instance inst, seen from cam_org
 * through pixel (x, y) (one thread per pixel at a time: it updates the pixel's memo). */
float evr_cpu_gi_indirect(const evr_cpu_gi *g, const evr_render_scene *rs, int inst, const evr_surface *s, evr_v3 cam_org, int x,
                          int y);
void evr_cpu_gi_free(evr_cpu_gi *g);

#endif
