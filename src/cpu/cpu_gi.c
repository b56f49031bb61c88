/* Global illumination in the CPU event pipeline: see cpu_gi.h. */
#include "cpu/cpu_gi.h"
#include "prep/gi_params.h"
#include "host_clock.h"
#include "core/shading.h"
#include "core/photon_blur.h"
#include "cpu/workers.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int evr_embree_closest1(RTCScene sc, const int *members, const int *group_first, evr_ray ray,
                        float tnear, float tfar, float f, evr_trace_hit *hit)
{
    struct RTCIntersectContext ctx;
    struct RTCRayHit rh;
    rtcInitIntersectContext(&ctx);
    rh.ray.org_x = ray.org.x;
    rh.ray.org_y = ray.org.y;
    rh.ray.org_z = ray.org.z;
    rh.ray.dir_x = ray.dir.x;
    rh.ray.dir_y = ray.dir.y;
    rh.ray.dir_z = ray.dir.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.time = f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(sc, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    hit->inst =
        members ? members[group_first[rh.hit.instID[0]] + (int)rh.hit.geomID] : (int)rh.hit.geomID;
    hit->prim = rh.hit.primID;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->t = rh.ray.tfar;
    return 1;
}

int evr_embree_occluded1(RTCScene sc, evr_ray ray, float tnear, float tfar, float f)
{
    struct RTCIntersectContext ctx;
    struct RTCRay r;
    rtcInitIntersectContext(&ctx);
    r.org_x = ray.org.x;
    r.org_y = ray.org.y;
    r.org_z = ray.org.z;
    r.dir_x = ray.dir.x;
    r.dir_y = ray.dir.y;
    r.dir_z = ray.dir.z;
    r.tnear = tnear;
    r.tfar = tfar;
    r.time = f;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(sc, &ctx, &r);
    return r.tfar < 0.0f;
}

static int gi_closest(void *user, evr_ray ray, float tnear, float tfar, float f, evr_trace_hit *hit)
{
    const evr_cpu_trace_ctx *c = (const evr_cpu_trace_ctx *)user;
    return evr_embree_closest1(c->top, c->members, c->group_first, ray, tnear, tfar, f, hit);
}

static int gi_occluded(void *user, evr_ray ray, float tnear, float tfar, float f)
{
    return evr_embree_occluded1(((const evr_cpu_trace_ctx *)user)->top, ray, tnear, tfar, f);
}

evr_status evr_cpu_gi_init(evr_cpu_gi *g, const evr_cpu_trace_ctx *tc, const evr_run_setup *setup,
                           const evr_scene *s, evr_error *err)
{
    evr_status st;
    int margin = 0;
    memset(g, 0, sizeof *g);
    evr_gi_run_params(setup, s, &g->photons, &g->gp, &g->pp, &margin, &g->window);
    g->tc = *tc;
    g->tr.user = &g->tc;
    g->tr.closest = gi_closest;
    g->tr.occluded = gi_occluded;
    if ((st = evr_photon_buffer_alloc(&g->end, setup->width, setup->height, setup->photon_layers,
                                      margin, err)) != EVR_OK ||
        (st = evr_photon_buffer_alloc(&g->start, setup->width, setup->height, setup->photon_layers,
                                      margin, err)) != EVR_OK)
        return st;
    g->sat = calloc((size_t)(g->end.width + 1) * (size_t)(g->end.height + 1), sizeof *g->sat);
    g->ch_before =
        malloc(((size_t)g->end.width + 1) * (size_t)g->end.height * sizeof *g->ch_before);
    g->ch_base = malloc(((size_t)g->end.height + 1) * sizeof *g->ch_base);
    g->ch_x = malloc((size_t)g->end.width * (size_t)g->end.height * sizeof *g->ch_x);
    if (!g->sat || !g->ch_before || !g->ch_base || !g->ch_x) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer");
        return EVR_ERR_NOMEM;
    }
    g->image_width = setup->width;
    /* EVR_GI_NO_MEMO (hidden, for tests): gather at every sample, to show the memo changes nothing */
    g->memo_off = getenv("EVR_GI_NO_MEMO") != NULL;
    g->trails_off = getenv("EVR_NO_PHOTON_REUSE") != NULL;
    g->memo = calloc((size_t)setup->width * (size_t)setup->height, sizeof *g->memo);
    if (!g->memo) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer");
        return EVR_ERR_NOMEM;
    }
    if (setup->gi_blur > 0.0f) {
        const size_t cells = (size_t)g->end.width * (size_t)g->end.height;
        evr_photon_buffer *bufs[2] = {&g->end, &g->start};
        g->blur_sigma = setup->gi_blur * g->gp.radius;
        g->blur_tmp = malloc(2 * EVR_BLUR_CH * cells * sizeof(float));
        for (int k = 0; k < 2; k++) {
            bufs[k]->view_inst = malloc(cells * sizeof(int));
            bufs[k]->blur = calloc(3 * cells, sizeof(float));
        }
        if (!g->blur_tmp || !g->end.view_inst || !g->end.blur || !g->start.view_inst ||
            !g->start.blur) {
            snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer");
            return EVR_ERR_NOMEM;
        }
    }
    return EVR_OK;
}

