/* CPU backend: Embree finds the triangles; motion-blurred instances carry each node's segment
 * keys as quaternion-decomposition time steps; tiles of pixels are spread over threads. */
#include "backend.h"
#include "host_clock.h"
#include "core/rng.h"
#include "core/adaptive.h"
#include "core/refine.h"
#include "core/pixel_flow.h"
#include "core/shade_hit.h"
#include "core/skip.h"
#include "cpu/workers.h"
#include "cpu/cpu_gi.h"
#include "cpu/deform_geometry.h"
#include "prep/instance_groups.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#if defined(__SSE__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

#define TILE 16

typedef struct {
    evr_backend base;
    const evr_scene *scene;
    evr_render_host host; /* copy of the views; keys are set per segment */
    evr_run_setup setup;
    RTCDevice device;
    /* One Embree instance per group of instances (prep/instance_groups.h) keeps overlapping
     * instances (lids over an eyeball) out of each other's way in the top-level BVH: a baked
     * group is one world-space scene, a static group an instance with its node's fixed transform
     * of one scene per mesh that all its instances share, a moving group its node's scene moved
     * by the node's motion keys. */
    evr_instance_groups groups;
    RTCScene *group_scenes;
    int *deform_keys_set;    /* per group: the keys a deforming group's vertices have (0: none) */
    evr_cpu_deform *deforms; /* per group: a deforming group's triangles and current keys */
    evr_cpu_filter_map filter_map; /* what the hit filters read (cpu/embree_filter.h) */
    RTCScene top;
    int time_grid; /* the segment's motion keys split it into this many equal intervals (1: none moves) */
    int gi;        /* global illumination on */
    evr_cpu_gi gi_state;
    evr_pixel_state *pixels;
    float *phase;      /* per-pixel sample-time offset in [0, 1) */
    float *next_t;     /* adaptive sampling: each pixel's next sample, segment-relative */
    unsigned *last_id; /* event ids (setup.event_ids): each pixel's last traced sample's */
    int tiles_x, tiles_y;
    evr_event_vec *tile_events;
    /* results of submitted segments not yet collected (a ring of two) */
    evr_event_vec done[2], scratch;
    float *done_intensity[2];
    int done_has_intensity[2];
    float *done_frames[2];     /* intensity frames of the segment (done_num_frames images) */
    size_t done_frames_cap[2]; /* images done_frames has room for */
    int done_num_frames[2];
    evr_hit *done_labels[2];   /* label hits of the segment (done_num_labels images) */
    size_t done_labels_cap[2]; /* images done_labels has room for */
    int done_num_labels[2];
    int collected;                        /* the slot collected last, -1: none yet */
    unsigned long long done_counts[2][4]; /* samples, rays, samples traced, pixels skipped */
    int head, queued;
    /* the packets' context flags: coherent (Embree's frustum traversal, faster for neighbouring
     * pixels), or incoherent under the hidden EVR_EMBREE_INCOHERENT (scripts/valgrind-eye.sh:
     * Embree 3.13's coherent traversal branches on values it leaves unset on its own stack) */
    enum RTCIntersectContextFlags packet_flags;
    char embree_error[256];
    /* per-segment work */
    const evr_segment *seg;
    float *frame_f; /* normalized segment time of each wanted frame */
    int frame_f_cap;
    float *frame_out; /* where the segment's frames go */
    float *label_f;   /* normalized segment time of each wanted label frame */
    int label_f_cap;
    evr_hit *label_out; /* where the segment's label hits go */
    atomic_int next_tile;
    atomic_ullong samples, rays, samples_traced, pixels_skipped;
    atomic_int failed;
} cpu_backend;

/* evr_sim_cancel asked the run to stop at once: the segment's work is given up. */
static int cancelled(const cpu_backend *b)
{
    return b->setup.cancel && __atomic_load_n(b->setup.cancel, __ATOMIC_RELAXED);
}

static void embree_error(void *user, enum RTCError code, const char *str)
{
    cpu_backend *b = (cpu_backend *)user;
    if (!b->embree_error[0])
        snprintf(b->embree_error, sizeof b->embree_error, "Embree error %d: %s", (int)code,
                 str ? str : "");
}

static void to_embree(const evr_motion_key *k, struct RTCQuaternionDecomposition *q)
{
    rtcInitQuaternionDecomposition(q);
    q->scale_x = k->scale[0];
    q->scale_y = k->scale[1];
    q->scale_z = k->scale[2];
    q->skew_xy = k->skew[0];
    q->skew_xz = k->skew[1];
    q->skew_yz = k->skew[2];
    q->quaternion_r = k->rot.w;
    q->quaternion_i = k->rot.x;
    q->quaternion_j = k->rot.y;
    q->quaternion_k = k->rot.z;
    q->translation_x = k->trans.x;
    q->translation_y = k->trans.y;
    q->translation_z = k->trans.z;
}

/* core/path.h's ray queries, one ray at a time (a path's rays after the primary hit, and
 * shadow rays through translucent surfaces): Embree at the sample's trace time. */
struct evr_occlusion {
    const cpu_backend *b;
    float trace_time; /* evr_skip_trace_time of the sample */
};

static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f)
{
    (void)f;
    return evr_embree_occluded1(o->b->top, r, tnear, tfar, o->trace_time);
}

static inline int evr_closest(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f,
                              evr_hit *h)
{
    (void)f;
    return evr_embree_closest1(o->b->top, o->b->groups.members, o->b->groups.group_first, r, tnear,
                               tfar, o->trace_time, h);
}

#include "core/path.h"

/* Intensity of eight samples at once (neighbouring pixels of a row, each at its own time):
 * Embree's packet traversal for the primary rays and for each light's shadow rays, then the
 * shared shading of src/core lane by lane. Counts the rays it traces; t_hit gets each primary
 * ray's hit distance (INFINITY: none); NULL for a frame's samples, which are not the pixel
 * model's (they leave its GI memo alone). direct (may be NULL): the direct light alone. */
#define PACKET 8

/* The primary rays of eight samples (pixel centres, each at its own time; pose_static: the
 * camera's pose for all of them, NULL: each at its time) through Embree's packet traversal:
 * their rays into ray, their closest hits into rh. Counts the rays it traces. */
static void primary_packet8(const cpu_backend *b, const evr_m34 *pose_static, const int *xs,
                            const int *ys, const float *fs, const int *valid, evr_ray *ray,
                            struct RTCRayHit8 *rh, unsigned long long *rays)
{
    const evr_render_scene *rs = &b->host.rs;
    struct RTCIntersectContext ctx;
    _Alignas(32) int vmask[PACKET]; /* Embree reads the valid mask with aligned vector loads */
    int i;
    rtcInitIntersectContext(&ctx);
    ctx.flags = b->packet_flags;
    for (i = 0; i < PACKET; i++) {
        evr_m34 pose = pose_static ? *pose_static : evr_rs_camera_pose(rs, fs[i]);
        ray[i] = evr_camera_ray(&rs->camera, &pose, (float)xs[i] + 0.5f, (float)ys[i] + 0.5f);
        vmask[i] = valid[i] ? -1 : 0;
        rh->ray.org_x[i] = ray[i].org.x;
        rh->ray.org_y[i] = ray[i].org.y;
        rh->ray.org_z[i] = ray[i].org.z;
        rh->ray.dir_x[i] = ray[i].dir.x;
        rh->ray.dir_y[i] = ray[i].dir.y;
        rh->ray.dir_z[i] = ray[i].dir.z;
        rh->ray.tnear[i] = 0.0f;
        rh->ray.tfar[i] = INFINITY;
        rh->ray.time[i] =
            evr_skip_trace_time(b->seg->skip, fs[i]); /* a still span: one time for Embree */
        rh->ray.mask[i] = 0xffffffffu;
        rh->ray.id[i] = (unsigned)i;
        rh->ray.flags[i] = 0;
        rh->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        if (valid[i]) (*rays)++;
    }
    rtcIntersect8(vmask, b->top, &ctx, rh);
}

