/* Per-segment plan of change-driven sampling (core/skip.h): which tracks moved, and the swept
 * bounds of the instances they carry. */
#ifndef EVR_SKIP_PLAN_H
#define EVR_SKIP_PLAN_H

#include "backend.h"
#include "core/skip.h"
#include "core/adaptive.h"
#include "prep/deform_keys.h"

typedef struct {
    int num_tracks;
    int have_prev;             /* a previous segment's keys are known */
    evr_motion_key *prev_last; /* per track: the last key of the previous segment */
    int *prev_count;           /* per track: its key count there */
    int *moved;                /* per track: moves in this segment or changed since the last */
    evr_motion_key *last;      /* per track: the last key of the segment seen last */
    int *last_count;
    /* mesh parts (evr_skip_tracker_parts; NULL: the plan bounds whole meshes): per mesh NULL or
     * EVR_SKIP_MESH_PARTS object-space boxes, lo xyz hi xyz (empty: lo > hi), made when the mesh
     * first moves */
    int num_meshes;
    float (**mesh_parts)[6];
    /* a deforming mesh's parts (boxed anew every segment from its keys): per mesh NULL or its
     * triangles in the parts' order followed by EVR_SKIP_MESH_PARTS + 1 part starts */
    uint32_t **tri_order;
} evr_skip_tracker;

/* Parts a moving mesh is bounded by at most: its triangles split eight times at the median of
 * their centroids along the widest axis. */
#define EVR_SKIP_MESH_PARTS 256

int evr_skip_tracker_init(evr_skip_tracker *t, int num_tracks);
void evr_skip_tracker_free(evr_skip_tracker *t);

/* Lets the plans of tracker t bound each moving instance by the parts of its mesh (swept each on
 * its own) as well as by its whole box; returns 0 when out of memory. */
int evr_skip_tracker_parts(evr_skip_tracker *t, const evr_scene *s);

/* Called with every segment's freshly computed keys (in order). A track that holds still in
 * this segment and in the previous one, within a billionth of the scene size, keeps the
 * previous segment's key bit for bit (re-evaluating a constant curve at another time can
 * differ in the last bit, which would count as motion); then marks which tracks moved. */
void evr_skip_tracker_update(evr_skip_tracker *t, evr_motion_key *keys, const int *track_offset,
                             const int *track_count, float scene_size);

/* Fills the plan of the segment whose keys the tracker saw last: enabled 0 (--no-skip) gives a
 * plan that neither reuses nor caches. rs holds the segment's keys, dk the deforming instances'
 * (NULL: none). */
void evr_skip_plan_build(evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                         const evr_deform_keys *dk, int enabled, evr_skip_plan *pl);

/* Fills the adaptive-sampling plan (core/adaptive.h) of the same segment: the swept bounds of
 * every instance that moves in it or changed since the previous one (all of them in one box past
 * EVR_SKIP_MAX_BOXES), each with a bound on its image speed; all_min when the camera or a light
 * moves. seconds: the segment's length. */
void evr_adapt_plan_build(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                          const evr_deform_keys *dk, const evr_adapt_params *ap, double seconds,
                          evr_adapt_plan *pl);

#endif
