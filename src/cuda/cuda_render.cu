/* The render kernels of the CUDA backend and their launches: one thread per pixel runs the
 * pixel's samples of the segment (camera ray, our BVH traversal with motion transforms, shading
 * and the pixel model from src/core, the very functions the CPU backend runs), uniformly or
 * adaptively, with change-driven sampling's skip kernel before; the static hits of a still
 * camera, the intensity frames and the pixels' first states. The deferred gathers' kernels are
 * cuda_gi_deferred.cu's. */
#include "cuda/cuda_render.cuh"
#include "core/rng.h"
#include "cuda/cuda_pixel.cuh"

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
/* Change-driven sampling, first pass: a pixel that keeps its cached intensity runs its samples
 * through the pixel model here (no rays); the others are listed for the render kernel. With
 * deferred gathers (d.requests set), a pixel whose rays meet nothing that moves but whose gather
 * window saw photons change gets here what gi_trace_kernel would make of it, without its rays:
 * its first sample settles on its last traced sample's direct light and surface point (the
 * same rays meet the same still surfaces: the same bits), and a gather request with the start
 * known; it is listed for the gather and pixel kernels only. With refined sampling (rf.plan set)
 * a sensor model's kept samples come at the times brute force would trace them
 * (evr_refine_keep). */
template <int SENSOR>
__global__ void __launch_bounds__(BLOCK) skip_kernel(kernel_args a, gi_deferred d, refine_args rf)
{
    int pix, x, y;
    const bool active =
        tiled_pixel(blockIdx.x * blockDim.x + threadIdx.x, a.width, a.height, &pix, &x, &y);
    const unsigned lane = threadIdx.x & 31u;
    evr_pixel_state st;
    evr_pixel_params own;
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    bool skip = false, indirect_only = false;
    float cache = -1.0f;
    const evr_m34 pose = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray = evr_camera_ray(&a.rs.camera, &pose, (float)x + 0.5f, (float)y + 0.5f);
    if (active) {
        skip = evr_skip_pixel(&a.rs, a.plan, st.started, st.cache_dist, ray);
        /* global illumination: a pixel whose gather window saw photons change over this segment
         * or the last traces (its indirect light moves, or moved after its last sample) */
        if (skip && a.gi &&
            evr_photon_window_changed(a.gi->sat, a.gi->end.width, a.gi->end.height,
                                      a.gi->end.margin, a.gi->window, x, y)) {
            skip = false;
            /* as the trace kernel would settle it: its hit the cached one, the cache kept */
            cache = evr_skip_cache_after_trace(&a.rs, a.plan, ray, st.cache_dist,
                                               st.cache_dist == EVR_SKIP_DEEP);
            indirect_only = d.requests && a.gi->ends_in && a.gi->ends_in[pix].g.dist >= 0.0f &&
                            evr_skip_clean(cache);
        }
    }
    const unsigned at = warp_append(a.list_count, active && !skip);
    if (active && !skip)
        a.list[at] = indirect_only ? (unsigned)pix | LIST_INDIRECT_ONLY : (unsigned)pix;
    const unsigned r =
        warp_append(&d.count[REQ_KNOWN], indirect_only); /* a request with the start known */
    if (indirect_only) {
        const gi_end *e = &a.gi->ends_in[pix];
        d.requests[r].g = e->g;
        d.requests[r].pix = pix;
        d.requests[r].ls = e->le;
        d.direct[at] = e->direct; /* sample 0's entry */
        if (d.ids) d.ids[at] = a.id_in[pix];
        d.req[at] = r;
        d.traced[at] = 1;
        d.cache_dist[at] = cache;
    }
    const unsigned skipped = __ballot_sync(0xffffffffu, skip);
    if (!skipped) return; /* the whole warp */
    if (lane == 0) atomicAdd(&a.counters[CTR_SKIPPED], (unsigned long long)__popc(skipped));
    const float kept = st.intensity;
    const unsigned id = skip && a.id_in ? a.id_in[pix] : 0u; /* its last traced sample's */
    if (SENSOR && rf.plan) { /* refined sampling: at brute force's times (evr_refine_keep) */
        evr_refine_pixel q;
        const float m0 = skip ? evr_refine_motion_dt_first(&a.rs, rf.plan, &rf.p, ray) : INFINITY;
        evr_refine_begin(&q, &st, evr_refine_step(&rf.p, m0, a.dt), a.dt);
        q.need = skip;
        evr_refine_keep(&q, &st, id);
        while (__any_sync(0xffffffffu, q.need || q.cand)) {
            if (q.need) evr_refine_kept(&q, a.plan, q.t / a.dt); /* settled: always kept */
            const bool consume = q.cand && evr_refine_decide(&q, &rf.p, &st, &own);
            pixel_sample_at<SENSOR>(a, st, own, consume, q.ct, q.ci, x, y, lane, q.cid);
            if (consume) evr_refine_next_bounded(&q, &a.rs, rf.plan, &rf.p, ray, a.dt);
        }
    } else {
        for (int k = 0; k < a.samples; k++)
            pixel_sample<SENSOR>(a, st, own, skip, ((float)k + phi) / (float)a.samples, kept, x, y,
                                 lane, id);
    }
    if (skip) {
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.id_out) a.id_out[pix] = id;
        if (a.gi && a.gi->ends_out)
            a.gi->ends_out[pix] = a.gi->ends_in[pix]; /* its last gather holds */
    }
}
/* SENSOR: 1 for the full sensor model of core/pixel.h (mismatch, bandwidth, leak, noise,
 * timestamps), 0 for the ideal sensor: then the kernel runs the ideal model's own functions on the
 * ideal part of the state and compiles to the same code as before the sensor model existed (same
 * size and layout: measured on an H100, the same time on the eye and square demos; an earlier
 * version a few instructions longer was 40% slower on the square through instruction fetch).
 * With a list (change-driven sampling), thread i renders pixel list[i]. */