/* Intensity of eight samples at once (neighbouring pixels of a row, each at its own time):
 * Embree's packet traversal for the primary rays and for each light's shadow rays, then the
 * shared shading of src/core lane by lane. Counts the rays it traces; t_hit gets each primary
 * ray's hit distance (INFINITY: none); NULL for a frame's samples, which are not the pixel
 * model's (they leave its GI memo alone). direct (may be NULL): the direct light alone. ids (may
 * be NULL): each sample's event id (evr_event.id: 1 + the instance hit, 0 none). */
static void sample_intensity8_rows(const cpu_backend *b, const evr_m34 *pose_static, const int *xs,
                                   const int *ys, const float *fs, const int *valid, float *out,
                                   float *t_hit, float *direct, int *deep, unsigned *ids,
                                   unsigned long long *rays)
{
    const evr_render_scene *rs = &b->host.rs;
    struct RTCIntersectContext ctx;
    struct RTCRayHit8 rh;
    struct RTCRay8 sr;
    evr_ray ray[PACKET];
    evr_surface s[PACKET];
    float acc[PACKET][3];
    _Alignas(32) int vmask[PACKET]; /* Embree reads the valid mask with aligned vector loads */
    int hit[PACKET], inst_of[PACKET], i, l;
    rtcInitIntersectContext(&ctx);
    ctx.flags = b->packet_flags;
    primary_packet8(b, pose_static, xs, ys, fs, valid, ray, &rh, rays);
    for (i = 0; i < PACKET; i++) {
        out[i] = 0.0f; /* nothing: black */
        if (direct) direct[i] = 0.0f;
        acc[i][0] = acc[i][1] = acc[i][2] = 0.0f;
        hit[i] = valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        if (t_hit) t_hit[i] = hit[i] ? rh.ray.tfar[i] : INFINITY;
        if (ids) ids[i] = 0;
        if (deep) deep[i] = 0;
        if (!hit[i]) continue;
        int inst =
            b->groups.members[b->groups.group_first[rh.hit.instID[0][i]] + (int)rh.hit.geomID[i]];
        inst_of[i] = inst;
        if (ids) ids[i] = (unsigned)inst + 1u;
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[inst].track), fs[i]);
        evr_surface_at(rs, inst, rh.hit.primID[i], rh.hit.u[i], rh.hit.v[i], &xf, fs[i], ray[i],
                       rh.ray.tfar[i], evr_camera_cone(&rs->camera, rh.ray.tfar[i]), &s[i]);
    }
    /* core/shade.h's steps light by light: each light's shadow rays as one packet; a blocked
     * ray in a scene with translucent surfaces is followed through them one ray at a time
     * (evr_shadow_pass). Embree reads every lane's fields, masked ones too: all start as an
     * empty ray (valgrind found the masked lanes' fields never written). */
    if (rs->num_lights > 0) memset(&sr, 0, sizeof sr);
    for (l = 0; l < rs->num_lights; l++) {
        evr_light_ray lr[PACKET];
        int any = 0;
        for (i = 0; i < PACKET; i++) {
            vmask[i] = 0;
            if (!hit[i] || !evr_shade_light_ray(rs, l, fs[i], &s[i], &lr[i])) continue;
            vmask[i] = -1;
            any = 1;
            (*rays)++;
            sr.org_x[i] = lr[i].ray.org.x;
            sr.org_y[i] = lr[i].ray.org.y;
            sr.org_z[i] = lr[i].ray.org.z;
            sr.dir_x[i] = lr[i].ray.dir.x;
            sr.dir_y[i] = lr[i].ray.dir.y;
            sr.dir_z[i] = lr[i].ray.dir.z;
            sr.tnear[i] = lr[i].tnear;
            sr.tfar[i] = lr[i].tfar;
            sr.time[i] = rh.ray.time[i];
            sr.mask[i] = 0xffffffffu;
            sr.id[i] = (unsigned)i;
            sr.flags[i] = 0;
        }
        if (!any) continue;
        rtcOccluded8(vmask, b->top, &ctx, &sr);
        for (i = 0; i < PACKET; i++) {
            if (!vmask[i]) continue;
            if (sr.tfar[i] < 0.0f) { /* blocked: through translucent surfaces, or not at all */
                struct evr_occlusion o = {b, rh.ray.time[i]};
                float T[3];
                if (!rs->translucent ||
                    !evr_shadow_pass(rs, &o, lr[i].ray, lr[i].tnear, lr[i].tfar, fs[i], T))
                    continue;
                for (int c = 0; c < 3; c++) lr[i].e[c] *= T[c];
            }
            evr_shade_add_light(&s[i], evr_v3_scale(ray[i].dir, -1.0f), &lr[i], acc[i]);
        }
    }
    for (i = 0; i < PACKET; i++) {
        if (!hit[i]) { /* GI: the pixel model's sample met nothing (frames leave the memo alone) */
            if (b->gi && valid[i] && t_hit) evr_cpu_gi_missed(&b->gi_state, xs[i], ys[i]);
            continue;
        }
        struct evr_occlusion o = {b, rh.ray.time[i]};
        unsigned r1 = 0;
        int dp = 0;
        out[i] = evr_path_intensity(rs, &s[i], ray[i].dir, rh.ray.tfar[i], acc[i], &o, fs[i],
                                    b->seg->skip->cache ? b->seg->skip : NULL, &r1, &dp);
        *rays += r1;
        if (deep) deep[i] = dp;
        if (direct) direct[i] = out[i];
        if (b->gi)
            out[i] += evr_cpu_gi_indirect(&b->gi_state, rs, inst_of[i], &s[i], ray[i].org, xs[i],
                                          ys[i], fs[i], t_hit != NULL);
    }
}

/* The same for eight pixels of one row. */
static void sample_intensity8(const cpu_backend *b, const evr_m34 *pose_static, const int *xs,
                              int y, const float *fs, const int *valid, float *out, float *t_hit,
                              unsigned long long *rays)
{
    int ys[PACKET], i;
    for (i = 0; i < PACKET; i++) ys[i] = y;
    sample_intensity8_rows(b, pose_static, xs, ys, fs, valid, out, t_hit, NULL, NULL, NULL, rays);
}

static void render_frames(cpu_backend *b, int x0, int y0, int x1, int y1);

/* core/pixel_flow.h's event sink: a tile's events. */
struct evr_event_sink {
    evr_event_vec *out;
    atomic_int *failed;
    unsigned id; /* the sample's event id */
};

static inline int evr_event_sink_push(struct evr_event_sink *k, int has, long long t_us, int x,
                                      int y, int polarity)
{
    evr_event e;
    if (!has) return 0;
    e.t = t_us;
    e.x = (uint16_t)x;
    e.y = (uint16_t)y;
    e.p = (int8_t)polarity;
    e.id = (uint16_t)k->id;
    if (!evr_event_vec_push(k->out, e)) atomic_store(k->failed, 1);
    return 1;
}

/* One sample of pixel (x, y) (intensity at t seconds from the segment's start, id its event id)
 * through its pixel model; its events go to out. Kept out of line with the loop inlined in it: inlined into its
 * callers instead, GCC kept the loop as a call of many arguments (about 1% slower). */
__attribute__((noinline)) static void pixel_sample(cpu_backend *b, evr_pixel_state *st,
                                                   const evr_pixel_params *pp, int ideal, float t,
                                                   float intensity, unsigned id, int x, int y,
                                                   evr_event_vec *out)
{
    struct evr_event_sink k;
    k.out = out;
    k.failed = &b->failed;
    k.id = id;
    evr_pixel_sample_events(st, pp, evr_pixel_ideal_of(pp), !ideal, 1, t, intensity, b->seg->t0, x,
                            y, &k);
}

/* A pixel of the tile in the segment's work. */
typedef struct {
    evr_pixel_state *st;
    evr_pixel_params pp;      /* its thresholds, leak and noise (a fixed pattern) */
    evr_ray ray;              /* its centre ray (the camera at the segment's start) */
    float phi, t_last, t_hit; /* sample phase; time of its last sample; last hit distance */
    int deep;                 /* its last traced sample's path went past the primary hit */
    float direct;             /* GI: its last traced sample's direct light */
    int last_span;            /* the still span (evr_skip_still_span) of its last traced sample */
    int keep;                 /* refined sampling: it keeps its intensity (evr_refine_keep) */
    unsigned id;              /* its last traced sample's event id */
    int x, y;
} tile_pixel;

