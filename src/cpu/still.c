/* evray still: one image at one time. Its own Embree scene (every instance baked into world
 * space at that time, geometry id = scene instance), the event pipeline's direct shading through
 * each pixel centre, and the indirect term from the photon buffer or from path tracing. */
#include "cpu/still.h"
#include "prep/deform_keys.h"
#include "host_clock.h"
#include "cpu/cpu_gi.h"
#include "cpu/embree_filter.h"
#include "cpu/workers.h"
#include "backend.h"
#include "core/photon.h"
#include "core/rng.h"
#include "core/shade_hit.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
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

void evr_still_defaults(evr_still_params *p)
{
    memset(p, 0, sizeof *p);
    p->width = 256;
    p->height = 256;
    p->gi = EVR_GI_NONE;
    p->spp = 64;
    p->gather_max = 256;
    p->gather_window = 48;
    p->gather_normal_cos = 0.7f;
    p->photon_layers = 16;
    p->auto_layers = 1;
    p->gather_area = 1;
    p->max_bounces = 8;
    p->ambient = 0.02f;
    p->seed = 1;
}

/* ---- Embree as an evr_tracer ---- */

/* The baked scene: geometry g is scene instance g. */
static int em_closest(void *user, evr_ray ray, float tnear, float tfar, float f, evr_trace_hit *hit)
{
    return evr_embree_closest1((RTCScene)user, NULL, NULL, ray, tnear, tfar, f, hit);
}

static int em_occluded(void *user, evr_ray ray, float tnear, float tfar, float f)
{
    return evr_embree_occluded1((RTCScene)user, ray, tnear, tfar, f);
}

/* ---- shading ---- */

typedef struct {
    const evr_still_params *p;
    const evr_render_scene *rs;
    evr_tracer tr;
    evr_m34 pose;
    const evr_photon_buffer *buf;
    evr_gather_params gp;
    evr_still_result *out;
    atomic_int next_row;
    double *row_used; /* photons used per row (summed in row order) */
    int *row_hits;
} shade_ctx;

/* core/shade_hit.h's shadow-ray query: the tracer's. */
struct evr_occlusion {
    const evr_tracer *tr;
};

static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f)
{
    return o->tr->occluded(o->tr->user, r, tnear, tfar, f);
}

static inline int evr_closest(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f,
                              evr_hit *h)
{
    return o->tr->closest(o->tr->user, r, tnear, tfar, f, h);
}

#include "core/path.h"

/* The lights' sum acc at surface s seen along wo, shadow rays included (evr_shade_direct_sum):
 * the event pipeline's direct term one ray at a time. */
static void direct_lights(const shade_ctx *c, const evr_surface *s, evr_v3 wo, float acc[3])
{
    struct evr_occlusion o;
    unsigned rays = 0;
    o.tr = &c->tr;
    evr_shade_direct_sum(c->rs, s, wo, 0.0f, &o, &rays, acc);
}

/* The surface ray meets beyond tnear, at distance *t; cam: the camera whose pixel cone the ray
 * carries (textures are filtered by the cone's width there; NULL: the sharpest level); *inst its
 * instance (inst and t may be NULL). */
static int surface_of(const shade_ctx *c, evr_ray ray, float tnear, const evr_camera_intr *cam,
                      evr_surface *s, int *inst, float *t)
{
    const evr_render_scene *rs = c->rs;
    evr_trace_hit h;
    if (!c->tr.closest(c->tr.user, ray, tnear, INFINITY, 0.0f, &h)) return 0;
    evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.inst].track), 0.0f);
    evr_surface_at(rs, h.inst, h.prim, h.u, h.v, &xf, 0.0f, ray, h.t,
                   cam ? evr_camera_cone(cam, h.t) : 0.0f, s);
    if (inst) *inst = h.inst;
    if (t) *t = h.t;
    return 1;
}

/* One path of the indirect light at the camera ray's hit s0 (the ray along d0): what the event
 * pipeline's direct term (evr_path_radiance: s0's lights and emission, and the mirror,
 * refraction and BLEND rays that core/path.h traces from it, with theirs) leaves out. The path
 * samples s0's BSDF (core/bsdf_sample.h) and goes on; at each surface it meets it adds that
 * surface's emission and its lights (next-event estimation with the direct term's code,
 * evr_shade_direct_sum and evr_material_add_light), unless every bounce so far was one the
 * direct term traces itself (then that surface was shaded there already). Point lights are met
 * only by their shadow rays and emissive surfaces only by the path, so no light is counted
 * twice. A path ends past --max-bounces, in the void (the ambient light is the direct term's),
 * or by Russian roulette after three bounces. */
