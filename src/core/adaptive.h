/* Adaptive per-pixel sampling (--sampling adaptive): each pixel picks its own next sample time.
 *
 * After a sample at t (log intensity l; the previous sample at t_prev, l_prev) the next comes
 * dt later, the smallest of
 *  - frac * threshold / |l - l_prev| * (t - t_prev): at the present rate, the log intensity moves
 *    by at most frac of a contrast threshold (the smaller of ON and OFF) between samples;
 *  - EVR_ADAPT_PX_PER_FRAC * frac / speed: when the sample's rays (primary up to its hit, and the
 *    shadow rays from there: exactly those of core/skip.h's evr_skip_rays_meet) meet the swept
 *    bounds of something moving in the segment, speed is a bound on how fast that thing moves in
 *    the image (pixels per second, the host's evr_adapt_plan), so it moves by at most
 *    2 frac pixels (half a pixel at the default frac 0.25) between samples;
 *  - max_dt,
 * and at least min_dt. While the camera or a light moves every pixel samples every min_dt.
 * A sample that changed by more than frac of a threshold since the previous one is held back
 * while the interval is bisected (evr_adapt_refine), and a pixel something moving can reach
 * takes a sample just before its segment's end (evr_adapt_next_time).
 *
 * Samples stay inside segments: a pixel's next scheduled time is carried across segments in
 * segment-relative seconds (as t_prev). At a segment's start a pixel whose last sample's rays meet
 * something moving in the new segment brings its next sample forward to t_prev + dt of that
 * motion (not before the segment's start), and to the segment's start when the thing jumped
 * between the segments: an edge entering a pixel that sampled long ago is not missed. A pixel
 * nothing moving reaches samples every max_dt. Every sample goes through the pixel model
 * (core/pixel.h) as uniform sampling's do, so noise and leak (continuous-time processes inside
 * the model) are unchanged by longer spans. Both backends call these functions; the host fills an
 * evr_adapt_plan per segment (evr_adapt_plan_build, src/prep/skip_plan.c). */
#ifndef EVR_CORE_ADAPTIVE_H
#define EVR_CORE_ADAPTIVE_H

#include <stdint.h>
#include "core/pixel.h"
#include "core/skip.h"

/* image motion allowed between samples, pixels per unit of frac */
#define EVR_ADAPT_PX_PER_FRAC 2.0f
#define EVR_ADAPT_DEPTH 16 /* samples a pixel holds back while it refines an interval */

typedef struct {
    float frac;           /* fraction of a threshold (and 2 frac pixels) between samples */
    float min_dt, max_dt; /* seconds */
} evr_adapt_params;

typedef struct {
    int all_min; /* the camera or a light moves: every pixel samples every min_dt */
    int num_boxes;
    float pad; /* added to every box on every side */
    float lo[EVR_SKIP_MAX_BOXES][3], hi[EVR_SKIP_MAX_BOXES][3]; /* swept bounds of what moves */
    float speed[EVR_SKIP_MAX_BOXES]; /* bound on the image speed of what each box holds, pixels/s
                                        (INFINITY: unbounded, e.g. the camera inside the box) */
    int jump[EVR_SKIP_MAX_BOXES];    /* it moved between the previous segment and this one */
} evr_adapt_plan;

/* The fastest image speed (pixels per second) of the moving things that a sample's rays meet:
 * the primary ray up to its hit at t_hit (1e29 or more: nothing hit, the whole ray) and the
 * segments from the hit to every light that sends light there (as evr_skip_rays_meet). *jump is
 * set when one of them moved between the segments. 0 when they meet nothing that moves.
 * t_hit EVR_SKIP_DEEP: the sample's path went on past its primary hit (a reflection, refraction
 * or blended layer: evr_adapt_hit), whose rays are not followed here: every moving thing counts
 * (the fastest speed; seen through a curved mirror or lens its image may move faster still, so
 * there the bound is an estimate). */