/* Whether, with GI, the pixel's last traced sample met a surface (its indirect light then moves
 * in time). */
static int gi_lit(const cpu_backend *b, const tile_pixel *q)
{
    return b->gi && q->t_hit >= 0.0f && q->t_hit < INFINITY;
}

/* The intensity of a sample at normalized time f that takes its pixel's last traced sample's
 * (settled, or held in a still span): that intensity, or with GI on a surface, that sample's
 * direct light and its gathers' indirect light at f (evr_cpu_gi_last). */
static float kept_intensity(const cpu_backend *b, const tile_pixel *q, float f)
{
    return gi_lit(b, q) ? q->direct + evr_cpu_gi_last(&b->gi_state, q->x, q->y, f)
                        : q->st->intensity;
}

/* The samples k0 .. n - 1 of a pixel that keeps its intensity: none when they cannot change it
 * (the ideal model, evr_pixel_quiet_ideal), else each through the pixel model. With GI, a pixel
 * that settled on a surface (gi_lit) keeps the direct light of that sample and its gather, whose
 * indirect light still moves in time (evr_cpu_gi_last). */
static void keep_samples(cpu_backend *b, tile_pixel *q, int ideal, int k0, int n, float dt,
                         evr_event_vec *out)
{
    const float in = q->st->intensity;
    int k;
    if (gi_lit(b, q) && !evr_cpu_gi_flat(&b->gi_state, q->x, q->y)) {
        for (k = k0; k < n; k++) {
            const float f = ((float)k + q->phi) / (float)n;
            pixel_sample(b, q->st, &q->pp, ideal, f * dt, kept_intensity(b, q, f), q->id, q->x,
                         q->y, out);
        }
        return;
    }
    if (ideal && evr_pixel_quiet_ideal(q->st, q->pp.log_floor, q->pp.pos_thres, q->pp.neg_thres, in,
                                       q->t_last)) {
        evr_pixel_quiet_finish(q->st, q->pp.log_floor, in, q->t_last);
        return;
    }
    for (k = k0; k < n; k++)
        pixel_sample(b, q->st, &q->pp, ideal, (((float)k + q->phi) / (float)n) * dt, in, q->id,
                     q->x, q->y, out);
}

/* The interval between the segment's motion keys that Embree traces a sample at normalized time f
 * in (evr_skip_trace_time): packets are grouped by it. */
static int key_interval(const cpu_backend *b, float f)
{
    const int g = (int)(evr_skip_trace_time(b->seg->skip, f) * (float)b->time_grid);
    return g < 0 ? 0 : g >= b->time_grid ? b->time_grid - 1 : g;
}

/* Samples k0 .. k1 - 1 of the listed pixels, traced eight at a time in packets (any pixels of the
 * tile: the packets stay full however few pixels trace). Sample by sample, each packet's lanes
 * are pixels whose ray times fall in the same interval between the segment's motion keys: Embree's
 * motion-blurred top level splits its nodes at the keys, and a packet whose lanes straddle them
 * traverses each part again (the eye's blink: 1.75x the time of packets at one time). A sample in
 * the still span of its pixel's last traced sample takes that sample's intensity (no rays). With
 * settle (k0 == 0, k1 == 1): a pixel whose first sample's rays meet nothing that moves in the
 * segment keeps that intensity for the rest of the segment (its later samples run here); the
 * others are listed in *more. Each pixel's samples reach its pixel model in time order. */
static void trace_samples(cpu_backend *b, tile_pixel *px, const int *list, int count, int k0,
                          int k1, int settle, int *more, int *num_more, const evr_m34 *pose_static,
                          int ideal, float dt, evr_event_vec *out, unsigned long long *rays,
                          unsigned long long *traced)
{
    const evr_render_scene *rs = &b->host.rs;
    const evr_segment *seg = b->seg;
    const int n = b->setup.samples_per_frame, grid = b->time_grid;
    int order[TILE * TILE], bucket[TILE * TILE], first[EVR_MAX_KEYS + 1];
    float fk[TILE * TILE]; /* listed pixel j's normalized time at sample k */
    int c, i, j, k, g;
    for (k = k0; k < k1; k++) {
        int ntr = 0;
        if (k > k0 && cancelled(b)) return; /* a long segment still stops at once */
        for (g = 0; g <= grid; g++) first[g] = 0;
        for (j = 0; j < count; j++) {
            tile_pixel *q = &px[list[j]];
            const float f = fk[j] = ((float)k + q->phi) / (float)n;
            /* held: in the still span of its last traced sample, the same scene bit for bit */
            const int span = evr_skip_still_span(seg->skip, f);
            if (evr_skip_held(seg->skip, span, q->last_span)) {
                bucket[j] = -1;
                pixel_sample(b, q->st, &q->pp, ideal, f * dt, kept_intensity(b, q, f), q->id, q->x,
                             q->y, out);
                continue;
            }
            q->last_span = span;
            bucket[j] = key_interval(b, f);
            first[bucket[j] + 1]++;
            ntr++;
        }
        for (g = 0; g < grid; g++) first[g + 1] += first[g];
        for (j = 0; j < count; j++)
            if (bucket[j] >= 0) order[first[bucket[j]]++] = j; /* list order within an interval */
        for (c = 0; c < ntr; c += PACKET) {
            int xs[PACKET], ys[PACKET], valid[PACKET];
            float fs[PACKET], intensity[PACKET], t_hit[PACKET], direct[PACKET];
            int deep[PACKET];
            unsigned ids[PACKET];
            tile_pixel *q[PACKET];
            for (i = 0; i < PACKET; i++) {
                valid[i] = c + i < ntr;
                j = order[valid[i] ? c + i : c];
                q[i] = &px[list[j]];
                xs[i] = q[i]->x;
                ys[i] = q[i]->y;
                fs[i] = fk[j];
            }
            sample_intensity8_rows(b, seg->camera_static ? pose_static : NULL, xs, ys, fs, valid,
                                   intensity, t_hit, direct, deep, b->last_id ? ids : NULL, rays);
            for (i = 0; i < PACKET; i++) {
                if (!valid[i]) continue;
                (*traced)++;
                q[i]->t_hit = t_hit[i];
                q[i]->deep = deep[i];
                q[i]->direct = direct[i];
                if (b->last_id) q[i]->id = ids[i];
                pixel_sample(b, q[i]->st, &q[i]->pp, ideal, fs[i] * dt, intensity[i], q[i]->id,
                             xs[i], ys[i], out);
            }
        }
    }
    if (!settle) return;
    for (j = 0; j < count; j++) {
        tile_pixel *q = &px[list[j]];
        float cd = evr_skip_cache_after_trace(rs, seg->skip, q->ray, q->t_hit, q->deep);
        if (evr_skip_clean(cd)) { /* settled: the same triangles at every sample */
            q->st->cache_dist = cd;
            keep_samples(b, q, ideal, k1, n, dt, out);
            q->t_hit = -1.0f; /* its cache is set */
        } else {
            more[(*num_more)++] = list[j];
        }
    }
}

/* Runs a pixel's refined sampling (core/refine.h) until it needs a sample traced (1) or is done
 * with the segment (0): samples it can take without rays, and every candidate the refinement
 * lets through, go through its pixel model here. */
static int refine_advance(cpu_backend *b, evr_refine_pixel *r, tile_pixel *q, int ideal, float dt,
                          evr_event_vec *out)
{
    for (;;) {
        if (r->need && !evr_refine_kept(r, b->seg->skip, r->t / dt)) return 1;
        if (!r->cand) return 0;
        if (!evr_refine_decide(r, &b->setup.refine_params, q->st, &q->pp)) continue;
        pixel_sample(b, q->st, &q->pp, ideal, r->ct, r->ci, r->cid, q->x, q->y, out);
        evr_refine_next_bounded(r, &b->host.rs, b->seg->adapt, &b->setup.refine_params, q->ray, dt);
    }
}

