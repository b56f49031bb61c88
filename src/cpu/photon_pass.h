/* The photon pass on the CPU: the image-space photon buffer and the loop that traces every
 * photon through a ray-tracing interface given as function pointers, so any CPU renderer (the
 * still renderer's Embree scene, the event pipeline's motion-blurred Embree scene) can run it.
 * Per-photon decisions are src/core/photon.h, the emitters prep/photon_emitters.h. */
#ifndef EVR_CPU_PHOTON_PASS_H
#define EVR_CPU_PHOTON_PASS_H

#include <stdint.h>
#include "evray.h"
#include "core/photon.h"
#include "backend.h"
#include "prep/photon_emitters.h"

/* What a closest-hit query returns (core/render_scene.h's evr_hit). */
typedef evr_hit evr_trace_hit;

/* The ray tracer the pass uses. Both calls must be safe to make from several threads at once.
 * f is the normalized segment time of the ray (motion blur); directions are unit vectors. */
typedef struct {
    void *user;
    /* closest hit along ray with distance in [tnear, tfar); returns 0 when nothing is hit */
    int (*closest)(void *user, evr_ray ray, float tnear, float tfar, float f, evr_trace_hit *hit);
    /* 1 when anything lies along ray with distance in [tnear, tfar) */
    int (*occluded)(void *user, evr_ray ray, float tnear, float tfar, float f);
} evr_tracer;

/* A buffer for a width x height image with a guard band of margin pixels. */
evr_status evr_photon_buffer_alloc(evr_photon_buffer *b, int width, int height, int layers,
                                   int margin, evr_error *err);
void evr_photon_buffer_clear(evr_photon_buffer *b);
void evr_photon_buffer_free(evr_photon_buffer *b);

/* The changed cells of a w x h buffer (core/photon.h's evr_changed_cells) from the summed-area
 * table of its changed cells (evr_sat_count's): before needs (w + 1) h entries, base h + 1, x w h. */
evr_changed_cells evr_changed_cells_from_sat(const uint32_t *sat, int w, int h, uint32_t *before,
                                             uint32_t *base, uint32_t *x);

/* Fills buf->gbuf (allocated here when NULL; freed by evr_photon_buffer_free): the surface the
 * camera (pose at time f) sees through every cell's centre, guard band included, and the area
 * the cell covers there (pixel area at unit distance * depth^2 * cos(off-axis angle) / |cos of
 * the incidence|, the cosine at least 0.1); where buf->view_inst is allocated, the scene
 * instance seen through each cell (-1: none). */
evr_status evr_photon_gbuffer(const evr_render_scene *rs, const evr_tracer *tr, float f,
                              evr_photon_buffer *buf, int threads, evr_error *err);

/* Energy bookkeeping (RGB flux) and counts of one pass. Absorbed is the estimate
 * sum(every hit: F (1 - albedo)) with the flux F arriving there and the surface's albedo (all
 * its lobes) as seen from the photon's side (core/photon_path.h); on a closed scene with enough
 * bounces emitted = absorbed + capped within Monte Carlo error (exactly in expectation where the
 * albedo does not depend on the direction light leaves in, as a Lambert surface's). */
typedef struct {
    double emitted[3], stored[3], absorbed[3], escaped[3], capped[3];
    uint64_t paths, stored_photons, visible, inserted, collisions;
    uint64_t reused; /* photons that took their trail's outcome (not in the flux sums) */
    double seconds;
} evr_photon_stats;

/* The photons' trails between the passes of a run (core/photon.h): zero-initialize; plan: the
 * segment's change-driven sampling plan, set before each pass. */
typedef struct {
    evr_photon_trail *t;
    evr_trail_ray *rays;
    uint32_t cap; /* photons */
    int len;      /* rays per trail */
    int valid;    /* they hold the previous pass's, whose emitters were em */
    evr_photon_emitters em;
    const evr_skip_plan *plan;
} evr_photon_trails;
void evr_photon_trails_free(evr_photon_trails *tt);

/* Traces every photon of the emitters (threads over chunks of photons), keeps each photon that
 * stays where the camera (pose at the photon's time) sees it, and inserts it into buf (cleared
 * first) in photon order: the buffer is identical for any thread count. trails (NULL: none): a
 * photon whose trail the plan lets it reuse takes its outcome instead of being traced; every
 * other photon's trail is recorded. The flux sums of st count traced photons only. */
evr_status evr_photon_pass(const evr_render_scene *rs, const evr_tracer *tr,
                           const evr_photon_params *pp, const evr_photon_emitters *em,
                           evr_photon_buffer *buf, evr_photon_stats *st, evr_photon_trails *trails,
                           evr_error *err);

#endif
