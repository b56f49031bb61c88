/* Device code of the per-pixel kernels (the render kernels of cuda_render.cu and the deferred
 * gathers' trace and pixel kernels of cuda_gi_deferred.cu): a camera sample's direct light (and
 * gathers), the pixel's state in and out, its samples through the pixel model of src/core with
 * events appended as keys, the launch's pixel of a thread. */
#ifndef EVR_CUDA_CUDA_PIXEL_CUH
#define EVR_CUDA_CUDA_PIXEL_CUH

#include "core/pixel_flow.h"
#include "core/shade_hit.h"
#include "cuda/cuda_gather.cuh"
#include "cuda/cuda_trace.cuh"

/* core/shade_hit.h's shadow-ray query: our traversal in the launch's node layout (a constant
 * once inlined into a kernel of that layout); hit is scratch space the query may write. */
struct evr_occlusion {
    const kernel_args *a;
    int layout;
    evr_gpu_hit *hit;
};

/* Our traversal in the launch's node layout for one query (any 1: any hit, a shadow ray; 0: the
 * closest, into *o->hit). */
EVR_HD static inline int evr_occlusion_trace(struct evr_occlusion *o, evr_ray r, float tnear,
                                             float tfar, float f, int any)
{
#ifdef __CUDA_ARCH__
    const int general = EVR_GPU_TRACE_GENERAL;
    if (o->layout == EVR_GPU_LAYOUT_CW8)
        return gpu_trace<EVR_GPU_LAYOUT_CW8>(&o->a->view, &o->a->rs, r, tnear, tfar, f, any,
                                             o->hit);
    if (o->layout == (EVR_GPU_LAYOUT_CW8 | general))
        return gpu_trace<EVR_GPU_LAYOUT_CW8 | general>(&o->a->view, &o->a->rs, r, tnear, tfar, f,
                                                       any, o->hit);
    if (o->layout == (EVR_GPU_LAYOUT_BVH4 | general))
        return gpu_trace<EVR_GPU_LAYOUT_BVH4 | general>(&o->a->view, &o->a->rs, r, tnear, tfar, f,
                                                        any, o->hit);
    return gpu_trace<EVR_GPU_LAYOUT_BVH4>(&o->a->view, &o->a->rs, r, tnear, tfar, f, any, o->hit);
#else
    (void)o, (void)r, (void)tnear, (void)tfar, (void)f, (void)any;
    return 0;
#endif
}

EVR_HD static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar,
                                      float f)
{
    return evr_occlusion_trace(o, r, tnear, tfar, f, 1);
}

/* core/path.h's closest-hit query for the rays after the primary hit, the same traversal. */
EVR_HD static inline int evr_closest(struct evr_occlusion *o, evr_ray r, float tnear, float tfar,
                                     float f, evr_hit *h)
{
    if (!evr_occlusion_trace(o, r, tnear, tfar, f, 0)) return 0;
    h->t = o->hit->t;
    h->u = o->hit->u;
    h->v = o->hit->v;
    h->prim = o->hit->prim;
    h->inst = o->hit->instance;
    return 1;
}

#include "core/path.h"

/* Direct light of one sample, as sample_intensity in cpu/cpu_backend.c, with our traversal; 0 on a
 * miss (returns false), else the surface met, its instance and the ray's origin for the gather. */
template <int LAYOUT>
__device__ static bool gpu_sample_direct(const kernel_args &a, const evr_m34 *pose, int x, int y,
                                         float f, unsigned *rays, float *t_hit, float hint,
                                         float *direct, evr_surface *s, int *inst, evr_v3 *cam_org,
                                         int *deep)
{
    const evr_render_scene *rs = &a.rs;
    evr_ray ray = evr_camera_ray(&rs->camera, pose, (float)x + 0.5f, (float)y + 0.5f);
    evr_gpu_hit hit;
    (*rays)++;
    *t_hit = INFINITY;
    *direct = 0.0f;
    *deep = 0;
    /* temporal coherence: the pixel's last hit distance (hint) bounds the search first; the
     * closest hit below that bound is the closest hit, and finding none, the ray is traced again
     * unbounded: the same hit either way */
    const float tf = hint < 1e30f ? hint * 1.0001f + 1e-6f : 1e30f;
    if (a.static_hits && a.camera_static) {
        /* the camera ray's hit in the static group is kept per pixel: the other groups are
         * searched for a nearer one only (evr_trace_closest_groups) */
        const gpu_static_hit sh = a.static_hits[y * a.width + x];
        const float ts = sh.instance >= 0 ? sh.t : 1e30f;
        if (!gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, fminf(tf, ts), f, 0, &hit,
                               EVR_GROUPS_MOVING) &&
            (tf >= ts ||
             !gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, ts, f, 0, &hit, EVR_GROUPS_MOVING))) {
            if (sh.instance < 0) return false;
            hit.t = sh.t;
            hit.u = sh.u;
            hit.v = sh.v;
            hit.prim = sh.prim;
            hit.instance = sh.instance;
        }
    } else if (!gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, tf, f, 0, &hit) &&
               (tf >= 1e30f || !gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, 1e30f, f, 0, &hit))) {
        return false;
    }
    *t_hit = hit.t;
    *inst = hit.instance;
    *cam_org = ray.org;
    evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[hit.instance].track), f);
    evr_surface_at(rs, hit.instance, hit.prim, hit.u, hit.v, &xf, f, ray, hit.t,
                   evr_camera_cone(&rs->camera, hit.t), s);
    struct evr_occlusion occ;
    occ.a = &a;
    occ.layout = LAYOUT;
    occ.hit = &hit;
    float acc[3];
    int dp = 0;
    evr_shade_direct_sum(rs, s, evr_v3_scale(ray.dir, -1.0f), f, &occ, rays, acc);
    *direct = evr_path_intensity(rs, s, ray.dir, *t_hit, acc, &occ, f,
                                 a.plan->cache ? a.plan : nullptr, rays, &dp);
    *deep = dp;
    return true;
}

