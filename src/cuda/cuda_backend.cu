/* CUDA backend: the same simulation as the CPU backend on an NVIDIA GPU.
 *
 * Per segment: the host builds the top-level BVH over the instances (bounds over the whole
 * segment) and uploads it with the motion keys; one kernel runs every pixel's samples of the
 * segment (one thread per pixel, its samples in a loop): camera ray, our own BVH traversal with
 * motion transforms (cuda/gpu_traverse.h), shading and the pixel model from src/core, the very
 * functions the CPU backend runs. Events are appended with warp-aggregated atomics as 64-bit
 * keys (time, y, x, polarity), sorted on the GPU with CUB's radix sort and copied to pinned host
 * memory on a second stream while the next segments render: NSLOT segments are in flight, so that
 * the GPU has work queued while the host takes in and writes earlier ones (render times vary
 * widely from segment to segment).
 *
 * Pixel states live in a ring of NRING device arrays: segment i reads ring[i % NRING] and writes
 * ring[(i + 1) % NRING], so when segment i's event buffer overflows (found at collect, when the
 * segments after it may already have rendered) segment i can be rendered again from its
 * unchanged input with a larger buffer: events are never dropped. */
#include <cuda_runtime.h>
#include <cub/device/device_radix_sort.cuh>

extern "C" {
#include "backend.h"
#include "cuda/cuda_backend.h"
#include "cuda/gpu_bvh.h"
#include "prep/gi_params.h"
#include "prep/photon_emitters.h"
}
#include "core/rng.h"
#include "core/shade_hit.h"
#include "core/pixel_flow.h"
#include "core/skip.h"
#include "core/adaptive.h"
#include "cuda/gpu_traverse.h"
#include "host_clock.h"
#include "par_pool.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define CK(call)                                                                                          \
    do {                                                                                                  \
        cudaError_t e_ = (call);                                                                          \
        if (e_ != cudaSuccess) {                                                                          \
            snprintf(err->msg, sizeof err->msg, "CUDA: %s failed: %s", #call, cudaGetErrorString(e_));   \
            return e_ == cudaErrorMemoryAllocation ? EVR_ERR_NOMEM : EVR_ERR_BACKEND;                     \
        }                                                                                                 \
    } while (0)

#define BLOCK 128
#ifndef NSLOT
#define NSLOT 4                 /* segments in flight: 4 measured 5-6% faster than 3 and than 6 (H100, eye 30 s) */
#endif
#define NRING (NSLOT + 1)       /* pixel-state arrays: the in-flight segments' inputs and the last output */
#ifndef MIN_BLOCKS
#define MIN_BLOCKS 6   /* 80 registers: measured faster than 128 (occupancy) on the H100 */
#endif
#ifndef MIN_BLOCKS_GI
#define MIN_BLOCKS_GI 4   /* with global illumination: 128 registers (the gather's state) */
#endif

/* Everything one launch reads, by value. */
/* A camera ray's nearest hit among the static group's triangles (instance -1: none). */
struct gpu_static_hit {
    float t, u, v;
    uint32_t prim;
    int32_t instance;
};

struct kernel_args {
    evr_render_scene rs;           /* device pointers */
    evr_gpu_scene_view view;       /* device pointers */
    const evr_pixel_state *state_in;
    evr_pixel_state *state_out;
    const float *phase;
    float *intensity;              /* NULL unless the segment's intensities are wanted */
    float pos_thres, neg_thres, refractory, log_floor;   /* the ideal pixel's parameters */
    int width, height, samples;
    float dt;                      /* segment length, seconds */
    double t0;                     /* segment start, seconds */
    long long base_us;             /* event keys hold t_us - base_us */
    int camera_static;
    unsigned long long *keys;      /* event keys */
    unsigned int capacity;
    unsigned int *count;
    unsigned long long *rays;      /* [0] rays traced, [1] pixels that reused their intensity, [2] samples traced */
    /* change-driven sampling: the segment's plan; with reuse, the skip kernel lists the pixels
     * that must trace (list, list_count) and the render kernel runs those only */
    const evr_skip_plan *plan;
    int *list;
    unsigned int *list_count;
    /* the sensor kernel's full parameters stay in device memory: this struct is copied per
     * thread (the traversal takes its address), so it is kept small, and this comes last so
     * that the ideal kernel sees the same layout as before the sensor model */
    const evr_pixel_params *sensor;
    const struct gpu_gi_view *gi;  /* global illumination (gpu_gi.cuh), NULL when off */
    int coherence;                 /* primary rays start with tfar just past the pixel's last hit */
    int xbits, ybits;              /* event keys: bits of x and of y (event_key_bits) */
    long long span_us;             /* event keys hold t_us - base_us in [0, span_us) */
    /* per pixel, its camera ray's hit in the static group while the camera holds still (NULL:
     * not this segment): primary rays search the other groups only */
    const gpu_static_hit *static_hits;
};


/* One traversal body for primary and shadow rays, not inlined: a kernel with four inlined copies
 * (two queries, two node layouts) stalled on instruction-cache misses (measured with ncu). */
template <int LAYOUT>
__device__ __noinline__ int gpu_trace(const evr_gpu_scene_view *view, const evr_render_scene *rs, evr_ray ray, float tnear,
                                      float tfar, float f, int any, evr_gpu_hit *hit, int groups = EVR_GROUPS_ALL)
{
    if (view->num_top_nodes == 0) return 0;
    if (LAYOUT == EVR_GPU_LAYOUT_CW8) return evr__trace8(view, rs, ray, tnear, tfar, f, any, hit, groups);
    return evr__trace4(view, rs, ray, tnear, tfar, f, any, hit, groups);
}

/* A warp-aggregated append: every lane of the warp calls it; the lanes with `want` get
 * consecutive slots after *count, claimed with one atomic for the warp. Returns this lane's slot
 * (meaningless without want). */
__device__ __forceinline__ unsigned warp_append(unsigned *count, bool want)
{
    const unsigned mask = __ballot_sync(0xffffffffu, want), lane = threadIdx.x & 31u;
    if (!mask) return 0;
    const unsigned leader = (unsigned)__ffs(mask) - 1u;
    unsigned base = 0;
    if (lane == leader) base = atomicAdd(count, (unsigned)__popc(mask));
    base = __shfl_sync(0xffffffffu, base, leader);
    return base + (unsigned)__popc(mask & ((1u << lane) - 1u));
}

#include "cuda/gpu_gi.cuh"

/* core/shade_hit.h's shadow-ray query: our traversal in the launch's node layout (a constant
 * once inlined into a kernel of that layout); hit is scratch space the query may write. */
struct evr_occlusion {
    const kernel_args *a;
    int layout;
    evr_gpu_hit *hit;
};

EVR_HD static inline int evr_occluded(struct evr_occlusion *o, evr_ray r, float tnear, float tfar, float f)
{
#ifdef __CUDA_ARCH__
    if (o->layout == EVR_GPU_LAYOUT_CW8)
        return gpu_trace<EVR_GPU_LAYOUT_CW8>(&o->a->view, &o->a->rs, r, tnear, tfar, f, 1, o->hit);
    return gpu_trace<EVR_GPU_LAYOUT_BVH4>(&o->a->view, &o->a->rs, r, tnear, tfar, f, 1, o->hit);
#else
    (void)o, (void)r, (void)tnear, (void)tfar, (void)f;
    return 0;
#endif
}

/* Direct light of one sample, as sample_intensity in cpu/cpu_backend.c, with our traversal; 0 on a
 * miss (returns false), else the surface met, its instance and the ray's origin for the gather. */
template <int LAYOUT>
__device__ static bool gpu_sample_direct(const kernel_args &a, const evr_m34 *pose, int x, int y, float f, unsigned *rays,
                                         float *t_hit, float hint, float *direct, evr_surface *s, int *inst, evr_v3 *cam_org)
{
    const evr_render_scene *rs = &a.rs;
    evr_ray ray = evr_camera_ray(&rs->camera, pose, (float)x + 0.5f, (float)y + 0.5f);
    evr_gpu_hit hit;
    (*rays)++;
    *t_hit = INFINITY;
    *direct = 0.0f;
    /* temporal coherence: the pixel's last hit distance (hint) bounds the search first; the
     * closest hit below that bound is the closest hit, and finding none, the ray is traced again
     * unbounded: the same hit either way */
    const float tf = hint < 1e30f ? hint * 1.0001f + 1e-6f : 1e30f;
    if (a.static_hits && a.camera_static) {
        /* the camera ray's hit in the static group is kept per pixel: the other groups are
         * searched for a nearer one only (evr_trace_closest_groups) */
        const gpu_static_hit sh = a.static_hits[y * a.width + x];
        const float ts = sh.instance >= 0 ? sh.t : 1e30f;
        if (!gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, fminf(tf, ts), f, 0, &hit, EVR_GROUPS_MOVING) &&
            (tf >= ts || !gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, ts, f, 0, &hit, EVR_GROUPS_MOVING))) {
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
    evr_surface_at(rs, hit.instance, hit.prim, hit.u, hit.v, &xf, ray, hit.t, s);
    struct evr_occlusion occ;
    occ.a = &a;
    occ.layout = LAYOUT;
    occ.hit = &hit;
    *direct = evr_shade_hit(rs, s, evr_v3_scale(ray.dir, -1.0f), f, &occ, rays);
    return true;
}

/* Intensity of one sample; GI: plus the indirect light gathered from the segment's photons (memo:
 * the pixel's last gather). direct (may be NULL): the direct light alone. */
template <int LAYOUT, int GI>
__device__ static float gpu_sample(const kernel_args &a, const evr_m34 *pose, int x, int y, float f, unsigned *rays,
                                  float *t_hit, gi_memo *memo, float hint = INFINITY, float *direct = nullptr)
{
    evr_surface s;
    int inst = 0;
    evr_v3 org;
    float out;
    if (!gpu_sample_direct<LAYOUT>(a, pose, x, y, f, rays, t_hit, hint, &out, &s, &inst, &org)) return 0.0f;
    if (direct) *direct = out;
    if (GI) out += gi_indirect(a.gi, &a.rs, inst, &s, org, x, y, f, memo);
    return out;
}

__device__ static unsigned long long pack_event(const kernel_args &a, long long t_abs_us, int x, int y, int p)
{
    long long t_us = t_abs_us - a.base_us;
    return ((unsigned long long)t_us << (1 + a.xbits + a.ybits)) | ((unsigned long long)y << (1 + a.xbits)) |
           ((unsigned long long)x << 1) | (unsigned long long)p;
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
__device__ __forceinline__ void store_state(const kernel_args &a, int pix, const evr_pixel_state &st)
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
__device__ __forceinline__ float pixel_begin(const kernel_args &a, bool active, int pix, int x, int y, evr_pixel_state &st,
                                             evr_pixel_params &own)
{
    evr_pixel_reset(&st);
    if (SENSOR) own = *a.sensor;
    if (!active) return 0.0f;
    load_state<SENSOR>(a, pix, st);
    if (SENSOR) evr_pixel_params_at(a.sensor, x, y, &own);   /* fixed-pattern thresholds, leak, noise */
    return a.phase[pix];
}

/* core/pixel_flow.h's event sink: the segment's event keys, appended with warp-aggregated
 * atomics (every lane of the warp pushes together). */
struct evr_event_sink {
    const kernel_args *a;
    unsigned lane;
};

EVR_HD static inline int evr_event_sink_push(struct evr_event_sink *k, int has, long long t_us, int x, int y, int polarity)
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
        if (t_us < a.base_us || t_us - a.base_us >= a.span_us) atomicAdd(&a.rays[KEY_RANGE], 1ull);   /* collect fails */
        else if (idx < a.capacity) a.keys[idx] = pack_event(a, t_us, x, y, polarity);   /* else: re-run */
    }
    return 1;
#else
    (void)k, (void)has, (void)t_us, (void)x, (void)y, (void)polarity;
    return 0;
#endif
}

/* One sample (intensity at t seconds from the segment's start) through the pixel model
 * (core/pixel_flow.h); its events are appended with warp-aggregated atomics. Every lane of the
 * warp calls it together; live: this lane has a sample. */
template <int SENSOR>
__device__ __forceinline__ void pixel_sample_at(const kernel_args &a, evr_pixel_state &st, const evr_pixel_params &own,
                                                bool live, float t, float intensity, int x, int y, unsigned lane)
{
    evr_pixel_ideal id;   /* the ideal kernel's parameters, from the launch's arguments */
    id.log_floor = a.log_floor;
    id.pos_thres = a.pos_thres;
    id.neg_thres = a.neg_thres;
    id.refractory = a.refractory;
    struct evr_event_sink k;
    k.a = &a;
    k.lane = lane;
    evr_pixel_sample_events(&st, &own, id, SENSOR, live, t, intensity, a.t0, x, y, &k);
}

/* The same at normalized segment time f (uniform sampling). */
template <int SENSOR>
__device__ __forceinline__ void pixel_sample(const kernel_args &a, evr_pixel_state &st, const evr_pixel_params &own,
                                             bool live, float f, float intensity, int x, int y, unsigned lane)
{
    pixel_sample_at<SENSOR>(a, st, own, live, f * a.dt, intensity, x, y, lane);
}

