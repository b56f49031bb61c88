/* The DVS pixel model, shared by every backend.
 *
 * A pixel sees a log intensity L(t) sampled at its own times; between two samples L is taken to
 * move linearly. An event fires when L has moved by the ON threshold above (or the OFF threshold
 * below) the pixel's reference level; its timestamp is the time L crosses that level, not the
 * sample time. The reference then moves by exactly one threshold, so a change spanning several
 * thresholds gives several events at their own crossing times. After an event the pixel is blind
 * for the refractory period, as a real pixel whose reset switch is held; when it ends the
 * reference is reset to the level L has then (with no refractory period this is the same as
 * moving by one threshold).
 *
 * Sensor non-idealities (docs/sensors.md has the laws, their sources and the presets); each is
 * off when its parameter is 0, and with all of them off the model is the ideal one above:
 *  - threshold mismatch: each pixel's ON and OFF thresholds are drawn once from N(nominal,
 *    sigma_thres), clipped to at least min(0.01, nominal) (a fixed pattern: a pure function of
 *    (seed, pixel), recomputed per segment rather than stored);
 *  - photoreceptor bandwidth: L goes through a first-order low-pass whose cutoff is
 *    cutoff_hz * (f + 20/255) / (1 + 20/255), f = min(I / full_intensity, 1) the intensity
 *    fraction (v2e's law, its rescale_intensity_frame: (I255 + 20) / 275); the filter is
 *    integrated exactly over each sample interval for the input moving linearly between the
 *    samples (closed form of a first-order system driven by a ramp), its time constant taken
 *    from the interval's mean intensity; events come from the filtered signal, its crossings
 *    interpolated linearly inside the interval as for the unfiltered one;
 *  - leak: the reference drifts down at leak * ON threshold per second, so a static pixel fires
 *    ON events at its leak rate (leak_rate * (1 + leak_jitter * N(0,1)), a fixed pattern, at
 *    least 0) from a random initial phase; the drift is exact (L - reference stays linear in
 *    each interval, the crossings are found in the reference's moving frame);
 *  - shot noise and hot pixels: a Poisson process of candidate times per pixel, in continuous
 *    time, at rate hot + shot_rate, its n-th gap and its n-th candidate's kind drawn from the
 *    counter-based RNG keyed by (seed, pixel, n), running from the start of the first segment,
 *    so the noise does not depend on threads, tiles, backend or sampling. A candidate is a hot-pixel ON event with probability
 *    hot / rate, else a shot-noise event (ON or OFF, even odds) accepted with probability
 *    shot(I) / shot_rate, shot(I) = shot_rate * (1 - 0.75 f) (thinning: an exact
 *    inhomogeneous Poisson process of rate shot(I(t)), I linear between samples; v2e's
 *    SHOT_NOISE_INTEN_FACTOR 0.25: a pixel at full brightness has a quarter of a black pixel's
 *    shot noise). A noise event resets the pixel as any event does (reference to the present
 *    level, refractory period); candidates falling while the pixel is blind are lost.
 *  - timestamps: quantized to time_res_us microseconds (rounded to the nearest multiple) after
 *    an optional Gaussian jitter (time_jitter seconds, clipped to 4 sigma) keyed by (seed,
 *    pixel, the unjittered microsecond).
 *
 * Times are in seconds relative to the start of the current segment (negative for the previous
 * one); evr_pixel_end_segment rebases them. */
#ifndef EVR_CORE_PIXEL_H
#define EVR_CORE_PIXEL_H

#include <stdint.h>
#include "core/hd.h"
#include "core/rng.h"
#include <math.h>

/* cutoff law offset: a black pixel keeps 7.3% of the cutoff */
#define EVR_CUTOFF_DARK (20.0f / 255.0f)
#define EVR_SHOT_BRIGHT 0.25f /* shot noise at full brightness / shot noise of a black pixel */
#define EVR_JITTER_CLIP 4.0f  /* timestamp jitter is clipped to this many sigma */

