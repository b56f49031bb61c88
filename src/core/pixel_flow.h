/* The per-pixel event loop, written once: one sample through the pixel model (core/pixel.h),
 * its events handed to the backend's event sink.
 *
 * A backend that includes this header defines `struct evr_event_sink` and the function
 * evr_event_sink_push declared below (the CPU appends to a tile's vector; the GPU appends with
 * warp-aggregated atomics, every lane of the warp calling it together), so the loop is inlined
 * with the backend's sink and no function pointer. */
#ifndef EVR_CORE_PIXEL_FLOW_H
#define EVR_CORE_PIXEL_FLOW_H

#include "core/pixel.h"

struct evr_event_sink;

/* Called once per turn of the loop: has says whether this pixel has an event (timestamp t_us,
 * microseconds; polarity 1 ON, 0 OFF). Returns 0 to end the loop: for one pixel, when it had none;
 * for a warp, when no lane had one. */
EVR_HD static inline int evr_event_sink_push(struct evr_event_sink *k, int has, long long t_us,
                                             int x, int y, int polarity);

/* The ideal model's parameters (evr_pixel_params_ideal): the GPU's ideal kernel keeps them apart
 * from the full parameters, which stay in device memory. */
typedef struct {
    float log_floor, pos_thres, neg_thres, refractory;
} evr_pixel_ideal;

EVR_HD static inline evr_pixel_ideal evr_pixel_ideal_of(const evr_pixel_params *p)
{
    evr_pixel_ideal id;
    id.log_floor = p->log_floor;
    id.pos_thres = p->pos_thres;
    id.neg_thres = p->neg_thres;
    id.refractory = p->refractory;
    return id;
}

/* One sample (intensity at t seconds from the segment's start t0) of pixel (x, y) through its
 * pixel model, its events to the sink. sensor 0 promises an ideal sensor (core/pixel.h's _s
 * forms): then id holds its parameters and p is not read. live 0: no sample (a GPU lane
 * that only takes part in the warp's appends). */
EVR_HD static inline void evr_pixel_sample_events(evr_pixel_state *st, const evr_pixel_params *p,
                                                  evr_pixel_ideal id, const int sensor, int live,
                                                  float t, float intensity, double t0, int x, int y,
                                                  struct evr_event_sink *sink)
{
    evr_pixel_span sp;
    int more = 0;
    sp.i0 = sp.i1 = sp.drift = 0.0f; /* unused by the ideal model (as evr_pixel_begin_s) */
    if (live)
        more = sensor ? evr_pixel_begin_s(st, p, t, intensity, &sp, 1)
                      : evr_pixel_begin_ideal(st, id.log_floor, t, intensity, &sp);
    const int began = more;
    for (;;) {
        float te = 0.0f;
        int pol = 0, has = 0;
        if (more) {
            has = sensor ? evr_pixel_next_s(st, p, &sp, &te, &pol, 1)
                         : evr_pixel_next_ideal(st, id.pos_thres, id.neg_thres, id.refractory, &sp,
                                                &te, &pol);
            more = has;
        }
        const long long t_us = has ? evr_event_time_us_s(p, t0 + (double)te, x, y, sensor) : 0;
        if (!evr_event_sink_push(sink, has, t_us, x, y, pol)) break;
    }
    if (began) evr_pixel_end_s(st, &sp, sensor);
}

#endif