template <int LAYOUT, int SENSOR, int GI>
__global__ void __launch_bounds__(BLOCK, GI ? MIN_BLOCKS_GI : MIN_BLOCKS)
    render_kernel(kernel_args a)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    evr_pixel_state st;
    evr_pixel_params own; /* the sensor kernel's parameters of this pixel */
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    unsigned rays = 0, traced = 0;
    float t_hit = INFINITY, direct = 0.0f;
    int deep = 0; /* the last traced sample's path went past its primary hit */
    bool tracing = active;
    gi_memo memo;
    memo.valid = false;
    evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 =
        evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    int last_span = -1; /* the still span of the last traced sample */
    unsigned id = active && a.id_in ? a.id_in[pix] : 0u; /* the last traced sample's event id */
    for (int k = 0; k < a.samples; k++) {
        float f = ((float)k + phi) / (float)a.samples,
              intensity = st.intensity; /* kept when settled or held */
        const int span = evr_skip_still_span(a.plan, f);
        if (tracing && !evr_skip_held(a.plan, span, last_span)) {
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            intensity = gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &t_hit, &memo,
                                               a.coherence ? t_hit : INFINITY, &direct, &deep,
                                               a.ids ? &id : nullptr);
            traced++;
            last_span = span;
        } else if (
            GI &&
            t_hit <
                INFINITY) { /* settled or held on a surface: its direct light, its gathers at f */
            intensity = direct + evr_gi_lerp(memo.ls, memo.le, f);
        }
        pixel_sample<SENSOR>(a, st, own, active, f, intensity, x, y, lane, id);
        if (k == 0 && tracing) {
            /* settle: the first sample's rays meet nothing that moves in the segment, so every
             * sample sees the same triangles: keep its intensity (GI: its direct light) */
            float c = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit, deep);
            if (evr_skip_clean(c)) {
                tracing = false;
                st.cache_dist = c;
            }
        }
    }
    if (active) {
        if (tracing) st.cache_dist = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit, deep);
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.id_out) a.id_out[pix] = id;
    }
    add_counts(a, lane, rays, traced);
}

/* Adaptive sampling (core/adaptive.h), one thread per pixel, the same steps as the CPU backend's
 * render_tile_adaptive: the pixel traces at its scheduled times; a sample that changed too much
 * is held back on the pixel's stack while the interval before it is refined; every sample goes
 * through the pixel model in time order. Lanes run their own schedules; the event appends stay
 * warp-synchronous (every lane calls pixel_sample_at each round). */