/* Refined sampling of the listed pixels (those that trace in the segment, and with a sensor model
 * those that keep their intensity: tile_pixel.keep): each round, every
 * pixel that needs a sample traced traces it, eight at a time in packets grouped by the interval
 * between the segment's motion keys their times fall in (as trace_samples), then runs on until
 * it needs the next. Each pixel's samples reach its pixel model in time order. */
static void refine_samples(cpu_backend *b, tile_pixel *px, const int *list, int count,
                           const evr_m34 *pose_static, int ideal, float dt, evr_event_vec *out,
                           unsigned long long *rays, unsigned long long *traced)
{
    const evr_render_scene *rs = &b->host.rs;
    const evr_segment *seg = b->seg;
    const int grid = b->time_grid, may_settle = !b->gi;
    evr_refine_pixel rq[TILE * TILE];
    int act[TILE * TILE], order[TILE * TILE], bucket[TILE * TILE], first[EVR_MAX_KEYS + 1];
    int nact = 0, j, g, c;
    for (j = 0; j < count; j++) {
        const tile_pixel *q = &px[list[j]];
        const float motion_dt =
            evr_refine_motion_dt_first(rs, seg->adapt, &b->setup.refine_params, q->ray);
        evr_refine_begin(&rq[j], q->st, evr_refine_step(&b->setup.refine_params, motion_dt, dt),
                         dt);
        if (q->keep) evr_refine_keep(&rq[j], q->st, q->id);
        if (refine_advance(b, &rq[j], &px[list[j]], ideal, dt, out)) act[nact++] = j;
    }
    while (nact > 0 && !cancelled(b)) {
        int kept = 0, a;
        for (g = 0; g <= grid; g++) first[g] = 0;
        for (a = 0; a < nact; a++) {
            bucket[a] = key_interval(b, rq[act[a]].t / dt);
            first[bucket[a] + 1]++;
        }
        for (g = 0; g < grid; g++) first[g + 1] += first[g];
        for (a = 0; a < nact; a++) order[first[bucket[a]]++] = act[a];
        for (c = 0; c < nact; c += PACKET) {
            int xs[PACKET], ys[PACKET], valid[PACKET], deep[PACKET], i;
            float fs[PACKET], intensity[PACKET], t_hit[PACKET];
            unsigned ids[PACKET];
            for (i = 0; i < PACKET; i++) {
                valid[i] = c + i < nact;
                j = order[valid[i] ? c + i : c];
                xs[i] = px[list[j]].x;
                ys[i] = px[list[j]].y;
                fs[i] = rq[j].t / dt;
                ids[i] = 0;
            }
            sample_intensity8_rows(b, seg->camera_static ? pose_static : NULL, xs, ys, fs, valid,
                                   intensity, t_hit, NULL, deep, b->last_id ? ids : NULL, rays);
            for (i = 0; i < PACKET; i++) {
                if (!valid[i]) continue;
                j = order[c + i];
                tile_pixel *q = &px[list[j]];
                (*traced)++;
                evr_refine_traced(&rq[j], rs, seg->skip, q->st, q->ray, fs[i], intensity[i],
                                  t_hit[i], deep[i], ids[i], may_settle);
                if (refine_advance(b, &rq[j], q, ideal, dt, out)) act[kept++] = j;
            }
        }
        nact = kept;
    }
    for (j = 0; j < count; j++) {
        tile_pixel *q = &px[list[j]];
        evr_refine_end(&rq[j], rs, seg->skip, q->st, q->ray);
        q->t_hit = -1.0f; /* its cache is set */
        if (rq[j].traced_any) q->id = rq[j].last_id;
    }
}

/* A tile's pixels through the segment. A pixel that nothing moving can reach keeps its intensity
 * (change-driven sampling) and runs its samples without rays; the others trace, compacted into
 * full packets: first every such pixel's first sample, then the samples of those that did not
 * settle. A pixel's samples always reach its pixel model in time order. */
