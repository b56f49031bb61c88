/* The per-pixel flow of src/core that every backend runs: the event loop with its sink
 * (core/pixel_flow.h), adaptive and refined sampling's state machines (core/adaptive.h,
 * core/refine.h) and the shading of a
 * hit with its shadow-ray query (core/shade_hit.h), each driven here by a sink and an occlusion
 * query of the test's own. */
#include "check.h"
#include "core/adaptive.h"
#include "core/pixel_flow.h"
#include "core/refine.h"
#include "core/shade_hit.h"

#include <math.h>
#include <string.h>

typedef struct {
    long long t;
    int x, y, p;
} ev_t;

struct evr_event_sink {
    ev_t ev[512];
    unsigned id, ids[512]; /* the sample's id (a backend's event id), and each event's */
    int n, pushes;
};

static inline int evr_event_sink_push(struct evr_event_sink *k, int has, long long t_us, int x,
                                      int y, int polarity)
{
    k->pushes++;
    if (!has) return 0;
    if (k->n < 512) {
        k->ev[k->n].t = t_us;
        k->ev[k->n].x = x;
        k->ev[k->n].y = y;
        k->ev[k->n].p = polarity;
        k->ids[k->n] = k->id;
    }
    k->n++;
    return 1;
}

struct evr_occlusion {
    int blocked, calls;
    evr_ray last;
    float tnear, tfar;
};

static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f)
{
    (void)f;
    o->calls++;
    o->last = r;
    o->tnear = tnear;
    o->tfar = tfar;
    return o->blocked;
}

/* Not called: the scenes here hold nothing translucent (shadow rays use evr_occluded). */
static inline int evr_closest(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f,
                              evr_hit *h)
{
    (void)o, (void)r, (void)tnear, (void)tfar, (void)f, (void)h;
    return 0;
}

/* The loop as the backends wrote it before it moved to core: begin, next until none, end. */
static int reference_events(evr_pixel_state *st, const evr_pixel_params *p, int sensor, float t,
                            float in, double t0, int x, int y, ev_t *out)
{
    evr_pixel_span sp;
    float te;
    int pol, n = 0;
    if (!evr_pixel_begin_s(st, p, t, in, &sp, sensor)) return 0;
    while (evr_pixel_next_s(st, p, &sp, &te, &pol, sensor)) {
        out[n].t = evr_event_time_us_s(p, t0 + (double)te, x, y, sensor);
        out[n].p = pol;
        n++;
    }
    evr_pixel_end_s(st, &sp, sensor);
    return n;
}

static void test_event_loop(void)
{
    evr_pixel_params run = {.pos_thres = 0.2f,
                            .neg_thres = 0.25f,
                            .refractory = 1e-4f,
                            .log_floor = 1e-3f,
                            .full_intensity = 4.0f,
                            .seed = 7};
    int sensor;
    for (sensor = 0; sensor <= 1; sensor++) {
        evr_pixel_params p;
        if (sensor) {
            run.sigma_thres = 0.03f;
            run.cutoff_hz = 200.0f;
            run.shot_rate = 5.0f;
            run.time_res_us = 10;
        }
        evr_pixel_params_at(&run, 3, 4, &p);
        evr_pixel_state a, b;
        struct evr_event_sink k;
        ev_t ref[512];
        int s, total = 0;
        evr_pixel_reset(&a);
        evr_pixel_reset(&b);
        for (s = 0; s < 200; s++) {
            const float t = 0.001f * (float)s, in = 1.0f + 0.9f * sinf(40.0f * t);
            const int n = reference_events(&a, &p, sensor, t, in, 2.0, 3, 4, ref);
            memset(&k, 0, sizeof k);
            evr_pixel_sample_events(&b, &p, evr_pixel_ideal_of(&p), sensor, 1, t, in, 2.0, 3, 4,
                                    &k);
            CHECK(k.n == n);
            CHECK(k.pushes == n + 1); /* one push with none ends the loop */
            for (int i = 0; i < n && i < k.n; i++) {
                CHECK(k.ev[i].t == ref[i].t && k.ev[i].p == ref[i].p);
                CHECK(k.ev[i].x == 3 && k.ev[i].y == 4);
            }
            CHECK(memcmp(&a, &b, sizeof a) == 0);
            total += n;
        }
        CHECK(total > 10);
        /* a lane without a sample: the state is untouched, the sink is asked once */
        memset(&k, 0, sizeof k);
        evr_pixel_state c = b;
        evr_pixel_sample_events(&b, &p, evr_pixel_ideal_of(&p), sensor, 0, 0.3f, 9.0f, 2.0, 3, 4,
                                &k);
        CHECK(k.n == 0 && k.pushes == 1);
        CHECK(memcmp(&b, &c, sizeof b) == 0);
    }
}

/* A step in intensity at t = 0.3 s: adaptive sampling's state machine refines the interval that
 * straddles it down to about min_dt, and the pixel model sees its samples in time order. */
