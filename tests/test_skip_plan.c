/* The per-segment plan of change-driven sampling (src/skip_plan.c): which tracks moved, a box per
 * moving instance, a box per moving track once there are more than EVR_SKIP_MAX_BOXES instances,
 * tracing everything once there are more moving tracks than that; the ray tests of core/skip.h
 * against those boxes; the still spans of a segment (before and after its motion). */
#include "check.h"
#include "prep/skip_plan.h"
#include "core/rng.h"

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
        w->inst[i].deform = -1;
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
    evr_skip_plan_build(&t, &w->s, &w->rs, NULL, 1, pl);
    evr_skip_tracker_free(&t);
}

/* Mesh parts: an arc of 8 small triangles (a quarter circle of radius 10 in the xy plane)
 * turning about z (10 degrees between keys) and moving along x. The plan's tree of swept parts
 * must hold every point of every triangle at every time of the segment (each point met by a ray
 * aimed at it), the instance's box also where it was at the previous segment's end; and the
 * parts leave the middle of the circle free, which the instance's box alone cannot. */
#define RING 8
static float uni(uint64_t *st)
{
    *st += 0x9E3779B97F4A7C15ull;
    return evr_uniform(evr_mix64(*st));
}

/* Five keys turning about z from deg0 by step degrees each, moving 0.1 along x each. */
static void ring_keys(evr_motion_key *keys, float deg0, float step)
{
    for (int k = 0; k < 5; k++) {
        const float a = (deg0 + step * (float)k) * 3.14159265f / 180.0f;
        evr_m34 m = evr_m34_identity();
        m.m[0][0] = cosf(a);
        m.m[0][1] = -sinf(a);
        m.m[1][0] = sinf(a);
        m.m[1][1] = cosf(a);
        m.m[0][3] = 0.1f * (float)k;
        keys[k] = evr_motion_key_from_matrix(&m);
    }
}