static void render_tile(cpu_backend *b, int tile, unsigned long long *samples,
                        unsigned long long *rays, unsigned long long *traced,
                        unsigned long long *skipped)
{
    const evr_render_scene *rs = &b->host.rs;
    const evr_segment *seg = b->seg;
    const evr_skip_plan *plan = seg->skip;
    const int w = b->setup.width, h = b->setup.height, n = b->setup.samples_per_frame;
    const float dt = (float)(seg->t1 - seg->t0);
    int tx = tile % b->tiles_x, ty = tile / b->tiles_x;
    int x0 = tx * TILE, y0 = ty * TILE, x1 = x0 + TILE < w ? x0 + TILE : w,
        y1 = y0 + TILE < h ? y0 + TILE : h;
    evr_event_vec *out = &b->tile_events[tile];
    evr_m34 pose_static = evr_rs_camera_pose(rs, 0.0f);
    const int ideal = evr_pixel_params_ideal(&b->setup.pixel);
    tile_pixel px[TILE * TILE];
    int list[TILE * TILE] = {0}, more[TILE * TILE], count = 0, num_more = 0, np = 0, x, y,
                    i; /* zeroed: GCC cannot see the listed entries set */
    out->n = 0;
    /* pixels in blocks of 4 x 2 (a packet's worth): rays of a packet then start close together in
     * both directions, which Embree's packet traversal rewards */
    for (int by = y0; by < y1; by += 2)
        for (int bx = x0; bx < x1; bx += 4)
            for (y = by; y < by + 2 && y < y1; y++) {
                for (x = bx; x < bx + 4 && x < x1; x++, np++) {
                    tile_pixel *q = &px[np];
                    q->x = x;
                    q->y = y;
                    q->st = &b->pixels[(size_t)y * (size_t)w + (size_t)x];
                    q->phi = b->phase[(size_t)y * (size_t)w + (size_t)x];
                    q->t_last = (((float)(n - 1) + q->phi) / (float)n) * dt;
                    q->t_hit = INFINITY;
                    q->deep = 0;
                    q->last_span = -1;
                    q->id = b->last_id ? b->last_id[(size_t)y * (size_t)w + (size_t)x] : 0u;
                    if (ideal) q->pp = b->setup.pixel;
                    else evr_pixel_params_at(&b->setup.pixel, x, y, &q->pp);
                    /* global illumination: whether the pixel's indirect light may differ from its last sample's */
                    const int gi_changed =
                        b->gi && evr_cpu_gi_pixel_begin(&b->gi_state, &rs->camera, x, y);
                    /* change-driven sampling: a pixel nothing moving can reach keeps its intensity */
                    q->ray =
                        evr_camera_ray(&rs->camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
                    if (evr_skip_pixel(rs, plan, q->st->started, q->st->cache_dist, q->ray) &&
                        !gi_changed) {
                        (*skipped)++;
                        q->keep = b->setup.refine && !ideal; /* evr_refine_keep */
                        if (q->keep) {
                            list[count++] = np;
                            continue;
                        }
                        keep_samples(b, q, ideal, 0, n, dt, out);
                        evr_pixel_end_segment(q->st, dt);
                    } else {
                        q->keep = 0;
                        list[count++] = np;
                    }
                }
            }
    if (b->setup.refine) {
        refine_samples(b, px, list, count, &pose_static, ideal, dt, out, rays, traced);
    } else {
        trace_samples(b, px, list, count, 0, n < 1 ? n : 1, 1, more, &num_more, &pose_static, ideal,
                      dt, out, rays, traced);
        trace_samples(b, px, more, num_more, 1, n, 0, NULL, NULL, &pose_static, ideal, dt, out,
                      rays, traced);
    }
    for (i = 0; i < count; i++) {
        tile_pixel *q = &px[list[i]];
        if (q->t_hit >= 0.0f)
            q->st->cache_dist = evr_skip_cache_after_trace(rs, plan, q->ray, q->t_hit, q->deep);
        evr_pixel_end_segment(q->st, dt);
        if (b->last_id) b->last_id[(size_t)q->y * (size_t)w + (size_t)q->x] = q->id;
    }
    render_frames(b, x0, y0, x1, y1);
    *samples +=
        (unsigned long long)(x1 - x0) * (unsigned long long)(y1 - y0) * (unsigned long long)n;
}

/* Intensity frames: one sample per pixel at each frame's exact time, kept away from the pixel
 * model and out of the sample and ray counts. */
static void render_frames(cpu_backend *b, int x0, int y0, int x1, int y1)
{
    const evr_render_scene *rs = &b->host.rs;
    const evr_segment *seg = b->seg;
    const int w = b->setup.width, h = b->setup.height;
    int x, y, k;
    for (k = 0; k < seg->num_frames; k++) {
        const float f = b->frame_f[k];
        evr_m34 pose = evr_rs_camera_pose(rs, f);
        float *img = b->frame_out + (size_t)k * (size_t)w * (size_t)h;
        unsigned long long frame_rays = 0;
        for (y = y0; y < y1; y++) {
            for (x = x0; x < x1; x += PACKET) {
                float fs[PACKET], intensity[PACKET];
                int xs[PACKET], valid[PACKET], i;
                for (i = 0; i < PACKET; i++) {
                    xs[i] = x + i < x1 ? x + i : x1 - 1;
                    valid[i] = x + i < x1;
                    fs[i] = f;
                }
                sample_intensity8(b, &pose, xs, y, fs, valid, intensity, NULL, &frame_rays);
                for (i = 0; i < PACKET && x + i < x1; i++)
                    img[(size_t)y * (size_t)w + (size_t)(x + i)] = intensity[i];
            }
        }
    }
    /* label frames: each pixel's primary hit at the label's exact time (core/labels.h) */
    for (k = 0; k < seg->num_labels; k++) {
        const float f = b->label_f[k];
        evr_m34 pose = evr_rs_camera_pose(rs, f);
        evr_hit *img = b->label_out + (size_t)k * (size_t)w * (size_t)h;
        unsigned long long label_rays = 0; /* not counted: not the pixel model's */
        for (y = y0; y < y1; y++) {
            for (x = x0; x < x1; x += PACKET) {
                struct RTCRayHit8 rh;
                evr_ray ray[PACKET];
                float fs[PACKET];
                int xs[PACKET], ys[PACKET], valid[PACKET], i;
                for (i = 0; i < PACKET; i++) {
                    xs[i] = x + i < x1 ? x + i : x1 - 1;
                    ys[i] = y;
                    valid[i] = x + i < x1;
                    fs[i] = f;
                }
                primary_packet8(b, &pose, xs, ys, fs, valid, ray, &rh, &label_rays);
                for (i = 0; i < PACKET && x + i < x1; i++) {
                    evr_hit *o = &img[(size_t)y * (size_t)w + (size_t)(x + i)];
                    o->inst = -1;
                    o->t = INFINITY;
                    o->u = o->v = 0.0f;
                    o->prim = 0;
                    if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
                    o->inst = b->groups.members[b->groups.group_first[rh.hit.instID[0][i]] +
                                                (int)rh.hit.geomID[i]];
                    o->t = rh.ray.tfar[i];
                    o->u = rh.hit.u[i];
                    o->v = rh.hit.v[i];
                    o->prim = rh.hit.primID[i];
                }
            }
        }
    }
}

/* Adaptive sampling (core/adaptive.h): every pixel of the tile takes its samples at its own
 * scheduled times; each round, the pixels that still have a sample to trace in the segment trace
 * it, eight at a time in packets (any pixels of the tile, each at its own time), then run what
 * they can through the pixel model: a sample that changed too much is held back on the pixel's
 * stack while the interval before it is refined (evr_adapt_refine). */
static void render_tile_adaptive(cpu_backend *b, int tile, unsigned long long *samples,
                                 unsigned long long *rays)
{
    const evr_render_scene *rs = &b->host.rs;
    const evr_segment *seg = b->seg;
    const evr_adapt_plan *plan = seg->adapt;
    const evr_adapt_params *ap = &b->setup.adapt;
    const int w = b->setup.width, h = b->setup.height;
    const float dt = (float)(seg->t1 - seg->t0);
    int tx = tile % b->tiles_x, ty = tile / b->tiles_x;
    int x0 = tx * TILE, y0 = ty * TILE, x1 = x0 + TILE < w ? x0 + TILE : w,
        y1 = y0 + TILE < h ? y0 + TILE : h;
    const int tw = x1 - x0, npx = tw * (y1 - y0);
    evr_event_vec *out = &b->tile_events[tile];
    evr_m34 pose_static = evr_rs_camera_pose(rs, 0.0f);
    const int ideal = evr_pixel_params_ideal(&b->setup.pixel);
    evr_pixel_params pp[TILE * TILE];
    evr_adapt_stack stack[TILE * TILE];
    float tnext[TILE * TILE];
    int act[TILE * TILE], nact = 0, j;
    out->n = 0;
    for (j = 0; j < npx; j++) {
        const int x = x0 + j % tw, y = y0 + j / tw;
        const size_t pix = (size_t)y * (size_t)w + (size_t)x;
        evr_pixel_state *st = &b->pixels[pix];
        if (ideal) pp[j] = b->setup.pixel;
        else evr_pixel_params_at(&b->setup.pixel, x, y, &pp[j]);
        /* global illumination: a gather window whose photons changed forgets the pixel's last
         * gather (else its memo would keep the previous segment's indirect light) */
        if (b->gi) evr_cpu_gi_pixel_begin(&b->gi_state, &rs->camera, x, y);
        stack[j].n = 0;
        const evr_ray ray =
            evr_camera_ray(&rs->camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
        tnext[j] = evr_adapt_start(rs, ap, plan, st, ray, b->next_t[pix], b->phase[pix], dt);
        if (tnext[j] < dt) act[nact++] = j;
    }
    while (nact > 0 && !cancelled(b)) {
        int base, kept = 0;
        for (base = 0; base < nact; base += PACKET) {
            int xs[PACKET], ys[PACKET], valid[PACKET], js[PACKET], i;
            float fs[PACKET], intensity[PACKET], t_hit[PACKET];
            unsigned ids[PACKET];
            int deep[PACKET];
            for (i = 0; i < PACKET; i++) {
                valid[i] = base + i < nact;
                js[i] = act[valid[i] ? base + i : base];
                xs[i] = x0 + js[i] % tw;
                ys[i] = y0 + js[i] / tw;
                fs[i] = tnext[js[i]] / dt;
            }
            sample_intensity8_rows(b, seg->camera_static ? &pose_static : NULL, xs, ys, fs, valid,
                                   intensity, t_hit, NULL, deep, ids, rays);
            for (i = 0; i < PACKET; i++) {
                if (!valid[i]) continue;
                const int jj = js[i];
                evr_pixel_state *st = &b->pixels[(size_t)ys[i] * (size_t)w + (size_t)xs[i]];
                const evr_ray ray = evr_camera_ray(&rs->camera, &pose_static, (float)xs[i] + 0.5f,
                                                   (float)ys[i] + 0.5f);
                evr_adapt_stack *sk = &stack[jj];
                float t = tnext[jj], in = intensity[i], hit = evr_adapt_hit(t_hit[i], deep[i]),
                      step;
                unsigned id = ids[i];
                int moving;
                (*samples)++;
                /* the pixel's candidate sample (t, in, hit, id): held back, or through the pixel
                 * model */
                while (evr_adapt_candidate(rs, ap, plan, st, &pp[jj], ray, sk, t, in, hit, id,
                                           &tnext[jj], &step, &moving)) {
                    pixel_sample(b, st, &pp[jj], ideal, t, in, id, xs[i], ys[i], out);
                    if (!evr_adapt_taken(ap, sk, step, moving, dt, &t, &in, &hit, &id, &tnext[jj]))
                        break;
                }
                if (tnext[jj] < dt) act[kept++] = jj; /* kept <= base + i: in place */
            }
        }
        nact = kept;
    }
    for (j = 0; j < npx; j++) {
        const size_t pix = (size_t)(y0 + j / tw) * (size_t)w + (size_t)(x0 + j % tw);
        b->next_t[pix] = tnext[j] - dt;
        evr_pixel_end_segment(&b->pixels[pix], dt);
    }
    render_frames(b, x0, y0, x1, y1);
}

static void *worker(void *arg)
{
    cpu_backend *b = (cpu_backend *)arg;
    unsigned long long samples = 0, rays = 0, traced = 0, skipped = 0;
#if defined(__SSE__)
    /* Embree asks for flush-to-zero and denormals-are-zero on every thread that traces */
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    int ntiles = b->tiles_x * b->tiles_y, t;
    while (!cancelled(b) && (t = atomic_fetch_add(&b->next_tile, 1)) < ntiles) {
        if (b->setup.adaptive) render_tile_adaptive(b, t, &samples, &rays);
        else render_tile(b, t, &samples, &rays, &traced, &skipped);
    }
    if (b->setup.adaptive) traced = samples; /* adaptive sampling traces every sample it takes */
    atomic_fetch_add(&b->samples, samples);
    atomic_fetch_add(&b->rays, rays);
    atomic_fetch_add(&b->samples_traced, traced);
    atomic_fetch_add(&b->pixels_skipped, skipped);
    return NULL;
}

/* A deforming group's triangles take the segment's vertex keys (cpu/deform_geometry.h): its tree
 * is rebuilt over their boxes when they changed. 0: out of memory. */
static int update_deform(cpu_backend *b, int g, const evr_segment *seg)
{
    const int d = b->host.instances[b->groups.members[b->groups.group_first[g]]].deform;
    const evr_deform_view *v = &seg->deforms[d];
    if (v->num_keys - 1 > b->time_grid) b->time_grid = v->num_keys - 1;
    b->deforms[g].view = *v; /* the keys' arrays of this segment, whatever happens below */
    /* one key, the same bits as the one it has: the tree holds */
    if (b->deform_keys_set[g] == 1 && v->num_keys == 1 && !seg->deform_moved[d]) return 1;
    b->deform_keys_set[g] = v->num_keys;
    rtcCommitGeometry(rtcGetGeometry(b->group_scenes[g], 0));
    rtcCommitScene(b->group_scenes[g]);
    rtcCommitGeometry(rtcGetGeometry(b->top, (unsigned)g)); /* its instance's bounds changed */
    return 1;
}

/* Whether group g's transform follows its node's track every segment. */
static int group_moves(const cpu_backend *b, int g)
{
    const int kind = b->groups.group_kind[g], node = b->groups.group_node[g];
    return kind == EVR_GROUP_MOVING ||
           (kind == EVR_GROUP_DEFORMING && node >= 0 && evr_node_chain_animated(b->scene, node));
}

static evr_status update_motion(cpu_backend *b, const evr_segment *seg, evr_error *err)
{
    int g, k;
    b->time_grid = 1;
    for (g = 0; g < b->groups.num_groups; g++) {
        int track = b->groups.group_node[g]; /* a moving group's node is its track */
        if (b->groups.group_kind[g] == EVR_GROUP_DEFORMING && !update_deform(b, g, seg)) {
            snprintf(err->msg, sizeof err->msg, "out of memory for a deforming mesh's vertices");
            return EVR_ERR_NOMEM;
        }
        if (!group_moves(b, g)) continue; /* static: set once */
        int n = seg->track_count[track];
        if (n - 1 > b->time_grid)
            b->time_grid = n - 1; /* 2^k + 1 uniform keys: the finest grid holds the others */
        RTCGeometry geom = rtcGetGeometry(b->top, (unsigned)g);
        rtcSetGeometryTimeStepCount(geom, (unsigned)n);
        for (k = 0; k < n; k++) {
            struct RTCQuaternionDecomposition q;
            to_embree(&seg->keys[seg->track_offset[track] + k], &q);
            rtcSetGeometryTransformQuaternion(geom, (unsigned)k, &q);
        }
        rtcCommitGeometry(geom);
    }
    rtcCommitScene(b->top);
    if (b->embree_error[0]) {
        snprintf(err->msg, sizeof err->msg, "%s", b->embree_error);
        return EVR_ERR_BACKEND;
    }
    return EVR_OK;
}

static evr_status cpu_submit(evr_backend *base, const evr_segment *seg, evr_error *err)
{
    cpu_backend *b = (cpu_backend *)base;
    if (b->queued == 2) {
        snprintf(err->msg, sizeof err->msg, "internal error: more than two segments submitted");
        return EVR_ERR_BACKEND;
    }
    int slot = (b->head + b->queued) % 2;
    evr_event_vec *out = &b->done[slot];
    out->n = 0;
    evr_status st;
    int nthreads = b->setup.threads, i, ntiles = b->tiles_x * b->tiles_y;
    b->host.rs.keys = seg->keys;
    b->host.rs.track_offset = seg->track_offset;
    b->host.rs.track_count = seg->track_count;
    b->host.rs.deforms = seg->deforms;
    if ((st = update_motion(b, seg, err)) != EVR_OK) return st;
    if (b->gi) { /* the segment's photons: still when nothing moved since the previous segment */
        if ((st = evr_cpu_gi_segment(&b->gi_state, &b->host.rs, seg->skip, b->setup.threads, base,
                                     err)) != EVR_OK)
            return st;
    }
    if (seg->num_frames > 0) {
        size_t npix = (size_t)b->setup.width * (size_t)b->setup.height,
               nf = (size_t)seg->num_frames;
        if (seg->num_frames > b->frame_f_cap) {
            float *ff = realloc(b->frame_f, nf * sizeof *ff);
            if (!ff) {
                snprintf(err->msg, sizeof err->msg, "out of memory for intensity frames");
                return EVR_ERR_NOMEM;
            }
            b->frame_f = ff;
            b->frame_f_cap = seg->num_frames;
        }
        if (nf > b->done_frames_cap[slot]) {
            float *img = realloc(b->done_frames[slot], nf * npix * sizeof *img);
            if (!img) {
                snprintf(err->msg, sizeof err->msg, "out of memory for intensity frames");
                return EVR_ERR_NOMEM;
            }
            b->done_frames[slot] = img;
            b->done_frames_cap[slot] = nf;
        }
        for (i = 0; i < seg->num_frames; i++) {
            double f =
                seg->t1 > seg->t0 ? (seg->frame_times[i] - seg->t0) / (seg->t1 - seg->t0) : 0.0;
            b->frame_f[i] = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
        }
        b->frame_out = b->done_frames[slot];
    }
    b->done_num_frames[slot] = seg->num_frames > 0 ? seg->num_frames : 0;
    if (seg->num_labels > 0) {
        size_t npix = (size_t)b->setup.width * (size_t)b->setup.height,
               nl = (size_t)seg->num_labels;
        if (seg->num_labels > b->label_f_cap) {
            float *ff = realloc(b->label_f, nl * sizeof *ff);
            if (!ff) {
                snprintf(err->msg, sizeof err->msg, "out of memory for label frames");
                return EVR_ERR_NOMEM;
            }
            b->label_f = ff;
            b->label_f_cap = seg->num_labels;
        }
        if (nl > b->done_labels_cap[slot]) {
            evr_hit *img = realloc(b->done_labels[slot], nl * npix * sizeof *img);
            if (!img) {
                snprintf(err->msg, sizeof err->msg, "out of memory for label frames");
                return EVR_ERR_NOMEM;
            }
            b->done_labels[slot] = img;
            b->done_labels_cap[slot] = nl;
        }
        for (i = 0; i < seg->num_labels; i++) {
            double f =
                seg->t1 > seg->t0 ? (seg->label_times[i] - seg->t0) / (seg->t1 - seg->t0) : 0.0;
            b->label_f[i] = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
        }
        b->label_out = b->done_labels[slot];
    }
    b->done_num_labels[slot] = seg->num_labels > 0 ? seg->num_labels : 0;
    b->seg = seg;
    atomic_store(&b->next_tile, 0);
    atomic_store(&b->samples, 0);
    atomic_store(&b->rays, 0);
    atomic_store(&b->samples_traced, 0);
    atomic_store(&b->pixels_skipped, 0);
    atomic_store(&b->failed, 0);
    if (!evr_run_workers(worker, b, nthreads)) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    /* counted when collected, so that the totals after a collect are those of the segments
     * collected so far */
    b->done_counts[slot][0] = atomic_load(&b->samples);
    b->done_counts[slot][1] = atomic_load(&b->rays);
    b->done_counts[slot][2] = atomic_load(&b->samples_traced);
    b->done_counts[slot][3] = atomic_load(&b->pixels_skipped);
    if (cancelled(b)) {
        snprintf(err->msg, sizeof err->msg, "stopped");
        return EVR_ERR_INTERRUPTED;
    }
    if (atomic_load(&b->failed)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for events");
        return EVR_ERR_NOMEM;
    }
    if (b->embree_error[0]) {
        snprintf(err->msg, sizeof err->msg, "%s", b->embree_error);
        return EVR_ERR_BACKEND;
    }
    for (i = 0; i < ntiles; i++) { /* tile order: deterministic whatever the thread count */
        evr_event_vec *te = &b->tile_events[i];
        if (!evr_event_vec_append(out, te->data, te->n)) {
            snprintf(err->msg, sizeof err->msg, "out of memory for events");
            return EVR_ERR_NOMEM;
        }
        /* a tile's buffer grows to its busiest segment; one far larger than this segment's needs
         * goes, so that the run's memory follows its current bursts rather than the sum of every
         * tile's worst ever */
        if (te->cap > 4 * te->n + 4096) evr_event_vec_free(te);
    }
    const double ts0 = evr_host_seconds();
    int sorted = evr_events_sort(out, &b->scratch);
    base->sort_seconds += evr_host_seconds() - ts0;
    if (!sorted) {
        snprintf(err->msg, sizeof err->msg, "out of memory sorting events");
        return EVR_ERR_NOMEM;
    }
    b->done_has_intensity[slot] = seg->want_intensity;
    if (seg->want_intensity) {
        size_t p, npix = (size_t)b->setup.width * (size_t)b->setup.height;
        for (p = 0; p < npix; p++) b->done_intensity[slot][p] = b->pixels[p].intensity;
    }
    b->queued++;
    return EVR_OK;
}

static evr_status cpu_collect(evr_backend *base, evr_event_vec *out, int64_t emit_before_us,
                              const float **intensity, const float **frames, evr_error *err)
{
    cpu_backend *b = (cpu_backend *)base;
    (void)emit_before_us; /* every event now: merged on the host */
    if (!b->queued) {
        snprintf(err->msg, sizeof err->msg, "internal error: collect without a submitted segment");
        return EVR_ERR_BACKEND;
    }
    int slot = b->head;
    b->head = (b->head + 1) % 2;
    b->queued--;
    b->collected = slot;
    base->samples += b->done_counts[slot][0];
    base->rays += b->done_counts[slot][1];
    base->samples_traced += b->done_counts[slot][2];
    base->pixels_skipped += b->done_counts[slot][3];
    *intensity = b->done_has_intensity[slot] ? b->done_intensity[slot] : NULL;
    *frames = b->done_num_frames[slot] > 0 ? b->done_frames[slot] : NULL;
    if (!evr_events_merge(out, b->done[slot].data, b->done[slot].n, &b->scratch)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for events");
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

static const evr_hit *cpu_label_hits(evr_backend *base)
{
    cpu_backend *b = (cpu_backend *)base;
    if (b->collected < 0 || b->done_num_labels[b->collected] <= 0) return NULL;
    return b->done_labels[b->collected];
}

static void cpu_release(evr_backend *base)
{
    cpu_backend *b = (cpu_backend *)base;
    int i;
    if (!b) return;
    if (b->gi) evr_cpu_gi_free(&b->gi_state);
    if (b->top) rtcReleaseScene(b->top);
    if (b->group_scenes) {
        for (i = 0; i < b->groups.num_groups; i++)
            if (b->group_scenes[i]) rtcReleaseScene(b->group_scenes[i]);
    }
    free(b->group_scenes);
    free(b->deform_keys_set);
    free(b->deforms);
    evr_instance_groups_free(&b->groups);
    if (b->device) rtcReleaseDevice(b->device);
    if (b->tile_events) {
        for (i = 0; i < b->tiles_x * b->tiles_y; i++) evr_event_vec_free(&b->tile_events[i]);
    }
    free(b->tile_events);
    for (i = 0; i < 2; i++) {
        evr_event_vec_free(&b->done[i]);
        free(b->done_intensity[i]);
        free(b->done_frames[i]);
        free(b->done_labels[i]);
    }
    evr_event_vec_free(&b->scratch);
    free(b->pixels);
    free(b->phase);
    free(b->next_t);
    free(b->last_id);
    free(b->frame_f);
    free(b->label_f);
    free(b);
}

/* Adds a mesh to an Embree scene as geometry geom_id, its vertices transformed by xf (NULL:
 * object space), with the hit filters of its material (filter: evr_mesh_view.filter). */
static int add_mesh_geometry(RTCDevice dev, RTCScene sc, const evr_mesh *m, const evr_m34 *xf,
                             unsigned geom_id, const evr_cpu_filter_map *map, int filter,
                             enum RTCBuildQuality quality)
{
    uint32_t v;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) return 0;
    rtcSetGeometryBuildQuality(g, quality);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), m->num_vertices);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), m->num_triangles);
    if (!vb || !ib) {
        rtcReleaseGeometry(g);
        return 0;
    }
    for (v = 0; v < m->num_vertices; v++) {
        evr_v3 p =
            evr_v3_make(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]);
        if (xf) p = evr_m34_point(xf, p);
        vb[3 * v] = p.x;
        vb[3 * v + 1] = p.y;
        vb[3 * v + 2] = p.z;
    }
    memcpy(ib, m->indices, sizeof(unsigned) * 3 * m->num_triangles);
    evr_cpu_filter_set(g, map, filter);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, geom_id);
    rtcReleaseGeometry(g);
    return 1;
}

