/* The CPU photon pass: buffer, the camera's view of its cells, and the tracing loop over all cores. */
#include "cpu/photon_pass.h"
#include "host_clock.h"
#include "cpu/workers.h"

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

evr_status evr_photon_buffer_alloc(evr_photon_buffer *b, int width, int height, int layers,
                                   int margin, evr_error *err)
{
    size_t npix;
    memset(b, 0, sizeof *b);
    if (width <= 0 || height <= 0 || layers <= 0 || margin < 0 || margin > 4096) {
        snprintf(err->msg, sizeof err->msg, "photon buffer: bad size %dx%d x %d layers, margin %d",
                 width, height, layers, margin);
        return EVR_ERR_ARG;
    }
    b->width = width + 2 * margin;
    b->height = height + 2 * margin;
    b->layers = layers;
    b->margin = margin;
    npix = (size_t)b->width * (size_t)b->height;
    b->slots = malloc(npix * (size_t)layers * sizeof *b->slots);
    b->count = calloc(npix, sizeof *b->count);
    b->collisions = calloc(1, sizeof *b->collisions);
    if (!b->slots || !b->count || !b->collisions) {
        evr_photon_buffer_free(b);
        snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d photon buffer of %d layers",
                 width, height, layers);
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

void evr_photon_buffer_clear(evr_photon_buffer *b)
{
    memset(b->count, 0, (size_t)b->width * (size_t)b->height * sizeof *b->count);
    *b->collisions = 0;
}

evr_changed_cells evr_changed_cells_from_sat(const uint32_t *sat, int w, int h, uint32_t *before,
                                             uint32_t *base, uint32_t *x)
{
    evr_changed_cells ch;
    int cx, cy;
    base[0] = 0;
    for (cy = 0; cy < h; cy++) {
        uint32_t *row = before + (size_t)cy * ((size_t)w + 1), n = 0;
        for (cx = 0; cx < w; cx++) {
            row[cx] = n;
            if (evr_sat_count(sat, w, cx, cy, cx + 1, cy + 1)) x[base[cy] + n++] = (uint32_t)cx;
        }
        row[w] = n;
        base[cy + 1] = base[cy] + n;
    }
    ch.before = before;
    ch.base = base;
    ch.x = x;
    return ch;
}

void evr_photon_buffer_free(evr_photon_buffer *b)
{
    free(b->gbuf);
    free(b->view_inst);
    free(b->blur);
    free(b->slots);
    free(b->count);
    free(b->collisions);
    memset(b, 0, sizeof *b);
}

/* ---- the camera's view of the cells ---- */

typedef struct {
    const evr_render_scene *rs;
    const evr_tracer *tr;
    evr_photon_buffer *buf;
    evr_m34 pose;
    evr_v3 fwd;
    float f;
    atomic_int next;
} gbuf_ctx;

static void *gbuf_worker(void *arg)
{
    gbuf_ctx *c = (gbuf_ctx *)arg;
    const evr_render_scene *rs = c->rs;
    int y, x;
#if defined(__SSE__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    while ((y = atomic_fetch_add(&c->next, 1)) < c->buf->height) {
        for (x = 0; x < c->buf->width; x++) {
            float *g = c->buf->gbuf + 8 * ((size_t)y * (size_t)c->buf->width + (size_t)x);
            evr_ray ray = evr_photon_cell_ray(rs, &c->pose, c->buf, x, y);
            evr_trace_hit h;
            evr_surface s;
            const size_t i = (size_t)y * (size_t)c->buf->width + (size_t)x;
            memset(g, 0, 8 * sizeof *g);
            if (c->buf->view_inst) c->buf->view_inst[i] = -1;
            if (!c->tr->closest(c->tr->user, ray, 0.0f, INFINITY, c->f, &h)) continue;
            if (c->buf->view_inst) c->buf->view_inst[i] = h.inst;
            evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), c->f);
            evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, c->f, ray, h.t,
                           evr_camera_cone(&rs->camera, h.t), &s);
            evr_photon_cell_view(rs, c->fwd, &s, ray, h.t, g);
        }
    }
    return NULL;
}