/* ---- the blurred estimate (core/photon_blur.h) ---- */

typedef struct {
    const evr_cpu_gi *g;
    const evr_render_scene *rs;
    const evr_photon_buffer *b;
    evr_v3 cam_org;
    const float *src; /* a step of the blur, or the finish: from */
    float *dst;       /* a step of the blur: to; NULL: the finish, into b->blur */
    int k;            /* the step; -1: the cells' flux and area into dst */
    atomic_int next;
} blur_ctx;

static void *blur_worker(void *arg)
{
    blur_ctx *c = (blur_ctx *)arg;
    const evr_photon_buffer *b = c->b;
    int y;
    while ((y = atomic_fetch_add(&c->next, 1)) < b->height)
        for (int x = 0; x < b->width; x++) {
            const size_t i = (size_t)y * (size_t)b->width + (size_t)x;
            if (b->view_inst[i] < 0) continue;
            if (!c->dst) evr_blur_cell_finish(b, c->src, i);
            else if (c->k < 0) evr_blur_cell_splat(b, &c->g->gp, i, c->dst + EVR_BLUR_CH * i);
            else
                evr_blur_cell(b, &c->rs->camera, c->cam_org, c->g->blur_sigma, c->src, c->dst, x, y,
                              c->k);
        }
    return NULL;
}

static evr_status blur_run(blur_ctx *c, int threads, evr_error *err)
{
    atomic_store(&c->next, 0);
    if (evr_run_workers(blur_worker, c, evr_cpu_threads(threads))) return EVR_OK;
    snprintf(err->msg, sizeof err->msg, "out of memory");
    return EVR_ERR_NOMEM;
}

/* After a pass at time f into b: the cells' flux and area, the blur's steps (as many as the
 * nearest cell asks for: a cell past its own keeps its values), their ratio into b->blur. */