static void test_adapt_machine(void)
{
    evr_render_scene rs;
    evr_adapt_plan plan;
    evr_adapt_params ap;
    evr_pixel_params p = {.pos_thres = 0.2f, .neg_thres = 0.2f, .log_floor = 1e-3f};
    evr_pixel_state st;
    evr_adapt_stack sk;
    struct evr_event_sink k;
    evr_ray ray0;
    const float seg = 1.0f;
    float t, last = -1.0f;
    int traced = 0, ok_order = 1;
    memset(&rs, 0, sizeof rs);
    memset(&plan, 0, sizeof plan);
    memset(&k, 0, sizeof k);
    ap.frac = 0.25f;
    ap.min_dt = 1e-3f;
    ap.max_dt = 0.1f;
    ray0.org = evr_v3_make(0, 0, 0);
    ray0.dir = evr_v3_make(0, 0, 1);
    evr_pixel_reset(&st);
    sk.n = 0;
    t = evr_adapt_start(&rs, &ap, &plan, &st, ray0, 0.0f, 0.5f, seg);
    CHECK_NEAR(t, 0.5e-3, 1e-9); /* a pixel's very first sample: its phase times min_dt */
    while (t < seg && traced < 1000) {
        /* id: what the sample saw (1 before the step, 2 after), carried with held samples */
        float in = t < 0.3f ? 1.0f : 2.0f, hit = INFINITY, step = 0.0f;
        unsigned id = t < 0.3f ? 1u : 2u;
        int moving = 0;
        traced++;
        while (evr_adapt_candidate(&rs, &ap, &plan, &st, &p, ray0, &sk, t, in, hit, id, &t, &step,
                                   &moving)) {
            if (t < last) ok_order = 0;
            last = t;
            k.id = id;
            CHECK(id == (t < 0.3f ? 1u : 2u));
            evr_pixel_sample_events(&st, &p, evr_pixel_ideal_of(&p), 0, 1, t, in, 0.0, 0, 0, &k);
            if (!evr_adapt_taken(&ap, &sk, step, moving, seg, &t, &in, &hit, &id, &t)) break;
        }
    }
    CHECK(ok_order);
    CHECK(sk.n == 0);
    CHECK(traced > 10 && traced < 100);
    CHECK(k.n == 3); /* ln 2 = 0.69: three ON thresholds of 0.2 */
    for (int i = 0; i < k.n && i < 3; i++) {
        CHECK(k.ev[i].p == 1);
        CHECK(fabs((double)k.ev[i].t * 1e-6 - 0.3) < 2.0 * ap.min_dt);
        CHECK(k.ids[i] == 2u); /* the sample after the crossing saw the new surface */
    }
}

/* Refined sampling's flow (core/refine.h) over one pixel and one segment of 1 s, 10 grid samples,
 * tol 1 ms, with a log intensity of the test's own (shape 0: a step of ln 2 at 0.3137 s; 1: a
 * ramp rising by 1.2 over the segment); the events and the samples traced. */
static int refine_pixel(int shape, struct evr_event_sink *k, int *ok_order)
{
    evr_render_scene rs;
    evr_pixel_params p = {.pos_thres = 0.2f, .neg_thres = 0.2f, .log_floor = 1e-3f};
    evr_pixel_state st;
    evr_refine_pixel q;
    const evr_refine_params rp = {.tol = 1e-3f, .n = 10, .px = 0.0f};
    evr_skip_plan pl;
    evr_ray ray0;
    const float seg = 1.0f;
    float last = -1.0f;
    int traced = 0;
    memset(&rs, 0, sizeof rs);
    memset(&pl, 0, sizeof pl);
    memset(k, 0, sizeof *k);
    ray0.org = evr_v3_make(0, 0, 0);
    ray0.dir = evr_v3_make(0, 0, 1);
    evr_pixel_reset(&st);
    *ok_order = 1;
    evr_refine_begin(&q, &st, evr_refine_step(&rp, INFINITY, seg), seg);
    CHECK(q.t == 0.0f); /* a pixel's very first sample: the segment's start */
    while ((q.need || q.cand) && traced < 1000) {
        if (q.need && !evr_refine_kept(&q, &pl, q.t / seg)) {
            const float in = shape == 0 ? (q.t < 0.3137f ? 1.0f : 2.0f) : expf(1.2f * q.t);
            traced++;
            evr_refine_traced(&q, &rs, &pl, &st, ray0, q.t / seg, in, INFINITY, 0, 0u, 1);
        }
        if (q.cand && evr_refine_decide(&q, &rp, &st, &p)) {
            if (q.ct < last) *ok_order = 0;
            last = q.ct;
            evr_pixel_sample_events(&st, &p, evr_pixel_ideal_of(&p), 0, 1, q.ct, q.ci, 0.0, 0, 0,
                                    k);
            evr_refine_next(&q, &rp, INFINITY, seg);
        }
    }
    CHECK(q.sk.n == 0 && st.t_prev == seg); /* the last sample at the segment's end */
    return traced;
}