evr_status evr_photon_gbuffer(const evr_render_scene *rs, const evr_tracer *tr, float f,
                              evr_photon_buffer *buf, int threads, evr_error *err)
{
    gbuf_ctx c;
    if (!buf->gbuf) {
        buf->gbuf = malloc((size_t)buf->width * (size_t)buf->height * 8 * sizeof(float));
        if (!buf->gbuf) {
            snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer's view");
            return EVR_ERR_NOMEM;
        }
    }
    memset(&c, 0, sizeof c);
    c.rs = rs;
    c.tr = tr;
    c.buf = buf;
    c.f = f;
    c.pose = evr_rs_camera_pose(rs, f);
    c.fwd = evr_v3_norm(evr_m34_vector(&c.pose, evr_v3_make(0.0f, 0.0f, -1.0f)));
    atomic_store(&c.next, 0);
    if (!evr_run_workers(gbuf_worker, &c, evr_cpu_threads(threads))) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

/* ---- the pass ---- */

#define CHUNK 1024

typedef struct {
    evr_photon ph;
    int x, y;
} pending;

typedef struct {
    pending *v;
    size_t n, cap;
    double emitted[3], stored[3], absorbed[3], escaped[3], capped[3];
    uint64_t paths, stored_photons, reused;
    int failed;
} chunk_out;

typedef struct {
    const evr_render_scene *rs;
    const evr_tracer *tr;
    const evr_photon_params *pp;
    const evr_photon_emitters *em;
    int margin, cells_w;
    evr_photon_trails *trails; /* NULL: none */
    int reuse;                 /* the trails are the previous pass's, with the same emitters */
    chunk_out *chunks;
    int nchunks;
    atomic_int next;
} pass_ctx;

static void add3(double a[3], const float b[3], float k)
{
    a[0] += (double)(b[0] * k);
    a[1] += (double)(b[1] * k);
    a[2] += (double)(b[2] * k);
}

/* Appends a visible photon of image pixel (x, y) to the chunk's list. */
static void push(chunk_out *co, const evr_photon *ph, int x, int y)
{
    if (co->n == co->cap) {
        size_t nc = co->cap ? 2 * co->cap : 256;
        pending *p = realloc(co->v, nc * sizeof *p);
        if (!p) {
            co->failed = 1;
            return;
        }
        co->v = p;
        co->cap = nc;
    }
    pending *p = &co->v[co->n++];
    p->ph = *ph;
    p->x = x;
    p->y = y;
}

/* Keeps a photon that stays where the camera sees it (its view ray goes to the trail t). */
static void keep(pass_ctx *c, chunk_out *co, const evr_surface *s, const float flux[3],
                 uint32_t key, float f, evr_photon_trail *t, evr_trail_ray *rays)
{
    evr_ray r;
    float tnear, tfar;
    int x, y;
    if (!evr_photon_view_ray(c->rs, s, f, c->margin, c->pp->ray_eps, &x, &y, &r, &tnear, &tfar))
        return;
    const int occluded = c->tr->occluded(c->tr->user, r, tnear, tfar, f);
    if (t) evr_photon_trail_ray(t, rays, c->trails->len, c->trails->plan, r, tfar);
    if (occluded) return;
    evr_photon ph = evr_photon_make(s, flux, key);
    if (t) {
        t->ph = ph;
        t->cell = (uint32_t)(y + c->margin) * (uint32_t)c->cells_w + (uint32_t)(x + c->margin);
    }
    push(co, &ph, x, y);
}

static void trace_path(pass_ctx *c, chunk_out *co, uint32_t i, evr_photon_trail *t,
                       evr_trail_ray *rays);

/* Photon i: its trail's outcome where the pass may reuse it, else its path (recorded). */
static void trace_photon(pass_ctx *c, chunk_out *co, uint32_t i)
{
    evr_photon_trails *tt = c->trails;
    if (!tt) {
        trace_path(c, co, i, NULL, NULL);
        return;
    }
    evr_photon_trail *t = &tt->t[i];
    evr_trail_ray *rays = tt->rays + (size_t)i * (size_t)tt->len;
    if (c->reuse && evr_photon_trail_reusable(t, rays, tt->plan)) {
        co->reused++;
        if (t->cell != EVR_TRAIL_NONE)
            push(co, &t->ph, (int)(t->cell % (uint32_t)c->cells_w) - c->margin,
                 (int)(t->cell / (uint32_t)c->cells_w) - c->margin);
        return;
    }
    evr_photon_trail_begin(t, tt->plan);
    trace_path(c, co, i, t, rays);
}

static void trace_path(pass_ctx *c, chunk_out *co, uint32_t i, evr_photon_trail *t,
                       evr_trail_ray *rays)
{
    const evr_render_scene *rs = c->rs;
    evr_photon_path path;
    if (!evr_photon_path_start(rs, c->em->e, c->em->n, c->em->cdf, c->pp, i, &path)) return;
    if (t) t->started = 1;
    co->paths++;
    add3(co->emitted, path.pr.flux, 1.0f);
    while (path.bounce < path.max_hits) {
        evr_trace_hit h;
        evr_surface s;
        float stored[3], absorbed[3];
        uint32_t key = 0;
        const int hit = c->tr->closest(c->tr->user, path.pr.ray, path.tnear, INFINITY, path.f, &h);
        if (t)
            evr_photon_trail_ray(t, rays, c->trails->len, c->trails->plan, path.pr.ray,
                                 hit ? h.t : 1e30f);
        if (!hit) {
            add3(co->escaped, path.pr.flux, 1.0f);
            return;
        }
        const evr_material_params *mat =
            &rs->materials[rs->meshes[rs->instances[h.inst].mesh].material];
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), path.f);
        evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, path.f, path.pr.ray, h.t, 0.0f, &s);
        int ev = evr_photon_path_hit(&path, c->pp, &s, mat, stored, absorbed, &key);
        add3(co->absorbed, absorbed, 1.0f);
        if (ev == EVR_PHOTON_STAY) {
            add3(co->stored, stored, 1.0f);
            co->stored_photons++;
            keep(c, co, &s, stored, key, path.f, t, rays);
            return;
        }
        if (ev == EVR_PHOTON_ABSORB) return;
    }
    add3(co->capped, path.pr.flux, 1.0f);
}

