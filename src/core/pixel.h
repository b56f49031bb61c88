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
 * Times are in seconds relative to the start of the current segment (negative for the previous
 * one); evr_pixel_end_segment rebases them. */
#ifndef EVR_CORE_PIXEL_H
#define EVR_CORE_PIXEL_H

#include <stdint.h>
#include "core/hd.h"
#include <math.h>

typedef struct {
    float pos_thres, neg_thres;   /* log-intensity contrast thresholds (> 0) */
    float refractory;             /* seconds */
    float log_floor;              /* below this intensity the response is linear */
} evr_pixel_params;

typedef struct {
    float ref;          /* reference log level */
    float l_prev;       /* log intensity at the previous sample */
    float t_prev;       /* time of the previous sample */
    float refr_end;     /* end of the refractory period, while blind */
    float intensity;    /* linear intensity at the previous sample (for previews) */
    uint16_t started;   /* 0 until the first sample */
    uint16_t blind;     /* 1 from an event until its refractory period ends and the reference resets */
} evr_pixel_state;

/* One sample interval being turned into events. */
typedef struct {
    float t0, l0, t1, l1;
    float cursor;       /* time up to which events have been emitted */
} evr_pixel_span;

/* Log response with a linear segment below the floor (value and slope continuous), so that
 * black stays finite and near-black noise does not explode in log space. */
EVR_HD static inline float evr_log_response(float intensity, float floor_)
{
    if (intensity >= floor_) return logf(intensity);
    return logf(floor_) + (intensity - floor_) / floor_;
}

EVR_HD static inline void evr_pixel_reset(evr_pixel_state *s)
{
    s->ref = 0.0f;
    s->l_prev = 0.0f;
    s->t_prev = 0.0f;
    s->refr_end = 0.0f;
    s->intensity = 0.0f;
    s->started = 0;
    s->blind = 0;
}

/* Starts a new sample (t, intensity). Returns 0 for the pixel's very first sample, which only
 * sets the reference (no events can come from it). */
EVR_HD static inline int evr_pixel_begin(evr_pixel_state *s, const evr_pixel_params *p, float t, float intensity,
                                         evr_pixel_span *sp)
{
    float l = evr_log_response(intensity, p->log_floor);
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

/* Emits the next event of the span, if any: its time (relative to the segment) and polarity
 * (1 ON, 0 OFF). Call until it returns 0, then evr_pixel_end. */
EVR_HD static inline int evr_pixel_next(evr_pixel_state *s, const evr_pixel_params *p, evr_pixel_span *sp,
                                        float *t_event, int *polarity)
{
    if (s->blind) {
        if (s->refr_end > sp->t1) return 0;           /* blind for the rest of this span */
        sp->cursor = fmaxf(sp->cursor, s->refr_end);
        s->ref = evr_span_level_at(sp, sp->cursor);   /* reset when the pixel wakes up */
        s->blind = 0;
    }
    if (sp->l1 - s->ref >= p->pos_thres) {
        float level = s->ref + p->pos_thres;
        *t_event = evr_span_level_time(sp, level);
        *polarity = 1;
        s->ref = level;
    } else if (s->ref - sp->l1 >= p->neg_thres) {
        float level = s->ref - p->neg_thres;
        *t_event = evr_span_level_time(sp, level);
        *polarity = 0;
        s->ref = level;
    } else {
        return 0;
    }
    sp->cursor = *t_event;
    if (p->refractory > 0.0f) {
        s->refr_end = *t_event + p->refractory;
        s->blind = 1;
    }
    return 1;
}

EVR_HD static inline void evr_pixel_end(evr_pixel_state *s, const evr_pixel_span *sp)
{
    s->l_prev = sp->l1;
    s->t_prev = sp->t1;
}

/* Rebases the pixel's times when the simulation moves to the next segment. */
EVR_HD static inline void evr_pixel_end_segment(evr_pixel_state *s, float segment_length)
{
    s->t_prev -= segment_length;
    s->refr_end -= segment_length;
}

#endif