template <int LAYOUT, int SENSOR, int GI>
__global__ void __launch_bounds__(BLOCK) adapt_kernel(kernel_args a, adapt_args d)
{
    int pix, x, y;
    const bool active =
        tiled_pixel(blockIdx.x * blockDim.x + threadIdx.x, a.width, a.height, &pix, &x, &y);
    const unsigned lane = threadIdx.x & 31u;
    evr_pixel_state st;
    evr_pixel_reset(&st);
    evr_pixel_params own = *a.sensor; /* the run's parameters; per pixel for the sensor kernel */
    const evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 =
        evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
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
    float ct = 0.0f, ci = 0.0f,
          ch = INFINITY; /* the candidate sample: time, intensity, hit distance, event id */
    unsigned cid = 0;
    bool cand = false;
    unsigned rays = 0, taken = 0;
    gi_memo memo;
    memo.valid = false;
    while (__any_sync(0xffffffffu, need || cand)) {
        if (need) {
            const float f = t / a.dt;
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            int deep = 0;
            ci = gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &ch, &memo, INFINITY, nullptr,
                                        &deep, a.ids ? &cid : nullptr);
            ch = evr_adapt_hit(ch, deep);
            ct = t;
            cand = true;
            need = false;
            taken++;
        }
        bool consume = false;
        float step = 0.0f;
        int moving = 0;
        if (cand) { /* held back (trace t first) or taken */
            consume = evr_adapt_candidate(&a.rs, &d.p, d.plan, &st, &own, ray0, &sk, ct, ci, ch,
                                          cid, &t, &step, &moving);
            if (!consume) {
                need = true;
                cand = false;
            }
        }
        pixel_sample_at<SENSOR>(a, st, own, consume, ct, ci, x, y, lane, cid);
        if (consume && !evr_adapt_taken(&d.p, &sk, step, moving, a.dt, &ct, &ci, &ch, &cid, &t)) {
            cand = false; /* none held back: t is the next to trace */
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

/* Refined sampling (core/refine.h), one thread per pixel that traces (the skip kernel's list, or
 * every pixel), the same steps as the CPU backend's refine_samples: the pixel traces its grid
 * samples and the bisections of intervals in which it fires; every sample goes through the pixel
 * model in time order. Lanes run their own schedules; the event appends stay warp-synchronous
 * (every lane calls pixel_sample_at each round). No global illumination (refused by the
 * configuration). */
template <int LAYOUT, int SENSOR>
__global__ void __launch_bounds__(BLOCK) refine_kernel(kernel_args a, refine_args d)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    evr_pixel_state st;
    evr_pixel_params own;
    (void)pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    if (!SENSOR) own = *a.sensor; /* the thresholds the refinement reads */
    const evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 =
        evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    evr_refine_pixel q;
    const float motion_dt =
        active ? evr_refine_motion_dt_first(&a.rs, d.plan, &d.p, ray0) : INFINITY;
    evr_refine_begin(&q, &st, evr_refine_step(&d.p, motion_dt, a.dt), a.dt);
    q.need = active;
    unsigned rays = 0, traced = 0;
    gi_memo memo;
    memo.valid = false;
    float hint = INFINITY; /* temporal coherence: the last traced sample's hit */
    while (__any_sync(0xffffffffu, q.need || q.cand)) {
        if (q.need && !evr_refine_kept(&q, a.plan, q.t / a.dt)) {
            const float f = q.t / a.dt;
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            float hit;
            int deep = 0;
            unsigned sid = 0;
            const float in = gpu_sample<LAYOUT, 0>(a, &pose, x, y, f, &rays, &hit, &memo,
                                                   a.coherence ? hint : INFINITY, nullptr, &deep,
                                                   a.ids ? &sid : nullptr);
            hint = hit;
            traced++;
            evr_refine_traced(&q, &a.rs, a.plan, &st, ray0, f, in, hit, deep, sid, 1);
        }
        const bool consume = q.cand && evr_refine_decide(&q, &d.p, &st, &own);
        pixel_sample_at<SENSOR>(a, st, own, consume, q.ct, q.ci, x, y, lane, q.cid);
        if (consume) evr_refine_next_bounded(&q, &a.rs, d.plan, &d.p, ray0, a.dt);
    }
    if (active) {
        evr_refine_end(&q, &a.rs, a.plan, &st, ray0);
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.id_out) a.id_out[pix] = q.traced_any ? q.last_id : (a.id_in ? a.id_in[pix] : 0u);
    }
    add_counts(a, lane, rays, traced);
}

/* Intensity frames: frame k is every pixel's intensity at normalized segment time frame_f[k], one
 * sample through the pixel centre (the same gpu_sample as the segment's samples), written to
 * frames[k * npix + pix]. A kernel of its own so that the render kernel and the pixel states are
 * untouched: events are the same with or without frames. Its rays are not counted. */
template <int LAYOUT, int GI>
__global__ void __launch_bounds__(BLOCK)
    frame_kernel(kernel_args a, const float *frame_f, int num_frames, float *frames)
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
        frames[(size_t)k * (size_t)npix + (size_t)pix] =
            gpu_sample<LAYOUT, GI>(a, &pose, x, y, f, &rays, &t_hit, &memo);
    }
}

