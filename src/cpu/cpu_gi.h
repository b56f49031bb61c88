/* Global illumination in the CPU event pipeline: a photon pass at each segment's end through
 * the backend's motion-blurred Embree scene (src/cpu/photon_pass.c, src/core/photon.h), the
 * gathers of a traced sample in the buffers of its segment's start and end, interpolated in time
 * (evr_gi_lerp), and which buffer cells changed over the segment (a pixel whose gather window saw
 * no change may keep its intensity: change-driven sampling stays exact). */
#ifndef EVR_CPU_GI_H
#define EVR_CPU_GI_H

#include <embree3/rtcore.h>
#include "backend.h"
#include "cpu/photon_pass.h"

typedef struct {
    RTCScene top;                     /* the backend's top-level scene */
    const int *members, *group_first; /* (instance, geometry) of a hit -> scene instance */
} evr_cpu_trace_ctx;

typedef struct {
    evr_cpu_trace_ctx tc;
    evr_tracer tr;
    /* the photons at the segment's end (this segment's pass) and at its start (the previous
     * segment's end, or the first segment's own pass at its start); start_same: no pass ran, the
     * start's photons are the end's */
    evr_photon_buffer end, start;
    int start_same;
    evr_photon_emitters em;
    evr_photon_trails trails; /* the photons' paths, reused where nothing moving meets them */
    int trails_off;           /* EVR_NO_PHOTON_REUSE set: none (tests, measurement) */
    evr_gather_params gp;
    evr_photon_params pp;
    uint32_t photons;
    uint32_t
        *sat; /* summed-area table of the cells that differ, end against start, (w + 1) x (h + 1) */
    int have_prev;
    int window; /* cells around a pixel a gather may read */
    /* per pixel, its last gather: the point, normal and distance (key) and its luminance in the
     * start and end buffers (ls, le; le to be made again where end_valid is 0), se its sums. flat: ls == le
     * (the indirect light of the key did not change over the segment). missed: the pixel's last
     * sample met nothing (no indirect light). The same key with no change in the window since
     * gives the same estimate bit for bit (most samples of a still surface). */
    struct evr_gi_memo {
        float key[7];
        int inst, valid, end_valid, flat, missed;
        float ls, le;
        evr_gather_sum se;
    } * memo;
    /* gp.max_photons 0: the memo's se holds the fixed-point sums of its end gather, which the
     * next segment updates from the changed cells (ch, in ch_before, ch_base, ch_x) */
    evr_changed_cells ch;
    uint32_t *ch_before, *ch_base, *ch_x;
    int image_width;
    int memo_off; /* EVR_GI_NO_MEMO set: no memo (tests) */
    /* --gi-blur (core/photon_blur.h): sigma in world units (0: off, a gather at every sample);
     * the buffers then hold their cells' instances and blurred estimates, sat counts the cells
     * whose lookups differ, end against start, and a pixel's window is its cell and the eight
     * around it; blur_tmp: the blur's two working arrays of flux and area (EVR_BLUR_CH a cell) */
    float blur_sigma;
    float *blur_tmp;
} evr_cpu_gi;

/* One ray through an Embree scene at normalized time f (the photon pass's evr_tracer calls, the
 * still renderer's too): the closest hit (0 when nothing is hit), or whether anything lies along
 * it. The hit's scene instance: members[group_first[instance] + geometry] with a mapping (the
 * backend's grouped scene), else the geometry itself (a scene of one geometry per instance). */
int evr_embree_closest1(RTCScene sc, const int *members, const int *group_first, evr_ray ray,
                        float tnear, float tfar, float f, evr_trace_hit *hit);
int evr_embree_occluded1(RTCScene sc, evr_ray ray, float tnear, float tfar, float f);

evr_status evr_cpu_gi_init(evr_cpu_gi *g, const evr_cpu_trace_ctx *tc, const evr_run_setup *setup,
                           const evr_scene *s, evr_error *err);
/* The photon pass at the end of a segment (rs holds its keys, plan its change-driven sampling
 * plan); the first segment also gets one at its start. When nothing moved in this segment or
 * since the previous one (camera, lights and instances) the photons are those of the previous
 * segment's end: no pass is run and no cell changed. Else the photons whose trails meet nothing
 * that moves keep their outcome (evr_photon_pass). */
evr_status evr_cpu_gi_segment(evr_cpu_gi *g, const evr_render_scene *rs, const evr_skip_plan *plan,
                              int threads, evr_backend *stats, evr_error *err);
/* Before pixel (x, y)'s samples of a segment (the thread that renders the pixel calls it): moves
 * its last gather to the segment's start, forgets its end where a cell of its window changed and
 * the change reaches the gather's point (evr_photon_gather_moved), and returns whether its
 * indirect light may differ in this segment from its last sample's: 0 when that sample met
 * nothing, or when its gather is the same at the start and end of this segment and was at the
 * start and end of the last one (a pixel the direct light lets keep its intensity may then keep
 * it: linear in time, the indirect light of the last segment's last sample is that of its end). */
int evr_cpu_gi_pixel_begin(evr_cpu_gi *g, const evr_camera_intr *cam, int x, int y);
/* Luminance of the indirect light leaving surface s of scene instance inst, seen from cam_org
 * through pixel (x, y) at normalized segment time f (evr_gi_lerp between the gathers in the start
 * and end buffers). memo: a sample of the pixel model (updates the pixel's memo: one thread per
 * pixel at a time); 0 for a frame's sample, which leaves the memo alone. */
float evr_cpu_gi_indirect(const evr_cpu_gi *g, const evr_render_scene *rs, int inst,
                          const evr_surface *s, evr_v3 cam_org, int x, int y, float f, int memo);
/* For a pixel whose last sample met a surface (its memo holds the gather): whether its indirect
 * light is the same over the segment, and that light at normalized segment time f. A pixel that
 * settles keeps its direct light and adds this (bit for bit what a traced sample adds). */
int evr_cpu_gi_flat(const evr_cpu_gi *g, int x, int y);
float evr_cpu_gi_last(const evr_cpu_gi *g, int x, int y, float f);
/* The pixel's last sample (of the pixel model) met nothing. */
void evr_cpu_gi_missed(const evr_cpu_gi *g, int x, int y);
void evr_cpu_gi_free(evr_cpu_gi *g);

#endif
