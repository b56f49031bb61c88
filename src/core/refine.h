/* Refined sampling (--sampling refine, the default): change-driven sampling's samples, refined in
 * time wherever the pixel model fires, until every event's timestamp is within a stated bound.
 *
 * A pixel that nothing moving can reach keeps its intensity for the segment without rays, and a
 * pixel whose first traced sample meets nothing moving settles on it, exactly as with uniform
 * sampling (core/skip.h). The others take a grid of n samples per segment at (k + 1) / n of it,
 * so every pixel's last sample of a segment is at its end and the next segment's first interval
 * starts there (it can then be refined with the next segment's motion alone). A sample at t that
 * makes the pixel model fire against the previous sample at t_prev (evr_refine_fires) is held
 * back while the interval is bisected: the midpoint m is traced first and, with the log
 * intensities l(t_prev), l(m), l(t), the timing error of events interpolated linearly on the two
 * halves is estimated as
 *     E = 2 |l(m) - (l(t_prev) + l(t)) / 2| (t - t_prev) / |l(t) - l(t_prev)|
 * (the deviation from a straight line over the slope: an edge that steps inside the interval
 * gives E = t - t_prev, a smooth ramp a fraction of it). E <= tol takes both halves as they are;
 * else each half that fires is bisected in turn, down to halves of tol. A pixel therefore spends
 * samples only while something moves across it, and those samples only where its events are.
 * The pixel model sees every sample in time order. Both backends run these functions per pixel;
 * the per-segment flow is theirs (the CPU's render_tile_refine, the GPU's refine_kernel). */
#ifndef EVR_CORE_REFINE_H
#define EVR_CORE_REFINE_H

#include <stdint.h>
#include "core/pixel.h"
#include "core/adaptive.h"
#include "core/skip.h"

#define EVR_REFINE_DEPTH 12 /* samples a pixel holds back while it refines an interval */

typedef struct {
    float tol; /* seconds: the bound on an event's timing error the refinement aims at */
    int n;     /* grid samples per segment at least */
    float px;  /* image motion between grid samples, pixels, at most (evr_refine_motion_dt; 0: no
                  bound, the grid alone) */
} evr_refine_params;

/* The samples a pixel holds back, latest at the bottom, each with its primary hit distance, its
 * path's EVR_DEEP_* bits (core/skip.h), its event id and whether a bisection above vouched for
 * the interval before it (sure). */
typedef struct {
    float t[EVR_REFINE_DEPTH], intensity[EVR_REFINE_DEPTH], hit[EVR_REFINE_DEPTH];
    unsigned id[EVR_REFINE_DEPTH];
    unsigned char deep[EVR_REFINE_DEPTH], sure[EVR_REFINE_DEPTH];
    int n;
} evr_refine_stack;

/* The longest time between grid samples in which nothing moving that the sample's rays meet
 * (core/adaptive.h; hit: its primary hit distance, deep its EVR_DEEP_* bits) moves by more than
 * px pixels in the image: a thin thing (a lash crossing a pixel at the speed of a blinking lid,
 * a lash's shadow, a glint) is so seen at least once; a wide thing is found by the grid alone and
 * its edges by the bisection. INFINITY: no bound (pl NULL, px 0, or the camera or a light
 * moving: the grid alone). */
EVR_HD static inline float evr_refine_motion_dt(const evr_render_scene *rs,
                                                const evr_adapt_plan *pl,
                                                const evr_refine_params *rp, evr_ray ray0,
                                                float hit, int deep)
{
    float dt = INFINITY;
    if (!pl || pl->all_min || !(rp->px > 0.0f) || pl->num_boxes == 0) return dt;
    const uint64_t met = evr_adapt_rays_met(rs, pl, ray0, evr_adapt_hit(hit, deep));
    for (int b = 0; b < pl->num_boxes; b++)
        if ((met >> b & 1u) && pl->speed[b] > 0.0f) dt = fminf(dt, rp->px / pl->speed[b]);
    return dt;
}

/* The same for a pixel's first grid sample of a segment: along its whole camera ray (its last
 * hit is not kept across segments, and the cache of change-driven sampling may not be read:
 * --no-skip must sample at the same times). */
EVR_HD static inline float evr_refine_motion_dt_first(const evr_render_scene *rs,
                                                      const evr_adapt_plan *pl,
                                                      const evr_refine_params *rp, evr_ray ray0)
{
    return evr_refine_motion_dt(rs, pl, rp, ray0, INFINITY, 0);
}

/* The time from a grid sample to the next: a segment over n, or motion_dt (evr_refine_motion_dt)
 * when shorter, but never below tol. */
EVR_HD static inline float evr_refine_step(const evr_refine_params *rp, float motion_dt, float seg)
{
    const float step = seg / (float)rp->n;
    return motion_dt < step ? fmaxf(motion_dt, rp->tol) : step;
}

/* The grid sample after one at t: step later, the segment's end when that is at most a fifth of
 * a step further (every pixel's last sample of a segment is at its end). */