static void path_sample(const shade_ctx *c, const evr_surface *s0, evr_v3 d0, uint64_t pix,
                        uint64_t sample, float out[3])
{
    const evr_render_scene *rs = c->rs;
    const uint64_t seed = c->p->seed ^ 0x70617468ull; /* "path" */
    evr_surface s = *s0;
    evr_v3 d = d0;
    float beta[3] = {1.0f, 1.0f, 1.0f}; /* the path's weight */
    float wdet[3] = {1.0f, 1.0f, 1.0f}; /* while det: the weight core/path.h gives the ray */
    int depth, dim = 0, det = 1, medium = -1, k;
    out[0] = out[1] = out[2] = 0.0f;
    for (depth = 0; depth < c->p->max_bounces; depth++) {
        const float xi = evr_uniform(evr_hash4(seed, pix, sample, (uint64_t)dim++));
        const float u1 = evr_uniform(evr_hash4(seed, pix, sample, (uint64_t)dim++));
        const float u2 = evr_uniform(evr_hash4(seed, pix, sample, (uint64_t)dim++));
        const evr_material_params *m = &rs->materials[s.material];
        float w[EVR_LOBES][3], wt[3], pick;
        evr_v3 dir;
        evr_bsdf_lobe_weights(&s, w);
        const int lobe = evr_bsdf_pick(w, xi, &pick);
        if (lobe < 0 || !evr_bsdf_sample(&s, m, lobe, d, u1, u2, 0, &dir, wt)) return;
        const int crossed = evr_v3_dot(dir, s.nv) < 0.0f;
        /* core/path.h traces the uncovered share, the transmission and a mirror's reflection
         * (total internal reflection joins the reflection) while deep and bright enough */
        const int traced =
            lobe == EVR_LOBE_PASS || (lobe == EVR_LOBE_TRANSMIT && crossed) ||
            ((lobe == EVR_LOBE_SPECULAR || lobe == EVR_LOBE_TRANSMIT) && evr_material_mirror(&s));
        for (k = 0; k < 3; k++) {
            beta[k] *= wt[k] / pick;
            wdet[k] *= wt[k];
        }
        det = det && traced && depth + 1 <= rs->max_bounces &&
              evr_luminance(wdet[0], wdet[1], wdet[2]) >= EVR_PATH_MIN_WEIGHT;
        if (lobe == EVR_LOBE_TRANSMIT && crossed) {
            const int cross = evr_bsdf_crossing(&s, m);
            if (cross) medium = cross > 0 ? s.material : -1;
        }
        if (depth >= 3) { /* Russian roulette */
            float q = fminf(fmaxf(beta[0], fmaxf(beta[1], beta[2])), 0.95f);
            if (evr_uniform(evr_hash4(seed, pix, sample, (uint64_t)dim++)) >= q) return;
            for (k = 0; k < 3; k++) beta[k] /= q;
        }
        if (!(beta[0] > 0.0f || beta[1] > 0.0f || beta[2] > 0.0f)) return;
        evr_ray r;
        evr_surface y;
        float t;
        r.org = s.p;
        r.dir = dir;
        /* the path's bounces sample textures sharply: many paths average them */
        if (!surface_of(c, r, rs->ray_eps / fmaxf(fabsf(evr_v3_dot(s.nv, dir)), 0.05f), NULL, &y,
                        NULL, &t))
            return;
        if (medium >= 0) { /* Beer-Lambert through the volume it crossed */
            evr_volume_attenuate(&rs->materials[medium], t, beta);
            evr_volume_attenuate(&rs->materials[medium], t, wdet);
        }
        if (!det) { /* y's emission and lights: its radiance as the direct term shades it */
            float acc[3], em[3];
            const evr_v3 back = evr_v3_scale(dir, -1.0f);
            direct_lights(c, &y, back, acc);
            evr_material_emission(&y, back, em);
            for (k = 0; k < 3; k++)
                out[k] += beta[k] * y.opacity * (y.unlit ? y.albedo[k] : em[k] + acc[k]);
        }
        s = y;
        d = dir;
    }
}

