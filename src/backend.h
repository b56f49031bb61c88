/* What a rendering backend does for the segment loop: render every pixel's samples of one
 * segment through the shared pixel model and return the segment's events. The CPU (Embree) and
 * CUDA backends differ only in how rays find triangles and how the work is scheduled. */
#ifndef EVR_BACKEND_H
#define EVR_BACKEND_H

#include <stdint.h>
#include "evray.h"
#include "events.h"
#include "core/render_scene.h"
#include "core/pixel.h"
#include "core/skip.h"
#include "core/adaptive.h"
#include "core/refine.h"
#include "scene/scene.h"

/* Everything fixed for a whole run. */
typedef struct {
    int width, height;
    int samples_per_frame;
    uint64_t seed;
    evr_pixel_params pixel;
    int threads;
    int gpu_bvh;                /* GPU node layout (0: default) */
    const char *bvh_cache;      /* GPU BVH cache folder (cuda/gpu_bvh_cache.h), NULL: none */
    int64_t gpu_event_capacity; /* initial GPU event buffer (0: automatic) */
    /* global illumination (CPU backend): image-space photon mapping, 0 photons: one per pixel */
    int gi;
    uint32_t photons;
    float gather_radius; /* world units (resolved: > 0) */
    int gather_max, gather_window, photon_layers, gi_bounces;
    float gi_blur;          /* evr_config.gi_blur */
    int adaptive;           /* adaptive sampling (core/adaptive.h): samples_per_frame unused */
    evr_adapt_params adapt; /* its parameters (max_dt resolved: > 0) */
    int refine;             /* refined sampling (core/refine.h): every pixel's phase is 1 */
    evr_refine_params refine_params; /* n: samples_per_frame */
    int event_ids; /* every event's id: 1 + the instance its sample's primary ray hit */
    /* non-zero (read with __atomic_load_n) once the run is to stop at once (evr_sim_cancel): a
     * backend may then give up the segment it renders, its submit() returning
     * EVR_ERR_INTERRUPTED; NULL: never */
    const int *cancel;
} evr_run_setup;

/* One segment: absolute times and the motion keys of every track (one track per scene node, and
 * a last one for the fixed world frame). The arrays are only valid during submit(). */
typedef struct {
    int index;
    double t0, t1;
    const evr_motion_key *keys;
    const int *track_offset, *track_count;
    int num_tracks, num_keys;
    /* The deforming instances' vertices over the segment (host arrays, evr_render_host's
     * deform order); deform_moved[d]: they change in the segment or since the last one */
    const evr_deform_view *deforms;
    const int *deform_moved;
    int num_deforms;
    int camera_static;  /* the camera does not move in this segment */
    int want_intensity; /* return every pixel's intensity at the segment's end */
    /* Intensity frames wanted inside this segment: num_frames absolute times in [t0, t1] (t1 only
     * for the last segment). Each frame is every pixel's intensity at exactly that time, one
     * sample through the pixel centre with the samples' own camera, motion and shading code; the
     * pixel model never sees these samples (events are the same with or without frames) and
     * they are not counted in samples or rays. */
    const double *frame_times;
    int num_frames;
    /* Label frames wanted inside this segment (--labels-fps): num_labels absolute times in
     * [t0, t1], like frame_times. For each, every pixel's primary hit through its centre at
     * exactly that time (the samples' camera and motion, no shading): what the host's ground
     * truth (core/labels.h) is computed from. Unseen by the pixel model, uncounted. */
    const double *label_times;
    int num_labels;
    /* Change-driven sampling (core/skip.h): which pixels may keep their cached intensity, and
     * which may cache one. Never NULL; a plan that neither reuses nor caches is brute force. */
    const evr_skip_plan *skip;
    /* Adaptive sampling (setup.adaptive): the segment's motion bounds; NULL otherwise. */
    const evr_adapt_plan *adapt;
} evr_segment;