static evr_status blur_build(evr_cpu_gi *g, const evr_render_scene *rs, float f,
                             evr_photon_buffer *b, int threads, evr_error *err)
{
    const size_t cells = (size_t)b->width * (size_t)b->height;
    const evr_m34 pose = evr_rs_camera_pose(rs, f);
    float *work[2] = {g->blur_tmp, g->blur_tmp + EVR_BLUR_CH * cells};
    evr_status st;
    blur_ctx c;
    int steps = 0;
    memset(&c, 0, sizeof c);
    c.g = g;
    c.rs = rs;
    c.b = b;
    c.cam_org = evr_m34_point(&pose, evr_v3_make(0.0f, 0.0f, 0.0f));
    for (size_t i = 0; i < cells && steps < EVR_BLUR_MAX_STEPS; i++) {
        const float *v = b->gbuf + 8 * i;
        if (b->view_inst[i] < 0) continue;
        const float d = evr_v3_len(evr_v3_sub(evr_v3_make(v[0], v[1], v[2]), c.cam_org));
        const int n = evr_blur_steps(g->blur_sigma, evr_camera_pixel_size(&rs->camera, d));
        if (n > steps) steps = n;
    }
    for (int k = -1; k < steps; k++) {
        c.k = k;
        c.src = work[(k + 2) % 2];
        c.dst = work[(k + 1) % 2];
        if ((st = blur_run(&c, threads, err)) != EVR_OK) return st;
    }
    c.src = work[steps % 2];
    c.dst = NULL;
    return blur_run(&c, threads, err);
}

/* One photon pass at normalized segment time f into buffer out: the photons are a sample in time
 * (every one traced at f), the view of the cells too. */
static evr_status gi_pass(evr_cpu_gi *g, const evr_render_scene *rs, const evr_skip_plan *plan,
                          float f, int threads, evr_photon_buffer *out, evr_backend *stats,
                          evr_error *err)
{
    evr_status st;
    evr_photon_stats ps;
    g->pp.threads = threads;
    g->pp.ray_eps = rs->ray_eps;
    g->pp.f0 = g->pp.f1 = f;
    if ((st = evr_photon_emitters_build(rs, f, g->pp.bounds, g->photons, &g->em, err)) != EVR_OK)
        return st;
    if (g->gp.flux_scale == 0.0f)
        g->gp.flux_scale = evr_gather_flux_scale(g->em.total_power, g->photons); /* the run's */
    memset(&ps, 0, sizeof ps);
    g->trails.plan = plan;
    if ((st = evr_photon_pass(rs, &g->tr, &g->pp, &g->em, out, &ps,
                              g->trails_off ? NULL : &g->trails, err)) != EVR_OK)
        return st;
    if ((st = evr_photon_gbuffer(rs, &g->tr, f, out, threads, err)) != EVR_OK) return st;
    if (g->blur_sigma > 0.0f && (st = blur_build(g, rs, f, out, threads, err)) != EVR_OK) return st;
    stats->photons_traced += ps.paths;
    stats->photons_reused += ps.reused;
    stats->photons_stored += ps.inserted;
    stats->photon_collisions += ps.collisions;
    stats->photon_passes++;
    return EVR_OK;
}

evr_status evr_cpu_gi_segment(evr_cpu_gi *g, const evr_render_scene *rs, const evr_skip_plan *plan,
                              int threads, evr_backend *stats, evr_error *err)
{
    const int still = evr_skip_plan_still(plan);
    const int w = g->end.width, h = g->end.height;
    evr_status st;
    int x, y;
    if (still && g->have_prev) { /* the photons of the last segment's end, here at both ends */
        g->start_same = 1;
        memset(g->sat, 0, (size_t)(w + 1) * (size_t)(h + 1) * sizeof *g->sat);
        return EVR_OK;
    }
    const double t0 = evr_host_seconds();
    if (g->have_prev) { /* the previous segment's end (the last pass's) is this one's start */
        evr_photon_buffer tmp = g->start;
        g->start = g->end;
        g->end = tmp;
    } else if ((st = gi_pass(g, rs, plan, 0.0f, threads, &g->start, stats, err)) != EVR_OK) {
        return st;
    }
    g->start_same = 0;
    if ((st = gi_pass(g, rs, plan, 1.0f, threads, &g->end, stats, err)) != EVR_OK) return st;
    uint64_t photon_cells = 0;
    for (y = 0; y < h; y++) {
        uint32_t row = 0;
        for (x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            const int same = evr_photon_cell_same(&g->end, &g->start, i);
            photon_cells += !same;
            /* --gi-blur: what changes a pixel's light is its cells' lookups */
            row += g->blur_sigma > 0.0f ? !evr_blur_cell_same(&g->end, &g->start, i) : !same;
            g->sat[(size_t)(y + 1) * (size_t)(w + 1) + (size_t)(x + 1)] =
                g->sat[(size_t)y * (size_t)(w + 1) + (size_t)(x + 1)] + row;
        }
    }
    if (g->gp.max_photons <= 0 && g->blur_sigma <= 0.0f)
        g->ch = evr_changed_cells_from_sat(g->sat, w, h, g->ch_before, g->ch_base, g->ch_x);
    g->have_prev = 1;
    stats->photon_cells_changed += photon_cells;
    stats->photon_seconds += evr_host_seconds() - t0;
    return EVR_OK;
}