/* Label frames (backend.h): every pixel's primary hit through its centre at normalized segment
 * time label_f[k], written to hits[k * npix + pix] (inst -1: none), the host's ground truth's
 * input (core/labels.h). Like the frames, a kernel of its own, its rays uncounted. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK)
    label_kernel(kernel_args a, const float *label_f, int num_labels, evr_hit *hits)
{
    const int npix = a.width * a.height;
    const int pix = blockIdx.x * blockDim.x + threadIdx.x;
    if (pix >= npix) return;
    const int x = pix % a.width, y = pix / a.width;
    for (int k = 0; k < num_labels; k++) {
        const float f = label_f[k];
        const evr_m34 pose = evr_rs_camera_pose(&a.rs, f);
        const evr_ray ray = evr_camera_ray(&a.rs.camera, &pose, (float)x + 0.5f, (float)y + 0.5f);
        evr_gpu_hit hit;
        evr_hit o;
        o.t = INFINITY;
        o.u = o.v = 0.0f;
        o.prim = 0;
        o.inst = -1;
        if (gpu_trace<LAYOUT>(&a.view, &a.rs, ray, 0.0f, 1e30f, f, 0, &hit)) {
            o.t = hit.t;
            o.u = hit.u;
            o.v = hit.v;
            o.prim = hit.prim;
            o.inst = hit.instance;
        }
        hits[(size_t)k * (size_t)npix + (size_t)pix] = o;
    }
}

/* Every pixel's first state and its sample phase. */
__global__ void init_pixels(evr_pixel_state *st, float *phase, int width, int height,
                            unsigned long long seed, int aligned)
{
    int pix = blockIdx.x * blockDim.x + threadIdx.x;
    if (pix >= width * height) return;
    evr_pixel_reset(&st[pix]);
    phase[pix] = aligned ? 1.0f : evr_pixel_phase(seed, pix % width, pix / width);
}

/* Calls f with the kernel variant v as compile-time constants: f(variant<LAYOUT, SENSOR, GI>{}). */
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
template <typename F> static void with_variant(kernel_variant v, F f)
{
    with_layout(v.layout, [&](auto l) { with_variant_of<decltype(l)::value>(v.sensor, v.gi, f); });
}

void cuda_launch_static_hits(const kernel_args &a, int layout, gpu_static_hit *out, unsigned grid,
                             cudaStream_t s)
{
    with_layout(layout, [&](auto l) {
        static_hits_kernel<decltype(l)::value><<<grid, BLOCK, 0, s>>>(a, out);
    });
}

void cuda_launch_skip(const kernel_args &a, const gi_deferred &d, const refine_args &r, bool ideal,
                      unsigned grid, cudaStream_t s)
{
    if (ideal) skip_kernel<0><<<grid, BLOCK, 0, s>>>(a, d, r);
    else skip_kernel<1><<<grid, BLOCK, 0, s>>>(a, d, r);
}

void cuda_launch_render(const kernel_args &a, kernel_variant v, unsigned grid, cudaStream_t s)
{
    with_variant(v, [&](auto k) {
        render_kernel<decltype(k)::layout, decltype(k)::sensor, decltype(k)::gi>
            <<<grid, BLOCK, 0, s>>>(a);
    });
}

void cuda_launch_adapt(const kernel_args &a, const adapt_args &d, kernel_variant v, unsigned grid,
                       cudaStream_t s)
{
    with_variant(v, [&](auto k) {
        adapt_kernel<decltype(k)::layout, decltype(k)::sensor, decltype(k)::gi>
            <<<grid, BLOCK, 0, s>>>(a, d);
    });
}

void cuda_launch_refine(const kernel_args &a, const refine_args &d, kernel_variant v, unsigned grid,
                        cudaStream_t s)
{
    with_layout(v.layout, [&](auto l) {
        if (v.sensor) refine_kernel<decltype(l)::value, 1><<<grid, BLOCK, 0, s>>>(a, d);
        else refine_kernel<decltype(l)::value, 0><<<grid, BLOCK, 0, s>>>(a, d);
    });
}

void cuda_launch_frames(const kernel_args &a, kernel_variant v, const float *frame_f,
                        int num_frames, float *frames, unsigned grid, cudaStream_t s)
{
    with_variant(v, [&](auto k) {
        frame_kernel<decltype(k)::layout, decltype(k)::gi>
            <<<grid, BLOCK, 0, s>>>(a, frame_f, num_frames, frames);
    });
}

void cuda_launch_labels(const kernel_args &a, kernel_variant v, const float *label_f,
                        int num_labels, evr_hit *hits, unsigned grid, cudaStream_t s)
{
    with_variant(v, [&](auto k) {
        label_kernel<decltype(k)::layout><<<grid, BLOCK, 0, s>>>(a, label_f, num_labels, hits);
    });
}

void cuda_launch_init_pixels(evr_pixel_state *st, float *phase, int width, int height,
                             unsigned long long seed, int aligned)
{
    const size_t npix = (size_t)width * (size_t)height;
    init_pixels<<<(unsigned)((npix + 255) / 256), 256>>>(st, phase, width, height, seed, aligned);
}