EVR_HD static inline uint64_t
evr_adapt_rays_met(const evr_render_scene *rs, const evr_adapt_plan *pl, evr_ray ray, float t_hit);

EVR_HD static inline float evr_adapt_rays_speed(const evr_render_scene *rs,
                                                const evr_adapt_plan *pl, evr_ray ray, float t_hit,
                                                int *jump)
{
    float v = 0.0f;
    *jump = 0;
    if (pl->num_boxes == 0) return 0.0f;
    const uint64_t met = evr_adapt_rays_met(rs, pl, ray, t_hit);
    for (int b = 0; b < pl->num_boxes; b++) {
        if (!(met >> b & 1u)) continue;
        v = fmaxf(v, pl->speed[b]);
        if (pl->jump[b]) *jump = 1;
    }
    return v;
}

/* The boxes of what moves (bit b: box b) that a sample's rays meet, as evr_adapt_rays_speed. */
EVR_HD static inline uint64_t evr_adapt_rays_met(const evr_render_scene *rs,
                                                 const evr_adapt_plan *pl, evr_ray ray, float t_hit)
{
    uint64_t met = 0;
    if (t_hit == EVR_SKIP_DEEP) return pl->num_boxes >= 64 ? ~0ull : (1ull << pl->num_boxes) - 1u;
    const int hit = t_hit < 1e29f && t_hit != EVR_SKIP_DEEP;
    const float tmax = hit ? t_hit * 1.0001f + pl->pad : INFINITY;
    for (int b = 0; b < pl->num_boxes; b++)
        if (!(met >> b & 1u) &&
            evr_skip_segment_meets(ray.org, ray.dir, tmax, pl->lo[b], pl->hi[b], pl->pad))
            met |= 1ull << b;
    if (hit) {
        const evr_v3 p = evr_v3_add(ray.org, evr_v3_scale(ray.dir, t_hit));
        for (int l = 0; l < rs->num_lights; l++) {
            evr_v3 wi;
            float dist, e[3];
            if (!evr_light_incident(rs, &rs->lights[l], 0.0f, p, &wi, &dist, e)) continue;
            for (int b = 0; b < pl->num_boxes; b++)
                if (!(met >> b & 1u) &&
                    evr_skip_segment_meets(p, wi, dist, pl->lo[b], pl->hi[b], pl->pad))
                    met |= 1ull << b;
        }
    }
    return met;
}

/* The hit distance a backend hands adaptive sampling for a sample (t_hit, its path's
 * EVR_DEEP_* bits): EVR_SKIP_DEEP when the path went past the primary hit. */
EVR_HD static inline float evr_adapt_hit(float t_hit, int deep)
{
    return deep ? EVR_SKIP_DEEP : t_hit;
}

/* Time between samples allowed by an image speed (pixels per second; 0: nothing moves). */
EVR_HD static inline float evr_adapt_motion_dt(const evr_adapt_params *ap, float speed)
{
    return speed > 0.0f ? EVR_ADAPT_PX_PER_FRAC * ap->frac / speed : ap->max_dt;
}

/* min_dt <= dt <= max_dt (NaN: min_dt). */
EVR_HD static inline float evr_adapt_clamp(const evr_adapt_params *ap, float dt)
{
    return dt >= ap->min_dt ? fminf(dt, ap->max_dt) : ap->min_dt;
}

/* The time to the next sample after one at t of log intensity l, the previous at t_prev with
 * l_prev (have_prev 0: none), thres the pixel's smaller threshold, speed the image speed bound of
 * what its rays meet (evr_adapt_rays_speed). */
EVR_HD static inline float evr_adapt_next_dt(const evr_adapt_params *ap, const evr_adapt_plan *pl,
                                             int have_prev, float t_prev, float l_prev, float t,
                                             float l, float thres, float speed)
{
    if (pl->all_min) return ap->min_dt;
    float dt = evr_adapt_motion_dt(ap, speed);
    const float dl = fabsf(l - l_prev);
    if (have_prev && t > t_prev && dl > 0.0f) dt = fminf(dt, ap->frac * thres * (t - t_prev) / dl);
    return evr_adapt_clamp(ap, dt);
}