static void shade_row(shade_ctx *c, int y)
{
    const evr_render_scene *rs = c->rs;
    const evr_still_params *p = c->p;
    evr_still_result *o = c->out;
    int x, k;
    double used = 0.0;
    int hits = 0;
    for (x = 0; x < p->width; x++) {
        size_t i = (size_t)y * (size_t)p->width + (size_t)x;
        float *rgb = o->rgb + 3 * i, *dir = o->direct + 3 * i, acc[3];
        evr_ray ray = evr_camera_ray(&rs->camera, &c->pose, (float)x + 0.5f, (float)y + 0.5f);
        evr_surface s;
        int inst;
        rgb[0] = rgb[1] = rgb[2] = dir[0] = dir[1] = dir[2] = 0.0f;
        o->instance[i] = -1;
        if (!surface_of(c, ray, 0.0f, &rs->camera, &s, &inst, NULL)) continue;
        o->instance[i] = inst;
        const evr_v3 wo = evr_v3_scale(ray.dir, -1.0f);
        direct_lights(c, &s, wo, acc);
        {
            struct evr_occlusion occ;
            unsigned rays = 0;
            int deep = 0;
            occ.tr = &c->tr;
            evr_path_radiance(rs, &s, ray.dir, evr_v3_len(evr_v3_sub(s.p, ray.org)), acc, &occ,
                              0.0f, NULL, &rays, &deep, dir);
        }
        for (k = 0; k < 3; k++) rgb[k] = dir[k];
        if (p->gi == EVR_GI_PHOTON) {
            float e[3], ind[3];
            float dist = evr_v3_len(evr_v3_sub(s.p, ray.org));
            used += evr_photon_gather(c->buf, &rs->camera, x, y, s.p, s.n, dist, &c->gp, e);
            hits++;
            evr_photon_indirect(&s, e, ind);
            for (k = 0; k < 3; k++) rgb[k] += ind[k];
        } else if (p->gi == EVR_GI_PATH) {
            double sum[3] = {0, 0, 0};
            int n;
            for (n = 0; n < p->spp; n++) {
                float l[3];
                path_sample(c, &s, ray.dir, (uint64_t)i, (uint64_t)n, l);
                for (k = 0; k < 3; k++) sum[k] += (double)l[k];
            }
            for (k = 0; k < 3; k++) rgb[k] += (float)(sum[k] / (double)p->spp);
        }
    }
    c->row_used[y] = used;
    c->row_hits[y] = hits;
}

static void *shade_worker(void *arg)
{
    shade_ctx *c = (shade_ctx *)arg;
    int y;
#if defined(__SSE__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    while ((y = atomic_fetch_add(&c->next_row, 1)) < c->p->height) shade_row(c, y);
    return NULL;
}

static void embree_error(void *user, enum RTCError code, const char *str)
{
    char *msg = (char *)user;
    if (!msg[0]) snprintf(msg, 256, "Embree error %d: %s", (int)code, str ? str : "");
}

void evr_still_result_free(evr_still_result *r)
{
    free(r->rgb);
    free(r->direct);
    free(r->instance);
    memset(r, 0, sizeof *r);
}