/* Fixed counters of the per-pixel random streams. */
#define EVR_TAG_THRES 0x7468726573ull    /* "thres" */
#define EVR_TAG_LEAK 0x6c65616bull       /* "leak" */
#define EVR_TAG_HOT 0x686f74ull          /* "hot" */
#define EVR_TAG_NOISE 0x6e6f697365ull    /* "noise" */
#define EVR_TAG_JITTER 0x6a6974746572ull /* "jitter" */

typedef struct {
    /* run-wide */
    float pos_thres,
        neg_thres; /* log-intensity contrast thresholds (> 0); per pixel after evr_pixel_params_at */
    float refractory;     /* seconds */
    float log_floor;      /* below this intensity the response is linear */
    float sigma_thres;    /* threshold mismatch, log units (0: off) */
    float cutoff_hz;      /* photoreceptor cutoff at full brightness (0: no filter) */
    float full_intensity; /* intensity of full brightness (bandwidth and shot-noise laws) */
    float leak_rate;      /* mean leak ON events per second (0: off) */
    float leak_jitter;    /* relative spread of the per-pixel leak rate */
    float shot_rate;      /* shot-noise events per second (ON + OFF) of a black pixel (0: off) */
    float hot_fraction;   /* fraction of hot pixels */
    float hot_rate;       /* ON events per second of a hot pixel */
    float time_jitter;    /* timestamp jitter, seconds (0: off) */
    int time_res_us;      /* timestamp quantum, microseconds (<= 1: 1 us) */
    uint64_t seed;
    /* per pixel, set by evr_pixel_params_at (0 in the run-wide parameters) */
    float leak;       /* reference drift, log units per second */
    float leak_phase; /* initial reference offset, in ON thresholds below the first level */
    float hot;        /* this pixel's hot-pixel rate (0: not hot) */
    float noise_rate; /* rate of noise candidates: hot + shot_rate */
    uint64_t key;     /* the pixel's noise stream */
} evr_pixel_params;

/* 32 bytes: it is copied per pixel per segment on the GPU. */
typedef struct {
    /* the ideal model's state (its first 24 bytes, as before the sensor model) */
    float ref;       /* reference log level at t_prev */
    float l_prev;    /* (filtered) log intensity at the previous sample */
    float t_prev;    /* time of the previous sample */
    float refr_end;  /* end of the refractory period, while blind */
    float intensity; /* linear intensity at the previous sample (previews, bandwidth, shot noise) */
    uint16_t started; /* 0 until the first sample */
    uint16_t blind; /* 1 from an event until its refractory period ends and the reference resets */
    /* noise */
    float noise_t;    /* time of the next noise candidate */
    uint32_t noise_n; /* index of that candidate in the pixel's noise stream */
    /* change-driven sampling (core/skip.h) */
    float cache_dist; /* hit distance of the last traced sample when its intensity may be reused
                           (INFINITY: it hit nothing), negative when it may not */
} evr_pixel_state;

/* One sample interval being turned into events. The levels are in the frame of the drifting
 * reference (the leak drift over the interval is added to l1), so the reference is constant
 * inside the interval. */
typedef struct {
    float t0, l0, t1, l1;
    float cursor; /* time up to which events have been emitted */
    float i0, i1; /* linear intensities at both ends */
    float drift;  /* leak drift over the interval, taken off the reference at its end */
} evr_pixel_span;

/* 1 when every non-ideality is off: backends may then run the plain model (the GPU compiles a
 * kernel without the sensor code). */
EVR_HD static inline int evr_pixel_params_ideal(const evr_pixel_params *p)
{
    return p->sigma_thres == 0.0f && p->cutoff_hz == 0.0f && p->leak_rate == 0.0f &&
           p->shot_rate == 0.0f && (p->hot_fraction == 0.0f || p->hot_rate == 0.0f) &&
           p->time_jitter == 0.0f && p->time_res_us <= 1;
}