/* The first sample of a segment (segment-relative seconds): next_t as carried from the previous
 * segment, brought forward as the segment's motion asks (speed and jump: evr_adapt_rays_speed of
 * the last sample's rays), never before the segment's start. A pixel's very first sample comes at
 * phase * min(min_dt, seg) (phase in [0, 1), the pixel's own; seg the segment's length). */
EVR_HD static inline float evr_adapt_first(const evr_adapt_params *ap, const evr_adapt_plan *pl,
                                           int started, float next_t, float t_prev, float phase,
                                           float speed, int jump, float seg)
{
    if (!started) return phase * fminf(ap->min_dt, seg);
    if (pl->all_min) next_t = fminf(next_t, t_prev + ap->min_dt);
    if (jump) next_t = 0.0f;
    else if (speed > 0.0f)
        next_t = fminf(next_t, t_prev + evr_adapt_clamp(ap, evr_adapt_motion_dt(ap, speed)));
    return fmaxf(next_t, 0.0f);
}

/* Refinement: a sample at t whose log intensity differs from the pixel's previous sample's (the
 * state s) by more than frac of a threshold is held back, and a sample is first taken halfway
 * (returned in *t_mid), as long as the interval is at least 2 min_dt long and inside the segment
 * (from max(t_prev, 0)). An edge found between two samples so gets its time to about min_dt
 * in log2(interval / min_dt) samples, and the pixel model sees the samples in time order. */
EVR_HD static inline int evr_adapt_refine(const evr_adapt_params *ap, const evr_pixel_state *s,
                                          const evr_pixel_params *p, float t, float intensity,
                                          float *t_mid)
{
    if (!s->started) return 0;
    const float lo = fmaxf(s->t_prev, 0.0f);
    if (!(t - lo >= 2.0f * ap->min_dt)) return 0;
    const float dl = fabsf(evr_log_response(intensity, p->log_floor) -
                           evr_log_response(s->intensity, p->log_floor));
    if (!(dl > ap->frac * fminf(p->pos_thres, p->neg_thres))) return 0;
    *t_mid = 0.5f * (lo + t);
    return 1;
}

/* Everything a backend does after tracing a sample at segment time t (intensity, primary ray
 * ray0 with hit distance t_hit) and before running it through the pixel model (s: the state
 * before the sample): returns the time to the next sample; *moving is set when something moving
 * can reach the pixel in this segment (evr_adapt_next_time). */
EVR_HD static inline float
evr_adapt_after_sample(const evr_render_scene *rs, const evr_adapt_params *ap,
                       const evr_adapt_plan *pl, const evr_pixel_state *s,
                       const evr_pixel_params *p, evr_ray ray0, float t_hit, float t,
                       float intensity, int *moving)
{
    *moving = 1;
    if (pl->all_min) return ap->min_dt;
    int jump;
    const float speed = evr_adapt_rays_speed(rs, pl, ray0, t_hit, &jump);
    *moving = speed > 0.0f;
    const float l = evr_log_response(intensity, p->log_floor);
    const float l_prev = evr_log_response(s->intensity, p->log_floor);
    return evr_adapt_next_dt(ap, pl, s->started, s->t_prev, l_prev, t, l,
                             fminf(p->pos_thres, p->neg_thres), speed);
}

/* The time of the next sample after one at t, step later (evr_adapt_after_sample). A pixel that
 * something moving can reach and whose next sample would fall past the segment's end (seg, its
 * length) takes one at the segment's end (min_dt / 2 before it) first: the next segment cannot
 * refine the part of an interval before its start (its motion keys are another segment's), so
 * that part stays short. At or past seg: no more samples in this segment. */
