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
    int i, j;
    for (i = 0; i < t->num_tracks; i++) {
        evr_motion_key *k = keys + track_offset[i];
        int n = track_count[i];
        if (n == 1 && t->have_prev && t->prev_count[i] == 1 && keys_close(&k[0], &t->prev_last[i], scene_size))
            k[0] = t->prev_last[i];
        /* the same inside the segment: a key as close to the one before is that key, so that a
         * part of the segment where the track holds still is still bit for bit */
        for (j = 1; j < n; j++)
            if (keys_close(&k[j], &k[j - 1], scene_size)) k[j] = k[j - 1];
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

/* Merges the plan's boxes of the same track (box_track[b]: box b's track) into one each. */
static void merge_by_track(evr_skip_plan *pl, int *box_track)
{
    int b, c, n = 0;
    for (b = 0; b < pl->num_boxes; b++) {
        for (c = 0; c < n && box_track[c] != box_track[b]; c++) {}
        if (c == n) {
            memcpy(pl->lo[n], pl->lo[b], 3 * sizeof(float));
            memcpy(pl->hi[n], pl->hi[b], 3 * sizeof(float));
            box_track[n++] = box_track[b];
        } else {
            box_union(pl->lo[c], pl->hi[c], pl->lo[b], pl->hi[b]);
        }
    }
    pl->num_boxes = n;
}

/* The plan's still span: before the first and after the last change between consecutive keys of
 * any moving instance's track (with a hundredth of a key interval to spare, so that a time's
 * float key position never lands in the interval of a change). */
static void still_span(const evr_render_scene *rs, const evr_skip_tracker *t, evr_skip_plan *pl)
{
    int i, j;
    pl->still_before = 2.0f;
    pl->still_after = -1.0f;
    for (i = 0; i < rs->num_instances; i++) {
        const int tr = rs->instances[i].track;
        if (!t->moved[tr]) continue;
        const evr_motion_track tk = evr_rs_track(rs, tr);
        for (j = 0; j + 1 < tk.n; j++) {
            if (evr_motion_key_same(&tk.keys[j], &tk.keys[j + 1])) continue;
            pl->still_before = fminf(pl->still_before, ((float)j - 0.01f) / (float)(tk.n - 1));
            pl->still_after = fmaxf(pl->still_after, ((float)j + 1.01f) / (float)(tk.n - 1));
        }
    }
}

void evr_skip_plan_build(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs, int enabled,
                         evr_skip_plan *pl)
{
    int i, tr, per_track = 0;
    int box_track[EVR_SKIP_MAX_BOXES];
    memset(pl, 0, sizeof *pl);
    pl->pad = rs->ray_eps;
    /* the camera and the lights must hold still: inside the segment to cache, and since the
     * previous segment too to reuse */
    int cam = rs->camera_track, cache = rs->track_count[cam] == 1, still = !t->moved[cam];
    for (i = 0; i < rs->num_lights; i++) {
        tr = rs->lights[i].track;
        if (tr < 0) continue;
        if (rs->track_count[tr] != 1) cache = 0;
        if (t->moved[tr]) still = 0;
    }
    /* still spans with and without skipping: brute force traces their samples at the same times */
    pl->spans = cache;
    still_span(rs, t, pl);
    if (!enabled) return;
    /* a box per moving instance; once they are too many, a box per moving track */
    for (i = 0; i < rs->num_instances; i++) {
        float lo[3], hi[3];
        int b = pl->num_boxes;
        tr = rs->instances[i].track;
        if (!t->moved[tr]) continue;
        instance_box(t, s, rs, i, lo, hi);
        if (per_track)
            for (b = 0; b < pl->num_boxes && box_track[b] != tr; b++) {}
        if (b == EVR_SKIP_MAX_BOXES && !per_track) {
            per_track = 1;
            merge_by_track(pl, box_track);
            for (b = 0; b < pl->num_boxes && box_track[b] != tr; b++) {}
        }
        if (b < pl->num_boxes) {
            box_union(pl->lo[b], pl->hi[b], lo, hi);
        } else if (b < EVR_SKIP_MAX_BOXES) {
            memcpy(pl->lo[b], lo, sizeof lo);
            memcpy(pl->hi[b], hi, sizeof hi);
            box_track[b] = tr;
            pl->num_boxes++;
        } else {   /* too many moving things to bound: trace all */
            pl->num_boxes = 0;
            return;
        }
    }
    pl->cache = cache;
    pl->reuse = cache && still;
}

/* Largest distance a point of box [lo, hi] (object space) moves between keys a and b: a point of
 * the box is a convex combination of its corners, and the keys' transforms are affine. */
static float corner_move(const float lo[3], const float hi[3], const evr_motion_key *a, const evr_motion_key *b)
{
    evr_m34 ma = evr_motion_key_matrix(a), mb = evr_motion_key_matrix(b);
    float d = 0.0f;
    int c;
    for (c = 0; c < 8; c++) {
        evr_v3 p = evr_v3_make(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
        evr_v3 q = evr_v3_sub(evr_m34_point(&mb, p), evr_m34_point(&ma, p));
        d = fmaxf(d, sqrtf(evr_v3_dot(q, q)));
    }
    return d;
}

void evr_adapt_plan_build(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                          const evr_adapt_params *ap, double seconds, evr_adapt_plan *pl)
{
    int i, k;
    memset(pl, 0, sizeof *pl);
    pl->pad = rs->ray_eps;
    int cam = rs->camera_track;
    if (rs->track_count[cam] != 1 || t->moved[cam]) pl->all_min = 1;
    for (i = 0; i < rs->num_lights; i++) {
        int tr = rs->lights[i].track;
        if (tr >= 0 && (rs->track_count[tr] != 1 || t->moved[tr])) pl->all_min = 1;
    }
    if (pl->all_min) return;
    /* a world displacement d at distance r from the camera moves the image by at most
     * d / r * f_px * (1 + tx^2 + ty^2) pixels (the pinhole's largest stretch, at the corners) */
    evr_m34 pose = evr_rs_camera_pose(rs, 0.0f);
    evr_v3 eye = evr_v3_make(pose.m[0][3], pose.m[1][3], pose.m[2][3]);
    const float ty = rs->camera.tan_half_y, tx = ty * rs->camera.aspect;
    const float px_per_rad = 0.5f * (float)rs->camera.height / ty * (1.0f + tx * tx + ty * ty);
    for (i = 0; i < rs->num_instances; i++) {
        int tr = rs->instances[i].track, b;
        if (!t->moved[tr]) continue;
        const evr_mesh *m = &s->meshes[rs->instances[i].mesh];
        const float lo[3] = {m->bounds_min.x, m->bounds_min.y, m->bounds_min.z};
        const float hi[3] = {m->bounds_max.x, m->bounds_max.y, m->bounds_max.z};
        float blo[3], bhi[3], r2 = 0.0f, move = 0.0f, jump = 0.0f;
        instance_box(t, s, rs, i, blo, bhi);
        for (k = 0; k < 3; k++) {   /* distance from the camera to the box */
            const float e = k == 0 ? eye.x : k == 1 ? eye.y : eye.z;
            const float d = e < blo[k] ? blo[k] - e : e > bhi[k] ? e - bhi[k] : 0.0f;
            r2 += d * d;
        }
        const evr_motion_track tk = evr_rs_track(rs, tr);
        for (k = 0; k + 1 < tk.n; k++) move = fmaxf(move, corner_move(lo, hi, &tk.keys[k], &tk.keys[k + 1]));
        if (t->prev_count[tr] > 0) jump = corner_move(lo, hi, &t->prev_last[tr], &tk.keys[0]);
        const float r = sqrtf(r2);
        /* keys are close (< 120 degrees apart, 1e-5 of the scene from the curves): 1.25 covers
         * a point's arc between keys being longer than its chord */
        float speed = tk.n > 1 ? 1.25f * move * (float)(tk.n - 1) / (float)seconds : 0.0f;
        float jump_px = jump * px_per_rad / r;
        speed = r > 0.0f ? speed * px_per_rad / r : INFINITY;
        if (!(speed >= 0.0f)) speed = INFINITY;
        if (pl->num_boxes < EVR_SKIP_MAX_BOXES) {
            b = pl->num_boxes++;
            memcpy(pl->lo[b], blo, sizeof blo);
            memcpy(pl->hi[b], bhi, sizeof bhi);
            pl->speed[b] = 0.0f;
        } else {   /* too many: the last box holds the rest */
            b = EVR_SKIP_MAX_BOXES - 1;
            box_union(pl->lo[b], pl->hi[b], blo, bhi);
        }
        pl->speed[b] = fmaxf(pl->speed[b], speed);
        if (!(jump_px <= EVR_ADAPT_PX_PER_FRAC * ap->frac)) pl->jump[b] = 1;
    }
}