static void *pass_worker(void *arg)
{
    pass_ctx *c = (pass_ctx *)arg;
    int k;
#if defined(__SSE__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    while ((k = atomic_fetch_add(&c->next, 1)) < c->nchunks) {
        uint32_t i0 = (uint32_t)k * CHUNK, i1 = i0 + CHUNK, i;
        if (i1 > c->em->photons) i1 = c->em->photons;
        for (i = i0; i < i1; i++) trace_photon(c, &c->chunks[k], i);
    }
    return NULL;
}

/* Room for the pass's trails and whether the previous pass's may be reused (see the header). */
static int trails_prepare(evr_photon_trails *tt, const evr_photon_params *pp,
                          const evr_photon_emitters *em)
{
    const int len = evr_photon_trail_len(pp);
    if (em->photons > tt->cap || len != tt->len) {
        free(tt->t);
        free(tt->rays);
        tt->t = calloc(em->photons, sizeof *tt->t);
        tt->rays = calloc((size_t)em->photons * (size_t)len, sizeof *tt->rays);
        tt->cap = tt->t && tt->rays ? em->photons : 0;
        tt->len = len;
        tt->valid = 0;
        if (!tt->cap) return -1;
    }
    return evr_photon_trails_pass(&tt->em, &tt->valid, em);
}

void evr_photon_trails_free(evr_photon_trails *tt)
{
    free(tt->t);
    free(tt->rays);
    evr_photon_emitters_free(&tt->em);
    memset(tt, 0, sizeof *tt);
}

evr_status evr_photon_pass(const evr_render_scene *rs, const evr_tracer *tr,
                           const evr_photon_params *pp, const evr_photon_emitters *em,
                           evr_photon_buffer *buf, evr_photon_stats *st, evr_photon_trails *trails,
                           evr_error *err)
{
    pass_ctx c;
    int i, k;
    evr_status rc = EVR_OK;
    const double t0 = evr_host_seconds();
    memset(st, 0, sizeof *st);
    evr_photon_buffer_clear(buf);
    if (em->n == 0 || em->photons == 0) return EVR_OK;
    if (em->photons > (1u << 28)) {
        snprintf(err->msg, sizeof err->msg, "too many photons (%u; at most 2^28)", em->photons);
        return EVR_ERR_ARG;
    }
    memset(&c, 0, sizeof c);
    c.rs = rs;
    c.tr = tr;
    c.pp = pp;
    c.em = em;
    c.margin = buf->margin;
    c.cells_w = buf->width;
    if (trails) { /* without the memory for them, every photon is traced (as without trails) */
        c.reuse = trails_prepare(trails, pp, em);
        c.trails = c.reuse < 0 ? NULL : trails;
        if (c.reuse < 0) c.reuse = 0;
    }
    c.nchunks = (int)((em->photons + CHUNK - 1) / CHUNK);
    c.chunks = calloc((size_t)c.nchunks, sizeof *c.chunks);
    atomic_store(&c.next, 0);
    if (!c.chunks || !evr_run_workers(pass_worker, &c, evr_cpu_threads(pp->threads))) {
        free(c.chunks);
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon pass");
        return EVR_ERR_NOMEM;
    }
    /* in photon order: the same buffer for any thread count */
    for (k = 0; k < c.nchunks; k++) {
        chunk_out *co = &c.chunks[k];
        size_t n;
        if (co->failed) rc = EVR_ERR_NOMEM;
        for (i = 0; i < 3; i++) {
            st->emitted[i] += co->emitted[i];
            st->stored[i] += co->stored[i];
            st->absorbed[i] += co->absorbed[i];
            st->escaped[i] += co->escaped[i];
            st->capped[i] += co->capped[i];
        }
        st->paths += co->paths;
        st->reused += co->reused;
        st->stored_photons += co->stored_photons;
        st->visible += co->n;
        for (n = 0; n < co->n; n++)
            st->inserted +=
                (uint64_t)evr_photon_buffer_insert(buf, co->v[n].x, co->v[n].y, &co->v[n].ph);
        free(co->v);
    }
    free(c.chunks);
    st->collisions = *buf->collisions;
    st->seconds = evr_host_seconds() - t0;
    if (rc != EVR_OK) snprintf(err->msg, sizeof err->msg, "out of memory for the photon pass");
    return rc;
}