/* The quality of the trees that are built once, by the triangles they hold in all
 * (evr_tree_high_quality). */
static enum RTCBuildQuality static_quality(const evr_scene *s, const evr_instance_groups *gr)
{
    uint64_t tris = 0;
    uint8_t *seen = calloc((size_t)s->num_meshes + 1, 1);
    for (int g = 0; g < gr->num_groups; g++) {
        const int kind = gr->group_kind[g];
        for (int j = gr->group_first[g]; j < gr->group_first[g + 1]; j++) {
            const int mesh = s->instances[gr->members[j]].mesh;
            if (kind == EVR_GROUP_BAKED || kind == EVR_GROUP_MOVING)
                tris += s->meshes[mesh].num_triangles;
            else if (kind == EVR_GROUP_STATIC && seen && !seen[mesh]) {
                seen[mesh] = 1; /* one tree per mesh, however many instances */
                tris += s->meshes[mesh].num_triangles;
            }
        }
    }
    free(seen);
    return evr_tree_high_quality(tris) ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
}

/* Groups the instances (see cpu_backend) and builds one Embree scene per group (per mesh for
 * static groups). */
static int build_groups(cpu_backend *b, const evr_scene *s)
{
    const evr_instance_groups *gr = &b->groups;
    int i, j, g, ok = 1;
    RTCScene *mesh_scenes = calloc((size_t)s->num_meshes + 1, sizeof *mesh_scenes);
    if (!mesh_scenes || !evr_instance_groups_build(s, 1, &b->groups)) {
        free(mesh_scenes);
        return 0;
    }
    const enum RTCBuildQuality quality = static_quality(s, gr);
    b->filter_map.rs = &b->host.rs;
    b->filter_map.members = gr->members;
    b->filter_map.group_first = gr->group_first;
    b->filter_map.group_kind = gr->group_kind;
    b->group_scenes = calloc((size_t)gr->num_groups + 1, sizeof *b->group_scenes);
    b->deform_keys_set = calloc((size_t)gr->num_groups + 1, sizeof *b->deform_keys_set);
    b->deforms = calloc((size_t)gr->num_groups + 1, sizeof *b->deforms);
    if (!b->group_scenes || !b->deform_keys_set || !b->deforms) ok = 0;
    for (g = 0; ok && g < gr->num_groups; g++) {
        RTCScene sc;
        if (gr->group_kind[g] ==
            EVR_GROUP_STATIC) { /* the mesh's scene, built once, one reference per group */
            int mesh = s->instances[gr->members[gr->group_first[g]]].mesh;
            if (!mesh_scenes[mesh]) {
                if (!(sc = rtcNewScene(b->device))) {
                    ok = 0;
                    break;
                }
                mesh_scenes[mesh] = sc;
                rtcSetSceneBuildQuality(sc, quality);
                if (!add_mesh_geometry(b->device, sc, &s->meshes[mesh], NULL, 0, &b->filter_map,
                                       b->host.meshes[mesh].filter, quality)) {
                    ok = 0;
                    break;
                }
                rtcCommitScene(sc);
            }
            rtcRetainScene(mesh_scenes[mesh]);
            b->group_scenes[g] = mesh_scenes[mesh];
            continue;
        }
        if (!(sc = rtcNewScene(b->device))) {
            ok = 0;
            break;
        }
        b->group_scenes[g] = sc;
        if (gr->group_kind[g] == EVR_GROUP_DEFORMING) { /* rebuilt every segment it moves */
            const int inst = gr->members[gr->group_first[g]];
            const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
            evr_cpu_deform *d = &b->deforms[g];
            RTCGeometry geom;
            d->filter = b->host.meshes[s->instances[inst].mesh].filter;
            d->instance = inst;
            d->map = &b->filter_map;
            d->indices = m->indices;
            d->num_triangles = m->num_triangles;
            d->view.num_keys = 1; /* the rest pose until the first segment's keys */
            d->view.num_vertices = m->num_vertices;
            d->view.positions = m->positions;
            d->view.normals = m->normals;
            rtcSetSceneFlags(sc, RTC_SCENE_FLAG_DYNAMIC);
            rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_MEDIUM);
            if (!(geom = evr_cpu_deform_geometry_new(b->device, d))) {
                ok = 0;
                break;
            }
            rtcCommitGeometry(geom);
            rtcAttachGeometryByID(sc, geom, 0);
            rtcReleaseGeometry(geom);
            rtcCommitScene(sc);
            continue;
        }
        rtcSetSceneBuildQuality(sc, quality); /* baked or moving: built once */
        for (j = gr->group_first[g]; j < gr->group_first[g + 1]; j++) {
            const evr_instance *in = &s->instances[gr->members[j]];
            evr_m34 world = evr_node_world_at(s, in->node, s->anim_start);
            if (!add_mesh_geometry(b->device, sc, &s->meshes[in->mesh],
                                   gr->group_kind[g] == EVR_GROUP_BAKED ? &world : NULL,
                                   (unsigned)(j - gr->group_first[g]), &b->filter_map,
                                   b->host.meshes[in->mesh].filter, quality)) {
                ok = 0;
                break;
            }
        }
        if (ok) rtcCommitScene(sc);
    }
    for (i = 0; i < s->num_meshes; i++)
        if (mesh_scenes[i]) rtcReleaseScene(mesh_scenes[i]);
    free(mesh_scenes);
    return ok;
}

