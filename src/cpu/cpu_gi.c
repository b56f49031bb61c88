/* Global illumination in the CPU event pipeline: see cpu_gi.h. */
#include "cpu/cpu_gi.h"
#include "core/shading.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int evr_embree_closest1(RTCScene sc, const int *members, const int *group_first, evr_ray ray, float tnear, float tfar,
                        float f, evr_trace_hit *hit)
{
    struct RTCIntersectContext ctx;
    struct RTCRayHit rh;
    rtcInitIntersectContext(&ctx);
    rh.ray.org_x = ray.org.x; rh.ray.org_y = ray.org.y; rh.ray.org_z = ray.org.z;
    rh.ray.dir_x = ray.dir.x; rh.ray.dir_y = ray.dir.y; rh.ray.dir_z = ray.dir.z;
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
    hit->inst = members ? members[group_first[rh.hit.instID[0]] + (int)rh.hit.geomID] : (int)rh.hit.geomID;
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
    r.org_x = ray.org.x; r.org_y = ray.org.y; r.org_z = ray.org.z;
    r.dir_x = ray.dir.x; r.dir_y = ray.dir.y; r.dir_z = ray.dir.z;
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

evr_status evr_cpu_gi_init(evr_cpu_gi *g, const evr_cpu_trace_ctx *tc, const evr_run_setup *setup, const evr_scene *s,
                           evr_error *err)
{
    evr_status st;
    int margin = setup->gather_window < 16 ? setup->gather_window : 16;
    memset(g, 0, sizeof *g);
    g->tc = *tc;
    g->tr.user = &g->tc;
    g->tr.closest = gi_closest;
    g->tr.occluded = gi_occluded;
    if ((st = evr_photon_buffer_alloc(&g->buf, setup->width, setup->height, setup->photon_layers, margin, err)) != EVR_OK ||
        (st = evr_photon_buffer_alloc(&g->prev, setup->width, setup->height, setup->photon_layers, margin, err)) != EVR_OK)
        return st;
    g->sat = calloc((size_t)(g->buf.width + 1) * (size_t)(g->buf.height + 1), sizeof *g->sat);
    if (!g->sat) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer");
        return EVR_ERR_NOMEM;
    }
    g->image_width = setup->width;
    /* EVR_GI_NO_MEMO (hidden, for tests): gather at every sample, to show the memo changes nothing */
    g->memo_off = getenv("EVR_GI_NO_MEMO") != NULL;
    g->memo = calloc((size_t)setup->width * (size_t)setup->height, sizeof *g->memo);
    if (!g->memo) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer");
        return EVR_ERR_NOMEM;
    }
    g->photons = setup->photons ? setup->photons : (uint32_t)((size_t)setup->width * (size_t)setup->height);
    g->gp.radius = setup->gather_radius;
    g->gp.max_photons = setup->gather_max;
    g->gp.max_window = setup->gather_window;
    g->gp.normal_cos = 0.7f;
    g->window = setup->gather_window + 1;
    g->pp.max_bounces = setup->gi_bounces;
    g->pp.f0 = 0.0f;   /* photons spread over the segment (motion blur), the same times every segment */
    g->pp.f1 = 1.0f;
    g->pp.seed = setup->seed;
    {   /* directional lights emit over a disk round the scene (its rest bounds, a little larger) */
        evr_v3 lo = s->bounds_min, hi = s->bounds_max;
        if (!(lo.x <= hi.x)) lo = hi = evr_v3_make(0.0f, 0.0f, 0.0f);
        g->pp.bounds.center = evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
        g->pp.bounds.radius = 0.55f * evr_v3_len(evr_v3_sub(hi, lo)) + 1e-6f;
    }
    return EVR_OK;
}

/* Whether cell i holds the same photons and the same surface in both buffers. */
static int cell_same(const evr_photon_buffer *a, const evr_photon_buffer *b, size_t i)
{
    size_t npix = (size_t)a->width * (size_t)a->height;
    uint32_t n = a->count[i] < (uint32_t)a->layers ? a->count[i] : (uint32_t)a->layers, l;
    if (a->count[i] != b->count[i]) return 0;
    for (l = 0; l < n; l++)
        if (memcmp(&a->slots[(size_t)l * npix + i], &b->slots[(size_t)l * npix + i], sizeof(evr_photon))) return 0;
    if (a->gbuf && b->gbuf && memcmp(a->gbuf + 8 * i, b->gbuf + 8 * i, 8 * sizeof(float))) return 0;
    return 1;
}