/* The parameters of pixel (x, y): its fixed-pattern thresholds, leak and hot-pixel rate. */
EVR_HD static inline void evr_pixel_params_at(const evr_pixel_params *run, int x, int y,
                                              evr_pixel_params *p)
{
    *p = *run;
    p->leak = 0.0f;
    p->leak_phase = 0.0f;
    p->hot = 0.0f;
    if (run->sigma_thres > 0.0f) {
        float z0, z1;
        evr_gauss2(evr_hash4(run->seed, (uint64_t)x, (uint64_t)y, EVR_TAG_THRES), &z0, &z1);
        p->pos_thres = fmaxf(run->pos_thres + run->sigma_thres * z0, fminf(0.01f, run->pos_thres));
        p->neg_thres = fmaxf(run->neg_thres + run->sigma_thres * z1, fminf(0.01f, run->neg_thres));
    }
    if (run->leak_rate > 0.0f) {
        uint64_t h = evr_hash4(run->seed, (uint64_t)x, (uint64_t)y, EVR_TAG_LEAK);
        float z0, z1;
        evr_gauss2(h, &z0, &z1);
        p->leak = fmaxf(run->leak_rate * (1.0f + run->leak_jitter * z0), 0.0f) * p->pos_thres;
        p->leak_phase = evr_uniform(evr_mix64(h));
    }
    if (run->hot_fraction > 0.0f && run->hot_rate > 0.0f &&
        evr_uniform(evr_hash4(run->seed, (uint64_t)x, (uint64_t)y, EVR_TAG_HOT)) <
            run->hot_fraction)
        p->hot = run->hot_rate;
    p->noise_rate = p->hot + run->shot_rate;
    p->key =
        p->noise_rate > 0.0f ? evr_hash4(run->seed, (uint64_t)x, (uint64_t)y, EVR_TAG_NOISE) : 0;
}

/* Log response with a linear segment below the floor (value and slope continuous), so that
 * black stays finite and near-black noise does not explode in log space. */
EVR_HD static inline float evr_log_response(float intensity, float floor_)
{
    if (intensity >= floor_) return logf(intensity);
    return logf(floor_) + (intensity - floor_) / floor_;
}

/* Intensity as a fraction of full brightness, in [0, 1]. */
EVR_HD static inline float evr_intensity_fraction(const evr_pixel_params *p, float intensity)
{
    return p->full_intensity > 0.0f ? fminf(fmaxf(intensity / p->full_intensity, 0.0f), 1.0f)
                                    : 1.0f;
}

/* Time constant of the photoreceptor at this intensity: 1 / (2 pi f_c), f_c as above. */
EVR_HD static inline float evr_lowpass_tau(const evr_pixel_params *p, float intensity)
{
    float fc = p->cutoff_hz * (evr_intensity_fraction(p, intensity) + EVR_CUTOFF_DARK) /
               (1.0f + EVR_CUTOFF_DARK);
    return 1.0f / (6.28318530718f * fc);
}

/* First-order low-pass y' = (u - y) / tau over dt for an input u moving linearly from a to b:
 * y(dt) = b + (y0 - a) e^(-x) - (b - a) (1 - e^(-x)) / x, x = dt / tau. Exact. */
EVR_HD static inline float evr_lowpass_step(float y0, float a, float b, float dt, float tau)
{
    if (!(dt > 0.0f)) return y0;
    float x = dt / tau;
    float em1 = expm1f(-x); /* e^(-x) - 1, accurate for small x */
    return b + (y0 - a) * (1.0f + em1) + (b - a) * (em1 / x);
}

/* Shot-noise rate (ON + OFF) at this intensity. */
EVR_HD static inline float evr_shot_rate(const evr_pixel_params *p, float intensity)
{
    return p->shot_rate * (1.0f - (1.0f - EVR_SHOT_BRIGHT) * evr_intensity_fraction(p, intensity));
}

/* The n-th draw of the pixel's noise stream: its top 24 bits give the gap before candidate n,
 * the next 24 its kind, the lowest its polarity. */
EVR_HD static inline uint64_t evr_noise_hash(const evr_pixel_params *p, uint32_t n)
{
    return evr_mix64(p->key ^ evr_mix64((uint64_t)n));
}

EVR_HD static inline float evr_noise_gap(const evr_pixel_params *p, uint32_t n)
{
    return -log1pf(-evr_uniform(evr_noise_hash(p, n))) / p->noise_rate;
}

