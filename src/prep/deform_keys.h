/* Per-segment vertex keys of the deforming instances (skins, morph targets), for both backends:
 * the fewest uniformly spaced keys (2^k + 1) whose linear interpolation follows the deformation
 * within the tolerance rigid motion keys meet, and what change-driven and adaptive sampling need
 * to know of them (whether they moved, their swept box, how far a vertex moves). */
#ifndef EVR_PREP_DEFORM_KEYS_H
#define EVR_PREP_DEFORM_KEYS_H

#include <stddef.h>
#include "backend.h"

/* What one segment's keys say of one deforming instance. */
typedef struct {
    int moved;          /* the vertices change in the segment, or since the previous one ended */
    float lo[3], hi[3]; /* box of every key of the segment and the previous segment's last */
    float move;         /* largest distance a vertex moves between two neighbouring keys */
    float jump;         /* largest distance a vertex moved since the previous segment's last key */
} evr_deform_motion;

/* The keys of one segment (one per planner slot; arrays reused from segment to segment). */
typedef struct {
    int num_deforms;
    evr_deform_view *views; /* host pointers into data */
    evr_deform_motion *motion;
    int *moved;  /* motion[d].moved, as evr_segment.deform_moved wants it */
    float *data; /* every key's positions and normals */
    size_t cap;  /* floats data holds */
} evr_deform_keys;

/* Threads one evaluation of a large mesh is spread over, at most. */
#define EVR_DEFORM_PARTS 16

/* The tracker's memory of the previous segment, on the planner's thread. */
typedef struct {
    struct evr_par_pool *pool; /* threads for evaluating large meshes (NULL: none yet) */
    int pool_tried;            /* the pool was asked for (once) */
    int num_deforms;
    int have_prev;
    float **last; /* per deform: positions and normals of the last key seen */
    float (*last_box)[6];
    float *scratch; /* evaluations between keys */
    size_t scratch_cap;
    float *work; /* the keys being fitted */
    size_t work_cap;
} evr_deform_tracker;

/* 0: out of memory. */
int evr_deform_tracker_init(evr_deform_tracker *t, const evr_scene *s, const evr_render_host *h);
void evr_deform_tracker_free(evr_deform_tracker *t);

/* The keys of segment [t0, t1] for every deforming instance of h, at most max_keys each, within
 * tol times the scene size; segments in order. 0: out of memory. */
int evr_deform_keys_make(evr_deform_tracker *t, const evr_scene *s, const evr_render_host *h,
                         double t0, double t1, float tol, int max_keys, evr_deform_keys *out);
void evr_deform_keys_free(evr_deform_keys *k);

#endif
