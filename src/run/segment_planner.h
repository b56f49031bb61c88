/* The motion keys and change-driven sampling plans of the coming segments, made on a thread of
 * their own ahead of the segment loop (on the loop's thread they took 0.4-0.5 s of the eye's
 * 30 s on the GPU machine). Segments are planned in order, each into a slot of a ring of
 * EVR_PLANNER_SLOTS: the planner runs ahead through still segments, which cost it little, to make
 * up for moving ones. The loop takes segment i's slot (waiting until it is planned) and releases
 * it once the backend has copied what it needs. */
#ifndef EVR_SEGMENT_PLANNER_H
#define EVR_SEGMENT_PLANNER_H

#include <stddef.h>

#include "core/adaptive.h"
#include "core/motion.h"
#include "core/skip.h"
#include "prep/deform_keys.h"

#ifndef EVR_PLANNER_SLOTS
#define EVR_PLANNER_SLOTS \
    32 /* 53 KB each; with 8 the H100 loop waited 0.15-0.24 s for the 30 s eye's plans, with 32 0.02 s */
#endif

typedef struct {
    evr_motion_key *keys;            /* room for keys_cap keys */
    int *track_offset, *track_count; /* num_tracks each */
    int num_keys;
    evr_deform_keys deform; /* the deforming instances' vertex keys */
    int failed;             /* out of memory planning it */
    evr_skip_plan plan;
    evr_adapt_plan adapt;
} evr_planned_segment;

/* Plans segment `segment` into out; called for 0, 1, 2, ... in order, on the planner's thread. */
typedef void (*evr_plan_fn)(void *user, int segment, evr_planned_segment *out);

typedef struct evr_planner evr_planner;

/* Starts planning segments 0 .. num_segments - 1 with fn. NULL when out of memory; without a
 * thread (it could not be started) evr_planner_take plans on the caller's. */
evr_planner *evr_planner_start(int num_segments, size_t keys_cap, int num_tracks, evr_plan_fn fn,
                               void *user);

/* Segment `segment`'s plan, once made (segments are taken in order). */
const evr_planned_segment *evr_planner_take(evr_planner *p, int segment);

/* Segment `segment`'s slot may be planned into again. */
void evr_planner_release(evr_planner *p, int segment);

/* Seconds the planner spent planning so far. */
double evr_planner_busy_seconds(evr_planner *p);

/* Stops planning (a segment being planned is finished first) and frees p (NULL is fine). */
void evr_planner_stop(evr_planner *p);

#endif