EVR_HD static inline void evr_pixel_reset(evr_pixel_state *s)
{
    s->ref = 0.0f;
    s->l_prev = 0.0f;
    s->t_prev = 0.0f;
    s->refr_end = 0.0f;
    s->intensity = 0.0f;
    s->noise_t = 0.0f;
    s->noise_n = 0;
    s->started = 0;
    s->blind = 0;
    s->cache_dist = -1.0f;
}

/* The functions below come in two forms: evr_pixel_X(...) runs the full model, checking which
 * non-idealities p turns on; evr_pixel_X_s(..., sensor) with sensor 0 promises that all are off
 * (evr_pixel_params_ideal) and runs the ideal model's own code, evr_pixel_X_ideal: the model as
 * it was before the sensor model existed, so that the GPU's ideal kernel compiles to the same
 * code as before (its speed is sensitive to code layout: a kernel a few instructions longer was
 * measured 40% slower on the square demo). Both forms give bit-identical events when everything
 * is off (tests/test_noise.c). */

EVR_HD static inline int evr_pixel_begin_ideal(evr_pixel_state *s, float log_floor, float t,
                                               float intensity, evr_pixel_span *sp)
{
    float l = evr_log_response(intensity, log_floor);
    if (!s->started) {
        s->started = 1;
        s->ref = l;
        s->l_prev = l;
        s->t_prev = t;
        s->intensity = intensity;
        return 0;
    }
    sp->t0 = s->t_prev;
    sp->l0 = s->l_prev;
    sp->t1 = t;
    sp->l1 = l;
    sp->cursor = s->t_prev;
    s->intensity = intensity;
    return 1;
}

/* Starts a new sample (t, intensity). Returns 0 for the pixel's very first sample, which only
 * sets the reference (no events can come from it). */
EVR_HD static inline int evr_pixel_begin_s(evr_pixel_state *s, const evr_pixel_params *p, float t,
                                           float intensity, evr_pixel_span *sp, const int sensor)
{
    if (!sensor) {
        sp->i0 = sp->i1 = sp->drift = 0.0f; /* unused by the ideal model */
        return evr_pixel_begin_ideal(s, p->log_floor, t, intensity, sp);
    }
    float l = evr_log_response(intensity, p->log_floor);
    if (!s->started) {
        s->started = 1;
        s->ref = l;
        if (p->leak > 0.0f) s->ref -= p->leak_phase * p->pos_thres;
        s->l_prev = l;
        s->t_prev = t;
        s->intensity = intensity;
        if (p->noise_rate > 0.0f) { /* the process runs from the start of this first segment */
            s->noise_n = 0;
            s->noise_t = evr_noise_gap(p, 0);
            while (s->noise_t < t) {
                s->noise_n++;
                s->noise_t += evr_noise_gap(p, s->noise_n);
            }
        }
        return 0;
    }
    float y = l;
    if (p->cutoff_hz > 0.0f)
        y = evr_lowpass_step(s->l_prev, evr_log_response(s->intensity, p->log_floor), l,
                             t - s->t_prev, evr_lowpass_tau(p, 0.5f * (s->intensity + intensity)));
    sp->t0 = s->t_prev;
    sp->l0 = s->l_prev;
    sp->t1 = t;
    sp->l1 = y;
    sp->cursor = s->t_prev;
    sp->i0 = s->intensity;
    sp->i1 = intensity;
    sp->drift = 0.0f;
    if (p->leak > 0.0f) {
        sp->drift = p->leak * (t - s->t_prev);
        sp->l1 += sp->drift;
    }
    s->l_prev = y;
    s->t_prev = t;
    s->intensity = intensity;
    return 1;
}

EVR_HD static inline int evr_pixel_begin(evr_pixel_state *s, const evr_pixel_params *p, float t,
                                         float intensity, evr_pixel_span *sp)
{
    return evr_pixel_begin_s(s, p, t, intensity, sp, 1);
}

EVR_HD static inline float evr_span_level_time(const evr_pixel_span *sp, float level)
{
    float dl = sp->l1 - sp->l0;
    float t = dl != 0.0f ? sp->t0 + (level - sp->l0) / dl * (sp->t1 - sp->t0) : sp->t1;
    return fminf(fmaxf(t, sp->cursor), sp->t1);
}