static void test_parts(void)
{
    static float pos[RING * 9];
    static uint32_t idx[RING * 3];
    evr_scene s;
    evr_mesh mesh;
    evr_instance_view inst;
    evr_motion_key keys[8];
    int offset[2] = {0, 5}, count[2] = {5, 1};
    evr_render_scene rs;
    evr_skip_tracker t;
    static evr_skip_plan pl;
    memset(&s, 0, sizeof s);
    memset(&mesh, 0, sizeof mesh);
    memset(&rs, 0, sizeof rs);
    for (int i = 0; i < RING; i++) {
        const float a = 1.5707963f * (float)i / RING, c = cosf(a), sn = sinf(a);
        const float v[9] = {10.0f * c,
                            10.0f * sn,
                            -0.2f,
                            10.5f * c,
                            10.5f * sn,
                            0.2f,
                            10.0f * c - 0.4f * sn,
                            10.0f * sn + 0.4f * c,
                            0.0f};
        memcpy(&pos[9 * i], v, sizeof v);
        for (int k = 0; k < 3; k++) idx[3 * i + k] = (uint32_t)(3 * i + k);
    }
    mesh.positions = pos;
    mesh.indices = idx;
    mesh.num_vertices = 3 * RING;
    mesh.num_triangles = RING;
    mesh.bounds_min = evr_v3_make(-0.5f, -0.5f, -0.2f);
    mesh.bounds_max = evr_v3_make(10.5f, 10.5f, 0.2f);
    s.meshes = &mesh;
    s.num_meshes = 1;
    inst.mesh = 0;
    inst.track = 0;
    inst.deform = -1;
    rs.instances = &inst;
    rs.num_instances = 1;
    rs.keys = keys;
    rs.track_offset = offset;
    rs.track_count = count;
    rs.camera_track = 1;
    rs.ray_eps = 1e-5f;
    CHECK(evr_skip_tracker_init(&t, 2));
    CHECK(evr_skip_tracker_parts(&t, &s));
    uint64_t rng = 12345u;
    evr_m34 prev_end = evr_m34_identity();
    for (int seg = 0; seg < 2; seg++) {
        /* segment 0 turns 0 -> 40 degrees; segment 1 jumps to 160 and turns to 320 in steps of
         * 40 degrees, so that the triangles pass the circle's extremes between keys (there the
         * boxes at the keys do not hold them) */
        ring_keys(keys, seg == 0 ? 0.0f : 160.0f, seg == 0 ? 10.0f : 40.0f);
        if (seg == 1) { /* where segment 0 ended */
            evr_motion_key k0[5];
            ring_keys(k0, 0.0f, 10.0f);
            prev_end = evr_motion_eval((evr_motion_track){k0, 5}, 1.0f);
        }
        keys[5] = evr_motion_key_from_matrix(
            &(evr_m34){{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}}); /* the camera's */
        evr_skip_tracker_update(&t, keys, offset, count, 1.0f);
        evr_skip_plan_build(&t, &s, &rs, NULL, 1, &pl);
        CHECK(pl.num_boxes == 1 && pl.part_first[1] - pl.part_first[0] > 1);
        int missed = 0;
        for (int n = 0; n < 20000; n++) {
            /* a point of a triangle at a time of the segment (or, one in ten, the previous end) */
            float r1 = uni(&rng), r2 = uni(&rng), f = uni(&rng);
            if (r1 + r2 > 1.0f) {
                r1 = 1.0f - r1;
                r2 = 1.0f - r2;
            }
            const int tri = (int)(uni(&rng) * RING) % RING;
            const float *v = &pos[9 * tri];
            evr_v3 p = evr_v3_make(v[0] + r1 * (v[3] - v[0]) + r2 * (v[6] - v[0]),
                                   v[1] + r1 * (v[4] - v[1]) + r2 * (v[7] - v[1]),
                                   v[2] + r1 * (v[5] - v[2]) + r2 * (v[8] - v[2]));
            const int before = seg == 1 && n % 10 == 0;
            evr_m34 m = before ? prev_end : evr_motion_eval(evr_rs_track(&rs, 0), f);
            p = evr_m34_point(&m, p);
            evr_v3 o = evr_v3_make(40.0f * uni(&rng) - 20.0f, 40.0f * uni(&rng) - 20.0f, 30.0f);
            evr_v3 d = evr_v3_sub(p, o);
            const float len = sqrtf(evr_v3_dot(d, d));
            d = evr_v3_scale(d, 1.0f / len);
            /* where it was at the previous segment's end: in the instance's box (adaptive sampling
             * needs that), not in the parts (a clean cache needs only where things are now) */
            if (before ? !evr_skip_segment_meets(o, d, len, pl.lo[0], pl.hi[0], pl.pad)
                       : !evr_skip_ray_meets_any(&pl, o, d, len))
                missed++;
        }
        CHECK(missed == 0);
        /* the middle of the circle: inside the instance's box, outside every part */
        evr_v3 o = evr_v3_make(0.2f, 0.0f, 30.0f), d = evr_v3_make(0.0f, 0.0f, -1.0f);
        CHECK(evr_skip_segment_meets(o, d, INFINITY, pl.lo[0], pl.hi[0], pl.pad));
        if (seg == 0) CHECK(!evr_skip_ray_meets_any(&pl, o, d, INFINITY));
    }
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
        CHECK(pl.lo[b][0] <= -1.0f && pl.hi[b][0] >= 2.0f && pl.lo[b][1] <= -1.0f &&
              pl.hi[b][1] >= 1.0f);

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
        CHECK(!evr_skip_ray_meets_any(&pl, o, d, 8.0f)); /* ends before the box */
        CHECK(!evr_skip_ray_meets_any(&pl, evr_v3_make(5.0f, 0.0f, 10.0f), d,
                                      INFINITY)); /* beside it */
        CHECK(evr_skip_ray_meets_any(&pl, evr_v3_make(1.9f, 0.0f, 10.0f), d,
                                     INFINITY)); /* the swept end */
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
        w.keys[6] = evr_motion_key_from_matrix(&m); /* the camera's */
        w.offset[0] = 0;
        w.count[0] = 6;
        w.offset[1] = 6;
        w.count[1] = 1;
        CHECK(evr_skip_tracker_init(&t, 2));
        evr_skip_tracker_update(&t, w.keys, w.offset, w.count, 1.0f);
        CHECK(evr_motion_key_same(&w.keys[1],
                                  &w.keys[0])); /* the billionth: snapped to the key before */
        evr_skip_plan_build(&t, &w.s, &w.rs, NULL, 1, &pl);
        CHECK(pl.spans && pl.cache);
        CHECK(fabsf(pl.still_before - 1.99f / 5.0f) < 1e-6f &&
              fabsf(pl.still_after - 4.01f / 5.0f) < 1e-6f);
        CHECK(evr_skip_still_span(&pl, 0.1f) == 1 && evr_skip_still_span(&pl, 0.5f) == 0 &&
              evr_skip_still_span(&pl, 0.9f) == 2);
        CHECK(evr_skip_held(&pl, 1, 1) && !evr_skip_held(&pl, 2, 1) && !evr_skip_held(&pl, 0, 0) &&
              !evr_skip_held(&pl, 1, -1));
        CHECK(evr_skip_trace_time(&pl, 0.1f) == 0.0f && evr_skip_trace_time(&pl, 0.9f) == 1.0f &&
              evr_skip_trace_time(&pl, 0.5f) == 0.5f);
        /* the transform is the same bits anywhere in a span, and moves in between */
        evr_motion_track tr = evr_rs_track(&w.rs, 0);
        evr_m34 a = evr_motion_eval(tr, 0.01f), b2 = evr_motion_eval(tr, 0.37f),
                c = evr_motion_eval(tr, 0.81f), d = evr_motion_eval(tr, 0.999f),
                e = evr_motion_eval(tr, 0.5f);
        CHECK(memcmp(&a, &b2, sizeof a) == 0 && memcmp(&c, &d, sizeof c) == 0 && e.m[0][3] > 0.0f &&
              e.m[0][3] < 1.0f);
        /* brute force: the same spans (its samples traced at the same times), nothing held */
        evr_skip_plan_build(&t, &w.s, &w.rs, NULL, 0, &pl);
        CHECK(pl.spans && !pl.cache && evr_skip_still_span(&pl, 0.1f) == 1 &&
              !evr_skip_held(&pl, 1, 1));
        evr_skip_tracker_free(&t);
    }
    test_parts();
    return check_report("test_skip_plan");
}