evr_status evr_still_render(const evr_scene *s, const evr_still_params *p, evr_still_result *out,
                            evr_error *err)
{
    evr_render_host host;
    evr_motion_key *keys = NULL;
    evr_deform_tracker dtrack;
    evr_deform_keys dkeys;
    memset(&dtrack, 0, sizeof dtrack);
    memset(&dkeys, 0, sizeof dkeys);
    int *toff = NULL, *tcnt = NULL;
    RTCDevice dev = NULL;
    RTCScene sc = NULL;
    evr_cpu_filter_map fmap;
    evr_photon_buffer buf;
    evr_photon_emitters em;
    shade_ctx c;
    char emsg[256] = "";
    int cam, i, nthreads = p->threads;
    evr_status st;
    double t0 = evr_host_seconds();
    size_t npix;
    memset(out, 0, sizeof *out);
    memset(&buf, 0, sizeof buf);
    memset(&em, 0, sizeof em);
    memset(&c, 0, sizeof c);
    memset(&host, 0, sizeof host);
    if (p->width <= 0 || p->height <= 0 || p->width > 16384 || p->height > 16384) {
        snprintf(err->msg, sizeof err->msg,
                 "resolution must be between 1x1 and 16384x16384 (got %dx%d)", p->width, p->height);
        return EVR_ERR_ARG;
    }
    if (p->gi == EVR_GI_PATH && p->spp <= 0) {
        snprintf(err->msg, sizeof err->msg, "--spp must be at least 1 (got %d)", p->spp);
        return EVR_ERR_ARG;
    }
    if (p->max_bounces < 1 || p->max_bounces > 15) {
        snprintf(err->msg, sizeof err->msg, "--max-bounces must be between 1 and 15 (got %d)",
                 p->max_bounces);
        return EVR_ERR_ARG;
    }
    if (p->gi == EVR_GI_PHOTON && (p->gather_max < 1 || p->photon_layers < 1 ||
                                   p->photon_layers > 64 || p->gather_window < 0)) {
        snprintf(err->msg, sizeof err->msg,
                 "--gather-max must be >= 1 and --photon-layers between 1 and 64");
        return EVR_ERR_ARG;
    }
    if (!(p->ambient >= 0.0f) || !isfinite(p->ambient)) {
        snprintf(err->msg, sizeof err->msg, "--ambient must be >= 0");
        return EVR_ERR_ARG;
    }
    if ((cam = evr_scene_find_camera(s, p->camera)) < 0) {
        snprintf(err->msg, sizeof err->msg, "the scene has no camera named '%s'", p->camera);
        return EVR_ERR_ARG;
    }
    nthreads = evr_cpu_threads(nthreads);
    if ((st = evr_render_host_init(&host, s, cam, p->width, p->height, p->ambient, err)) != EVR_OK)
        return st;
    npix = (size_t)p->width * (size_t)p->height;
    out->width = p->width;
    out->height = p->height;
    out->threads = nthreads;
    out->rgb = malloc(npix * 3 * sizeof(float));
    out->direct = malloc(npix * 3 * sizeof(float));
    out->instance = malloc(npix * sizeof(int));
    keys = malloc(((size_t)s->num_nodes + 1) * sizeof *keys);
    toff = malloc(((size_t)s->num_nodes + 1) * sizeof *toff);
    tcnt = malloc(((size_t)s->num_nodes + 1) * sizeof *tcnt);
    c.row_used = calloc((size_t)p->height, sizeof *c.row_used);
    c.row_hits = calloc((size_t)p->height, sizeof *c.row_hits);
    if (!out->rgb || !out->direct || !out->instance || !keys || !toff || !tcnt || !c.row_used ||
        !c.row_hits) {
        snprintf(err->msg, sizeof err->msg, "out of memory for a %dx%d image", p->width, p->height);
        st = EVR_ERR_NOMEM;
        goto done;
    }
    /* one key per track: every node's world transform at the time; the last track is the world */
    for (i = 0; i <= s->num_nodes; i++) {
        evr_m34 w = i < s->num_nodes ? evr_node_world_at(s, i, p->time) : evr_m34_identity();
        keys[i] = evr_motion_key_from_matrix(&w);
        toff[i] = i;
        tcnt[i] = 1;
    }
    host.rs.keys = keys;
    host.rs.track_offset = toff;
    host.rs.track_count = tcnt;
    /* deforming instances: their vertices at the time, one key each */
    if (!evr_deform_tracker_init(&dtrack, s, &host) ||
        !evr_deform_keys_make(&dtrack, s, &host, p->time, p->time, 1e-5f, 1, &dkeys)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the deforming meshes");
        st = EVR_ERR_NOMEM;
        goto done;
    }
    host.rs.deforms = dkeys.views;

    dev = rtcNewDevice(NULL);
    if (!dev) {
        snprintf(err->msg, sizeof err->msg, "cannot create the Embree device");
        st = EVR_ERR_BACKEND;
        goto done;
    }
    rtcSetDeviceErrorFunction(dev, embree_error, emsg);
    /* the hit filters' map: geometry g is instance g, in world space */
    fmap.rs = &host.rs;
    fmap.members = fmap.group_first = fmap.group_kind = NULL;
    sc = rtcNewScene(dev);
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
    evr_v3 lo = evr_v3_make(INFINITY, INFINITY, INFINITY),
           hi = evr_v3_make(-INFINITY, -INFINITY, -INFINITY);
    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        evr_m34 xf = evr_motion_eval(evr_rs_track(&host.rs, host.rs.instances[i].track), 0.0f);
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            3 * sizeof(float), m->num_vertices);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                               3 * sizeof(unsigned), m->num_triangles);
        uint32_t v;
        if (!vb || !ib) {
            rtcReleaseGeometry(g);
            break;
        }
        for (v = 0; v < m->num_vertices; v++) {
            evr_v3 q = evr_m34_point(
                &xf, evr_rs_vertex(&host.rs, i, &host.meshes[s->instances[i].mesh], v, 0.0f));
            vb[3 * v] = q.x;
            vb[3 * v + 1] = q.y;
            vb[3 * v + 2] = q.z;
            lo = evr_v3_make(fminf(lo.x, q.x), fminf(lo.y, q.y), fminf(lo.z, q.z));
            hi = evr_v3_make(fmaxf(hi.x, q.x), fmaxf(hi.y, q.y), fmaxf(hi.z, q.z));
        }
        memcpy(ib, m->indices, sizeof(unsigned) * 3 * m->num_triangles);
        evr_cpu_filter_set(g, &fmap, host.meshes[s->instances[i].mesh].filter);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(sc, g, (unsigned)i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(sc);
    if (emsg[0]) {
        snprintf(err->msg, sizeof err->msg, "%s", emsg);
        st = EVR_ERR_BACKEND;
        goto done;
    }
    c.p = p;
    c.rs = &host.rs;
    c.tr.user = sc;
    c.tr.closest = em_closest;
    c.tr.occluded = em_occluded;
    c.pose = evr_rs_camera_pose(&host.rs, 0.0f);
    c.out = out;
    out->seconds_setup = evr_host_seconds() - t0;

    if (p->gi == EVR_GI_PHOTON) {
        evr_photon_params pp;
        evr_photon_bounds bb;
        double t1 = evr_host_seconds();
        uint32_t nph =
            p->photons ? p->photons : (npix > (1u << 25) ? (1u << 28) : (uint32_t)(8 * npix));
        /* the scene at the time, baked: a sphere round its bounds (a little larger) */
        if (!(lo.x <= hi.x)) lo = hi = evr_v3_make(0.0f, 0.0f, 0.0f);
        bb.center = evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
        bb.radius = 0.5f * evr_v3_len(evr_v3_sub(hi, lo)) * 1.001f + host.rs.ray_eps;
        if ((st = evr_photon_emitters_build(&host.rs, 0.0f, bb, nph, &em, err)) != EVR_OK)
            goto done;
        if ((st = evr_photon_buffer_alloc(&buf, p->width, p->height, p->photon_layers,
                                          p->gather_window < 16 ? p->gather_window : 16, err)) !=
            EVR_OK)
            goto done;
        memset(&pp, 0, sizeof pp);
        pp.max_bounces = p->max_bounces;
        pp.f0 = pp.f1 = 0.0f;
        pp.seed = p->seed;
        pp.threads = nthreads;
        pp.bounds = bb;
        pp.ray_eps = host.rs.ray_eps;
        if ((st = evr_photon_pass(&host.rs, &c.tr, &pp, &em, &buf, &out->photon, NULL, err)) !=
            EVR_OK)
            goto done;
        /* more than 3% of the photons found their pixel full: twice the layers (up to 64), again */
        while (p->auto_layers && buf.layers < 64 && out->photon.visible > 0 &&
               (double)out->photon.collisions > 0.03 * (double)out->photon.visible) {
            int layers = 2 * buf.layers, margin = buf.margin;
            evr_photon_buffer_free(&buf);
            if ((st = evr_photon_buffer_alloc(&buf, p->width, p->height, layers > 64 ? 64 : layers,
                                              margin, err)) != EVR_OK)
                goto done;
            if ((st = evr_photon_pass(&host.rs, &c.tr, &pp, &em, &buf, &out->photon, NULL, err)) !=
                EVR_OK)
                goto done;
        }
        out->photon_layers = buf.layers;
        if (p->gather_area &&
            (st = evr_photon_gbuffer(&host.rs, &c.tr, 0.0f, &buf, nthreads, err)) != EVR_OK)
            goto done;
        c.buf = &buf;
        c.gp.radius = p->gather_radius > 0.0f ? p->gather_radius : 0.02f * host.scene_size;
        c.gp.max_photons = p->gather_max;
        c.gp.max_window = p->gather_window;
        c.gp.normal_cos = p->gather_normal_cos;
        out->gather_radius = c.gp.radius;
        out->seconds_photons = evr_host_seconds() - t1;
    }
    {
        double t2 = evr_host_seconds();
        atomic_store(&c.next_row, 0);
        if (!evr_run_workers(shade_worker, &c, nthreads)) {
            snprintf(err->msg, sizeof err->msg, "out of memory");
            st = EVR_ERR_NOMEM;
            goto done;
        }
        out->seconds_shading = evr_host_seconds() - t2;
    }
    {
        double used = 0.0;
        long hits = 0;
        for (i = 0; i < p->height; i++) {
            used += c.row_used[i];
            hits += c.row_hits[i];
        }
        out->photons_per_estimate = hits ? used / (double)hits : 0.0;
    }
    if (emsg[0]) {
        snprintf(err->msg, sizeof err->msg, "%s", emsg);
        st = EVR_ERR_BACKEND;
    }
done:
    if (sc) rtcReleaseScene(sc);
    if (dev) rtcReleaseDevice(dev);
    evr_photon_buffer_free(&buf);
    evr_photon_emitters_free(&em);
    free(keys);
    free(toff);
    free(tcnt);
    evr_deform_keys_free(&dkeys);
    evr_deform_tracker_free(&dtrack);
    free(c.row_used);
    free(c.row_hits);
    evr_render_host_free(&host);
    if (st != EVR_OK) evr_still_result_free(out);
    return st;
}