EVR_HD static inline float evr_adapt_next_time(const evr_adapt_params *ap, float t, float step,
                                               float seg, int moving)
{
    const float next = t + step, last = seg - 0.5f * ap->min_dt;
    return moving && next >= seg && t < last ? last : next;
}

/* ---- the per-pixel state machine both backends run ----
 * A pixel starts the segment at evr_adapt_start's time. Each traced sample becomes the pixel's
 * candidate; evr_adapt_candidate either holds it back on the pixel's stack (trace the midpoint
 * first) or takes it: then it goes through the pixel model, and evr_adapt_taken gives the next
 * candidate (the latest held back) or the next time to trace. At or past the segment's length
 * the pixel is done for the segment; its next time, less the length, is carried to the next. */

typedef struct {
    float t[EVR_ADAPT_DEPTH], intensity[EVR_ADAPT_DEPTH], hit[EVR_ADAPT_DEPTH];
    unsigned id[EVR_ADAPT_DEPTH]; /* the event id of each (evr_event.id) */
    int n;
} evr_adapt_stack;

/* The pixel's first sample time in the segment (seg: its length), from its state st, the next
 * time next_t carried from the previous segment, its phase and its centre ray ray0. */
EVR_HD static inline float evr_adapt_start(const evr_render_scene *rs, const evr_adapt_params *ap,
                                           const evr_adapt_plan *pl, const evr_pixel_state *st,
                                           evr_ray ray0, float next_t, float phase, float seg)
{
    float speed = 0.0f;
    int jump = 0;
    if (st->started && !pl->all_min)
        speed = evr_adapt_rays_speed(rs, pl, ray0, st->cache_dist, &jump);
    return evr_adapt_first(ap, pl, st->started, next_t, st->t_prev, phase, speed, jump, seg);
}

/* The candidate sample (t, intensity, primary hit distance hit, event id): 0 when it is held back (pushed;
 * *t_trace: the time to trace first), 1 when it is taken: *step and *moving are set for
 * evr_adapt_taken and the pixel's cache of change-driven sampling keeps its hit. Call before the
 * sample goes through the pixel model (st is the state before it). */
EVR_HD static inline int evr_adapt_candidate(const evr_render_scene *rs, const evr_adapt_params *ap,
                                             const evr_adapt_plan *pl, evr_pixel_state *st,
                                             const evr_pixel_params *p, evr_ray ray0,
                                             evr_adapt_stack *sk, float t, float intensity,
                                             float hit, unsigned id, float *t_trace, float *step,
                                             int *moving)
{
    float mid;
    if (sk->n < EVR_ADAPT_DEPTH && evr_adapt_refine(ap, st, p, t, intensity, &mid)) {
        sk->t[sk->n] = t;
        sk->intensity[sk->n] = intensity;
        sk->hit[sk->n] = hit;
        sk->id[sk->n] = id;
        sk->n++;
        *t_trace = mid; /* trace halfway first */
        return 0;
    }
    *step = evr_adapt_after_sample(rs, ap, pl, st, p, ray0, hit, t, intensity, moving);
    st->cache_dist = hit;
    return 1;
}

/* After a taken sample at *t went through the pixel model: 1 with the next candidate in (*t,
 * *intensity, *hit, *id), the latest held back; else 0 with *t_trace the next time to trace (at or
 * past seg: none in this segment). */
EVR_HD static inline int evr_adapt_taken(const evr_adapt_params *ap, evr_adapt_stack *sk,
                                         float step, int moving, float seg, float *t,
                                         float *intensity, float *hit, unsigned *id, float *t_trace)
{
    if (sk->n > 0) {
        sk->n--;
        *t = sk->t[sk->n];
        *intensity = sk->intensity[sk->n];
        *hit = sk->hit[sk->n];
        *id = sk->id[sk->n];
        return 1;
    }
    *t_trace = evr_adapt_next_time(ap, *t, step, seg, moving);
    return 0;
}

#endif