/* Adds the warp's rays and traced samples to the segment's counters (a.rays[0] and a.rays[2]). */
__device__ __forceinline__ void add_counts(const kernel_args &a, unsigned lane, unsigned rays, unsigned traced)
{
    unsigned long long r = rays, ts = traced;
    for (int o = 16; o > 0; o >>= 1) {
        r += __shfl_down_sync(0xffffffffu, r, o);
        ts += __shfl_down_sync(0xffffffffu, ts, o);
    }
    if (lane == 0 && r) atomicAdd(a.rays, r);
    if (lane == 0 && ts) atomicAdd(&a.rays[2], ts);
}

/* Launches over every pixel give each warp a tile of TILE_W x TILE_H pixels (8 x 4) rather than a
 * run of 32 along a row: the warp's rays, and the cells its pixels' gathers read, then lie close
 * together in both directions. Edge tiles have lanes outside the image (inactive). The skip
 * kernel lists the pixels that trace in this order too. */
#ifndef TILE_W
#define TILE_W 8
#endif
#define TILE_H (32 / TILE_W)
static unsigned tiled_threads(int w, int h)
{
    return (unsigned)((w + TILE_W - 1) / TILE_W) * (unsigned)((h + TILE_H - 1) / TILE_H) * 32u;
}
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

/* Every pixel's camera ray against the static group alone (the camera holds still). */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK) static_hits_kernel(kernel_args a, gpu_static_hit *out)
{
    const int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= a.width * a.height) return;
    const int x = i % a.width, y = i / a.width;
    const evr_m34 pose = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray = evr_camera_ray(&a.rs.camera, &pose, (float)x + 0.5f, (float)y + 0.5f);
    evr_gpu_hit h;
    gpu_static_hit sh;
    if (gpu_trace<LAYOUT>(&a.view, &a.rs, ray, 0.0f, 1e30f, 0.0f, 0, &h, EVR_GROUPS_STATIC)) {
        sh.t = h.t;
        sh.u = h.u;
        sh.v = h.v;
        sh.prim = h.prim;
        sh.instance = h.instance;
    } else {
        sh.t = sh.u = sh.v = 0.0f;
        sh.prim = 0;
        sh.instance = -1;
    }
    out[i] = sh;
}

/* A listed pixel whose direct light stays while its indirect light changes (deferred gathers):
 * the skip kernel makes its samples, the trace kernel leaves it alone. */
#define LIST_INDIRECT_ONLY 0x80000000u

/* Change-driven sampling, first pass: a pixel that keeps its cached intensity runs its samples
 * through the pixel model here (no rays); the others are listed for the render kernel. With
 * deferred gathers (d.requests set), a pixel whose rays meet nothing that moves but whose gather
 * window saw photons change gets here what gi_trace_kernel would make of it, without its rays:
 * its first sample settles on its last traced sample's direct light and surface point (the
 * same rays meet the same still surfaces: the same bits), and a gather request with the start
 * known; it is listed for the gather and pixel kernels only. */
template <int SENSOR>
__global__ void __launch_bounds__(BLOCK) skip_kernel(kernel_args a, gi_deferred d)
{
    int pix, x, y;
    const bool active = tiled_pixel(blockIdx.x * blockDim.x + threadIdx.x, a.width, a.height, &pix, &x, &y);
    const unsigned lane = threadIdx.x & 31u;
    evr_pixel_state st;
    evr_pixel_params own;
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    bool skip = false, indirect_only = false;
    float cache = -1.0f;
    if (active) {
        evr_m34 pose = evr_rs_camera_pose(&a.rs, 0.0f);
        evr_ray ray = evr_camera_ray(&a.rs.camera, &pose, (float)x + 0.5f, (float)y + 0.5f);
        skip = evr_skip_pixel(&a.rs, a.plan, st.started, st.cache_dist, ray);
        /* global illumination: a pixel whose gather window saw photons change over this segment
         * or the last traces (its indirect light moves, or moved after its last sample) */
        if (skip && a.gi &&
            evr_photon_window_changed(a.gi->sat, a.gi->end.width, a.gi->end.height, a.gi->end.margin, a.gi->window, x, y)) {
            skip = false;
            /* as the trace kernel would settle it: its hit the cached one, the cache kept */
            cache = evr_skip_cache_after_trace(&a.rs, a.plan, ray, st.cache_dist);
            indirect_only = d.requests && a.gi->ends_in && a.gi->ends_in[pix].g.dist >= 0.0f && cache >= 0.0f;
        }
    }
    const unsigned at = warp_append(a.list_count, active && !skip);
    if (active && !skip) a.list[at] = indirect_only ? (unsigned)pix | LIST_INDIRECT_ONLY : (unsigned)pix;
    const unsigned r = warp_append(d.count, indirect_only);   /* a request with the start known */
    if (indirect_only) {
        const gi_end *e = &a.gi->ends_in[pix];
        d.requests[r].g = e->g;
        d.requests[r].pix = pix;
        d.requests[r].ls = e->le;
        d.direct[at] = e->direct;   /* sample 0's entry */
        d.req[at] = r;
        d.traced[at] = 1;
        d.cache_dist[at] = cache;
    }
    const unsigned skipped = __ballot_sync(0xffffffffu, skip);
    if (!skipped) return;   /* the whole warp */
    if (lane == 0) atomicAdd(&a.rays[1], (unsigned long long)__popc(skipped));
    const float kept = st.intensity;
    for (int k = 0; k < a.samples; k++)
        pixel_sample<SENSOR>(a, st, own, skip, ((float)k + phi) / (float)a.samples, kept, x, y, lane);
    if (skip) {
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.gi && a.gi->ends_out) a.gi->ends_out[pix] = a.gi->ends_in[pix];   /* its last gather holds */
    }
}

/* Thread threadIdx of a launch over every pixel, or over the skip kernel's list of pixels that
 * trace: its pixel, or none (active false; such threads still take part in warp votes). Returns
 * false when the whole block is past the pixels (the block returns). */
struct launch_pixel {
    int i, pix, x, y;
    bool active;
    bool indirect_only;   /* listed by the skip kernel with its samples made (LIST_INDIRECT_ONLY) */
    unsigned lane;
};
__device__ __forceinline__ bool launch_pixel_of(const kernel_args &a, launch_pixel *p)
{
    p->i = blockIdx.x * blockDim.x + threadIdx.x;
    p->lane = threadIdx.x & 31u;
    p->indirect_only = false;
    if (!a.list) {   /* every pixel, in warp tiles */
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

/* SENSOR: 1 for the full sensor model of core/pixel.h (mismatch, bandwidth, leak, noise,
 * timestamps), 0 for the ideal sensor: then the kernel runs the ideal model's own functions on the
 * ideal part of the state and compiles to the same code as before the sensor model existed (same
 * size and layout: measured on an H100, the same time on the eye and square demos; an earlier
 * version a few instructions longer was 40% slower on the square through instruction fetch).
 * With a list (change-driven sampling), thread i renders pixel list[i]. */
template <int LAYOUT, int SENSOR, int GI>
__global__ void __launch_bounds__(BLOCK, GI ? MIN_BLOCKS_GI : MIN_BLOCKS) render_kernel(kernel_args a)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    evr_pixel_state st;
    evr_pixel_params own;                /* the sensor kernel's parameters of this pixel */
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    unsigned rays = 0, traced = 0;
    float t_hit = INFINITY, direct = 0.0f;
    bool tracing = active;
    gi_memo memo;
    memo.valid = false;
    evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 = evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    int last_span = -1;   /* the still span of the last traced sample */
    for (int k = 0; k < a.samples; k++) {
        float f = ((float)k + phi) / (float)a.samples, intensity = st.intensity;   /* kept when settled or held */
        const int span = evr_skip_still_span(a.plan, f);
        if (tracing && !evr_skip_held(a.plan, span, last_span)) {
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            intensity = gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &t_hit, &memo, a.coherence ? t_hit : INFINITY, &direct);
            traced++;
            last_span = span;
        } else if (GI && t_hit < INFINITY) {   /* settled or held on a surface: its direct light, its gathers at f */
            intensity = direct + evr_gi_lerp(memo.ls, memo.le, f);
        }
        pixel_sample<SENSOR>(a, st, own, active, f, intensity, x, y, lane);
        if (k == 0 && tracing) {
            /* settle: the first sample's rays meet nothing that moves in the segment, so every
             * sample sees the same triangles: keep its intensity (GI: its direct light) */
            float c = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit);
            if (c >= 0.0f) {
                tracing = false;
                st.cache_dist = c;
            }
        }
    }
    if (active) {
        if (tracing) st.cache_dist = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit);
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
    }
    add_counts(a, lane, rays, traced);
}

/* Adaptive sampling's own arguments: a second kernel parameter, so that kernel_args (and the
 * uniform kernels) keep their layout. */
struct adapt_args {
    const float *next_in;          /* each pixel's next sample time, segment-relative (a ring as the states) */
    float *next_out;
    const evr_adapt_plan *plan;    /* the segment's motion bounds (device memory) */
    evr_adapt_params p;
};

/* Adaptive sampling (core/adaptive.h), one thread per pixel, the same steps as the CPU backend's
 * render_tile_adaptive: the pixel traces at its scheduled times; a sample that changed too much
 * is held back on the pixel's stack while the interval before it is refined; every sample goes
 * through the pixel model in time order. Lanes run their own schedules; the event appends stay
 * warp-synchronous (every lane calls pixel_sample_at each round). */
template <int LAYOUT, int SENSOR, int GI>
__global__ void __launch_bounds__(BLOCK) adapt_kernel(kernel_args a, adapt_args d)
{
    int pix, x, y;
    const bool active = tiled_pixel(blockIdx.x * blockDim.x + threadIdx.x, a.width, a.height, &pix, &x, &y);
    const unsigned lane = threadIdx.x & 31u;
    evr_pixel_state st;
    evr_pixel_reset(&st);
    evr_pixel_params own = *a.sensor;   /* the run's parameters; per pixel for the sensor kernel */
    const evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 = evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    float t = 0.0f;
    bool need = false;
    if (active) {
        load_state<SENSOR>(a, pix, st);
        if (SENSOR) evr_pixel_params_at(a.sensor, x, y, &own);
        t = evr_adapt_start(&a.rs, &d.p, d.plan, &st, ray0, d.next_in[pix], a.phase[pix], a.dt);
        need = t < a.dt;
    }
    evr_adapt_stack sk;
    sk.n = 0;
    float ct = 0.0f, ci = 0.0f, ch = INFINITY;   /* the candidate sample: time, intensity, hit distance */
    bool cand = false;
    unsigned rays = 0, taken = 0;
    gi_memo memo;
    memo.valid = false;
    while (__any_sync(0xffffffffu, need || cand)) {
        if (need) {
            const float f = t / a.dt;
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            ci = gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &ch, &memo);
            ct = t;
            cand = true;
            need = false;
            taken++;
        }
        bool consume = false;
        float step = 0.0f;
        int moving = 0;
        if (cand) {   /* held back (trace t first) or taken */
            consume = evr_adapt_candidate(&a.rs, &d.p, d.plan, &st, &own, ray0, &sk, ct, ci, ch, &t, &step, &moving);
            if (!consume) {
                need = true;
                cand = false;
            }
        }
        pixel_sample_at<SENSOR>(a, st, own, consume, ct, ci, x, y, lane);
        if (consume && !evr_adapt_taken(&d.p, &sk, step, moving, a.dt, &ct, &ci, &ch, &t)) {
            cand = false;   /* none held back: t is the next to trace */
            need = t < a.dt;
        }
    }
    if (active) {
        d.next_out[pix] = t - a.dt;
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
    }
    add_counts(a, lane, rays, taken);
}

/* Intensity frames: frame k is every pixel's intensity at normalized segment time frame_f[k], one
 * sample through the pixel centre (the same gpu_sample as the segment's samples), written to
 * frames[k * npix + pix]. A kernel of its own so that the render kernel and the pixel states are
 * untouched: events are the same with or without frames. Its rays are not counted. */
template <int LAYOUT, int GI>
__global__ void __launch_bounds__(BLOCK) frame_kernel(kernel_args a, const float *frame_f, int num_frames, float *frames)
{
    const int npix = a.width * a.height;
    const int pix = blockIdx.x * blockDim.x + threadIdx.x;
    if (pix >= npix) return;
    const int x = pix % a.width, y = pix / a.width;
    unsigned rays = 0;
    gi_memo memo;
    memo.valid = false;
    for (int k = 0; k < num_frames; k++) {
        const float f = frame_f[k];
        evr_m34 pose = evr_rs_camera_pose(&a.rs, f);
        float t_hit;
        frames[(size_t)k * (size_t)npix + (size_t)pix] = gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &t_hit, &memo);
    }
}

#include "cuda/gpu_gi_deferred.cuh"

