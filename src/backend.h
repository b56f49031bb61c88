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
#include "scene/scene.h"

/* Everything fixed for a whole run. */
typedef struct {
    int width, height;
    int samples_per_frame;
    uint64_t seed;
    evr_pixel_params pixel;
    int threads;
} evr_run_setup;

/* One segment: absolute times and the motion keys of every track (one track per scene node). */
typedef struct {
    int index;
    double t0, t1;
    const evr_motion_key *keys;
    const int *track_offset, *track_count;
    int camera_static;            /* the camera does not move in this segment */
} evr_segment;

typedef struct evr_backend evr_backend;
struct evr_backend {
    const char *name;
    /* Renders a segment and appends its events (unsorted) to out. */
    evr_status (*render)(evr_backend *b, const evr_segment *seg, evr_event_vec *out, evr_error *err);
    /* Copies every pixel's last linear intensity (row-major, top row first). */
    void (*intensity)(evr_backend *b, float *out);
    void (*release)(evr_backend *b);
    uint64_t samples, rays;       /* totals so far */
};

/* Host arrays behind an evr_render_scene (everything but the per-segment keys). */
typedef struct {
    evr_render_scene rs;
    evr_mesh_view *meshes;
    evr_material_view *materials;
    evr_texture_view *textures;
    evr_instance_view *instances;
    evr_light_view *lights;
    float scene_size;             /* diagonal of the rest-pose bounds */
} evr_render_host;

evr_status evr_render_host_init(evr_render_host *h, const evr_scene *s, int camera, int width, int height,
                                float ambient, evr_error *err);
void evr_render_host_free(evr_render_host *h);

evr_status evr_cpu_backend_new(const evr_scene *s, const evr_render_host *h, const evr_run_setup *setup,
                               evr_backend **out, evr_error *err);

#endif