static const evr_photon_buffer *start_of(const evr_cpu_gi *g)
{
    return g->start_same ? &g->end : &g->start;
}

int evr_cpu_gi_pixel_begin(evr_cpu_gi *g, const evr_camera_intr *cam, int x, int y)
{
    struct evr_gi_memo *m = &g->memo[(size_t)y * (size_t)g->image_width + (size_t)x];
    if (m->valid && !m->end_valid) m->valid = 0; /* its end was never gathered: forgotten */
    if (m->valid) m->ls = m->le;                 /* the last segment's end is this one's start */
    if (!m->valid && !m->missed) return 1;       /* nothing known of the last sample */
    const int was_flat = m->missed || m->flat;
    int changed = evr_photon_window_changed(g->sat, g->end.width, g->end.height, g->end.margin,
                                            g->window, x, y);
    /* the window changed: the pixel's last gather still holds if nothing that changed reaches it */
    if (changed && m->valid && !g->memo_off && g->blur_sigma <= 0.0f)
        changed = evr_photon_gather_moved(&g->end, &g->start, g->sat, cam, &g->gp, x, y,
                                          evr_v3_make(m->key[0], m->key[1], m->key[2]),
                                          evr_v3_make(m->key[3], m->key[4], m->key[5]), m->key[6]);
    if (changed) {
        m->end_valid = 0;
        return !m->missed;
    }
    m->flat = 1; /* its end is its start */
    return !was_flat;
}

/* The luminance of the indirect light leaving surface s seen through pixel (x, y), from the
 * photons at the segment's start (ls) and end (le); one gather where the window saw no change
 * over the segment (the same cells, the same estimate); end_only: le alone. (Walking the two
 * buffers together, cell by cell, was 4-6% faster here and 4% slower on the GPU: one walk kept.) */
static void gather_ends(const evr_cpu_gi *g, const evr_render_scene *rs, int inst,
                        const evr_surface *s, evr_v3 cam_org, int x, int y, int end_only, float *ls,
                        float *le, evr_gather_sum *se)
{
    const int changed = evr_photon_window_changed(g->sat, g->end.width, g->end.height,
                                                  g->end.margin, g->window, x, y);
    evr_gather_point gp;
    evr_gather_point_at(s, inst, cam_org, &gp);
    if (g->gp.max_photons <=
        0) { /* fixed-point sums: the end's from the start's (se) and the cells that changed */
        if (!end_only) {
            evr_gather_point_sum(start_of(g), &rs->camera, &g->gp, &gp, x, y, se);
            *ls = evr_gather_sum_lum(&g->end, &rs->camera, &g->gp, &gp, x, y, se);
        }
        if (changed)
            evr_gather_point_delta(&g->end, start_of(g), &g->ch, &rs->camera, &g->gp, &gp, x, y,
                                   se);
        *le = changed ? evr_gather_sum_lum(&g->end, &rs->camera, &g->gp, &gp, x, y, se) : *ls;
        return;
    }
    if (!end_only) *ls = evr_gather_point_lum(start_of(g), &rs->camera, &g->gp, &gp, x, y);
    *le = changed ? evr_gather_point_lum(&g->end, &rs->camera, &g->gp, &gp, x, y) : *ls;
}

