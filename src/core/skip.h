/* Change-driven sampling: which pixels can keep their last intensity for a whole segment.
 *
 * A pixel's intensity depends on its primary ray (up to the surface it hits) and on the shadow
 * rays from that surface to the lights. While the camera and the lights hold still, the pixel's
 * last traced sample is reused when none of those rays meets the swept bounds of anything that
 * moves in the segment, and when that sample was itself taken with none of its rays meeting
 * anything that moved in its own segment (the pixel's cache is "clean"). Then every sample of
 * the segment would trace exactly the same rays against exactly the same triangles: the cached
 * intensity is bit for bit what brute force computes, and the pixel model, run on it sample by
 * sample, gives identical events (noise included). A pixel that must trace traces its first
 * sample; when that sample's rays meet nothing moving in the segment, every later sample would
 * see the same triangles, so it keeps that intensity for the rest of the segment ("settles") and
 * its cache is clean. The host fills an evr_skip_plan per segment (src/prep/skip_plan.c); both
 * backends run these functions per pixel. */
#ifndef EVR_CORE_SKIP_H
#define EVR_CORE_SKIP_H

#include "core/render_scene.h"
#include "core/shading.h"

#define EVR_SKIP_MAX_BOXES 64
#define EVR_SKIP_MAX_PARTS 2048

typedef struct {
    int reuse; /* clean caches may be reused this segment (camera and lights still, and
                             unchanged since the previous segment) */
    int cache; /* samples traced this segment may become clean caches (camera and
                             lights still in the segment) */
    int num_boxes;
    float pad; /* added to every box on every side (float error of the tests) */
    float lo[EVR_SKIP_MAX_BOXES][3], hi[EVR_SKIP_MAX_BOXES][3]; /* swept bounds of what moves */
    /* tighter: box b's mesh split into parts, each part's triangles swept on their own (a ray
     * that meets box b can still pass between them: the eye's lids are thin sheets in a large
     * box), as a binary tree of boxes: box b's nodes are part_lo/hi[part_first[b] + n] for
     * n < part_first[b + 1] - part_first[b] (none: the box alone decides), node n's children
     * 2n + 1 and 2n + 2, a node without children a leaf; an empty node (lo > hi) holds nothing */
    int part_first[EVR_SKIP_MAX_BOXES + 1];
    float part_lo[EVR_SKIP_MAX_PARTS][3], part_hi[EVR_SKIP_MAX_PARTS][3];
    /* spans (with or without skipping): the camera and the lights hold still in the segment, and
     * nothing moves (every instance's transform the same bits) at normalized times
     * f < still_before, nor at f > still_after (evr_skip_still_span) */
    int spans;
    float still_before, still_after;
} evr_skip_plan;

/* Whether nothing moves in the segment nor changed since the previous one (camera, lights and
 * instances): the photons of the previous segment's end hold for this one too. */
EVR_HD static inline int evr_skip_plan_still(const evr_skip_plan *pl)
{
    return pl->reuse && pl->num_boxes == 0;
}

/* The still span of normalized segment time f: 1 before anything of the segment moves, 2 after
 * all of it has, 0 while things move or where the plan does not tell (the camera or a light
 * moves). Two samples of a pixel in the same nonzero span see the same scene bit for bit
 * (evr_motion_eval; Embree at evr_skip_trace_time), so with skipping (cache) the later takes the
 * earlier's intensity without rays (evr_skip_held); brute force traces both, to the same bits. */
EVR_HD static inline int evr_skip_still_span(const evr_skip_plan *pl, float f)
{
    if (!pl->spans) return 0;
    return f < pl->still_before ? 1 : f > pl->still_after ? 2 : 0;
}

/* Whether a sample in span `span` takes the intensity of its pixel's last traced sample, traced
 * in span last_span (-1: none yet). */
EVR_HD static inline int evr_skip_held(const evr_skip_plan *pl, int span, int last_span)
{
    return pl->cache && span != 0 && span == last_span;
}

/* The time a ray of a sample at f is traced at where the tracer interpolates motion its own way
 * (Embree: equal keys give slightly different transforms at different times): the start of a
 * still span before all motion, the end after it, else f. */
EVR_HD static inline float evr_skip_trace_time(const evr_skip_plan *pl, float f)
{
    const int span = evr_skip_still_span(pl, f);
    return span == 1 ? 0.0f : span == 2 ? 1.0f : f;
}

/* Whether the part [0, tmax] of the ray o + t d meets the box (padded): the slab test. Any NaN
 * makes it answer yes, so that a doubtful case is traced. */
EVR_HD static inline int evr_skip_segment_meets(evr_v3 o, evr_v3 d, float tmax, const float lo[3],
                                                const float hi[3], float pad)
{
    const float org[3] = {o.x, o.y, o.z}, dir[3] = {d.x, d.y, d.z};
    float t0 = 0.0f, t1 = tmax;
    for (int a = 0; a < 3; a++) {
        const float l = lo[a] - pad, h = hi[a] + pad;
        if (dir[a] == 0.0f) {
            if (org[a] < l || org[a] > h) return 0;
            continue;
        }
        const float inv = 1.0f / dir[a];
        float ta = (l - org[a]) * inv, tb = (h - org[a]) * inv;
        if (ta > tb) {
            float s = ta;
            ta = tb;
            tb = s;
        }
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
        if (t0 > t1) return 0;
    }
    return 1;
}