/* Intensity of one sample; GI: plus the indirect light gathered from the segment's photons (memo:
 * the pixel's last gather). direct (may be NULL): the direct light alone; id (may be NULL): the
 * sample's event id (evr_event.id: 1 + the instance hit, 0 none). */
template <int LAYOUT, int GI>
__device__ static float gpu_sample(const kernel_args &a, const evr_m34 *pose, int x, int y, float f,
                                   unsigned *rays, float *t_hit, gi_memo *memo,
                                   float hint = INFINITY, float *direct = nullptr,
                                   int *deep = nullptr, unsigned *id = nullptr)
{
    evr_surface s;
    int inst = 0;
    evr_v3 org;
    float out;
    int dp = 0;
    if (deep) *deep = 0;
    if (id) *id = 0;
    if (!gpu_sample_direct<LAYOUT>(a, pose, x, y, f, rays, t_hit, hint, &out, &s, &inst, &org, &dp))
        return 0.0f;
    if (id) *id = (unsigned)inst + 1u;
    if (deep) *deep = dp;
    if (direct) *direct = out;
    if (GI) out += gi_indirect(a.gi, &a.rs, inst, &s, org, x, y, f, memo);
    return out;
}

__device__ static unsigned long long pack_event(const kernel_args &a, long long t_abs_us, int x,
                                                int y, int p)
{
    long long t_us = t_abs_us - a.base_us;
    return ((unsigned long long)t_us << (1 + a.xbits + a.ybits)) |
           ((unsigned long long)y << (1 + a.xbits)) | ((unsigned long long)x << 1) |
           (unsigned long long)p;
}

/* The pixel's state: all of it for the sensor kernel, the ideal model's part (and the cache of
 * change-driven sampling) for the ideal kernel. */
template <int SENSOR>
__device__ __forceinline__ void load_state(const kernel_args &a, int pix, evr_pixel_state &st)
{
    if (SENSOR) {
        st = a.state_in[pix];
    } else {
        const evr_pixel_state *in = &a.state_in[pix];
        st.ref = in->ref;
        st.l_prev = in->l_prev;
        st.t_prev = in->t_prev;
        st.refr_end = in->refr_end;
        st.intensity = in->intensity;
        st.started = in->started;
        st.blind = in->blind;
        st.cache_dist = in->cache_dist;
    }
}

template <int SENSOR>
__device__ __forceinline__ void store_state(const kernel_args &a, int pix,
                                            const evr_pixel_state &st)
{
    if (SENSOR) {
        a.state_out[pix] = st;
    } else {
        evr_pixel_state *out = &a.state_out[pix];
        out->ref = st.ref;
        out->l_prev = st.l_prev;
        out->t_prev = st.t_prev;
        out->refr_end = st.refr_end;
        out->intensity = st.intensity;
        out->started = st.started;
        out->blind = st.blind;
        out->cache_dist = st.cache_dist;
    }
    if (a.intensity) a.intensity[pix] = st.intensity;
}

/* A launch's pixel before its samples: its state and (sensor kernel) its own parameters. Returns
 * its sample phase; an inactive lane (which still takes part in warp votes) gets a reset state. */
template <int SENSOR>
__device__ __forceinline__ float pixel_begin(const kernel_args &a, bool active, int pix, int x,
                                             int y, evr_pixel_state &st, evr_pixel_params &own)
{
    evr_pixel_reset(&st);
    if (SENSOR) own = *a.sensor;
    if (!active) return 0.0f;
    load_state<SENSOR>(a, pix, st);
    if (SENSOR)
        evr_pixel_params_at(a.sensor, x, y, &own); /* fixed-pattern thresholds, leak, noise */
    return a.phase[pix];
}

/* core/pixel_flow.h's event sink: the segment's event keys, appended with warp-aggregated
 * atomics (every lane of the warp pushes together). */
struct evr_event_sink {
    const kernel_args *a;
    unsigned lane;
    unsigned id; /* the sample's event id */
};