static void test_refine_machine(void)
{
    struct evr_event_sink k;
    int ok_order;
    /* the step: its interval bisected down to tol (100 ms: 7 halvings), its three ON events
     * within tol of it */
    int traced = refine_pixel(0, &k, &ok_order);
    CHECK(ok_order);
    CHECK(traced >= 11 + 6 && traced <= 11 + 8);
    CHECK(k.n == 3); /* ln 2 = 0.69: three ON thresholds of 0.2 */
    for (int i = 0; i < k.n && i < 3; i++)
        CHECK(k.ev[i].p == 1 && fabs((double)k.ev[i].t * 1e-6 - 0.3137) <= 1e-3);
    /* the ramp: straight, so each interval that fires takes one midpoint that vouches for it;
     * its six events where the line crosses each level (linear interpolation is exact) */
    traced = refine_pixel(1, &k, &ok_order);
    CHECK(ok_order);
    CHECK(traced <= 11 + 6);
    CHECK(k.n == 6);
    for (int i = 0; i < k.n && i < 6; i++)
        CHECK(k.ev[i].p == 1 && fabs((double)k.ev[i].t * 1e-6 - 0.2 * (i + 1) / 1.2) <= 2e-6);
}

/* A surface of material mat at the origin, normal n, seen along wo: its record as
 * evr_material_at leaves it. */
static void flow_surface(const evr_render_scene *rs, const evr_material_params *mat, evr_v3 n,
                         evr_v3 wo, evr_surface *s)
{
    memset(s, 0, sizeof *s);
    s->p = evr_v3_make(0, 0, 0);
    s->n = s->nv = n;
    s->front = 1;
    for (int c = 0; c < 3; c++) s->albedo[c] = mat->base_color[c];
    s->rough = mat->roughness;
    s->alpha = mat->roughness * mat->roughness;
    s->opacity = s->occlusion = 1.0f;
    s->eta = 1.0f / mat->ior;
    evr_material_view(rs, mat, mat->transmission, wo, s);
}

/* One point light straight above a grey patch with no specular layer (KHR_materials_specular
 * factor 0: Lambert): E = I / d^2 at normal incidence. */
static void test_shade_hit(void)
{
    evr_render_scene rs;
    evr_light_view light;
    evr_material_params mat;
    evr_surface s;
    struct evr_occlusion o;
    const evr_v3 wo = evr_v3_make(0, 0, 1);
    unsigned rays = 0;
    evr_material_defaults(&mat);
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = 0.5f;
    mat.specular = 0.0f;
    memset(&rs, 0, sizeof rs);
    rs.materials = &mat;
    memset(&light, 0, sizeof light);
    memset(&o, 0, sizeof o);
    light.type = 0;
    light.track = -1;
    light.color[0] = light.color[1] = light.color[2] = 8.0f;
    light.pos = evr_v3_make(0, 0, 2);
    rs.lights = &light;
    rs.num_lights = 1;
    rs.ambient = 0.1f;
    rs.ray_eps = 1e-3f;
    flow_surface(&rs, &mat, evr_v3_make(0, 0, 1), wo, &s);
    const float lit = evr_shade_hit(&rs, &s, wo, 0.0f, &o, &rays);
    CHECK_NEAR(lit, 0.5 * (0.1 + 2.0 / EVR_PI), 1e-5);
    CHECK(rays == 1 && o.calls == 1);
    CHECK_NEAR(o.last.dir.z, 1.0, 1e-6);
    CHECK_NEAR(o.tnear, 1e-3, 1e-9);
    CHECK_NEAR(o.tfar, 2.0 * (1.0 - 1e-4), 1e-6);
    o.blocked = 1;
    CHECK_NEAR(evr_shade_hit(&rs, &s, wo, 0.0f, &o, &rays), 0.5 * 0.1, 1e-6);
    /* the light behind the surface: no shadow ray */
    flow_surface(&rs, &mat, evr_v3_make(0, 0, -1), wo, &s);
    o.calls = 0;
    CHECK_NEAR(evr_shade_hit(&rs, &s, wo, 0.0f, &o, &rays), 0.5 * 0.1, 1e-6);
    CHECK(o.calls == 0);
    /* the packet form (the CPU backend's steps light by light) gives the same bits */
    {
        evr_light_ray lr;
        float acc[3] = {0.0f, 0.0f, 0.0f};
        flow_surface(&rs, &mat, evr_v3_make(0, 0.6f, 0.8f), wo, &s);
        o.blocked = 0;
        CHECK(evr_shade_light_ray(&rs, 0, 0.0f, &s, &lr));
        evr_shade_add_light(&s, wo, &lr, acc);
        CHECK(evr_shade_intensity(&rs, &s, wo, acc) == evr_shade_hit(&rs, &s, wo, 0.0f, &o, &rays));
    }
}

int main(void)
{
    test_event_loop();
    test_adapt_machine();
    test_refine_machine();
    test_shade_hit();
    return check_report("test_flow");
}