/* --gi-blur: the luminance of a sample's irradiance at its segment's ends (evr_blur_ends). */
static void blur_ends(const evr_cpu_gi *g, int inst, const evr_surface *s, evr_v3 cam_org, int x,
                      int y, float *ls, float *le)
{
    evr_gather_point gp;
    evr_gather_point_at(s, inst, cam_org, &gp);
    evr_blur_point_lum(start_of(g), &g->end, &gp, x, y, ls, le);
}

float evr_cpu_gi_indirect(const evr_cpu_gi *g, const evr_render_scene *rs, int inst,
                          const evr_surface *s, evr_v3 cam_org, int x, int y, float f, int memo)
{
    struct evr_gi_memo *m = &g->memo[(size_t)y * (size_t)g->image_width + (size_t)x];
    if (g->blur_sigma > 0.0f) {
        float ls, le;
        blur_ends(g, inst, s, cam_org, x, y, &ls, &le);
        if (memo) {
            /* what a kept sample takes (evr_cpu_gi_last); it holds while the pixel's nine cells
             * do not change (evr_cpu_gi_pixel_begin) */
            m->missed = 0;
            m->ls = ls;
            m->le = le;
            m->flat = ls == le;
            m->valid = m->end_valid = !g->memo_off;
        }
        return evr_gi_lerp(ls, le, f);
    }
    if (!memo) {
        float ls, le;
        evr_gather_sum se;
        gather_ends(g, rs, inst, s, cam_org, x, y, 0, &ls, &le, &se);
        return evr_gi_lerp(ls, le, f);
    }
    float dist = evr_v3_len(evr_v3_sub(s->p, cam_org));
    const float key[7] = {s->p.x, s->p.y, s->p.z, s->n.x, s->n.y, s->n.z, dist};
    m->missed = 0;
    /* the gather depends on the surface's diffuse weight as the camera sees it: the same
     * instance, point, normal and distance bit for bit are the same view (a camera that moves
     * moves every point it sees) */
    if (!g->memo_off && m->valid && m->inst == inst && !memcmp(m->key, key, sizeof key)) {
        if (!m->end_valid) {
            gather_ends(g, rs, inst, s, cam_org, x, y, 1, &m->ls, &m->le, &m->se);
            m->end_valid = 1;
            m->flat = m->le == m->ls;
        }
        return evr_gi_lerp(m->ls, m->le, f);
    }
    memcpy(m->key, key, sizeof key);
    m->inst = inst;
    gather_ends(g, rs, inst, s, cam_org, x, y, 0, &m->ls, &m->le, &m->se);
    m->valid = m->end_valid = 1;
    m->flat = m->le == m->ls;
    return evr_gi_lerp(m->ls, m->le, f);
}

int evr_cpu_gi_flat(const evr_cpu_gi *g, int x, int y)
{
    return g->memo[(size_t)y * (size_t)g->image_width + (size_t)x].flat;
}

float evr_cpu_gi_last(const evr_cpu_gi *g, int x, int y, float f)
{
    const struct evr_gi_memo *m = &g->memo[(size_t)y * (size_t)g->image_width + (size_t)x];
    return evr_gi_lerp(m->ls, m->le, f);
}

void evr_cpu_gi_missed(const evr_cpu_gi *g, int x, int y)
{
    g->memo[(size_t)y * (size_t)g->image_width + (size_t)x].missed = 1;
}

void evr_cpu_gi_free(evr_cpu_gi *g)
{
    evr_photon_buffer_free(&g->end);
    evr_photon_buffer_free(&g->start);
    evr_photon_emitters_free(&g->em);
    evr_photon_trails_free(&g->trails);
    free(g->sat);
    free(g->ch_before);
    free(g->ch_base);
    free(g->ch_x);
    free(g->memo);
    free(g->blur_tmp);
    memset(g, 0, sizeof *g);
}