EVR_HD static inline int evr_event_sink_push(struct evr_event_sink *k, int has, long long t_us,
                                             int x, int y, int polarity)
{
#ifdef __CUDA_ARCH__
    const kernel_args &a = *k->a;
    unsigned mask = __ballot_sync(0xffffffffu, has);
    if (!mask) return 0;
    unsigned leader = (unsigned)__ffs(mask) - 1u, base = 0;
    if (k->lane == leader) base = atomicAdd(a.count, (unsigned)__popc(mask));
    base = __shfl_sync(0xffffffffu, base, leader);
    if (has) {
        unsigned idx = base + (unsigned)__popc(mask & ((1u << k->lane) - 1u));
        if (t_us < a.base_us || t_us - a.base_us >= a.span_us)
            atomicAdd(&a.counters[CTR_KEY_RANGE], 1ull); /* collect fails */
        else if (idx < a.capacity) {                     /* else: re-run */
            a.keys[idx] = pack_event(a, t_us, x, y, polarity);
            if (a.ids) a.ids[idx] = (uint16_t)k->id;
        }
    }
    return 1;
#else
    (void)k, (void)has, (void)t_us, (void)x, (void)y, (void)polarity;
    return 0;
#endif
}

/* One sample (intensity at t seconds from the segment's start; event_id: its id) through the
 * pixel model (core/pixel_flow.h); its events are appended with warp-aggregated atomics. Every
 * lane of the warp calls it together; live: this lane has a sample. */
template <int SENSOR>
__device__ __forceinline__ void
pixel_sample_at(const kernel_args &a, evr_pixel_state &st, const evr_pixel_params &own, bool live,
                float t, float intensity, int x, int y, unsigned lane, unsigned event_id)
{
    evr_pixel_ideal id; /* the ideal kernel's parameters, from the launch's arguments */
    id.log_floor = a.log_floor;
    id.pos_thres = a.pos_thres;
    id.neg_thres = a.neg_thres;
    id.refractory = a.refractory;
    struct evr_event_sink k;
    k.a = &a;
    k.lane = lane;
    k.id = event_id;
    evr_pixel_sample_events(&st, &own, id, SENSOR, live, t, intensity, a.t0, x, y, &k);
}

/* The same at normalized segment time f (uniform sampling). */
template <int SENSOR>
__device__ __forceinline__ void
pixel_sample(const kernel_args &a, evr_pixel_state &st, const evr_pixel_params &own, bool live,
             float f, float intensity, int x, int y, unsigned lane, unsigned id)
{
    pixel_sample_at<SENSOR>(a, st, own, live, f * a.dt, intensity, x, y, lane, id);
}

/* Adds the warp's rays and traced samples to the segment's counters. */
__device__ __forceinline__ void add_counts(const kernel_args &a, unsigned lane, unsigned rays,
                                           unsigned traced)
{
    unsigned long long r = rays, ts = traced;
    for (int o = 16; o > 0; o >>= 1) {
        r += __shfl_down_sync(0xffffffffu, r, o);
        ts += __shfl_down_sync(0xffffffffu, ts, o);
    }
    if (lane == 0 && r) atomicAdd(&a.counters[CTR_RAYS], r);
    if (lane == 0 && ts) atomicAdd(&a.counters[CTR_TRACED], ts);
}

/* Thread i of a launch over every pixel in warp tiles (TILE_W, cuda_args.cuh): its pixel; false
 * for a lane outside the image. */
__device__ __forceinline__ bool tiled_pixel(int i, int w, int h, int *pix, int *x, int *y)
{
    const int warp = i >> 5, lane = i & 31, tiles_x = (w + TILE_W - 1) / TILE_W;
    *x = (warp % tiles_x) * TILE_W + lane % TILE_W;
    *y = (warp / tiles_x) * TILE_H + lane / TILE_W;
    const bool in = *x < w && *y < h;
    *pix = in ? *y * w + *x : 0;
    if (!in) *x = *y = 0;
    return in;
}

/* Thread threadIdx of a launch over every pixel, or over the skip kernel's list of pixels that
 * trace: its pixel, or none (active false; such threads still take part in warp votes). Returns
 * false when the whole block is past the pixels (the block returns). */
struct launch_pixel {
    int i, pix, x, y;
    bool active;
    bool indirect_only; /* listed by the skip kernel with its samples made (LIST_INDIRECT_ONLY) */
    unsigned lane;
};
__device__ __forceinline__ bool launch_pixel_of(const kernel_args &a, launch_pixel *p)
{
    p->i = blockIdx.x * blockDim.x + threadIdx.x;
    p->lane = threadIdx.x & 31u;
    p->indirect_only = false;
    if (!a.list) { /* every pixel, in warp tiles */
        p->active = tiled_pixel(p->i, a.width, a.height, &p->pix, &p->x, &p->y);
        return true;
    }
    const int n = (int)*a.list_count;
    if ((int)(blockIdx.x * blockDim.x) >= n) return false;
    p->active = p->i < n;
    const unsigned e = p->active ? (unsigned)a.list[p->i] : 0u;
    p->indirect_only = (e & LIST_INDIRECT_ONLY) != 0u;
    p->pix = (int)(e & ~LIST_INDIRECT_ONLY);
    p->x = p->active ? p->pix % a.width : 0;
    p->y = p->active ? p->pix / a.width : 0;
    return true;
}

#endif