evr_status evr_cpu_gi_segment(evr_cpu_gi *g, const evr_render_scene *rs, int still, int threads, evr_backend *stats,
                              evr_error *err)
{
    const int w = g->buf.width, h = g->buf.height;
    evr_status st;
    evr_photon_stats ps;
    struct timespec t0, t1;
    int x, y;
    if (still && g->have_prev) {   /* the same photons as last time: nothing changed */
        memset(g->sat, 0, (size_t)(w + 1) * (size_t)(h + 1) * sizeof *g->sat);
        return EVR_OK;
    }
    clock_gettime(CLOCK_MONOTONIC, &t0);
    {   /* the previous segment's buffer becomes prev */
        evr_photon_buffer tmp = g->prev;
        g->prev = g->buf;
        g->buf = tmp;
    }
    g->pp.threads = threads;
    g->pp.ray_eps = rs->ray_eps;
    if ((st = evr_photon_emitters_build(rs, 0.0f, g->pp.bounds, g->photons, &g->em, err)) != EVR_OK) return st;
    memset(&ps, 0, sizeof ps);
    if ((st = evr_photon_pass(rs, &g->tr, &g->pp, &g->em, &g->buf, &ps, err)) != EVR_OK) return st;
    if ((st = evr_photon_gbuffer(rs, &g->tr, 0.0f, &g->buf, threads, err)) != EVR_OK) return st;
    for (y = 0; y < h; y++) {
        uint32_t row = 0;
        for (x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            row += !g->have_prev || !cell_same(&g->buf, &g->prev, i);
            g->sat[(size_t)(y + 1) * (size_t)(w + 1) + (size_t)(x + 1)] = g->sat[(size_t)y * (size_t)(w + 1) + (size_t)(x + 1)] + row;
        }
    }
    g->have_prev = 1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    stats->photons_traced += ps.paths;
    stats->photons_stored += ps.inserted;
    stats->photon_collisions += ps.collisions;
    stats->photon_passes++;
    stats->photon_seconds += (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    return EVR_OK;
}

/* 1 when a cell the gather of pixel (x, y) may read changed in this segment. */
static int window_changed(const evr_cpu_gi *g, int x, int y)
{
    const int w = g->buf.width, h = g->buf.height, m = g->buf.margin;
    int x0 = x + m - g->window, x1 = x + m + g->window + 1, y0 = y + m - g->window, y1 = y + m + g->window + 1;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > w) x1 = w;
    if (y1 > h) y1 = h;
    if (x0 >= x1 || y0 >= y1) return 0;
    const size_t W = (size_t)w + 1;
    uint32_t n = g->sat[(size_t)y1 * W + (size_t)x1] - g->sat[(size_t)y0 * W + (size_t)x1] - g->sat[(size_t)y1 * W + (size_t)x0] +
                 g->sat[(size_t)y0 * W + (size_t)x0];
    return n != 0;
}

int evr_cpu_gi_pixel_begin(evr_cpu_gi *g, int x, int y)
{
    if (!window_changed(g, x, y)) return 0;
    g->memo[(size_t)y * (size_t)g->image_width + (size_t)x].valid = 0;
    return 1;
}

float evr_cpu_gi_indirect(const evr_cpu_gi *g, const evr_render_scene *rs, int inst, const evr_surface *s, evr_v3 cam_org, int x,
                          int y)
{
    const evr_material_view *mat = &rs->materials[rs->meshes[rs->instances[inst].mesh].material];
    struct evr_gi_memo *m = &g->memo[(size_t)y * (size_t)g->image_width + (size_t)x];
    float e[3], ind[3];
    float dist = evr_v3_len(evr_v3_sub(s->p, cam_org));
    const float key[7] = {s->p.x, s->p.y, s->p.z, s->n.x, s->n.y, s->n.z, dist};
    /* the albedo is the surface's at p (same point, same triangle side: same albedo) */
    if (!g->memo_off && m->valid && m->inst == inst && !memcmp(m->key, key, sizeof key)) return m->lum;
    evr_photon_gather(&g->buf, &rs->camera, x, y, s->p, s->n, dist, &g->gp, e);
    evr_photon_indirect(s, mat, e, ind);
    memcpy(m->key, key, sizeof key);
    m->inst = inst;
    m->lum = evr_luminance(ind[0], ind[1], ind[2]);
    m->valid = 1;
    return m->lum;
}

void evr_cpu_gi_free(evr_cpu_gi *g)
{
    evr_photon_buffer_free(&g->buf);
    evr_photon_buffer_free(&g->prev);
    evr_photon_emitters_free(&g->em);
    free(g->sat);
    free(g->memo);
    memset(g, 0, sizeof *g);
}