typedef struct evr_backend evr_backend;
struct evr_backend {
    const char *name;
    /* Starts rendering a segment; segments are submitted in order, at most `depth` of them ahead
     * of collect(), so a backend can render while the host takes in and writes earlier ones. */
    evr_status (*submit)(evr_backend *b, const evr_segment *seg, evr_error *err);
    /* Waits for the oldest submitted segment and appends its events, sorted by (t, y, x), to out:
     * at least those before emit_before_us (the loop writes them; INT64_MAX: all of them), the
     * rest now or with a later segment's (a backend may carry them into that segment's sort).
     * *intensity is set to every pixel's last linear intensity (row-major, top row first) when the
     * segment asked for it, else NULL; *frames to the segment's num_frames intensity frames, one
     * after the other (each row-major, top row first), or NULL when it asked for none. Both stay
     * valid until the next collect(). */
    evr_status (*collect)(evr_backend *b, evr_event_vec *out, int64_t emit_before_us,
                          const float **intensity, const float **frames, evr_error *err);
    /* Set by the caller (may be NULL): collect may hand a large segment's events over in pieces,
     * calling this after appending each piece but the last to out, with a limit no later event
     * of the segment precedes; the caller takes out's events before it (and may swap out's
     * buffer). Host memory then holds a piece, not a segment's burst. */
    evr_status (*emit_piece)(void *user, int64_t limit_us, evr_error *err);
    void *emit_user;
    void (*release)(evr_backend *b);
    /* The primary hits of the segment collected last: its num_labels images, one after the
     * other (each row-major, top row first; inst -1: the pixel sees nothing), or NULL when it
     * asked for none. Valid until the next collect(). */
    const evr_hit *(*label_hits)(evr_backend *b);
    int depth; /* segments the backend holds submitted and not yet collected, at most */
    uint64_t samples, rays;  /* totals so far (samples: every pixel sample, traced or not;
                                     adaptive sampling: every sample taken) */
    uint64_t samples_traced; /* samples that traced rays (the others reused a cached intensity) */
    uint64_t pixels_skipped; /* pixel-segments that reused their cached intensity */
    uint64_t photons_traced, photons_stored, photon_collisions, photon_passes; /* GI */
    uint64_t
        photons_reused; /* GI: photons whose path was not traced again (their trail's outcome) */
    uint64_t photon_cells_changed; /* GI: buffer cells whose photons or view changed, all passes */
    double photon_seconds;
    double device_seconds; /* time the device spent rendering (GPU kernels; 0 on the CPU) */
    double wait_seconds; /* the calling thread blocked on the device in submit and collect (GPU) */
    double sort_seconds, copy_seconds;
    uint64_t device_bytes; /* memory held on the device */
    double bvh_seconds;    /* set-up: the acceleration structures' builds (0: not measured) */
    int bvh_trees, bvh_trees_cached; /* set-up: trees made, and of them read from the BVH cache */
    char notice[256]; /* something the user should know that did not stop the run ("" none) */
};

/* Host arrays behind an evr_render_scene (everything but the per-segment keys). */
typedef struct {
    evr_render_scene rs;
    evr_mesh_view *meshes;
    evr_material_params *materials;
    evr_texture_view *textures;
    evr_instance_view *instances;
    evr_light_view *lights;
    int num_deforms;      /* instances that deform (evr_instance_view.deform) */
    int *deform_instance; /* per deform: its scene instance */
    float scene_size;     /* diagonal of the rest-pose bounds */
    float *bsdf_table;    /* core/bsdf.h's albedo table */
} evr_render_host;

evr_status evr_render_host_init(evr_render_host *h, const evr_scene *s, int camera, int width,
                                int height, float ambient, evr_error *err);
void evr_render_host_free(evr_render_host *h);
/* The hit filter bits of mesh m of s (evr_mesh_view.filter, core/hit_filter.h): its material's,
 * 0 for a mesh without a valid material. The GPU BVH copies them into its triangles. */
int evr_render_mesh_filter(const evr_scene *s, const evr_mesh *m);

evr_status evr_cpu_backend_new(const evr_scene *s, const evr_render_host *h,
                               const evr_run_setup *setup, evr_backend **out, evr_error *err);
int evr_cpu_backend_threads(const evr_backend *b);

#endif