/* A buffer that grows (contents not kept), in device memory or in pinned host memory. */
struct device_memory {
    static cudaError_t alloc(void **p, size_t n) { return cudaMalloc(p, n); }
    static void release(void *p) { cudaFree(p); }
};
struct pinned_memory {
    static cudaError_t alloc(void **p, size_t n) { return cudaMallocHost(p, n); }
    static void release(void *p) { cudaFreeHost(p); }
};

template <typename T, typename M> struct growing_buffer {
    T *p = nullptr;
    size_t cap = 0;
    cudaError_t reserve(size_t n, bool exact = false)
    {
        if (n <= cap) return cudaSuccess;
        size_t c = cap ? cap : 1;
        while (c < n) c *= 2;
        if (exact) c = n;
        release();
        void *q = nullptr;
        cudaError_t e = M::alloc(&q, c * sizeof(T));
        if (e == cudaSuccess) {
            p = (T *)q;
            cap = c;
        }
        return e;
    }
    void release()
    {
        if (p) M::release(p);
        p = nullptr;
        cap = 0;
    }
};
template <typename T> using dbuf = growing_buffer<T, device_memory>;
template <typename T> using hbuf = growing_buffer<T, pinned_memory>;

/* Bits an event key gives x (values 0 .. n - 1). Keys are (time, y, x, polarity) packed with no
 * spare bits, so that the radix sort takes as few 8-bit passes as the segment needs (1280x720:
 * 22 bits of pixel and polarity instead of 33). */
static int event_key_bits(int n)
{
    int b = 1;
    while (b < 16 && (1 << b) < n) b++;
    return b;
}

/* Bits below an event key's time: polarity, x, y (pack_event). */
static int key_time_shift(int width, int height)
{
    return 1 + event_key_bits(width) + event_key_bits(height);
}

/* One segment in flight. */
struct slot {
    int index;
    double t0, t1;
    int camera_static, want_intensity;
    int num_frames;                    /* intensity frames wanted in this segment */
    long long base_us;
    int end_bit;
    hbuf<evr_motion_key> h_keys;
    hbuf<int> h_tracks;                /* offsets then counts */
    dbuf<evr_motion_key> d_keys;
    dbuf<int> d_tracks;
    evr_gpu_top top;                   /* host top level */
    dbuf<evr_gpu_node4> d_top4;
    dbuf<evr_gpu_node8> d_top8;
    dbuf<evr_gpu_inst> d_insts;
    dbuf<unsigned long long> d_keys_ev, d_keys_sorted;
    dbuf<unsigned char> d_sort_temp;
    dbuf<unsigned int> d_count;
    dbuf<unsigned long long> d_rays;   /* rays, pixels skipped */
    dbuf<evr_skip_plan> d_plan;
    hbuf<evr_skip_plan> h_plan;
    dbuf<int> d_list;                  /* pixels that trace (change-driven sampling) */
    dbuf<evr_adapt_plan> d_adapt;      /* adaptive sampling's plan */
    hbuf<evr_adapt_plan> h_adapt;
    int reuse;                         /* the plan lets pixels reuse their intensity */
    dbuf<float> d_intensity;
    hbuf<unsigned int> h_count;
    hbuf<unsigned long long> h_rays;
    hbuf<unsigned long long> h_sorted;
    hbuf<float> h_intensity;
    hbuf<float> h_frame_f;             /* normalized times of the frames */
    dbuf<float> d_frame_f;
    dbuf<float> d_frames;
    hbuf<float> h_frames;
    cudaStream_t copy = nullptr;
    cudaEvent_t framed = nullptr;      /* the frame kernel is done */
    cudaEvent_t started = nullptr, rendered = nullptr, counted = nullptr, sorted = nullptr, copied = nullptr;
    int num_tracks, num_keys;
    /* global illumination: the changed cells, the view the kernels read (which ring buffers) */
    dbuf<uint32_t> d_sat;
    dbuf<uint32_t> d_ch_before, d_ch_base, d_ch_x;   /* the cells that changed (gp.max_photons 0) */
    dbuf<gpu_gi_view> d_gi_view;
    hbuf<gpu_gi_view> h_gi_view;
    hbuf<evr_photon_emitter> h_em;
    dbuf<evr_photon_emitter> d_em;
    hbuf<float> h_cdf;
    dbuf<float> d_cdf;
    cudaEvent_t gi_started = nullptr, gi_done = nullptr;
    int gi_passes;                     /* photon passes run for this segment (0: a still copy) */
    int copying;                       /* the sort and copy of this render's events are queued */
    size_t total;                      /* keys sorted and copied: its own, then those carried in */
    cudaEvent_t sort_from = nullptr;   /* start of the sort (copy stream) */
    int static_gen = -1;               /* the static hits it renders with (cuda_backend.static_gen), -1: none */
};

/* A photon buffer in device memory (gpu_gi.cuh): a ring of them, indexed by segment. */
struct gi_buffer {
    dbuf<evr_photon> slots;
    dbuf<uint32_t> count;
    dbuf<float> gbuf;
    evr_photon_buffer ph;              /* the shape and the device pointers */
};

struct cuda_backend {
    evr_backend base;
    const evr_scene *scene;
    /* every pixel's camera ray in the static group, for a still camera at static_cam (the
     * camera track's key); static_gen counts the times it was made (0: not yet); static_off:
     * never (EVR_NO_STATIC_HITS, for measurements) */
    dbuf<gpu_static_hit> d_static;
    evr_motion_key static_cam;
    int static_gen, static_off;
    evr_par_pool *par;                 /* decodes the sorted keys (NULL: on the main thread) */
    evr_render_host host;
    evr_run_setup setup;
    evr_gpu_bvh bvh;
    int device;
    char device_name[256];
    /* scene on the device */
    dbuf<float> d_floats;                  /* all vertex data */
    dbuf<uint32_t> d_indices;
    dbuf<evr_mesh_view> d_meshes;
    dbuf<evr_material_params> d_materials;
    dbuf<evr_texture_view> d_textures;
    dbuf<float> d_texels;
    dbuf<evr_instance_view> d_instances;
    dbuf<evr_light_view> d_lights;
    dbuf<evr_gpu_node4> d_nodes4;
    dbuf<evr_gpu_node8> d_nodes8;
    dbuf<evr_gpu_tri> d_tris;
    dbuf<evr_pixel_state> d_state[NRING];
    dbuf<float> d_next[NRING];             /* adaptive sampling: next sample times, a ring as d_state */
    dbuf<float> d_phase;
    dbuf<evr_pixel_params> d_sensor;       /* the run's pixel parameters, for the sensor kernel */
    cudaStream_t render = nullptr;
    slot slots[NSLOT];
    int head, queued;
    size_t capacity;                       /* event keys per segment */
    /* the collected segment's sorted keys at or after its emit_before, still on the device
     * (slots[carry_slot].d_keys_sorted from carry_at, carry_n of them, keys on carry_base_us,
     * times carry_t_lo .. carry_t_hi): sorted again with the next segment's (carry_slot -1: none) */
    int carry_slot;
    size_t carry_at, carry_n;
    long long carry_base_us, carry_t_lo, carry_t_hi;
    evr_event_vec scratch;
    /* global illumination (gpu_gi.cuh): the pass's photons and their sort, shared by the slots
     * (one pass at a time on the render stream) */
    int gi, gi_have_prev;
    gi_buffer gi_ring[NRING];              /* segment i ends in gi_ring[i % NRING], starts in the one before */
    dbuf<uint8_t> d_gi_last;               /* per cell: changed over the last segment */
    dbuf<gi_end> d_gi_ends[NRING];         /* deferred gathers: each pixel's last gather, a ring as d_state */
    uint32_t photons;
    evr_photon_params pp;
    evr_gather_params gp;
    evr_photon_emitters em;                /* host: rebuilt per segment */
    dbuf<evr_photon> d_pending;
    dbuf<unsigned long long> d_pkeys, d_pkeys_sorted;
    dbuf<unsigned> d_pvals, d_pvals_sorted, d_pcount;
    dbuf<unsigned char> d_ptemp;
    /* the photons' trails (core/photon.h) and the emitter table of the pass that recorded them */
    dbuf<evr_photon_trail> d_trails;
    dbuf<evr_trail_ray> d_trail_rays;
    dbuf<unsigned> d_todo, d_todo_count;   /* the photons a pass traces when others reuse their trails */
    int trails_valid, trails_off;
    evr_photon_emitters trail_em;
    /* GI with deferred gathers (gpu_gi_deferred.cuh): off when its buffers do not fit, or with
     * adaptive sampling (its kernel gathers inline) */
    int gi_deferred;
    unsigned gather_grid;
    dbuf<float> d_gd_direct, d_gd_cache;
    dbuf<float2> d_gd_lum;
    dbuf<unsigned> d_gd_req, d_gd_count;
    dbuf<int> d_gd_traced, d_gd_newpix;
    dbuf<unsigned long long> d_gd_delta;
    dbuf<gi_request> d_gd_requests;
    /* EVR_TIMELINE=path (hidden, for measurement): per segment, host times (evr_host_seconds) and
     * GPU times (seconds after tl_base, recorded at tl_h0 on the host), written at release */
    FILE *tl;
    cudaEvent_t tl_base;
    double tl_h0;
    struct tl_rec { double sub0, sub1, col0, counted, copied, col1, g_start, g_rendered, g_sort, g_copied; size_t n; } *tl_recs;
    int tl_cap, tl_lost;
};
/* Segment i's timeline record (nullptr: no timeline, or no memory for it, which the file then says). */
static cuda_backend::tl_rec *tl_at(cuda_backend *b, int i)
{
    if (!b->tl || b->tl_lost) return nullptr;
    if (i >= b->tl_cap) {
        int cap = b->tl_cap ? 2 * b->tl_cap : 1024;
        while (cap <= i) cap *= 2;
        void *p = realloc(b->tl_recs, (size_t)cap * sizeof *b->tl_recs);
        if (!p) {
            b->tl_lost = 1;
            return nullptr;
        }
        b->tl_recs = (cuda_backend::tl_rec *)p;
        memset(b->tl_recs + b->tl_cap, 0, (size_t)(cap - b->tl_cap) * sizeof *b->tl_recs);
        b->tl_cap = cap;
    }
    return &b->tl_recs[i];
}

