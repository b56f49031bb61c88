/* The per-segment plan of change-driven sampling (src/skip_plan.c): which tracks moved, a box per
 * moving instance, a box per moving track once there are more than EVR_SKIP_MAX_BOXES instances,
 * tracing everything once there are more moving tracks than that; the ray tests of core/skip.h
 * against those boxes; the still spans of a segment (before and after its motion). */
#include "check.h"
#include "skip_plan.h"

#include <math.h>
#include <string.h>

#define MAX_TRACKS 80

typedef struct {
    evr_scene s;
    evr_mesh mesh;
    evr_instance_view inst[200];
    evr_motion_key keys[2 * MAX_TRACKS + 1];
    int offset[MAX_TRACKS + 1], count[MAX_TRACKS + 1];
    evr_render_scene rs;
} world;

/* num_instances unit cubes; instance i on track i % moving_tracks; every moving track translates
 * by (1, 0, 0) over the segment; the last track (the camera's) holds still. */
static void make_world(world *w, int num_instances, int moving_tracks)
{
    evr_m34 id = evr_m34_identity();
    int i, k = 0;
    memset(w, 0, sizeof *w);
    w->mesh.bounds_min = evr_v3_make(-1.0f, -1.0f, -1.0f);
    w->mesh.bounds_max = evr_v3_make(1.0f, 1.0f, 1.0f);
    w->s.meshes = &w->mesh;
    w->s.num_meshes = 1;
    for (i = 0; i < num_instances; i++) {
        w->inst[i].mesh = 0;
        w->inst[i].track = i % moving_tracks;
    }
    for (i = 0; i <= moving_tracks; i++) {
        w->offset[i] = k;
        w->keys[k] = evr_motion_key_from_matrix(&id);
        w->count[i] = 1;
        k++;
        if (i < moving_tracks) {
            evr_m34 m = id;
            m.m[0][3] = 1.0f;
            w->keys[k++] = evr_motion_key_from_matrix(&m);
            w->count[i] = 2;
        }
    }
    w->rs.instances = w->inst;
    w->rs.num_instances = num_instances;
    w->rs.keys = w->keys;
    w->rs.track_offset = w->offset;
    w->rs.track_count = w->count;
    w->rs.camera_track = moving_tracks;
    w->rs.ray_eps = 1e-5f;
}

static void plan_of(world *w, int moving_tracks, evr_skip_plan *pl)
{
    evr_skip_tracker t;
    CHECK(evr_skip_tracker_init(&t, moving_tracks + 1));
    evr_skip_tracker_update(&t, w->keys, w->offset, w->count, 1.0f);
    evr_skip_plan_build(&t, &w->s, &w->rs, 1, pl);
    evr_skip_tracker_free(&t);
}