EVR_HD static inline float evr_span_level_at(const evr_pixel_span *sp, float t)
{
    float dt = sp->t1 - sp->t0;
    return dt > 0.0f ? sp->l0 + (sp->l1 - sp->l0) * ((t - sp->t0) / dt) : sp->l1;
}

/* Takes the pixel's next noise candidate (at s->noise_t, inside the span): returns its polarity,
 * or -1 when thinning drops it. */
EVR_HD static inline int evr__noise_take(evr_pixel_state *s, const evr_pixel_params *p,
                                         const evr_pixel_span *sp)
{
    uint64_t h = evr_noise_hash(p, s->noise_n);
    float r = (float)((h >> 16) & 0xffffffu) * (1.0f / 16777216.0f) * p->noise_rate;
    int pol = -1;
    if (r < p->hot) {
        pol = 1;
    } else if (p->shot_rate > 0.0f) {
        float dt = sp->t1 - sp->t0;
        float w = dt > 0.0f ? fminf(fmaxf((s->noise_t - sp->t0) / dt, 0.0f), 1.0f) : 1.0f;
        if (r - p->hot < evr_shot_rate(p, sp->i0 + (sp->i1 - sp->i0) * w)) pol = (int)(h & 1u);
    }
    s->noise_n++;
    s->noise_t += evr_noise_gap(p, s->noise_n);
    return pol;
}

EVR_HD static inline int evr_pixel_next_ideal(evr_pixel_state *s, float pos_thres, float neg_thres,
                                              float refractory, evr_pixel_span *sp, float *t_event,
                                              int *polarity)
{
    if (s->blind) {
        if (s->refr_end > sp->t1) return 0; /* blind for the rest of this span */
        sp->cursor = fmaxf(sp->cursor, s->refr_end);
        s->ref = evr_span_level_at(sp, sp->cursor); /* reset when the pixel wakes up */
        s->blind = 0;
    }
    if (sp->l1 - s->ref >= pos_thres) {
        float level = s->ref + pos_thres;
        *t_event = evr_span_level_time(sp, level);
        *polarity = 1;
        s->ref = level;
    } else if (s->ref - sp->l1 >= neg_thres) {
        float level = s->ref - neg_thres;
        *t_event = evr_span_level_time(sp, level);
        *polarity = 0;
        s->ref = level;
    } else {
        return 0;
    }
    sp->cursor = *t_event;
    if (refractory > 0.0f) {
        s->refr_end = *t_event + refractory;
        s->blind = 1;
    }
    return 1;
}

/* Emits the next event of the span, if any: its time (relative to the segment) and polarity
 * (1 ON, 0 OFF). Call until it returns 0, then evr_pixel_end. */
EVR_HD static inline int evr_pixel_next_s(evr_pixel_state *s, const evr_pixel_params *p,
                                          evr_pixel_span *sp, float *t_event, int *polarity,
                                          const int sensor)
{
    if (!sensor)
        return evr_pixel_next_ideal(s, p->pos_thres, p->neg_thres, p->refractory, sp, t_event,
                                    polarity);
    for (;;) {
        if (s->blind) {
            if (p->noise_rate > 0.0f) { /* candidates while blind are lost */
                while (s->noise_t < s->refr_end && s->noise_t <= sp->t1) {
                    s->noise_n++;
                    s->noise_t += evr_noise_gap(p, s->noise_n);
                }
            }
            if (s->refr_end > sp->t1) return 0; /* blind for the rest of this span */
            sp->cursor = fmaxf(sp->cursor, s->refr_end);
            s->ref = evr_span_level_at(sp, sp->cursor); /* reset when the pixel wakes up */
            s->blind = 0;
        }
        float level = 0.0f, t = 0.0f;
        int pol = -1;
        if (sp->l1 - s->ref >= p->pos_thres) {
            level = s->ref + p->pos_thres;
            t = evr_span_level_time(sp, level);
            pol = 1;
        } else if (s->ref - sp->l1 >= p->neg_thres) {
            level = s->ref - p->neg_thres;
            t = evr_span_level_time(sp, level);
            pol = 0;
        }
        if (p->noise_rate > 0.0f && s->noise_t <= sp->t1 && (pol < 0 || s->noise_t < t)) {
            float tn = fmaxf(s->noise_t, sp->cursor);
            int np = evr__noise_take(s, p, sp);
            if (np < 0) continue; /* thinned out: look again */
            t = tn;
            pol = np;
            level = evr_span_level_at(sp, tn); /* a noise event resets the pixel */
        } else if (pol < 0) {
            return 0;
        }
        *t_event = t;
        *polarity = pol;
        s->ref = level;
        sp->cursor = t;
        if (p->refractory > 0.0f) {
            s->refr_end = t + p->refractory;
            s->blind = 1;
        }
        return 1;
    }
}