static evr_status upload_scene(cuda_backend *b, evr_error *err)
{
    const evr_scene *s = b->scene;
    size_t nf = 0, ni = 0, nt = 0;
    int i;
    for (i = 0; i < s->num_meshes; i++) {
        const evr_mesh *m = &s->meshes[i];
        nf += (size_t)m->num_vertices * (m->uvs ? 8 : 6);
        ni += (size_t)m->num_triangles * 3;
    }
    for (i = 0; i < s->num_textures; i++) nt += (size_t)s->textures[i].width * s->textures[i].height * 4;
    CK(b->d_floats.reserve(nf + 1));
    CK(b->d_indices.reserve(ni + 1));
    CK(b->d_texels.reserve(nt + 1));
    evr_mesh_view *mv = (evr_mesh_view *)calloc((size_t)s->num_meshes + 1, sizeof *mv);
    evr_texture_view *tv = (evr_texture_view *)calloc((size_t)s->num_textures + 1, sizeof *tv);
    if (!mv || !tv) {
        free(mv);
        free(tv);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    size_t of = 0, oi = 0, ot = 0;
    cudaError_t e = cudaSuccess;
    for (i = 0; i < s->num_meshes && e == cudaSuccess; i++) {
        const evr_mesh *m = &s->meshes[i];
        size_t nv = m->num_vertices;
        mv[i] = b->host.meshes[i];
        e = cudaMemcpy(b->d_floats.p + of, m->positions, nv * 3 * sizeof(float), cudaMemcpyHostToDevice);
        mv[i].positions = b->d_floats.p + of;
        of += nv * 3;
        if (e == cudaSuccess) e = cudaMemcpy(b->d_floats.p + of, m->normals, nv * 3 * sizeof(float), cudaMemcpyHostToDevice);
        mv[i].normals = b->d_floats.p + of;
        of += nv * 3;
        mv[i].uvs = NULL;
        if (m->uvs && e == cudaSuccess) {
            e = cudaMemcpy(b->d_floats.p + of, m->uvs, nv * 2 * sizeof(float), cudaMemcpyHostToDevice);
            mv[i].uvs = b->d_floats.p + of;
            of += nv * 2;
        }
        if (e == cudaSuccess)
            e = cudaMemcpy(b->d_indices.p + oi, m->indices, (size_t)m->num_triangles * 3 * sizeof(uint32_t), cudaMemcpyHostToDevice);
        mv[i].indices = b->d_indices.p + oi;
        oi += (size_t)m->num_triangles * 3;
    }
    for (i = 0; i < s->num_textures && e == cudaSuccess; i++) {
        size_t n = (size_t)s->textures[i].width * s->textures[i].height * 4;
        tv[i] = b->host.textures[i];
        e = cudaMemcpy(b->d_texels.p + ot, s->textures[i].rgba, n * sizeof(float), cudaMemcpyHostToDevice);
        tv[i].rgba = b->d_texels.p + ot;
        ot += n;
    }
    if (e == cudaSuccess) e = b->d_meshes.reserve((size_t)s->num_meshes + 1);
    if (e == cudaSuccess) e = cudaMemcpy(b->d_meshes.p, mv, ((size_t)s->num_meshes + 1) * sizeof *mv, cudaMemcpyHostToDevice);
    if (e == cudaSuccess) e = b->d_textures.reserve((size_t)s->num_textures + 1);
    if (e == cudaSuccess) e = cudaMemcpy(b->d_textures.p, tv, ((size_t)s->num_textures + 1) * sizeof *tv, cudaMemcpyHostToDevice);
    free(mv);
    free(tv);
    CK(e);
    CK(b->d_materials.reserve((size_t)s->num_materials + 1));
    CK(cudaMemcpy(b->d_materials.p, b->host.materials, ((size_t)s->num_materials + 1) * sizeof(evr_material_params), cudaMemcpyHostToDevice));
    CK(b->d_instances.reserve((size_t)s->num_instances + 1));
    CK(cudaMemcpy(b->d_instances.p, b->host.instances, ((size_t)s->num_instances + 1) * sizeof(evr_instance_view), cudaMemcpyHostToDevice));
    CK(b->d_lights.reserve((size_t)s->num_lights + 1));
    CK(cudaMemcpy(b->d_lights.p, b->host.lights, ((size_t)s->num_lights + 1) * sizeof(evr_light_view), cudaMemcpyHostToDevice));
    if (b->bvh.nodes4) {
        CK(b->d_nodes4.reserve(b->bvh.num_nodes + 1));
        CK(cudaMemcpy(b->d_nodes4.p, b->bvh.nodes4, b->bvh.num_nodes * sizeof(evr_gpu_node4), cudaMemcpyHostToDevice));
    }
    if (b->bvh.nodes8) {
        CK(b->d_nodes8.reserve(b->bvh.num_nodes + 1));
        CK(cudaMemcpy(b->d_nodes8.p, b->bvh.nodes8, b->bvh.num_nodes * sizeof(evr_gpu_node8), cudaMemcpyHostToDevice));
    }
    CK(b->d_tris.reserve(b->bvh.num_tris + 1));
    CK(cudaMemcpy(b->d_tris.p, b->bvh.tris, b->bvh.num_tris * sizeof(evr_gpu_tri), cudaMemcpyHostToDevice));
    return EVR_OK;
}

/* Microseconds after a slot's base_us its event keys can hold. */
static long long slot_span_us(const cuda_backend *b, const slot *sl)
{
    return 1ll << (sl->end_bit - key_time_shift(b->setup.width, b->setup.height));
}

static kernel_args make_args(cuda_backend *b, slot *sl)
{
    kernel_args a;
    memset(&a, 0, sizeof a);
    a.rs = b->host.rs;
    a.rs.meshes = b->d_meshes.p;
    a.rs.materials = b->d_materials.p;
    a.rs.textures = b->d_textures.p;
    a.rs.instances = b->d_instances.p;
    a.rs.lights = b->d_lights.p;
    a.rs.keys = sl->d_keys.p;
    a.rs.track_offset = sl->d_tracks.p;
    a.rs.track_count = sl->d_tracks.p + sl->num_tracks;
    a.view.layout = b->bvh.layout;
    a.view.nodes4 = b->d_nodes4.p;
    a.view.nodes8 = b->d_nodes8.p;
    a.view.tris = b->d_tris.p;
    a.view.top4 = sl->d_top4.p;
    a.view.top8 = sl->d_top8.p;
    a.view.insts = sl->d_insts.p;
    a.view.num_nodes = b->bvh.num_nodes;
    a.view.num_tris = b->bvh.num_tris;
    a.view.num_top_nodes = sl->top.num_nodes;
    a.view.num_insts = sl->top.num_insts;
    a.state_in = b->d_state[sl->index % NRING].p;
    a.state_out = b->d_state[(sl->index + 1) % NRING].p;
    a.phase = b->d_phase.p;
    a.intensity = sl->want_intensity ? sl->d_intensity.p : NULL;
    a.pos_thres = b->setup.pixel.pos_thres;
    a.neg_thres = b->setup.pixel.neg_thres;
    a.refractory = b->setup.pixel.refractory;
    a.log_floor = b->setup.pixel.log_floor;
    a.sensor = b->d_sensor.p;
    a.width = b->setup.width;
    a.height = b->setup.height;
    a.samples = b->setup.samples_per_frame;
    a.dt = (float)(sl->t1 - sl->t0);
    a.t0 = sl->t0;
    a.base_us = sl->base_us;
    a.camera_static = sl->camera_static;
    a.keys = sl->d_keys_ev.p;
    a.capacity = (unsigned)sl->d_keys_ev.cap;
    a.count = sl->d_count.p;
    a.rays = sl->d_rays.p;
    a.plan = sl->d_plan.p;
    a.list = sl->reuse ? sl->d_list.p : NULL;
    a.list_count = sl->d_count.p + 1;
    a.gi = b->gi ? sl->d_gi_view.p : nullptr;
    /* EVR_NO_COHERENCE (hidden, for tests and measurement): every primary ray unbounded */
    a.coherence = getenv("EVR_NO_COHERENCE") == NULL;
    a.xbits = event_key_bits(b->setup.width);
    a.ybits = event_key_bits(b->setup.height);
    a.span_us = slot_span_us(b, sl);
    /* a re-render at overflow after the camera moved on renders without them */
    a.static_hits = sl->static_gen >= 0 && sl->static_gen == b->static_gen ? b->d_static.p : nullptr;
    return a;
}

/* Calls f with the kernel variant of the run as compile-time constants: f(variant<LAYOUT, SENSOR, GI>{}). */
template <int L, int S, int G> struct variant {
    static constexpr int layout = L, sensor = S, gi = G;
};
template <int L, typename F> static void with_variant_of(bool sensor, bool gi, F f)
{
    if (sensor) {
        if (gi) f(variant<L, 1, 1>{});
        else f(variant<L, 1, 0>{});
    } else {
        if (gi) f(variant<L, 0, 1>{});
        else f(variant<L, 0, 0>{});
    }
}
template <typename F> static void with_variant(const cuda_backend *b, F f)
{
    const bool sensor = !evr_pixel_params_ideal(&b->setup.pixel), gi = b->gi != 0;
    if (b->bvh.layout == EVR_GPU_LAYOUT_CW8) with_variant_of<EVR_GPU_LAYOUT_CW8>(sensor, gi, f);
    else with_variant_of<EVR_GPU_LAYOUT_BVH4>(sensor, gi, f);
}

static gi_deferred deferred_args(const cuda_backend *b)
{
    gi_deferred d;
    d.direct = b->d_gd_direct.p;
    d.req = b->d_gd_req.p;
    d.traced = b->d_gd_traced.p;
    d.cache_dist = b->d_gd_cache.p;
    d.requests = b->d_gd_requests.p;
    d.lum = b->d_gd_lum.p;
    d.count = b->d_gd_count.p;
    d.cap = (unsigned)b->d_gd_requests.cap;
    d.newpix = b->d_gd_newpix.p;
    d.delta = b->d_gd_delta.p;
    d.stride = b->setup.width * b->setup.height;
    return d;
}

static void gi_deferred_release(cuda_backend *b)
{
    b->d_gd_direct.release();
    b->d_gd_req.release();
    b->d_gd_lum.release();
    b->d_gd_requests.release();
    b->d_gd_traced.release();
    b->d_gd_cache.release();
    b->d_gd_count.release();
    b->d_gd_newpix.release();
    b->d_gd_delta.release();
    for (int i = 0; i < NRING; i++) b->d_gi_ends[i].release();
}

/* The pixels' last gathers (gi_end), none known yet; without the memory, none are kept (every
 * start gathered again). */
static void gi_ends_alloc(cuda_backend *b, size_t npix)
{
    for (int i = 0; i < NRING; i++) {
        if (b->d_gi_ends[i].reserve(npix, true) != cudaSuccess ||
            cudaMemset(b->d_gi_ends[i].p, 0xff, npix * sizeof(gi_end)) != cudaSuccess) {   /* dist NaN: none */
            (void)cudaGetLastError();
            for (int j = 0; j < NRING; j++) b->d_gi_ends[j].release();
            return;
        }
    }
}

/* The deferred gathers' buffers: every sample of every pixel may make a request (the moving
 * object's pixels do). Where they do not fit in device memory the render kernel gathers inline,
 * with a notice. EVR_GI_INLINE=1 (hidden, for tests and measurement) chooses that too. */
static void gi_deferred_alloc(cuda_backend *b, const cudaDeviceProp *prop)
{
    b->gi_deferred = 0;
    if (!b->gi || b->setup.adaptive || getenv("EVR_GI_INLINE")) return;
    const size_t npix = (size_t)b->setup.width * b->setup.height, n = npix * (size_t)b->setup.samples_per_frame;
    if (b->d_gd_direct.reserve(n, true) == cudaSuccess && b->d_gd_req.reserve(n, true) == cudaSuccess &&
        b->d_gd_lum.reserve(n, true) == cudaSuccess && b->d_gd_requests.reserve(n, true) == cudaSuccess &&
        b->d_gd_traced.reserve(npix, true) == cudaSuccess && b->d_gd_cache.reserve(npix, true) == cudaSuccess &&
        b->d_gd_count.reserve(3) == cudaSuccess && b->d_gd_newpix.reserve(npix, true) == cudaSuccess &&
        b->d_gd_delta.reserve(2 * npix, true) == cudaSuccess) {
        b->gi_deferred = 1;
        gi_ends_alloc(b, npix);
        b->gather_grid = (unsigned)prop->multiProcessorCount * 64u;   /* grid-stride: 64 blocks an SM balanced the gathers best (16: 9% slower) */
        return;
    }
    (void)cudaGetLastError();   /* the failed allocation: not sticky, cleared */
    gi_deferred_release(b);
    fprintf(stderr, "evray: notice: not enough GPU memory to defer the gathers of %zu samples a segment; "
                    "gathering inside the render kernel (slower)\n", n);
}

/* Renders a slot's segment on the render stream and queues the read-back of its event count. */
static evr_status launch(cuda_backend *b, slot *sl, evr_error *err)
{
    CK(cudaMemsetAsync(sl->d_count.p, 0, 2 * sizeof(unsigned int), b->render));
    CK(cudaMemsetAsync(sl->d_rays.p, 0, 3 * sizeof(unsigned long long), b->render));
    CK(cudaMemsetAsync(sl->d_rays.p + KEY_RANGE, 0, sizeof(unsigned long long), b->render));
    kernel_args a = make_args(b, sl);
    CK(cudaEventRecord(sl->started, b->render));
    const unsigned grid = (tiled_threads(b->setup.width, b->setup.height) + BLOCK - 1) / BLOCK;   /* >= npix threads */
    const bool ideal = evr_pixel_params_ideal(&b->setup.pixel);
    cudaStream_t rs = b->render;
    if (b->setup.adaptive) {
        adapt_args d;
        d.next_in = b->d_next[sl->index % NRING].p;
        d.next_out = b->d_next[(sl->index + 1) % NRING].p;
        d.plan = sl->d_adapt.p;
        d.p = b->setup.adapt;
        with_variant(b, [&](auto v) { adapt_kernel<decltype(v)::layout, decltype(v)::sensor, decltype(v)::gi><<<grid, BLOCK, 0, rs>>>(a, d); });
    } else {
        gi_deferred d{};   /* no requests: none made by the skip kernel */
        if (b->gi_deferred) {
            d = deferred_args(b);
            CK(cudaMemsetAsync(d.count, 0, 3 * sizeof(unsigned), rs));
        }
        if (sl->reuse) {
            if (ideal) skip_kernel<0><<<grid, BLOCK, 0, rs>>>(a, d);
            else skip_kernel<1><<<grid, BLOCK, 0, rs>>>(a, d);
            CK(cudaGetLastError());
        }
        if (b->gi_deferred) {
            if (b->bvh.layout == EVR_GPU_LAYOUT_CW8) gi_trace_kernel<EVR_GPU_LAYOUT_CW8><<<grid, BLOCK, 0, rs>>>(a, d);
            else gi_trace_kernel<EVR_GPU_LAYOUT_BVH4><<<grid, BLOCK, 0, rs>>>(a, d);
            CK(cudaGetLastError());
            if (b->gp.max_photons <= 0) {
                if (b->d_gi_ends[0].p) {   /* what the changed cells add to the pixels' last gathers */
                    CK(cudaMemsetAsync(d.delta, 0, 2 * (size_t)b->setup.width * (size_t)b->setup.height * sizeof(unsigned long long), rs));
                    gi_scatter_kernel<<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
                }
                gi_gather_known_kernel<true><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
                gi_gather_new_kernel<true><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
            } else {
                gi_gather_known_kernel<false><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
                gi_gather_new_kernel<false><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
            }
            CK(cudaGetLastError());
            if (ideal) gi_pixel_kernel<0><<<grid, BLOCK, 0, rs>>>(a, d);
            else gi_pixel_kernel<1><<<grid, BLOCK, 0, rs>>>(a, d);
        } else {
            with_variant(b, [&](auto v) { render_kernel<decltype(v)::layout, decltype(v)::sensor, decltype(v)::gi><<<grid, BLOCK, 0, rs>>>(a); });
        }
    }
    CK(cudaGetLastError());
    CK(cudaEventRecord(sl->rendered, b->render));
    if (sl->num_frames > 0) {   /* after the timed render: device time stays the events' */
        with_variant(b, [&](auto v) {
            frame_kernel<decltype(v)::layout, decltype(v)::gi><<<grid, BLOCK, 0, rs>>>(a, sl->d_frame_f.p, sl->num_frames, sl->d_frames.p);
        });
        CK(cudaGetLastError());
        CK(cudaEventRecord(sl->framed, b->render));
    }
    CK(cudaStreamWaitEvent(sl->copy, sl->rendered, 0));
    CK(cudaMemcpyAsync(sl->h_count.p, sl->d_count.p, sizeof(unsigned int), cudaMemcpyDeviceToHost, sl->copy));
    CK(cudaMemcpyAsync(sl->h_rays.p, sl->d_rays.p, GI_COUNTERS * sizeof(unsigned long long), cudaMemcpyDeviceToHost, sl->copy));
    CK(cudaEventRecord(sl->counted, sl->copy));
    sl->copying = 0;
    return EVR_OK;
}

/* The pass's trails: reused where the previous pass recorded them with the same emitters; room
 * for n photons (a pass that needs more starts them afresh). Without the memory, no trails (every
 * photon traced, as before them), nor with EVR_NO_PHOTON_REUSE set (trails_off). */
static void trail_args(cuda_backend *b, unsigned n, photon_args *p)
{
    p->trails = nullptr;
    p->trail_rays = nullptr;
    p->trail_len = evr_photon_trail_len(&b->pp);
    p->reuse = 0;
    p->todo = nullptr;
    p->todo_count = nullptr;
    if (b->trails_off) return;
    const size_t len = (size_t)p->trail_len;
    if (n > b->d_trails.cap || (size_t)n * len > b->d_trail_rays.cap) {
        b->trails_valid = 0;
        if (b->d_trails.reserve(n, true) != cudaSuccess || b->d_trail_rays.reserve((size_t)n * len, true) != cudaSuccess) {
            (void)cudaGetLastError();   /* not sticky: cleared */
            b->d_trails.release();
            b->d_trail_rays.release();
            b->trails_off = 1;
            return;
        }
    }
    if (b->d_todo.reserve(n) != cudaSuccess || b->d_todo_count.reserve(1) != cudaSuccess) {
        (void)cudaGetLastError();
        b->trails_valid = 0;
        return;   /* no reuse this pass, no trails recorded */
    }
    p->trails = b->d_trails.p;
    p->trail_rays = b->d_trail_rays.p;
    p->todo = b->d_todo.p;
    p->todo_count = b->d_todo_count.p;
    p->reuse = evr_photon_trails_pass(&b->trail_em, &b->trails_valid, &b->em);
}

/* One photon pass (gpu_gi.cuh) at normalized segment time f into buffer out, on the render stream:
 * the photons, traced at f, and the camera's view of the cells at f. hrs: the segment's scene
 * with host pointers (the emitters are built on the host). */
static evr_status gi_pass(cuda_backend *b, slot *sl, const evr_render_scene *hrs, float f, const evr_photon_buffer *out,
                          evr_error *err)
{
    const size_t cells = (size_t)out->width * (size_t)out->height;
    const unsigned cgrid = (unsigned)((cells + BLOCK - 1) / BLOCK);
    cudaStream_t rs = b->render;
    evr_status st;
    if ((st = evr_photon_emitters_build(hrs, f, b->pp.bounds, b->photons, &b->em, err)) != EVR_OK) return st;
    if (b->gp.flux_scale == 0.0f) b->gp.flux_scale = evr_gather_flux_scale(b->em.total_power, b->photons);   /* the run's */
    if (b->em.photons > (1u << 28)) {
        snprintf(err->msg, sizeof err->msg, "too many photons (%u; at most 2^28)", b->em.photons);
        return EVR_ERR_ARG;
    }
    const unsigned n = b->em.n > 0 ? b->em.photons : 0u;
    CK(sl->h_em.reserve((size_t)b->em.n + 1));
    CK(sl->d_em.reserve((size_t)b->em.n + 1));
    CK(sl->h_cdf.reserve((size_t)b->em.cdf_n + 1));
    CK(sl->d_cdf.reserve((size_t)b->em.cdf_n + 1));
    if (b->em.n) memcpy(sl->h_em.p, b->em.e, (size_t)b->em.n * sizeof(evr_photon_emitter));
    if (b->em.cdf_n) memcpy(sl->h_cdf.p, b->em.cdf, (size_t)b->em.cdf_n * sizeof(float));
    CK(cudaMemcpyAsync(sl->d_em.p, sl->h_em.p, ((size_t)b->em.n + 1) * sizeof(evr_photon_emitter), cudaMemcpyHostToDevice, rs));
    CK(cudaMemcpyAsync(sl->d_cdf.p, sl->h_cdf.p, ((size_t)b->em.cdf_n + 1) * sizeof(float), cudaMemcpyHostToDevice, rs));
    CK(b->d_pending.reserve((size_t)n + 1));
    CK(b->d_pkeys.reserve((size_t)n + 1));
    CK(b->d_pkeys_sorted.reserve((size_t)n + 1));
    CK(b->d_pvals.reserve((size_t)n + 1));
    CK(b->d_pvals_sorted.reserve((size_t)n + 1));
    CK(cudaMemsetAsync(out->count, 0, cells * sizeof(uint32_t), rs));
    CK(cudaMemsetAsync(b->d_pcount.p, 0, sizeof(unsigned), rs));
    kernel_args a = make_args(b, sl);
    if (n) {
        photon_args p;
        p.em = sl->d_em.p;
        p.n_em = b->em.n;
        p.cdf = sl->d_cdf.p;
        p.pp = b->pp;
        p.pp.ray_eps = hrs->ray_eps;
        p.pp.f0 = p.pp.f1 = f;
        p.photons = n;
        p.margin = out->margin;
        p.cells_w = out->width;
        p.sort_keys = b->d_pkeys.p;
        p.sort_vals = b->d_pvals.p;
        p.pending = b->d_pending.p;
        p.pending_count = b->d_pcount.p;
        trail_args(b, n, &p);
        CK(cudaMemsetAsync(b->d_pkeys.p, 0xff, (size_t)n * sizeof(unsigned long long), rs));
        const unsigned pgrid = (n + BLOCK - 1) / BLOCK;
        if (p.reuse) {
            CK(cudaMemsetAsync(p.todo_count, 0, sizeof(unsigned), rs));
            photon_reuse_kernel<<<pgrid, BLOCK, 0, rs>>>(a, p);
            CK(cudaGetLastError());
        }
        if (b->bvh.layout == EVR_GPU_LAYOUT_CW8) photon_kernel<EVR_GPU_LAYOUT_CW8><<<pgrid, BLOCK, 0, rs>>>(a, p);
        else photon_kernel<EVR_GPU_LAYOUT_BVH4><<<pgrid, BLOCK, 0, rs>>>(a, p);
        CK(cudaGetLastError());
        /* the cell in the high bits (up to 2^end - 1), the photon key in the low 32 */
        int end_bit = 33;
        while (end_bit < 64 && (1ull << (end_bit - 32)) <= cells) end_bit++;
        size_t temp = 0;
        CK(cub::DeviceRadixSort::SortPairs(nullptr, temp, b->d_pkeys.p, b->d_pkeys_sorted.p, b->d_pvals.p, b->d_pvals_sorted.p,
                                           (int)n, 0, end_bit, rs));
        CK(b->d_ptemp.reserve(temp));
        CK(cub::DeviceRadixSort::SortPairs(b->d_ptemp.p, temp, b->d_pkeys.p, b->d_pkeys_sorted.p, b->d_pvals.p, b->d_pvals_sorted.p,
                                           (int)n, 0, end_bit, rs));
        photon_place_kernel<<<pgrid, BLOCK, 0, rs>>>(b->d_pkeys_sorted.p, b->d_pvals_sorted.p, n, b->d_pending.p, *out, sl->d_rays.p);
        CK(cudaGetLastError());
    }
    if (b->bvh.layout == EVR_GPU_LAYOUT_CW8) photon_view_kernel<EVR_GPU_LAYOUT_CW8><<<cgrid, BLOCK, 0, rs>>>(a, *out, f);
    else photon_view_kernel<EVR_GPU_LAYOUT_BVH4><<<cgrid, BLOCK, 0, rs>>>(a, *out, f);
    CK(cudaGetLastError());
    sl->gi_passes++;
    return EVR_OK;
}

/* The segment's photons on the render stream, before its render: the pass at its end (the first
 * segment's at its start too), the cells that changed, the view its kernels read. A still segment
 * (nothing moved in it or since the previous one) copies the previous segment's buffer. */
static evr_status gi_segment(cuda_backend *b, slot *sl, const evr_segment *seg, const evr_render_scene *hrs, evr_error *err)
{
    const gi_buffer *end = &b->gi_ring[sl->index % NRING], *start = &b->gi_ring[(sl->index + NRING - 1) % NRING];
    const evr_photon_buffer *eb = &end->ph, *sb = &start->ph;
    const size_t cells = (size_t)eb->width * (size_t)eb->height;
    const unsigned cgrid = (unsigned)((cells + BLOCK - 1) / BLOCK);
    cudaStream_t rs = b->render;
    evr_status st;
    sl->gi_passes = 0;
    CK(cudaMemsetAsync(sl->d_rays.p + GI_PATHS, 0, (GI_COUNTERS - GI_PATHS) * sizeof(unsigned long long), rs));
    if (evr_skip_plan_still(seg->skip) && b->gi_have_prev) {
        CK(cudaMemcpyAsync(eb->count, sb->count, cells * sizeof(uint32_t), cudaMemcpyDeviceToDevice, rs));
        CK(cudaMemcpyAsync(eb->slots, sb->slots, cells * (size_t)eb->layers * sizeof(evr_photon), cudaMemcpyDeviceToDevice, rs));
        CK(cudaMemcpyAsync(eb->gbuf, sb->gbuf, cells * 8 * sizeof(float), cudaMemcpyDeviceToDevice, rs));
    } else {
        CK(cudaEventRecord(sl->gi_started, rs));
        if (!b->gi_have_prev) {
            if ((st = gi_pass(b, sl, hrs, 0.0f, sb, err)) != EVR_OK) return st;
            CK(cudaStreamSynchronize(rs));   /* the emitters' staging is the slot's: its copy done */
        }
        if ((st = gi_pass(b, sl, hrs, 1.0f, eb, err)) != EVR_OK) return st;
    }
    photon_changed_kernel<<<cgrid, BLOCK, 0, rs>>>(*eb, *sb, b->d_gi_last.p, sl->d_sat.p, sl->d_rays.p);
    sat_rows_kernel<<<(unsigned)((32 * (size_t)eb->height + BLOCK - 1) / BLOCK), BLOCK, 0, rs>>>(sl->d_sat.p, eb->width, eb->height);
    sat_cols_kernel<<<(unsigned)((eb->width + 31) / 32), 32 * SAT_CHUNKS, 0, rs>>>(sl->d_sat.p, eb->width, eb->height);
    if (b->gp.max_photons <= 0) {
        const evr_changed_cells ch = sl->h_gi_view.p->ch;
        changed_rows_kernel<<<(unsigned)((32 * (size_t)eb->height + BLOCK - 1) / BLOCK), BLOCK, 0, rs>>>(b->d_gi_last.p, eb->width,
                                                                                                          eb->height, sl->d_ch_before.p);
        changed_base_kernel<<<1, 32, 0, rs>>>(sl->d_ch_before.p, eb->width, eb->height, sl->d_ch_base.p);
        changed_list_kernel<<<cgrid, BLOCK, 0, rs>>>(b->d_gi_last.p, eb->width, eb->height, ch, sl->d_ch_x.p);
    }
    CK(cudaGetLastError());
    if (sl->gi_passes) CK(cudaEventRecord(sl->gi_done, rs));
    /* the slot's last copy from its staging finished before its previous segment was collected */
    gpu_gi_view *v = sl->h_gi_view.p;
    v->end = *eb;
    v->start = *sb;
    v->gp = b->gp;   /* with the run's flux scale, known after the first pass */
    v->ends_in = b->d_gi_ends[0].p ? b->d_gi_ends[sl->index % NRING].p : nullptr;
    v->ends_out = b->d_gi_ends[0].p ? b->d_gi_ends[(sl->index + 1) % NRING].p : nullptr;
    CK(cudaMemcpyAsync(sl->d_gi_view.p, v, sizeof *v, cudaMemcpyHostToDevice, rs));
    b->gi_have_prev = 1;
    return EVR_OK;
}

/* Device memory of the ring's photon buffers and the per-cell changes (shared by the slots). */
static evr_status gi_ring_alloc(cuda_backend *b, int margin, evr_error *err)
{
    for (int i = 0; i < NRING; i++) {
        gi_buffer *g = &b->gi_ring[i];
        evr_photon_buffer *buf = &g->ph;
        memset(buf, 0, sizeof *buf);
        buf->width = b->setup.width + 2 * margin;
        buf->height = b->setup.height + 2 * margin;
        buf->layers = b->setup.photon_layers;
        buf->margin = margin;
        const size_t cells = (size_t)buf->width * (size_t)buf->height;
        CK(g->slots.reserve(cells * (size_t)buf->layers));
        CK(g->count.reserve(cells));
        CK(g->gbuf.reserve(cells * 8));
        CK(cudaMemset(g->count.p, 0, cells * sizeof(uint32_t)));
        CK(cudaMemset(g->gbuf.p, 0, cells * 8 * sizeof(float)));
        buf->slots = g->slots.p;
        buf->count = g->count.p;
        buf->gbuf = g->gbuf.p;
        buf->collisions = nullptr;   /* the place kernel counts them (GI_COLLISIONS) */
    }
    const size_t cells = (size_t)b->gi_ring[0].ph.width * (size_t)b->gi_ring[0].ph.height;
    CK(b->d_gi_last.reserve(cells));
    CK(cudaMemset(b->d_gi_last.p, 0, cells));
    return EVR_OK;
}

/* A slot's changed-cell table and the view its kernels read. */
static evr_status gi_alloc(cuda_backend *b, slot *sl, int window, evr_error *err)
{
    const evr_photon_buffer *shape = &b->gi_ring[0].ph;
    const size_t sat_n = (size_t)(shape->width + 1) * (size_t)(shape->height + 1);
    CK(sl->d_sat.reserve(sat_n));
    CK(cudaMemset(sl->d_sat.p, 0, sat_n * sizeof(uint32_t)));
    if (b->gp.max_photons <= 0) {
        CK(sl->d_ch_before.reserve(((size_t)shape->width + 1) * (size_t)shape->height));
        CK(sl->d_ch_base.reserve((size_t)shape->height + 1));
        CK(sl->d_ch_x.reserve((size_t)shape->width * (size_t)shape->height));
    }
    CK(sl->h_gi_view.reserve(1));
    gpu_gi_view *v = sl->h_gi_view.p;
    v->end = v->start = *shape;
    v->sat = sl->d_sat.p;
    v->ch.before = sl->d_ch_before.p;
    v->ch.base = sl->d_ch_base.p;
    v->ch.x = sl->d_ch_x.p;
    v->gp = b->gp;
    v->window = window;
    v->ends_in = nullptr;
    v->ends_out = nullptr;
    CK(sl->d_gi_view.reserve(1));
    CK(cudaMemcpy(sl->d_gi_view.p, v, sizeof *v, cudaMemcpyHostToDevice));
    CK(cudaEventCreate(&sl->gi_started));
    CK(cudaEventCreate(&sl->gi_done));
    return EVR_OK;
}

/* Keys carried from the segment before, moved onto this segment's time base (both bases are
 * whole microseconds, the times in range: start_copy checks them). */
__global__ void carry_keys(const unsigned long long *from, size_t n, unsigned long long delta, unsigned long long *to)
{
    for (size_t i = blockIdx.x * (size_t)blockDim.x + threadIdx.x; i < n; i += (size_t)gridDim.x * blockDim.x)
        to[i] = from[i] - delta;
}

/* Grows d to hold n keys, keeping its first keep (the buffer is reallocated rarely: doubling). */
static cudaError_t grow_keeping(dbuf<unsigned long long> &d, size_t n, size_t keep, cudaStream_t s)
{
    if (n <= d.cap) return cudaSuccess;
    dbuf<unsigned long long> g;
    cudaError_t e = g.reserve(n);
    if (e == cudaSuccess && keep) e = cudaMemcpyAsync(g.p, d.p, keep * sizeof(unsigned long long), cudaMemcpyDeviceToDevice, s);
    if (e == cudaSuccess) e = cudaStreamSynchronize(s);
    if (e != cudaSuccess) {
        g.release();
        return e;
    }
    d.release();
    d.p = g.p;
    d.cap = g.cap;
    g.p = nullptr;
    g.cap = 0;
    return cudaSuccess;
}

/* Queues the sort and copy to the host of a rendered segment's n events, with the keys the
 * segment before it carried (b->carry_*: its events at or after its emit_before), and of its
 * intensity and frames, on the slot's copy stream. The segment before has been collected. */
static evr_status start_copy(cuda_backend *b, slot *sl, size_t n, evr_error *err)
{
    const size_t carried = b->carry_slot >= 0 ? b->carry_n : 0;
    CK(cudaEventRecord(sl->sort_from, sl->copy));
    if (carried) {
        if (b->carry_t_lo < sl->base_us || b->carry_t_hi - sl->base_us >= slot_span_us(b, sl)) {
            snprintf(err->msg, sizeof err->msg, "internal error: events carried to the segment at %.6f s fall outside its time window",
                     sl->t0);
            return EVR_ERR_BACKEND;
        }
        const int shift = key_time_shift(b->setup.width, b->setup.height);
        const unsigned long long delta = (unsigned long long)(sl->base_us - b->carry_base_us) << shift;
        CK(grow_keeping(sl->d_keys_ev, n + carried, n, sl->copy));
        const unsigned blocks = (unsigned)((carried + BLOCK - 1) / BLOCK < 1024 ? (carried + BLOCK - 1) / BLOCK : 1024);
        carry_keys<<<blocks, BLOCK, 0, sl->copy>>>(b->slots[b->carry_slot].d_keys_sorted.p + b->carry_at, carried, delta,
                                                   sl->d_keys_ev.p + n);
        CK(cudaGetLastError());
    }
    n += carried;
    sl->total = n;
    if (n) {
        size_t temp = 0;
        CK(sl->d_keys_sorted.reserve(n));
        CK(cub::DeviceRadixSort::SortKeys(nullptr, temp, sl->d_keys_ev.p, sl->d_keys_sorted.p, (int)n, 0, sl->end_bit, sl->copy));
        CK(sl->d_sort_temp.reserve(temp));
        CK(cub::DeviceRadixSort::SortKeys(sl->d_sort_temp.p, temp, sl->d_keys_ev.p, sl->d_keys_sorted.p, (int)n, 0, sl->end_bit, sl->copy));
        CK(sl->h_sorted.reserve(n));
        CK(cudaEventRecord(sl->sorted, sl->copy));
        CK(cudaMemcpyAsync(sl->h_sorted.p, sl->d_keys_sorted.p, n * sizeof(unsigned long long), cudaMemcpyDeviceToHost, sl->copy));
    }
    if (sl->want_intensity) {
        size_t npix = (size_t)b->setup.width * b->setup.height;
        CK(sl->h_intensity.reserve(npix));
        CK(cudaMemcpyAsync(sl->h_intensity.p, sl->d_intensity.p, npix * sizeof(float), cudaMemcpyDeviceToHost, sl->copy));
    }
    if (sl->num_frames) {
        size_t nf = (size_t)sl->num_frames * (size_t)b->setup.width * b->setup.height;
        CK(sl->h_frames.reserve(nf));
        CK(cudaStreamWaitEvent(sl->copy, sl->framed, 0));
        CK(cudaMemcpyAsync(sl->h_frames.p, sl->d_frames.p, nf * sizeof(float), cudaMemcpyDeviceToHost, sl->copy));
    }
    CK(cudaEventRecord(sl->copied, sl->copy));
    sl->copying = 1;
    return EVR_OK;
}

/* Queues the sort and copy of the oldest submitted segment when its render is done (its count is
 * on the host) and its events fit its buffer (else collect renders it again): it runs on the GPU
 * while the host is busy elsewhere, instead of after the host asks for it. */
static evr_status start_ready_copies(cuda_backend *b, evr_error *err)
{
    /* only the oldest: a sort takes the keys its segment before carries, known once collected */
    if (!b->queued) return EVR_OK;
    slot *sl = &b->slots[b->head];
    if (sl->copying) return EVR_OK;
    const cudaError_t e = cudaEventQuery(sl->counted);
    if (e == cudaErrorNotReady) return EVR_OK;
    CK(e);
    const size_t n = *sl->h_count.p;
    if (n > sl->d_keys_ev.cap) return EVR_OK;   /* collect renders it again */
    return start_copy(b, sl, n, err);
}

static evr_status cuda_submit(evr_backend *base, const evr_segment *seg, evr_error *err)
{
    cuda_backend *b = (cuda_backend *)base;
    evr_status st;
    const double tl_sub0 = evr_host_seconds();
    if (b->queued == NSLOT) {
        snprintf(err->msg, sizeof err->msg, "internal error: more than %d segments submitted", NSLOT);
        return EVR_ERR_BACKEND;
    }
    /* the segments rendered since the last call: their sorts start now, before the host work below */
    if ((st = start_ready_copies(b, err)) != EVR_OK) return st;
    slot *sl = &b->slots[(b->head + b->queued) % NSLOT];
    /* the slot's previous segment was collected, so its copy stream is idle */
    CK(sl->d_keys_ev.reserve(b->capacity));
    sl->index = seg->index;
    sl->t0 = seg->t0;
    sl->t1 = seg->t1;
    sl->camera_static = seg->camera_static;
    sl->want_intensity = seg->want_intensity;
    sl->reuse = seg->skip->reuse;
    *sl->h_plan.p = *seg->skip;
    CK(cudaMemcpyAsync(sl->d_plan.p, sl->h_plan.p, sizeof(evr_skip_plan), cudaMemcpyHostToDevice, b->render));
    if (b->setup.adaptive) {
        *sl->h_adapt.p = *seg->adapt;
        CK(cudaMemcpyAsync(sl->d_adapt.p, sl->h_adapt.p, sizeof(evr_adapt_plan), cudaMemcpyHostToDevice, b->render));
    }
    sl->num_frames = seg->num_frames > 0 ? seg->num_frames : 0;
    if (sl->num_frames) {
        size_t nf = (size_t)sl->num_frames, npix = (size_t)b->setup.width * b->setup.height;
        CK(sl->h_frame_f.reserve(nf));
        CK(sl->d_frame_f.reserve(nf));
        CK(sl->d_frames.reserve(nf * npix));
        for (int k = 0; k < sl->num_frames; k++) {
            double f = seg->t1 > seg->t0 ? (seg->frame_times[k] - seg->t0) / (seg->t1 - seg->t0) : 0.0;
            sl->h_frame_f.p[k] = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
        }
        CK(cudaMemcpyAsync(sl->d_frame_f.p, sl->h_frame_f.p, nf * sizeof(float), cudaMemcpyHostToDevice, b->render));
    }
    /* events reach back to the previous segment (a pixel's last sample there; with adaptive
     * sampling up to max_dt back), and timestamp jitter and rounding move them by up to
     * EVR_JITTER_CLIP sigma plus one resolution step either way; one more segment to spare. An
     * event outside the window is counted (KEY_RANGE) and fails the run, never wraps. */
    const evr_pixel_params *px = &b->setup.pixel;
    double slack = (double)EVR_JITTER_CLIP * (double)px->time_jitter + (px->time_res_us > 1 ? 1e-6 * (double)px->time_res_us : 0.0);
    double dt = seg->t1 - seg->t0, back = 2.0 * dt + slack;
    if (b->setup.adaptive) back += (double)b->setup.adapt.max_dt;   /* a pixel's last sample: up to max_dt back */
    sl->base_us = (long long)floor((seg->t0 - back) * 1e6);
    double span_us = (back + dt + slack) * 1e6 + 2.0;
    int tbits = 1;
    while (tbits < 31 && (double)(1ull << tbits) < span_us) tbits++;
    sl->end_bit = key_time_shift(b->setup.width, b->setup.height) + tbits;
    sl->num_tracks = seg->num_tracks;
    sl->num_keys = seg->num_keys;
    CK(sl->h_keys.reserve((size_t)seg->num_keys));
    CK(sl->h_tracks.reserve(2 * (size_t)seg->num_tracks));
    memcpy(sl->h_keys.p, seg->keys, (size_t)seg->num_keys * sizeof(evr_motion_key));
    memcpy(sl->h_tracks.p, seg->track_offset, (size_t)seg->num_tracks * sizeof(int));
    memcpy(sl->h_tracks.p + seg->num_tracks, seg->track_count, (size_t)seg->num_tracks * sizeof(int));
    /* top level over the instances, bounds over the whole segment */
    evr_render_scene hrs = b->host.rs;
    hrs.keys = sl->h_keys.p;
    hrs.track_offset = sl->h_tracks.p;
    hrs.track_count = sl->h_tracks.p + seg->num_tracks;
    if ((st = evr_gpu_top_build(&b->bvh, &hrs, &sl->top, err)) != EVR_OK) return st;
    CK(sl->d_keys.reserve((size_t)seg->num_keys));
    CK(sl->d_tracks.reserve(2 * (size_t)seg->num_tracks));
    CK(sl->d_insts.reserve(sl->top.num_insts + 1));
    CK(cudaMemcpyAsync(sl->d_keys.p, sl->h_keys.p, (size_t)seg->num_keys * sizeof(evr_motion_key), cudaMemcpyHostToDevice, b->render));
    CK(cudaMemcpyAsync(sl->d_tracks.p, sl->h_tracks.p, 2 * (size_t)seg->num_tracks * sizeof(int), cudaMemcpyHostToDevice, b->render));
    if (sl->top.nodes4) {
        CK(sl->d_top4.reserve(sl->top.num_nodes + 1));
        CK(cudaMemcpyAsync(sl->d_top4.p, sl->top.nodes4, sl->top.num_nodes * sizeof(evr_gpu_node4), cudaMemcpyHostToDevice, b->render));
    }
    if (sl->top.nodes8) {
        CK(sl->d_top8.reserve(sl->top.num_nodes + 1));
        CK(cudaMemcpyAsync(sl->d_top8.p, sl->top.nodes8, sl->top.num_nodes * sizeof(evr_gpu_node8), cudaMemcpyHostToDevice, b->render));
    }
    CK(cudaMemcpyAsync(sl->d_insts.p, sl->top.insts, sl->top.num_insts * sizeof(evr_gpu_inst), cudaMemcpyHostToDevice, b->render));
    /* the host top-level arrays are reused by the next build of this slot only after collect,
     * by which time these copies are done (collect synchronizes) */
    /* a still camera: its rays' hits in the static group, made again when the camera has moved */
    sl->static_gen = -1;
    if (seg->camera_static && !b->static_off) {
        const evr_motion_key *cam = &seg->keys[seg->track_offset[b->host.rs.camera_track]];
        if (b->static_gen == 0 || memcmp(cam, &b->static_cam, sizeof *cam) != 0) {
            const int npix = b->setup.width * b->setup.height;
            CK(b->d_static.reserve((size_t)npix));
            b->static_gen++;
            kernel_args a = make_args(b, sl);
            const unsigned grid = (unsigned)((npix + BLOCK - 1) / BLOCK);
            if (b->bvh.layout == EVR_GPU_LAYOUT_CW8) static_hits_kernel<EVR_GPU_LAYOUT_CW8><<<grid, BLOCK, 0, b->render>>>(a, b->d_static.p);
            else static_hits_kernel<EVR_GPU_LAYOUT_BVH4><<<grid, BLOCK, 0, b->render>>>(a, b->d_static.p);
            CK(cudaGetLastError());
            b->static_cam = *cam;
        }
        sl->static_gen = b->static_gen;
    }
    if (b->gi && (st = gi_segment(b, sl, seg, &hrs, err)) != EVR_OK) return st;
    if ((st = launch(b, sl, err)) != EVR_OK) return st;
    b->queued++;
    if (cuda_backend::tl_rec *r = tl_at(b, seg->index)) {
        r->sub0 = tl_sub0;
        r->sub1 = evr_host_seconds();
    }
    return EVR_OK;
}

template <typename T> static uint64_t bytes(const dbuf<T> &d) { return (uint64_t)d.cap * sizeof(T); }

static uint64_t device_bytes(const cuda_backend *b)
{
    uint64_t n = bytes(b->d_floats) + bytes(b->d_indices) + bytes(b->d_meshes) + bytes(b->d_materials) +
                 bytes(b->d_textures) + bytes(b->d_texels) + bytes(b->d_instances) + bytes(b->d_lights) +
                 bytes(b->d_nodes4) + bytes(b->d_nodes8) + bytes(b->d_tris) + bytes(b->d_phase) +
                 bytes(b->d_sensor);
    for (int i = 0; i < NRING; i++) n += bytes(b->d_state[i]) + bytes(b->d_next[i]);
    for (int i = 0; i < NSLOT; i++) {
        const slot *sl = &b->slots[i];
        n += bytes(sl->d_keys) + bytes(sl->d_tracks) + bytes(sl->d_top4) + bytes(sl->d_top8) + bytes(sl->d_insts) +
             bytes(sl->d_keys_ev) + bytes(sl->d_keys_sorted) + bytes(sl->d_sort_temp) + bytes(sl->d_count) +
             bytes(sl->d_rays) + bytes(sl->d_plan) + bytes(sl->d_list) + bytes(sl->d_intensity) + bytes(sl->d_frame_f) + bytes(sl->d_frames) +
             bytes(sl->d_sat) + bytes(sl->d_ch_before) + bytes(sl->d_ch_base) + bytes(sl->d_ch_x) + bytes(sl->d_em) + bytes(sl->d_cdf);
    }
    for (int i = 0; i < NRING; i++) n += bytes(b->gi_ring[i].slots) + bytes(b->gi_ring[i].count) + bytes(b->gi_ring[i].gbuf);
    n += bytes(b->d_gi_last);
    for (int i = 0; i < NRING; i++) n += bytes(b->d_gi_ends[i]);
    n += bytes(b->d_pending) + bytes(b->d_pkeys) + bytes(b->d_pkeys_sorted) + bytes(b->d_pvals) + bytes(b->d_pvals_sorted) +
         bytes(b->d_pcount) + bytes(b->d_ptemp) + bytes(b->d_trails) + bytes(b->d_trail_rays) + bytes(b->d_todo) +
         bytes(b->d_gd_direct) + bytes(b->d_gd_cache) + bytes(b->d_gd_lum) + bytes(b->d_gd_req) + bytes(b->d_gd_traced) +
         bytes(b->d_gd_requests) + bytes(b->d_gd_newpix) + bytes(b->d_gd_delta);
    return n;
}

/* The event of a sorted key (pack_event's layout). */
static inline evr_event decode_key(unsigned long long k, long long base_us, int xb, int yb)
{
    evr_event e;
    e.t = base_us + (long long)(k >> (1 + xb + yb));
    e.y = (uint16_t)((k >> (1 + xb)) & ((1u << yb) - 1u));
    e.x = (uint16_t)((k >> 1) & ((1u << xb) - 1u));
    e.p = (int8_t)(k & 1u);
    return e;
}

/* Decodes n sorted keys into dst, a segment of many events in parts on the pool: on one thread it
 * was most of the main thread's own time (the eye's 218.7 M events in 30 s at 1280x720), and
 * threads started per segment cost about as much as the work. */
struct decode_job {
    const unsigned long long *keys;
    size_t n, parts;
    long long base_us;
    int xb, yb;
    evr_event *dst;
};
static void decode_part(void *ctx, int k, int)
{
    const decode_job *j = (const decode_job *)ctx;
    size_t i0, i1;
    evr_par_share(j->n, (int)j->parts, k, &i0, &i1);
    for (size_t i = i0; i < i1; i++) j->dst[i] = decode_key(j->keys[i], j->base_us, j->xb, j->yb);
}
static void decode_keys(evr_par_pool *pool, const unsigned long long *keys, size_t n, long long base_us, int xb, int yb,
                        evr_event *dst)
{
    const size_t chunk = (size_t)1 << 17;
    size_t parts = (n + chunk - 1) / chunk, most = (size_t)evr_par_pool_threads(pool);
    if (parts > most) parts = most;
    if (parts < 1) parts = 1;
    decode_job j = {keys, n, parts, base_us, xb, yb, dst};
    evr_par_pool_run(pool, (int)parts, decode_part, &j);
}

static evr_status cuda_collect(evr_backend *base, evr_event_vec *out, int64_t emit_before_us, const float **intensity,
                               const float **frames, evr_error *err)
{
    cuda_backend *b = (cuda_backend *)base;
    evr_status st;
    if (!b->queued) {
        snprintf(err->msg, sizeof err->msg, "internal error: collect without a submitted segment");
        return EVR_ERR_BACKEND;
    }
    slot *sl = &b->slots[b->head];
    double tw = evr_host_seconds();
    const double tl_col0 = tw;
    CK(cudaEventSynchronize(sl->counted));
    const double tl_counted = evr_host_seconds();
    base->wait_seconds += evr_host_seconds() - tw;
    size_t n = *sl->h_count.p;
    while (n > sl->d_keys_ev.cap) {
        /* overflow: grow and render this segment again from its unchanged input states (the
         * next segment, if rendering, reads states this re-run rewrites identically: wait) */
        CK(cudaDeviceSynchronize());
        CK(sl->d_keys_ev.reserve(n + n / 4));
        if (sl->d_keys_ev.cap > b->capacity) b->capacity = sl->d_keys_ev.cap;   /* the other slots grow at their next submit */
        if ((st = launch(b, sl, err)) != EVR_OK) return st;
        CK(cudaEventSynchronize(sl->counted));
        n = *sl->h_count.p;
    }
    if (sl->h_rays.p[KEY_RANGE]) {
        snprintf(err->msg, sizeof err->msg, "internal error: %llu events of the segment at %.6f s fell outside its time window",
                 (unsigned long long)sl->h_rays.p[KEY_RANGE], sl->t0);
        return EVR_ERR_BACKEND;
    }
    base->rays += sl->h_rays.p[0];
    base->pixels_skipped += sl->h_rays.p[1];
    base->samples_traced += sl->h_rays.p[2];
    if (b->gi && sl->gi_passes) {
        float gi_ms = 0.0f;
        CK(cudaEventElapsedTime(&gi_ms, sl->gi_started, sl->gi_done));
        base->photon_seconds += 1e-3 * (double)gi_ms;
        base->photons_traced += sl->h_rays.p[GI_PATHS];
        base->photons_reused += sl->h_rays.p[GI_REUSED];
        base->photons_stored += sl->h_rays.p[GI_INSERTED];
        base->photon_collisions += sl->h_rays.p[GI_COLLISIONS];
        base->photon_cells_changed += sl->h_rays.p[GI_CHANGED];
        base->photon_passes += (uint64_t)sl->gi_passes;
        sl->gi_passes = 0;   /* a re-render at overflow does not run the passes again */
    }
    float ms = 0.0f;
    CK(cudaEventElapsedTime(&ms, sl->started, sl->rendered));
    base->device_seconds += 1e-3 * (double)ms;
    if (b->setup.adaptive) base->samples += sl->h_rays.p[2];   /* the samples taken, all traced */
    else base->samples += (uint64_t)b->setup.width * (uint64_t)b->setup.height * (uint64_t)b->setup.samples_per_frame;
    if (!sl->copying && (st = start_copy(b, sl, n, err)) != EVR_OK) return st;
    tw = evr_host_seconds();
    CK(cudaStreamSynchronize(sl->copy));
    base->wait_seconds += evr_host_seconds() - tw;
    const double tl_copied = evr_host_seconds();
    if (cuda_backend::tl_rec *r = tl_at(b, sl->index)) {
        const cudaEvent_t ev[4] = {sl->started, sl->rendered, sl->sort_from, sl->copied};
        double *g[4] = {&r->g_start, &r->g_rendered, &r->g_sort, &r->g_copied};
        for (int k = 0; k < 4; k++) {
            float ms = 0.0f;
            CK(cudaEventElapsedTime(&ms, b->tl_base, ev[k]));
            *g[k] = 1e-3 * ms;
        }
        r->col0 = tl_col0;
        r->counted = tl_counted;
        r->copied = tl_copied;
        r->n = n;
    }
    if (n) {
        float sort_ms = 0.0f, copy_ms = 0.0f;
        CK(cudaEventElapsedTime(&sort_ms, sl->sort_from, sl->sorted));
        CK(cudaEventElapsedTime(&copy_ms, sl->sorted, sl->copied));
        base->sort_seconds += 1e-3 * (double)sort_ms;
        base->copy_seconds += 1e-3 * (double)copy_ms;
    }
    /* The keys before emit_before are decoded; the rest stay on the device and are sorted again
     * with the next segment's, which can precede them (a pixel's first sample there reaches back
     * to its last one here). On the host they had to be merged with the next segment's events:
     * 0.21 s of the main thread for the 30 s eye, and a copy of them at every hand-over. */
    const int xb = event_key_bits(b->setup.width), yb = event_key_bits(b->setup.height);
    const int shift = key_time_shift(b->setup.width, b->setup.height);
    const size_t total = sl->total;   /* its own n and those carried in */
    size_t split = total;
    if (emit_before_us != INT64_MAX) {
        const long long rel = (long long)emit_before_us - sl->base_us;
        const unsigned long long limit = rel <= 0 ? 0ull : (unsigned long long)rel << shift;   /* the first key at or after it */
        size_t lo = 0, hi = total;
        if (rel >= slot_span_us(b, sl)) lo = total;
        while (lo < hi) {
            const size_t mid = lo + (hi - lo) / 2;
            if (sl->h_sorted.p[mid] < limit) lo = mid + 1;
            else hi = mid;
        }
        split = lo;
    }
    b->carry_slot = split < total ? b->head : -1;
    b->carry_at = split;
    b->carry_n = total - split;
    b->carry_base_us = sl->base_us;
    if (split < total) {
        b->carry_t_lo = decode_key(sl->h_sorted.p[split], sl->base_us, xb, yb).t;
        b->carry_t_hi = decode_key(sl->h_sorted.p[total - 1], sl->base_us, xb, yb).t;
    }
    /* decoded straight after any events held back in out, the two runs merged where they overlap */
    const size_t held = out->n;
    if (!evr_event_vec_reserve(out, split)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for events");
        return EVR_ERR_NOMEM;
    }
    decode_keys(b->par, sl->h_sorted.p, split, sl->base_us, xb, yb, out->data + held);
    out->n += split;
    if (!evr_events_merge_runs(out, held, &b->scratch)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for events");
        return EVR_ERR_NOMEM;
    }
    *intensity = sl->want_intensity ? sl->h_intensity.p : NULL;
    *frames = sl->num_frames ? sl->h_frames.p : NULL;
    base->device_bytes = device_bytes(b);
    if (cuda_backend::tl_rec *r = tl_at(b, sl->index)) r->col1 = evr_host_seconds();
    b->head = (b->head + 1) % NSLOT;
    b->queued--;
    return start_ready_copies(b, err);
}

static void cuda_release(evr_backend *base)
{
    cuda_backend *b = (cuda_backend *)base;
    if (!b) return;
    cudaDeviceSynchronize();
    if (b->tl) {   /* seconds from the base event; a segment's row once it was submitted */
        const double h0 = b->tl_h0;
        fprintf(b->tl, "seg sub0 sub1 col0 counted copied col1 g_start g_rendered g_sort g_copied n\n");
        for (int i = 0; i < b->tl_cap; i++) {
            const cuda_backend::tl_rec *r = &b->tl_recs[i];
            if (r->sub1 == 0.0) continue;
            fprintf(b->tl, "%d %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %zu\n", i, r->sub0 - h0, r->sub1 - h0,
                    r->col0 - h0, r->counted - h0, r->copied - h0, r->col1 - h0, r->g_start, r->g_rendered, r->g_sort,
                    r->g_copied, r->n);
        }
        if (b->tl_lost) fprintf(b->tl, "# incomplete: out of memory for the timeline\n");
        if (fclose(b->tl) != 0 || b->tl_lost) fprintf(stderr, "evray: warning: the timeline (EVR_TIMELINE) is incomplete\n");
        free(b->tl_recs);
        if (b->tl_base) cudaEventDestroy(b->tl_base);
    }
    for (int i = 0; i < NSLOT; i++) {
        slot *sl = &b->slots[i];
        sl->h_keys.release(); sl->h_tracks.release(); sl->d_keys.release(); sl->d_tracks.release();
        evr_gpu_top_free(&sl->top);
        sl->d_top4.release(); sl->d_top8.release(); sl->d_insts.release();
        sl->d_keys_ev.release(); sl->d_keys_sorted.release(); sl->d_sort_temp.release();
        sl->d_count.release(); sl->d_rays.release(); sl->d_intensity.release();
        sl->d_plan.release(); sl->h_plan.release(); sl->d_list.release();
        sl->d_adapt.release(); sl->h_adapt.release();
        sl->h_count.release(); sl->h_rays.release(); sl->h_sorted.release(); sl->h_intensity.release();
        sl->h_frame_f.release(); sl->d_frame_f.release(); sl->d_frames.release(); sl->h_frames.release();
        sl->d_sat.release(); sl->d_ch_before.release(); sl->d_ch_base.release(); sl->d_ch_x.release(); sl->h_gi_view.release();
        sl->d_gi_view.release(); sl->h_em.release(); sl->d_em.release(); sl->h_cdf.release(); sl->d_cdf.release();
        if (sl->gi_started) cudaEventDestroy(sl->gi_started);
        if (sl->gi_done) cudaEventDestroy(sl->gi_done);
        if (sl->framed) cudaEventDestroy(sl->framed);
        if (sl->copy) cudaStreamDestroy(sl->copy);
        if (sl->started) cudaEventDestroy(sl->started);
        if (sl->rendered) cudaEventDestroy(sl->rendered);
        if (sl->counted) cudaEventDestroy(sl->counted);
        if (sl->sorted) cudaEventDestroy(sl->sorted);
        if (sl->copied) cudaEventDestroy(sl->copied);
        if (sl->sort_from) cudaEventDestroy(sl->sort_from);
    }
    b->d_floats.release(); b->d_indices.release(); b->d_meshes.release(); b->d_materials.release();
    b->d_textures.release(); b->d_texels.release(); b->d_instances.release(); b->d_lights.release();
    b->d_nodes4.release(); b->d_nodes8.release(); b->d_tris.release(); b->d_phase.release(); b->d_static.release();
    evr_par_pool_free(b->par);
    b->par = nullptr;
    b->d_sensor.release();
    for (int i = 0; i < NRING; i++) {
        b->d_state[i].release();
        b->d_next[i].release();
        b->gi_ring[i].slots.release();
        b->gi_ring[i].count.release();
        b->gi_ring[i].gbuf.release();
    }
    b->d_gi_last.release();
    b->d_pending.release(); b->d_pkeys.release(); b->d_pkeys_sorted.release(); b->d_pvals.release();
    b->d_pvals_sorted.release(); b->d_pcount.release(); b->d_ptemp.release();
    b->d_trails.release(); b->d_trail_rays.release(); b->d_todo.release(); b->d_todo_count.release();
    evr_photon_emitters_free(&b->trail_em);
    gi_deferred_release(b);
    evr_photon_emitters_free(&b->em);
    if (b->render) cudaStreamDestroy(b->render);
    evr_gpu_bvh_free(&b->bvh);
    evr_event_vec_free(&b->scratch);
    delete b;
}

__global__ void init_pixels(evr_pixel_state *st, float *phase, int width, int height, unsigned long long seed)
{
    int pix = blockIdx.x * blockDim.x + threadIdx.x;
    if (pix >= width * height) return;
    evr_pixel_reset(&st[pix]);
    phase[pix] = evr_pixel_phase(seed, pix % width, pix / width);
}

static evr_status init(cuda_backend *b, evr_error *err)
{
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess || count == 0) {
        /* without an NVIDIA driver the runtime says "driver version is insufficient": say it plainly */
        const char *why = e == cudaSuccess || e == cudaErrorNoDevice ? "no NVIDIA GPU found"
                        : e == cudaErrorInsufficientDriver ? "no NVIDIA driver, or one too old for CUDA 13"
                        : cudaGetErrorString(e);
        snprintf(err->msg, sizeof err->msg, "no usable CUDA device (%s)", why);
        return EVR_ERR_BACKEND;
    }
    CK(cudaGetDevice(&b->device));
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, b->device));
    snprintf(b->device_name, sizeof b->device_name, "%s", prop.name);
    evr_status st;
    if ((st = evr_gpu_bvh_build(b->scene, b->setup.gpu_bvh, &b->bvh, err)) != EVR_OK) return st;
    if ((st = upload_scene(b, err)) != EVR_OK) return st;
    size_t npix = (size_t)b->setup.width * b->setup.height;
    for (int i = 0; i < NRING; i++) CK(b->d_state[i].reserve(npix));
    if (b->setup.adaptive) {
        for (int i = 0; i < NRING; i++) {
            CK(b->d_next[i].reserve(npix));
            CK(cudaMemset(b->d_next[i].p, 0, npix * sizeof(float)));
        }
    }
    CK(b->d_phase.reserve(npix));
    CK(b->d_sensor.reserve(1));
    CK(cudaMemcpy(b->d_sensor.p, &b->setup.pixel, sizeof(evr_pixel_params), cudaMemcpyHostToDevice));
    init_pixels<<<(unsigned)((npix + 255) / 256), 256>>>(b->d_state[0].p, b->d_phase.p, b->setup.width, b->setup.height,
                                                        (unsigned long long)b->setup.seed);
    CK(cudaGetLastError());
    CK(cudaStreamCreateWithFlags(&b->render, cudaStreamNonBlocking));
    /* four events a pixel per segment: the eye's busiest segments at 1280x720 take 3.3 (a segment
     * that needs more grows every slot's buffers, after rendering it again); but the slots' key,
     * sorted-key and sort buffers (24 bytes a key each) take at most an eighth of the free device
     * memory up front, so that a large image on a small GPU still starts (and grows as needed) */
    size_t free_bytes = 0, total_bytes = 0;
    CK(cudaMemGetInfo(&free_bytes, &total_bytes));
    const size_t fit = free_bytes / 8 / (NSLOT * 24);
    b->capacity = npix * 4 < fit ? npix * 4 : fit;
    if (b->capacity < (1u << 20)) b->capacity = 1u << 20;
    b->carry_slot = -1;
    int gi_margin = 0, gi_window = 0;
    b->gi = b->setup.gi;
    if (b->gi) evr_gi_run_params(&b->setup, b->scene, &b->photons, &b->gp, &b->pp, &gi_margin, &gi_window);
    b->trails_off = getenv("EVR_NO_PHOTON_REUSE") != NULL;   /* hidden, for tests and measurement: every photon traced */
    b->static_off = getenv("EVR_NO_STATIC_HITS") != NULL;
    b->par = evr_par_pool_new(evr_par_threads(8));   /* NULL: keys decoded on this thread */
    if (b->setup.gpu_event_capacity > 0) b->capacity = (size_t)b->setup.gpu_event_capacity;
    if (b->gi && (st = gi_ring_alloc(b, gi_margin, err)) != EVR_OK) return st;
    for (int i = 0; i < NSLOT; i++) {
        slot *sl = &b->slots[i];
        /* the sort and copy of segment i run while segment i + 1 renders: at the highest
         * priority, so that their few blocks go first and the host can take in segment i's
         * events while the GPU is still busy (at equal priority the sort waited for the whole
         * render kernel and the GPU then idled while the host worked) */
        int least = 0, greatest = 0;
        CK(cudaDeviceGetStreamPriorityRange(&least, &greatest));
        CK(cudaStreamCreateWithPriority(&sl->copy, cudaStreamNonBlocking, greatest));
        CK(cudaEventCreate(&sl->started));
        CK(cudaEventCreate(&sl->rendered));
        CK(cudaEventCreate(&sl->counted));
        CK(cudaEventCreate(&sl->sorted));
        CK(cudaEventCreate(&sl->copied));
        CK(cudaEventCreate(&sl->sort_from));
        CK(cudaEventCreate(&sl->framed));
        CK(sl->d_keys_ev.reserve(b->capacity));
        /* the sort's buffers too, up front: allocated as segments first need them, the frees
         * and pinned allocations stalled the GPU for 0.2 s of the eye's first second */
        CK(sl->d_keys_sorted.reserve(b->capacity));
        CK(sl->h_sorted.reserve(b->capacity));
        size_t temp = 0;
        CK(cub::DeviceRadixSort::SortKeys(nullptr, temp, sl->d_keys_ev.p, sl->d_keys_sorted.p, (int)sl->d_keys_sorted.cap, 0, 64));
        CK(sl->d_sort_temp.reserve(temp));
        CK(sl->d_count.reserve(2));
        CK(sl->d_rays.reserve(GI_COUNTERS));
        CK(sl->d_plan.reserve(1));
        CK(sl->h_plan.reserve(1));
        if (b->setup.adaptive) {
            CK(sl->d_adapt.reserve(1));
            CK(sl->h_adapt.reserve(1));
        }
        CK(sl->d_list.reserve((size_t)b->setup.width * (size_t)b->setup.height));
        CK(sl->d_intensity.reserve(npix));
        CK(sl->h_count.reserve(1));
        CK(sl->h_rays.reserve(GI_COUNTERS));
        CK(cudaMemset(sl->d_rays.p, 0, GI_COUNTERS * sizeof(unsigned long long)));
        if (b->gi && (st = gi_alloc(b, sl, gi_window, err)) != EVR_OK) return st;
    }
    if (b->gi) CK(b->d_pcount.reserve(1));
    gi_deferred_alloc(b, &prop);
    CK(cudaDeviceSynchronize());
    if (const char *tl = getenv("EVR_TIMELINE")) {
        if (!(b->tl = fopen(tl, "w"))) {
            snprintf(err->msg, sizeof err->msg, "cannot write the timeline %s (EVR_TIMELINE): %s", tl, strerror(errno));
            return EVR_ERR_IO;
        }
        CK(cudaEventCreate(&b->tl_base));
        CK(cudaEventRecord(b->tl_base, b->render));
        CK(cudaEventSynchronize(b->tl_base));
        b->tl_h0 = evr_host_seconds();
    }
    return EVR_OK;
}

extern "C" evr_status evr_cuda_backend_new(const evr_scene *s, const evr_render_host *h, const evr_run_setup *setup,
                                           evr_backend **out, evr_error *err)
{
    cuda_backend *b = new (std::nothrow) cuda_backend();
    if (!b) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    b->base.name = "cuda";
    b->base.depth = NSLOT;
    b->base.submit = cuda_submit;
    b->base.collect = cuda_collect;
    b->base.release = cuda_release;
    b->base.samples = 0;
    b->base.rays = 0;
    b->base.device_seconds = 0.0;
    b->scene = s;
    b->host = *h;
    b->setup = *setup;
    evr_status st = init(b, err);
    if (st != EVR_OK) {
        cuda_release(&b->base);
        return st;
    }
    *out = &b->base;
    return EVR_OK;
}

extern "C" const char *evr_cuda_device_name(const evr_backend *base)
{
    return ((const cuda_backend *)base)->device_name;
}