evr_status evr_cpu_backend_new(const evr_scene *s, const evr_render_host *h,
                               const evr_run_setup *setup, evr_backend **out, evr_error *err)
{
    cpu_backend *b = calloc(1, sizeof *b);
    size_t npix = (size_t)setup->width * (size_t)setup->height, i;
    int m, x, y;
    if (!b) goto nomem;
    b->base.name = "cpu";
    b->base.depth = 2;
    b->base.submit = cpu_submit;
    b->base.collect = cpu_collect;
    b->base.release = cpu_release;
    b->base.label_hits = cpu_label_hits;
    b->packet_flags = getenv("EVR_EMBREE_INCOHERENT") ? RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
                                                      : RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    b->collected = -1;
    b->scene = s;
    b->host = *h;
    b->setup = *setup;
    b->setup.threads = evr_cpu_threads(b->setup.threads);
    b->tiles_x = (setup->width + TILE - 1) / TILE;
    b->tiles_y = (setup->height + TILE - 1) / TILE;
    b->pixels = malloc(npix * sizeof *b->pixels);
    b->phase = malloc(npix * sizeof *b->phase);
    b->next_t = calloc(npix, sizeof *b->next_t);
    if (b->setup.event_ids) b->last_id = calloc(npix, sizeof *b->last_id);
    b->tile_events = calloc((size_t)b->tiles_x * (size_t)b->tiles_y, sizeof *b->tile_events);
    b->done_intensity[0] = malloc(npix * sizeof(float));
    b->done_intensity[1] = malloc(npix * sizeof(float));
    if (!b->pixels || !b->phase || !b->next_t || !b->tile_events || !b->done_intensity[0] ||
        !b->done_intensity[1] || (b->setup.event_ids && !b->last_id))
        goto nomem;
    for (i = 0; i < npix; i++) evr_pixel_reset(&b->pixels[i]);
    for (y = 0; y < setup->height; y++)
        for (x = 0; x < setup->width; x++)
            b->phase[(size_t)y * (size_t)setup->width + (size_t)x] =
                setup->refine ? 1.0f : evr_pixel_phase(setup->seed, x, y);

    b->device = rtcNewDevice(NULL);
    if (!b->device) {
        snprintf(err->msg, sizeof err->msg, "cannot create the Embree device (error %d)",
                 (int)rtcGetDeviceError(NULL));
        cpu_release(&b->base);
        return EVR_ERR_BACKEND;
    }
    rtcSetDeviceErrorFunction(b->device, embree_error, b);
    const double t_bvh = evr_host_seconds();
    if (!build_groups(b, s) || b->embree_error[0]) goto embree_fail;
    b->base.bvh_seconds = evr_host_seconds() - t_bvh;
    b->top = rtcNewScene(b->device);
    if (!b->top) goto embree_fail;
    /* rebuilt every segment, but over a handful of instances (thousands when static instances are
     * not baked: then nothing in it moves and Embree does not rebuild it): quality costs little */
    rtcSetSceneBuildQuality(b->top, RTC_BUILD_QUALITY_HIGH);
    for (m = 0; m < b->groups.num_groups; m++) {
        const evr_instance_groups *gr = &b->groups;
        RTCGeometry g = rtcNewGeometry(b->device, RTC_GEOMETRY_TYPE_INSTANCE);
        if (!g) goto embree_fail;
        rtcSetGeometryInstancedScene(g, b->group_scenes[m]);
        if (!group_moves(b, m)) { /* baked into world space (identity), or the node's fixed
                                     transform; no motion */
            const int kind = gr->group_kind[m];
            evr_m34 xf =
                kind == EVR_GROUP_STATIC
                    ? evr_node_world_at(s, s->instances[gr->members[gr->group_first[m]]].node,
                                        s->anim_start)
                : kind == EVR_GROUP_DEFORMING && gr->group_node[m] >= 0
                    ? evr_node_world_at(s, gr->group_node[m], s->anim_start)
                    : evr_m34_identity();
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, &xf.m[0][0]);
            rtcCommitGeometry(g);
        }
        rtcAttachGeometryByID(b->top, g, (unsigned)m);
        rtcReleaseGeometry(g);
    }
    if (b->embree_error[0]) goto embree_fail;
    if (setup->gi) {
        evr_cpu_trace_ctx tc;
        evr_status st;
        tc.top = b->top;
        tc.members = b->groups.members;
        tc.group_first = b->groups.group_first;
        b->gi = 1;
        if ((st = evr_cpu_gi_init(&b->gi_state, &tc, &b->setup, s, err)) != EVR_OK) {
            cpu_release(&b->base);
            return st;
        }
    }
    *out = &b->base;
    return EVR_OK;
embree_fail:
    snprintf(err->msg, sizeof err->msg, "%s",
             b->embree_error[0] ? b->embree_error : "Embree failed to build the scene");
    cpu_release(&b->base);
    return EVR_ERR_BACKEND;
nomem:
    snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d image", setup->width,
             setup->height);
    cpu_release(b ? &b->base : NULL);
    return EVR_ERR_NOMEM;
}

int evr_cpu_backend_threads(const evr_backend *b)
{
    return ((const cpu_backend *)b)->setup.threads;
}