EVR_HD static inline float evr_refine_grid_next(float t, float step, float seg)
{
    const float next = t + step;
    return next > seg - 0.2f * step ? seg : next;
}

/* Whether a sample of log intensity l after the pixel's last makes its model fire: l has moved a
 * threshold from the reference (the ideal model's test, for the other sensors an estimate:
 * their filter, leak and noise decide the events themselves). */
EVR_HD static inline int evr_refine_fires(const evr_pixel_state *st, const evr_pixel_params *p,
                                          float l)
{
    return l - st->ref >= p->pos_thres || st->ref - l >= p->neg_thres;
}

/* The candidate sample (t, intensity; hit, deep and id kept with it if held back): 1 when it goes
 * through the pixel model now, 0 when it is held back and *t_trace is to be traced first.
 * fresh: it was just traced (not taken off the stack); sure: it was taken off the stack with its
 * interval vouched for. st is the pixel's state before the sample. */
EVR_HD static inline int evr_refine_candidate(const evr_refine_params *rp,
                                              const evr_pixel_state *st, const evr_pixel_params *p,
                                              evr_refine_stack *sk, float t, float intensity,
                                              float hit, int deep, unsigned id, int fresh, int sure,
                                              float *t_trace)
{
    if (sure || !st->started) return 1;
    const float lo = fmaxf(st->t_prev, 0.0f);
    const float l = evr_log_response(intensity, p->log_floor);
    if (fresh && sk->n > 0) { /* the midpoint of (lo, the top's time): is the interval straight? */
        const int top = sk->n - 1;
        const float la = evr_log_response(st->intensity, p->log_floor),
                    lb = evr_log_response(sk->intensity[top], p->log_floor);
        const float dev = fabsf(l - 0.5f * (la + lb)), rise = fabsf(lb - la);
        if (2.0f * dev * (sk->t[top] - lo) <= rp->tol * rise) {
            sk->sure[top] = 1;
            return 1;
        }
    }
    if (sk->n >= EVR_REFINE_DEPTH || !(t - lo > rp->tol) || !evr_refine_fires(st, p, l)) return 1;
    const int i = sk->n++;
    sk->t[i] = t;
    sk->intensity[i] = intensity;
    sk->hit[i] = hit;
    sk->deep[i] = (unsigned char)deep;
    sk->id[i] = id;
    sk->sure[i] = 0;
    *t_trace = 0.5f * (lo + t);
    return 0;
}

/* After a sample went through the pixel model: 1 with the next candidate taken off the stack
 * (its time, intensity, hit, deep bits, id and sure flag), 0 when none is held back. */
EVR_HD static inline int evr_refine_pop(evr_refine_stack *sk, float *t, float *intensity,
                                        float *hit, int *deep, unsigned *id, int *sure)
{
    if (sk->n == 0) return 0;
    const int i = --sk->n;
    *t = sk->t[i];
    *intensity = sk->intensity[i];
    *hit = sk->hit[i];
    *deep = sk->deep[i];
    *id = sk->id[i];
    *sure = sk->sure[i];
    return 1;
}

/* ---- the per-pixel flow both backends run for a pixel that traces in the segment ----
 * evr_refine_begin sets its first time to trace. Each round a backend serves that time without
 * rays when evr_refine_kept says so, else traces it and hands it to evr_refine_traced; then, while
 * evr_refine_decide says the candidate goes through the pixel model, runs it there and calls
 * evr_refine_next, which brings the next candidate off the stack or schedules the next grid
 * sample. need is set while a time is to be traced; the pixel is done when neither need nor cand
 * is set. evr_refine_end leaves the pixel's cache for the next segment. */
typedef struct {
    evr_refine_stack sk;
    int need, cand; /* a time to trace (t); a candidate sample (c*) */
    float t;
    float ct, ci, ch; /* the candidate: time, intensity, primary hit distance */
    int cdeep, cfresh, csure;
    unsigned cid;
    /* change-driven sampling: settled on its first traced sample, or (last_span) the still span
     * of its last traced sample, whose values (k*) a later sample in the same span takes */
    int settled, traced_any, last_span;
    float kin, khit;
    int kdeep;
    unsigned kid;
    float last_hit; /* the latest sample through the model: its hit, deep bits and id */
    int last_deep;
    unsigned last_id;
} evr_refine_pixel;

/* step: the time to the first grid sample (evr_refine_step); a pixel with no sample yet takes
 * its first at the segment's start. */
EVR_HD static inline void evr_refine_begin(evr_refine_pixel *q, const evr_pixel_state *st,
                                           float step, float seg)
{
    q->sk.n = 0;
    q->t = st->started ? evr_refine_grid_next(0.0f, step, seg) : 0.0f;
    q->need = 1;
    q->cand = 0;
    q->settled = q->traced_any = 0;
    q->last_span = -1;
    q->last_hit = INFINITY;
    q->last_deep = 0;
    q->last_id = 0;
}

