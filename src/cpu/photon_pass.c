/* The CPU photon pass: emitters, buffer, and the tracing loop over all cores. */
#include "cpu/photon_pass.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#if defined(__SSE__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

static int emitter_push(evr_photon_emitters *em, const evr_photon_emitter *e)
{
    if (em->n == em->cap) {
        int nc = em->cap ? 2 * em->cap : 16;
        evr_photon_emitter *p = realloc(em->e, (size_t)nc * sizeof *p);
        if (!p) return 0;
        em->e = p;
        em->cap = nc;
    }
    em->e[em->n++] = *e;
    return 1;
}

evr_status evr_photon_emitters_build(const evr_render_scene *rs, float f, evr_photon_bounds bb, uint32_t photons,
                                     evr_photon_emitters *em, evr_error *err)
{
    int i;
    uint32_t next = 0;
    em->n = 0;
    em->cdf_n = 0;
    em->total_power = 0.0f;
    for (i = 0; i < rs->num_lights; i++) {
        evr_photon_emitter e;
        float flux[3];
        memset(&e, 0, sizeof e);
        evr_photon_light_flux(rs, &rs->lights[i], f, bb, flux);
        e.kind = 0;
        e.index = i;
        e.power = evr_luminance(flux[0], flux[1], flux[2]);
        if (!(e.power > 0.0f)) continue;
        if (!emitter_push(em, &e)) goto nomem;
    }
    for (i = 0; i < rs->num_instances; i++) {
        const evr_mesh_view *m = &rs->meshes[rs->instances[i].mesh];
        const evr_material_view *mat = &rs->materials[m->material];
        float le = evr_luminance(mat->emissive[0], mat->emissive[1], mat->emissive[2]);
        evr_photon_emitter e;
        uint32_t t;
        double area = 0.0;
        if (!(le > 0.0f) || m->num_triangles == 0) continue;
        if (em->cdf_n + (int)m->num_triangles > em->cdf_cap) {
            int nc = em->cdf_cap ? em->cdf_cap : 64;
            while (nc < em->cdf_n + (int)m->num_triangles) nc *= 2;
            float *p = realloc(em->cdf, (size_t)nc * sizeof *p);
            if (!p) goto nomem;
            em->cdf = p;
            em->cdf_cap = nc;
        }
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[i].track), f);
        for (t = 0; t < m->num_triangles; t++) {
            uint32_t i0 = m->indices[3 * t], i1 = m->indices[3 * t + 1], i2 = m->indices[3 * t + 2];
            evr_v3 p0 = evr_m34_point(&xf, evr_v3_make(m->positions[3 * i0], m->positions[3 * i0 + 1], m->positions[3 * i0 + 2]));
            evr_v3 p1 = evr_m34_point(&xf, evr_v3_make(m->positions[3 * i1], m->positions[3 * i1 + 1], m->positions[3 * i1 + 2]));
            evr_v3 p2 = evr_m34_point(&xf, evr_v3_make(m->positions[3 * i2], m->positions[3 * i2 + 1], m->positions[3 * i2 + 2]));
            area += 0.5 * (double)evr_v3_len(evr_v3_cross(evr_v3_sub(p1, p0), evr_v3_sub(p2, p0)));
            em->cdf[em->cdf_n + (int)t] = (float)area;
        }
        if (!(area > 0.0)) continue;
        memset(&e, 0, sizeof e);
        e.kind = 1;
        e.index = i;
        e.tri_first = em->cdf_n;
        e.ntri = (int)m->num_triangles;
        e.area = (float)area;
        e.power = (float)(2.0 * EVR_PI * area) * le;   /* both sides */
        em->cdf_n += (int)m->num_triangles;
        if (!emitter_push(em, &e)) goto nomem;
    }
    for (i = 0; i < em->n; i++) em->total_power += em->e[i].power;
    for (i = 0; i < em->n; i++) {
        double share = (double)em->e[i].power / (double)em->total_power * (double)photons;
        uint32_t c = (uint32_t)floor(share + 0.5);
        if (c == 0 && photons > 0) c = 1;
        em->e[i].first = next;
        em->e[i].count = c;
        next += c;
    }
    em->photons = next;
    return EVR_OK;