int main(void)
{
    static world w;
    evr_skip_plan pl;
    int b;

    /* few moving instances: one box each, holding the cube over its whole motion */
    make_world(&w, 10, 2);
    plan_of(&w, 2, &pl);
    CHECK(pl.num_boxes == 10 && pl.reuse && pl.cache);
    for (b = 0; b < pl.num_boxes; b++)
        CHECK(pl.lo[b][0] <= -1.0f && pl.hi[b][0] >= 2.0f && pl.lo[b][1] <= -1.0f && pl.hi[b][1] >= 1.0f);

    /* more moving instances than boxes: a box per track, each the union of its instances' */
    make_world(&w, 150, 3);
    plan_of(&w, 3, &pl);
    CHECK(pl.num_boxes == 3 && pl.reuse && pl.cache);
    for (b = 0; b < pl.num_boxes; b++) CHECK(pl.lo[b][0] <= -1.0f && pl.hi[b][0] >= 2.0f);

    /* more moving tracks than boxes: nothing can be bounded, every pixel traces */
    make_world(&w, 150, 70);
    plan_of(&w, 70, &pl);
    CHECK(pl.num_boxes == 0 && !pl.reuse && !pl.cache);

    /* the ray tests: through a box, beside it, stopping short of it */
    make_world(&w, 1, 1);
    plan_of(&w, 1, &pl);
    CHECK(pl.num_boxes == 1);
    {
        evr_v3 o = evr_v3_make(0.5f, 0.0f, 10.0f), d = evr_v3_make(0.0f, 0.0f, -1.0f);
        CHECK(evr_skip_ray_meets_any(&pl, o, d, INFINITY));
        CHECK(!evr_skip_ray_meets_any(&pl, o, d, 8.0f));                        /* ends before the box */
        CHECK(!evr_skip_ray_meets_any(&pl, evr_v3_make(5.0f, 0.0f, 10.0f), d, INFINITY));   /* beside it */
        CHECK(evr_skip_ray_meets_any(&pl, evr_v3_make(1.9f, 0.0f, 10.0f), d, INFINITY));    /* the swept end */
    }
    /* still spans: one track of six keys, still, still (but for a billionth), still, moving,
     * moving, still: nothing moves before key 2 nor after key 4 */
    make_world(&w, 1, 1);
    {
        evr_m34 m = evr_m34_identity();
        const float x[6] = {0.0f, 1e-12f, 0.0f, 0.5f, 1.0f, 1.0f};
        evr_skip_tracker t;
        int k;
        for (k = 0; k < 6; k++) {
            m.m[0][3] = x[k];
            w.keys[k] = evr_motion_key_from_matrix(&m);
        }
        w.keys[6] = evr_motion_key_from_matrix(&m);   /* the camera's */
        w.offset[0] = 0;
        w.count[0] = 6;
        w.offset[1] = 6;
        w.count[1] = 1;
        CHECK(evr_skip_tracker_init(&t, 2));
        evr_skip_tracker_update(&t, w.keys, w.offset, w.count, 1.0f);
        CHECK(evr_motion_key_same(&w.keys[1], &w.keys[0]));   /* the billionth: snapped to the key before */
        evr_skip_plan_build(&t, &w.s, &w.rs, 1, &pl);
        CHECK(pl.spans && pl.cache);
        CHECK(fabsf(pl.still_before - 1.99f / 5.0f) < 1e-6f && fabsf(pl.still_after - 4.01f / 5.0f) < 1e-6f);
        CHECK(evr_skip_still_span(&pl, 0.1f) == 1 && evr_skip_still_span(&pl, 0.5f) == 0 && evr_skip_still_span(&pl, 0.9f) == 2);
        CHECK(evr_skip_held(&pl, 1, 1) && !evr_skip_held(&pl, 2, 1) && !evr_skip_held(&pl, 0, 0) && !evr_skip_held(&pl, 1, -1));
        CHECK(evr_skip_trace_time(&pl, 0.1f) == 0.0f && evr_skip_trace_time(&pl, 0.9f) == 1.0f && evr_skip_trace_time(&pl, 0.5f) == 0.5f);
        /* the transform is the same bits anywhere in a span, and moves in between */
        evr_motion_track tr = evr_rs_track(&w.rs, 0);
        evr_m34 a = evr_motion_eval(tr, 0.01f), b2 = evr_motion_eval(tr, 0.37f), c = evr_motion_eval(tr, 0.81f),
                d = evr_motion_eval(tr, 0.999f), e = evr_motion_eval(tr, 0.5f);
        CHECK(memcmp(&a, &b2, sizeof a) == 0 && memcmp(&c, &d, sizeof c) == 0 && e.m[0][3] > 0.0f && e.m[0][3] < 1.0f);
        /* brute force: the same spans (its samples traced at the same times), nothing held */
        evr_skip_plan_build(&t, &w.s, &w.rs, 0, &pl);
        CHECK(pl.spans && !pl.cache && evr_skip_still_span(&pl, 0.1f) == 1 && !evr_skip_held(&pl, 1, 1));
        evr_skip_tracker_free(&t);
    }
    return check_report("test_skip_plan");
}