/* Whether the ray meets a leaf of box b's tree of parts (evr_skip_plan.part_first). */
EVR_HD static inline int evr_skip_parts_meet(const evr_skip_plan *pl, int b, evr_v3 o, evr_v3 d,
                                             float tmax)
{
    const int base = pl->part_first[b], n = pl->part_first[b + 1] - base;
    int stack[24], sp = 0, node = 0;
    for (;;) {
        const float *lo = pl->part_lo[base + node], *hi = pl->part_hi[base + node];
        if (!(lo[0] > hi[0]) && evr_skip_segment_meets(o, d, tmax, lo, hi, pl->pad)) {
            if (2 * node + 1 >= n) return 1; /* a leaf */
            if (sp < 24) {
                stack[sp++] = 2 * node + 2;
                node = 2 * node + 1;
                continue;
            }
            return 1; /* deeper than planned for: say yes */
        }
        if (sp == 0) return 0;
        node = stack[--sp];
    }
}

EVR_HD static inline int evr_skip_ray_meets_any(const evr_skip_plan *pl, evr_v3 o, evr_v3 d,
                                                float tmax)
{
    for (int b = 0; b < pl->num_boxes; b++) {
        if (!evr_skip_segment_meets(o, d, tmax, pl->lo[b], pl->hi[b], pl->pad)) continue;
        if (pl->part_first[b] >= pl->part_first[b + 1] || evr_skip_parts_meet(pl, b, o, d, tmax))
            return 1;
    }
    return 0;
}

/* Whether the segment from surface point p to a light that sends light there meets anything that
 * moves (the lights do not move when this is asked: their position at time 0 is theirs). */
EVR_HD static inline int evr_skip_lights_meet(const evr_render_scene *rs, const evr_skip_plan *pl,
                                              evr_v3 p)
{
    for (int l = 0; l < rs->num_lights; l++) {
        evr_v3 wi;
        float dist, e[3];
        if (!evr_light_incident(rs, &rs->lights[l], 0.0f, p, &wi, &dist, e)) continue;
        if (evr_skip_ray_meets_any(pl, p, wi, dist)) return 1;
    }
    return 0;
}

/* Whether the ray from its origin up to its hit at distance t_hit (INFINITY or more than 1e29:
 * nothing hit, the whole ray) meets anything that moves. */
EVR_HD static inline int evr_skip_hit_ray_meets(const evr_skip_plan *pl, evr_ray ray, float t_hit)
{
    /* a little past the hit: the surface itself may lie on a box's face */
    return evr_skip_ray_meets_any(pl, ray.org, ray.dir,
                                  t_hit < 1e29f ? t_hit * 1.0001f + pl->pad : INFINITY);
}

/* Whether a sample's rays meet anything that moves: the primary ray up to its hit at distance
 * t_hit and, from the hit point computed exactly as the shading computes it, the segment to
 * every light that sends light there. */
EVR_HD static inline int evr_skip_rays_meet(const evr_render_scene *rs, const evr_skip_plan *pl,
                                            evr_ray ray, float t_hit)
{
    if (pl->num_boxes == 0) return 0;
    if (evr_skip_hit_ray_meets(pl, ray, t_hit)) return 1;
    if (!(t_hit < 1e29f)) return 0;
    return evr_skip_lights_meet(rs, pl, evr_v3_add(ray.org, evr_v3_scale(ray.dir, t_hit)));
}

/* What a sample's path beyond its primary hit tells change-driven sampling (core/path.h sets
 * it): EVR_DEEP_PATH when the path went on past the primary hit (a reflection, refraction or
 * blended layer), with EVR_DEEP_MOVED when one of those rays, or a shadow ray from where it
 * hit, meets anything that moves in the segment. */
#define EVR_DEEP_PATH 1
#define EVR_DEEP_MOVED 2

/* The pixel's cache as stored in its state: the distance of its last traced sample's hit
 * (INFINITY: none) when clean, negative when not. EVR_SKIP_DEEP: clean, but its path went on
 * past the primary hit, whose rays the cache does not keep: it may be reused only in a segment
 * where nothing moves (within its own segment, a deep sample whose rays all miss what moves
 * settles like any other). */
#define EVR_SKIP_DIRTY (-1.0f)
#define EVR_SKIP_DEEP (-2.0f)

/* Whether a cache value is clean (reusable under the rules above). */
EVR_HD static inline int evr_skip_clean(float cache_dist)
{
    return cache_dist >= 0.0f || cache_dist == EVR_SKIP_DEEP;
}

/* 1 when a pixel whose camera ray is `ray` keeps its last intensity for the whole segment. */
EVR_HD static inline int evr_skip_pixel(const evr_render_scene *rs, const evr_skip_plan *pl,
                                        int started, float cache_dist, evr_ray ray)
{
    if (cache_dist == EVR_SKIP_DEEP) return pl->reuse && started && pl->num_boxes == 0;
    return pl->reuse && started && cache_dist >= 0.0f &&
           !evr_skip_rays_meet(rs, pl, ray, cache_dist);
}

/* The cache a traced pixel keeps: its last sample's hit distance if clean, else EVR_SKIP_DIRTY;
 * deep: the sample's EVR_DEEP_* bits (EVR_SKIP_DEEP when clean). */
EVR_HD static inline float evr_skip_cache_after_trace(const evr_render_scene *rs,
                                                      const evr_skip_plan *pl, evr_ray ray,
                                                      float t_hit, int deep)
{
    if (!pl->cache || (deep & EVR_DEEP_MOVED)) return EVR_SKIP_DIRTY;
    if (deep && pl->num_boxes == 0) return EVR_SKIP_DEEP; /* t_hit may be EVR_SKIP_DEEP itself */
    const float d = t_hit < 1e29f ? t_hit : INFINITY;
    if (evr_skip_rays_meet(rs, pl, ray, d)) return EVR_SKIP_DIRTY;
    return deep ? EVR_SKIP_DEEP : d;
}

#endif