nomem:
    snprintf(err->msg, sizeof err->msg, "out of memory for the photon emitters");
    return EVR_ERR_NOMEM;
}

void evr_photon_emitters_free(evr_photon_emitters *em)
{
    free(em->e);
    free(em->cdf);
    memset(em, 0, sizeof *em);
}

evr_status evr_photon_buffer_alloc(evr_photon_buffer *b, int width, int height, int layers, int margin, evr_error *err)
{
    size_t npix;
    memset(b, 0, sizeof *b);
    if (width <= 0 || height <= 0 || layers <= 0 || margin < 0 || margin > 4096) {
        snprintf(err->msg, sizeof err->msg, "photon buffer: bad size %dx%d x %d layers, margin %d", width, height, layers, margin);
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
        snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d photon buffer of %d layers", width, height, layers);
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

void evr_photon_buffer_clear(evr_photon_buffer *b)
{
    memset(b->count, 0, (size_t)b->width * (size_t)b->height * sizeof *b->count);
    *b->collisions = 0;
}

void evr_photon_buffer_free(evr_photon_buffer *b)
{
    free(b->gbuf);
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
    const float a = 4.0f * rs->camera.tan_half_y * rs->camera.tan_half_y / ((float)rs->camera.height * (float)rs->camera.height);
    int y, x;
#if defined(__SSE__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    while ((y = atomic_fetch_add(&c->next, 1)) < c->buf->height) {
        for (x = 0; x < c->buf->width; x++) {
            float *g = c->buf->gbuf + 8 * ((size_t)y * (size_t)c->buf->width + (size_t)x);
            evr_ray ray = evr_camera_ray(&rs->camera, &c->pose, (float)(x - c->buf->margin) + 0.5f, (float)(y - c->buf->margin) + 0.5f);
            evr_trace_hit h;
            evr_surface s;
            memset(g, 0, 8 * sizeof *g);
            if (!c->tr->closest(c->tr->user, ray, 0.0f, INFINITY, c->f, &h)) continue;
            evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), c->f);
            evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, ray, h.t, &s);
            float ca = evr_v3_dot(ray.dir, c->fwd), z = h.t * ca;
            float ct = fmaxf(fabsf(evr_v3_dot(s.n, ray.dir)), 0.1f);
            g[0] = s.p.x; g[1] = s.p.y; g[2] = s.p.z;
            g[3] = s.n.x; g[4] = s.n.y; g[5] = s.n.z;
            g[6] = a * z * z * ca / ct;
        }
    }
    return NULL;
}

evr_status evr_photon_gbuffer(const evr_render_scene *rs, const evr_tracer *tr, float f, evr_photon_buffer *buf,
                              int threads, evr_error *err)
{
    gbuf_ctx c;
    int i, started = 0;
    if (!buf->gbuf) {
        buf->gbuf = malloc((size_t)buf->width * (size_t)buf->height * 8 * sizeof(float));
        if (!buf->gbuf) {
            snprintf(err->msg, sizeof err->msg, "out of memory for the photon buffer's view");
            return EVR_ERR_NOMEM;
        }
    }
    if (threads <= 0) {
        long nc = sysconf(_SC_NPROCESSORS_ONLN);
        threads = nc > 0 ? (int)nc : 1;
    }
    memset(&c, 0, sizeof c);
    c.rs = rs;
    c.tr = tr;
    c.buf = buf;
    c.f = f;
    c.pose = evr_rs_camera_pose(rs, f);
    c.fwd = evr_v3_norm(evr_m34_vector(&c.pose, evr_v3_make(0.0f, 0.0f, -1.0f)));
    atomic_store(&c.next, 0);
    pthread_t *th = malloc(sizeof *th * (size_t)threads);
    if (!th) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (i = 1; i < threads; i++) {
        if (pthread_create(&th[i], NULL, gbuf_worker, &c) != 0) break;
        started++;
    }
    gbuf_worker(&c);
    for (i = 1; i <= started; i++) pthread_join(th[i], NULL);
    free(th);
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
    uint64_t paths, stored_photons;
    int failed;
} chunk_out;