EVR_HD static inline int evr_pixel_next(evr_pixel_state *s, const evr_pixel_params *p,
                                        evr_pixel_span *sp, float *t_event, int *polarity)
{
    return evr_pixel_next_s(s, p, sp, t_event, polarity, 1);
}

EVR_HD static inline void evr_pixel_end_s(evr_pixel_state *s, const evr_pixel_span *sp,
                                          const int sensor)
{
    if (!sensor) { /* the ideal model keeps its previous sample here */
        s->l_prev = sp->l1;
        s->t_prev = sp->t1;
        return;
    }
    s->ref -= sp->drift; /* back from the reference's moving frame */
}

EVR_HD static inline void evr_pixel_end(evr_pixel_state *s, const evr_pixel_span *sp)
{
    evr_pixel_end_s(s, sp, 1);
}

/* The ideal pixel given the same intensity at each of its remaining samples in the segment, the
 * last at time t_last: 1 when none of them can change anything but the previous sample, i.e. the
 * pixel is awake and its log intensity lies within both thresholds of the reference, or it stays
 * blind past t_last. Then evr_pixel_quiet_finish leaves it exactly as those samples through
 * evr_pixel_begin_ideal / next / end would (a pixel that keeps its intensity skips them). */
EVR_HD static inline int evr_pixel_quiet_ideal(const evr_pixel_state *s, float log_floor,
                                               float pos_thres, float neg_thres, float intensity,
                                               float t_last)
{
    if (!s->started) return 0;
    if (s->blind) return s->refr_end > t_last;
    float l = evr_log_response(intensity, log_floor);
    return l - s->ref < pos_thres && s->ref - l < neg_thres;
}

EVR_HD static inline void evr_pixel_quiet_finish(evr_pixel_state *s, float log_floor,
                                                 float intensity, float t_last)
{
    s->l_prev = evr_log_response(intensity, log_floor);
    s->t_prev = t_last;
    s->intensity = intensity;
}

/* Rebases the pixel's times when the simulation moves to the next segment. */
EVR_HD static inline void evr_pixel_end_segment(evr_pixel_state *s, float segment_length)
{
    s->t_prev -= segment_length;
    s->refr_end -= segment_length;
    s->noise_t -= segment_length;
}

/* An event's timestamp in microseconds from its absolute time in seconds: jittered, then
 * quantized to the timestamp resolution. */
EVR_HD static inline long long evr_event_time_us_s(const evr_pixel_params *p, double t, int x,
                                                   int y, const int sensor)
{
    if (!sensor) return llround(t * 1e6);
    if (p->time_jitter > 0.0f) {
        float z0, z1;
        evr_gauss2(evr_hash4(p->seed ^ EVR_TAG_JITTER, (uint64_t)x, (uint64_t)y,
                             (uint64_t)llround(t * 1e6)),
                   &z0, &z1);
        t += (double)(p->time_jitter * fminf(fmaxf(z0, -EVR_JITTER_CLIP), EVR_JITTER_CLIP));
        if (t < 0.0) t = 0.0;
    }
    if (p->time_res_us > 1)
        return llround(t * 1e6 / (double)p->time_res_us) * (long long)p->time_res_us;
    return llround(t * 1e6);
}

EVR_HD static inline long long evr_event_time_us(const evr_pixel_params *p, double t, int x, int y)
{
    return evr_event_time_us_s(p, t, x, y, 1);
}

#endif
