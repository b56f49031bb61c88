/* A photon's trail: its path kept for the next pass.
 *
 * A pass that traces photon i records the rays its path traced (origin, direction, length: the
 * hit's distance, 1e30 for a ray that met nothing, the whole ray for the camera's occlusion test)
 * and what it stored: the photon and its cell, or nothing. The trail is clean when none of those
 * rays met the swept bounds of what moves in that segment (the change-driven sampling plan,
 * core/skip.h): the path met static triangles only. A later pass, with the camera, the lights and
 * the emitters unchanged (the plan's reuse and the same emitter table), takes a clean trail's
 * outcome instead of tracing it again when its rays meet none of its own segment's moving
 * bounds: the same rays would meet the same static triangles, and the outcome would be the same
 * bit for bit. As with pixels, a photon a moving object touches is traced again. */
#ifndef EVR_CORE_PHOTON_TRAIL_H
#define EVR_CORE_PHOTON_TRAIL_H

#include <stdint.h>
#include "core/skip.h"
#include "core/photon_buffer.h"
#include "core/photon_path.h"

#define EVR_TRAIL_NONE 0xffffffffu

typedef struct {
    evr_photon ph; /* what the path stored */
    uint32_t cell; /* its buffer cell; EVR_TRAIL_NONE: nothing stored (or no trail yet) */
    uint16_t n;    /* rays recorded */
    uint8_t clean,
        started; /* clean: see above; started: the path had a start (evr_photon_path_start) */
} evr_photon_trail;

typedef struct {
    float org[3], dir[3], tmax;
} evr_trail_ray;

/* Rays a trail holds at most: one per hit (max_bounces + 1 for a light's photon) and the
 * camera's occlusion test. */
EVR_HD static inline int evr_photon_trail_len(const evr_photon_params *pp)
{
    return pp->max_bounces + 2;
}

/* A trail for a pass of plan pl: clean only if the plan may cache (camera and lights still). */
EVR_HD static inline void evr_photon_trail_begin(evr_photon_trail *t, const evr_skip_plan *pl)
{
    t->cell = EVR_TRAIL_NONE;
    t->n = 0;
    t->clean = (uint8_t)(pl != NULL && pl->cache);
    t->started = 0;
}

/* Records a ray of the path (len: the trail's capacity; a ray beyond it leaves the trail unclean). */
EVR_HD static inline void evr_photon_trail_ray(evr_photon_trail *t, evr_trail_ray *rays, int len,
                                               const evr_skip_plan *pl, evr_ray r, float tmax)
{
    if (!t->clean) return; /* never reused: nothing more to keep */
    if (t->n >= len || evr_skip_ray_meets_any(pl, r.org, r.dir, tmax)) {
        t->clean = 0;
        return;
    }
    evr_trail_ray *k = &rays[t->n++];
    k->org[0] = r.org.x;
    k->org[1] = r.org.y;
    k->org[2] = r.org.z;
    k->dir[0] = r.dir.x;
    k->dir[1] = r.dir.y;
    k->dir[2] = r.dir.z;
    k->tmax = tmax;
}

/* Whether a pass of plan pl may take the trail's outcome: clean, and none of its rays meets
 * what moves in the segment. The caller checks that the camera, lights and emitters are those
 * of the pass that recorded it. */
EVR_HD static inline int evr_photon_trail_reusable(const evr_photon_trail *t,
                                                   const evr_trail_ray *rays,
                                                   const evr_skip_plan *pl)
{
    int k;
    if (!t->clean || !pl->reuse) return 0;
    for (k = 0; k < (int)t->n; k++) {
        const evr_trail_ray *r = &rays[k];
        if (evr_skip_ray_meets_any(pl, evr_v3_make(r->org[0], r->org[1], r->org[2]),
                                   evr_v3_make(r->dir[0], r->dir[1], r->dir[2]), r->tmax))
            return 0;
    }
    return 1;
}

#endif