typedef struct {
    const evr_render_scene *rs;
    const evr_tracer *tr;
    const evr_photon_params *pp;
    const evr_photon_emitters *em;
    int margin;
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

/* Keeps a photon that stays where the camera sees it. */
static void keep(pass_ctx *c, chunk_out *co, const evr_surface *s, const float flux[3], uint32_t key, float f)
{
    const evr_render_scene *rs = c->rs;
    evr_m34 pose = evr_rs_camera_pose(rs, f), inv = evr_m34_inverse(&pose);
    evr_v3 cam = evr_v3_make(pose.m[0][3], pose.m[1][3], pose.m[2][3]);
    evr_v3 d = evr_v3_sub(cam, s->p);
    float dist = evr_v3_len(d);
    int x, y;
    if (!(dist > 0.0f) || evr_v3_dot(d, s->n) <= 0.0f) return;   /* the camera is behind the surface */
    if (!evr_photon_pixel(&rs->camera, &inv, s->p, c->margin, &x, &y)) return;
    evr_ray r;
    r.org = s->p;
    r.dir = evr_v3_scale(d, 1.0f / dist);
    if (c->tr->occluded(c->tr->user, r, evr_shadow_tnear(s, r.dir, c->pp->ray_eps), dist * (1.0f - 1e-4f), f)) return;
    if (co->n == co->cap) {
        size_t nc = co->cap ? 2 * co->cap : 256;
        pending *p = realloc(co->v, nc * sizeof *p);
        if (!p) { co->failed = 1; return; }
        co->v = p;
        co->cap = nc;
    }
    pending *p = &co->v[co->n++];
    p->ph.p[0] = s->p.x; p->ph.p[1] = s->p.y; p->ph.p[2] = s->p.z;
    p->ph.n[0] = s->n.x; p->ph.n[1] = s->n.y; p->ph.n[2] = s->n.z;
    p->ph.flux[0] = flux[0]; p->ph.flux[1] = flux[1]; p->ph.flux[2] = flux[2];
    p->ph.key = key;
    p->x = x;
    p->y = y;
}

static int emitter_of(const evr_photon_emitters *em, uint32_t i)
{
    int lo = 0, hi = em->n - 1;
    while (lo < hi) {   /* last emitter whose first <= i */
        int mid = (lo + hi + 1) / 2;
        if (em->e[mid].first <= i) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

static void trace_photon(pass_ctx *c, chunk_out *co, uint32_t i)
{
    const evr_render_scene *rs = c->rs;
    const evr_photon_params *pp = c->pp;
    int ei = emitter_of(c->em, i);
    const evr_photon_emitter *e = &c->em->e[ei];
    uint32_t j = i - e->first;
    float f = evr_photon_time(j, pp->f0, pp->f1), u[5];
    evr_photon_ray pr;
    int k, bounce, max_hits;
    if (j >= e->count) return;
    for (k = 0; k < 5; k++) u[k] = evr_photon_rand(pp->seed, ei, j, k);
    if (e->kind == 0) {
        if (!evr_photon_emit_light(rs, &rs->lights[e->index], f, pp->bounds, u, e->count, &pr)) return;
    } else {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[e->index].track), f);
        if (!evr_photon_emit_surface(rs, e, c->em->cdf, &xf, u, &pr)) return;
    }
    co->paths++;
    add3(co->emitted, pr.flux, 1.0f);
    max_hits = pr.from_light ? pp->max_bounces + 1 : pp->max_bounces;
    float tnear = pr.from_light ? 0.0f : pp->ray_eps;
    for (bounce = 0; bounce < max_hits; bounce++) {
        evr_trace_hit h;
        evr_surface s;
        float w, xi;
        int ev;
        if (!c->tr->closest(c->tr->user, pr.ray, tnear, INFINITY, f, &h)) {
            add3(co->escaped, pr.flux, 1.0f);
            return;
        }
        const evr_mesh_view *m = &rs->meshes[rs->instances[h.inst].mesh];
        const evr_material_view *mat = &rs->materials[m->material];
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), f);
        evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, pr.ray, h.t, &s);
        xi = evr_photon_rand(pp->seed, ei, j, 5 + 3 * bounce);
        ev = evr_photon_scatter(mat->t_diffuse, mat->t_specular, xi, !(pr.from_light && bounce == 0), &w);
        if (ev == EVR_PHOTON_STAY) {
            float fl[3] = {pr.flux[0] * w, pr.flux[1] * w, pr.flux[2] * w};
            float ab[3] = {fl[0] * (1.0f - s.albedo[0]), fl[1] * (1.0f - s.albedo[1]), fl[2] * (1.0f - s.albedo[2])};
            add3(co->stored, fl, 1.0f);
            add3(co->absorbed, ab, 1.0f);
            co->stored_photons++;
            keep(c, co, &s, fl, i * 16u + (uint32_t)(bounce < 15 ? bounce : 15), f);
            return;
        }
        if (pr.from_light && bounce == 0) {   /* the direct term's light: absorbed part counted here */
            float ab[3] = {pr.flux[0] * (1.0f - s.albedo[0]), pr.flux[1] * (1.0f - s.albedo[1]), pr.flux[2] * (1.0f - s.albedo[2])};
            add3(co->absorbed, ab, 1.0f);
        }
        if (ev == EVR_PHOTON_ABSORB) return;
        pr.flux[0] *= s.albedo[0] * w;
        pr.flux[1] *= s.albedo[1] * w;
        pr.flux[2] *= s.albedo[2] * w;
        if (ev == EVR_PHOTON_DIFFUSE)
            pr.ray.dir = evr_cosine_dir(s.n, evr_photon_rand(pp->seed, ei, j, 6 + 3 * bounce),
                                        evr_photon_rand(pp->seed, ei, j, 7 + 3 * bounce));
        else
            pr.ray.dir = evr_v3_norm(evr_mirror_dir(pr.ray.dir, s.n));
        pr.ray.org = s.p;
        tnear = evr_shadow_tnear(&s, pr.ray.dir, pp->ray_eps);
    }
    add3(co->capped, pr.flux, 1.0f);
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