/* A pixel that keeps its intensity for the whole segment (change-driven sampling's skip test,
 * core/skip.h) runs as one settled on its last traced sample: the intensity and cache in st, its
 * event id. Its samples come at the times brute force traces them, which a sensor whose filter,
 * leak and noise run between samples needs (the ideal model gives no events from a constant
 * intensity, whenever sampled). Call after evr_refine_begin. */
EVR_HD static inline void evr_refine_keep(evr_refine_pixel *q, const evr_pixel_state *st,
                                          unsigned id)
{
    q->settled = 1;
    q->kin = st->intensity;
    q->kdeep = st->cache_dist == EVR_SKIP_DEEP ? EVR_DEEP_PATH : 0;
    q->khit = q->kdeep ? INFINITY : st->cache_dist;
    q->kid = id;
}

/* Whether the pending time t (normalized f) takes the values of an earlier traced sample without
 * rays (settled, or the same still span: core/skip.h); then the candidate is set. */
EVR_HD static inline int evr_refine_kept(evr_refine_pixel *q, const evr_skip_plan *pl, float f)
{
    if (!q->settled && !evr_skip_held(pl, evr_skip_still_span(pl, f), q->last_span)) return 0;
    q->ct = q->t;
    q->ci = q->kin;
    q->ch = q->khit;
    q->cdeep = q->kdeep;
    q->cid = q->kid;
    q->cfresh = 1;
    q->csure = 0;
    q->need = 0;
    q->cand = 1;
    return 1;
}

/* A sample traced at the pending time (f normalized): it becomes the candidate. The segment's
 * first traced sample settles the pixel when its rays meet nothing moving (may_settle: the
 * backend allows it; global illumination does not); st keeps the cache then. */
EVR_HD static inline void evr_refine_traced(evr_refine_pixel *q, const evr_render_scene *rs,
                                            const evr_skip_plan *pl, evr_pixel_state *st,
                                            evr_ray ray0, float f, float intensity, float hit,
                                            int deep, unsigned id, int may_settle)
{
    q->kin = intensity;
    q->khit = hit;
    q->kdeep = deep;
    q->kid = id;
    q->last_span = may_settle ? evr_skip_still_span(pl, f) : -1;
    if (!q->traced_any && may_settle) {
        const float c = evr_skip_cache_after_trace(rs, pl, ray0, hit, deep);
        if (evr_skip_clean(c)) {
            q->settled = 1;
            st->cache_dist = c;
        }
    }
    q->traced_any = 1;
    q->ct = q->t;
    q->ci = intensity;
    q->ch = hit;
    q->cdeep = deep;
    q->cid = id;
    q->cfresh = 1;
    q->csure = 0;
    q->need = 0;
    q->cand = 1;
}

/* 1: the candidate goes through the pixel model now; 0: it is held back and t is to be traced. */
EVR_HD static inline int evr_refine_decide(evr_refine_pixel *q, const evr_refine_params *rp,
                                           const evr_pixel_state *st, const evr_pixel_params *p)
{
    if (evr_refine_candidate(rp, st, p, &q->sk, q->ct, q->ci, q->ch, q->cdeep, q->cid, q->cfresh,
                             q->csure, &q->t))
        return 1;
    q->cand = 0;
    q->need = 1;
    return 0;
}

/* After the candidate went through the pixel model: 1 with the next candidate (from the stack),
 * 0 when none is held back (need: the next grid sample, if the segment has one; motion_dt: the
 * candidate's evr_refine_motion_dt, read only then). */
EVR_HD static inline int evr_refine_next(evr_refine_pixel *q, const evr_refine_params *rp,
                                         float motion_dt, float seg)
{
    q->last_hit = q->ch;
    q->last_deep = q->cdeep;
    q->last_id = q->cid;
    if (evr_refine_pop(&q->sk, &q->ct, &q->ci, &q->ch, &q->cdeep, &q->cid, &q->csure)) {
        q->cfresh = 0;
        return 1;
    }
    q->cand = 0;
    q->need = q->ct < seg;
    if (q->need) q->t = evr_refine_grid_next(q->ct, evr_refine_step(rp, motion_dt, seg), seg);
    return 0;
}

/* evr_refine_next with the candidate's own motion bound (evr_refine_motion_dt; none while
 * samples are held back: the stack's next comes first). */
EVR_HD static inline int evr_refine_next_bounded(evr_refine_pixel *q, const evr_render_scene *rs,
                                                 const evr_adapt_plan *pl,
                                                 const evr_refine_params *rp, evr_ray ray0,
                                                 float seg)
{
    const float m = q->sk.n ? INFINITY : evr_refine_motion_dt(rs, pl, rp, ray0, q->ch, q->cdeep);
    return evr_refine_next(q, rp, m, seg);
}

/* The pixel's cache after the segment (core/skip.h), as uniform sampling leaves it. */
EVR_HD static inline void evr_refine_end(const evr_refine_pixel *q, const evr_render_scene *rs,
                                         const evr_skip_plan *pl, evr_pixel_state *st, evr_ray ray0)
{
    if (q->traced_any && !q->settled)
        st->cache_dist = evr_skip_cache_after_trace(rs, pl, ray0, q->last_hit, q->last_deep);
}

#endif
