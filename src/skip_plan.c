/* Per-segment plan of change-driven sampling: see skip_plan.h and core/skip.h. */
#include "skip_plan.h"
#include "cuda/gpu_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int evr_skip_tracker_init(evr_skip_tracker *t, int num_tracks)
{
    memset(t, 0, sizeof *t);
    t->num_tracks = num_tracks;
    t->prev_last = calloc((size_t)num_tracks, sizeof *t->prev_last);
    t->prev_count = calloc((size_t)num_tracks, sizeof *t->prev_count);
    t->moved = calloc((size_t)num_tracks, sizeof *t->moved);
    return t->prev_last && t->prev_count && t->moved;
}

void evr_skip_tracker_free(evr_skip_tracker *t)
{
    free(t->prev_last);
    free(t->prev_count);
    free(t->moved);
    memset(t, 0, sizeof *t);
}

static int close_to(float a, float b, float tol) { return fabsf(a - b) <= tol; }

static int keys_close(const evr_motion_key *a, const evr_motion_key *b, float size)
{
    const float r = 1e-6f, d = 1e-9f * size;
    int i;
    for (i = 0; i < 3; i++)
        if (!close_to(a->scale[i], b->scale[i], r * fmaxf(1.0f, fabsf(a->scale[i]))) ||
            !close_to(a->skew[i], b->skew[i], r * fmaxf(1.0f, fabsf(a->skew[i]))))
            return 0;
    return close_to(a->rot.w, b->rot.w, r) && close_to(a->rot.x, b->rot.x, r) && close_to(a->rot.y, b->rot.y, r) &&
           close_to(a->rot.z, b->rot.z, r) && close_to(a->trans.x, b->trans.x, d + r * fabsf(a->trans.x)) &&
           close_to(a->trans.y, b->trans.y, d + r * fabsf(a->trans.y)) &&
           close_to(a->trans.z, b->trans.z, d + r * fabsf(a->trans.z));
}

void evr_skip_tracker_update(evr_skip_tracker *t, evr_motion_key *keys, const int *track_offset,
                             const int *track_count, float scene_size)
{
    int i;
    for (i = 0; i < t->num_tracks; i++) {
        evr_motion_key *k = keys + track_offset[i];
        int n = track_count[i];
        if (n == 1 && t->have_prev && t->prev_count[i] == 1 && keys_close(&k[0], &t->prev_last[i], scene_size))
            k[0] = t->prev_last[i];
        t->moved[i] = n > 1 || (t->have_prev && memcmp(&k[0], &t->prev_last[i], sizeof k[0]) != 0);
        t->prev_last[i] = k[n - 1];
        t->prev_count[i] = n;
    }
    t->have_prev = 1;
}

static void box_union(float lo[3], float hi[3], const float l2[3], const float h2[3])
{
    int a;
    for (a = 0; a < 3; a++) {
        lo[a] = fminf(lo[a], l2[a]);
        hi[a] = fmaxf(hi[a], h2[a]);
    }
}

/* World box of instance i over the segment, and where it was at the previous segment's end. */
static void instance_box(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs, int i, float blo[3],
                         float bhi[3])
{
    int tr = rs->instances[i].track;
    const evr_mesh *m = &s->meshes[rs->instances[i].mesh];
    float lo[3] = {m->bounds_min.x, m->bounds_min.y, m->bounds_min.z};
    float hi[3] = {m->bounds_max.x, m->bounds_max.y, m->bounds_max.z};
    evr_gpu_segment_bounds(lo, hi, evr_rs_track(rs, tr), blo, bhi);
    if (t->prev_count[tr] > 0) {
        evr_motion_track prev;
        float plo[3], phi[3];
        prev.keys = &t->prev_last[tr];
        prev.n = 1;
        evr_gpu_segment_bounds(lo, hi, prev, plo, phi);
        box_union(blo, bhi, plo, phi);
    }
}

/* Adds a box; 0 when the plan is full. */
static int add_box(evr_skip_plan *pl, const float lo[3], const float hi[3])
{
    if (pl->num_boxes == EVR_SKIP_MAX_BOXES) return 0;
    memcpy(pl->lo[pl->num_boxes], lo, 3 * sizeof(float));
    memcpy(pl->hi[pl->num_boxes], hi, 3 * sizeof(float));
    pl->num_boxes++;
    return 1;
}

void evr_skip_plan_build(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs, int enabled,
                         evr_skip_plan *pl)
{
    int i, tr, ok = 1;
    memset(pl, 0, sizeof *pl);
    pl->pad = rs->ray_eps;
    if (!enabled) return;
    /* the camera and the lights must hold still: inside the segment to cache, and since the
     * previous segment too to reuse */
    int cam = rs->camera_track, cache = rs->track_count[cam] == 1, still = !t->moved[cam];
    for (i = 0; i < rs->num_lights; i++) {
        tr = rs->lights[i].track;
        if (tr < 0) continue;
        if (rs->track_count[tr] != 1) cache = 0;
        if (t->moved[tr]) still = 0;
    }
    /* a box per moving instance; if they are too many, a box per moving track */
    for (i = 0; i < rs->num_instances && ok; i++) {
        float lo[3], hi[3];
        if (!t->moved[rs->instances[i].track]) continue;
        instance_box(t, s, rs, i, lo, hi);
        ok = add_box(pl, lo, hi);
    }
    if (!ok) {
        pl->num_boxes = 0;
        for (tr = 0; tr < t->num_tracks; tr++) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            int any = 0;
            if (!t->moved[tr]) continue;
            for (i = 0; i < rs->num_instances; i++) {
                float l2[3], h2[3];
                if (rs->instances[i].track != tr) continue;
                instance_box(t, s, rs, i, l2, h2);
                box_union(lo, hi, l2, h2);
                any = 1;
            }
            if (any && !add_box(pl, lo, hi)) {   /* too many moving things to bound: trace all */
                pl->num_boxes = 0;
                return;
            }
        }
    }
    pl->cache = cache;
    pl->reuse = cache && still;
}