evr_status evr_photon_pass(const evr_render_scene *rs, const evr_tracer *tr, const evr_photon_params *pp,
                           const evr_photon_emitters *em, evr_photon_buffer *buf, evr_photon_stats *st,
                           evr_error *err)
{
    pass_ctx c;
    struct timespec t0, t1;
    int nthreads = pp->threads, i, k, started = 0;
    evr_status rc = EVR_OK;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    memset(st, 0, sizeof *st);
    evr_photon_buffer_clear(buf);
    if (em->n == 0 || em->photons == 0) return EVR_OK;
    if (em->photons > (1u << 28)) {
        snprintf(err->msg, sizeof err->msg, "too many photons (%u; at most 2^28)", em->photons);
        return EVR_ERR_ARG;
    }
    if (nthreads <= 0) {
        long nc = sysconf(_SC_NPROCESSORS_ONLN);
        nthreads = nc > 0 ? (int)nc : 1;
    }
    memset(&c, 0, sizeof c);
    c.rs = rs;
    c.tr = tr;
    c.pp = pp;
    c.em = em;
    c.margin = buf->margin;
    c.nchunks = (int)((em->photons + CHUNK - 1) / CHUNK);
    c.chunks = calloc((size_t)c.nchunks, sizeof *c.chunks);
    pthread_t *th = malloc(sizeof *th * (size_t)nthreads);
    if (!c.chunks || !th) {
        free(c.chunks);
        free(th);
        snprintf(err->msg, sizeof err->msg, "out of memory for the photon pass");
        return EVR_ERR_NOMEM;
    }
    atomic_store(&c.next, 0);
    for (i = 1; i < nthreads; i++) {
        if (pthread_create(&th[i], NULL, pass_worker, &c) != 0) break;
        started++;
    }
    pass_worker(&c);
    for (i = 1; i <= started; i++) pthread_join(th[i], NULL);
    free(th);
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
        st->stored_photons += co->stored_photons;
        st->visible += co->n;
        for (n = 0; n < co->n; n++) st->inserted += (uint64_t)evr_photon_buffer_insert(buf, co->v[n].x, co->v[n].y, &co->v[n].ph);
        free(co->v);
    }
    free(c.chunks);
    st->collisions = *buf->collisions;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    st->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (rc != EVR_OK) snprintf(err->msg, sizeof err->msg, "out of memory for the photon pass");
    return rc;
}
