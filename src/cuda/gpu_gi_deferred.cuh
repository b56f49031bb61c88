/* Global illumination with the gathers deferred (uniform sampling): the render of a segment in
 * three kernels instead of one.
 *
 *   gi_trace_kernel   the pixels' samples: rays and direct light; a sample that needs a gather
 *                     (its pixel's memo does not hold its surface point) appends a request
 *   gi_gather_kernel  one thread per request: the gathers at the segment's start (unless the
 *                     pixel's last gather of the previous segment was at the same point) and end
 *   gi_pixel_kernel   the pixels' samples through the pixel model: direct + gathered light at the
 *                     sample's time (a settled pixel: its last direct light, its gathers)
 *
 * Why: a gather inside the render kernel cost 31 ns against 3.8 ns in a kernel of its own
 * (H100, Cornell box at 1280x720; docs/benchmarks.md): there it ran at the render kernel's
 * occupancy, its lanes beside lanes that trace. The samples, their intensities (direct + gathered,
 * the same float addition as gpu_sample) and the events are those of render_kernel<GI> bit for
 * bit; tests/test_cuda.py compares the two (EVR_GI_INLINE=1 selects the single kernel).
 *
 * Included by cuda_backend.cu after render_kernel (it uses its helpers). */
#ifndef EVR_CUDA_GPU_GI_DEFERRED_CUH
#define EVR_CUDA_GPU_GI_DEFERRED_CUH

#define GI_NO_REQUEST 0xffffffffu

/* A deferred gather: the surface point and its pixel; has_ls: its start gather is known (ls, the
 * pixel's end gather of the previous segment at the same point). */
struct gi_request {
    evr_gather_point g;
    int pix;
    float ls;
    int has_ls;
};

/* The three kernels' shared buffers (device memory, reused by every launch: the kernels of a
 * segment run in order on the render stream). Per-sample arrays are [sample][thread]. */
struct gi_deferred {
    float *direct;        /* a traced sample's direct light */
    unsigned *req;        /* its gather request, GI_NO_REQUEST for a miss (no light) */
    int *traced;          /* per thread: samples with an entry (traced or held); later samples keep the last */
    float *cache_dist;    /* per thread: the change-driven sampling cache after the segment */
    gi_request *requests;
    float2 *lum;          /* per request: the gathers' luminance at the segment's start and end */
    unsigned *count;      /* requests made */
    int stride;           /* threads of a launch at most: the pixel count */
};

/* First kernel: render_kernel's rays and settling, without the pixel model. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK, MIN_BLOCKS) gi_trace_kernel(kernel_args a, gi_deferred d)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int i = lp.i, pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    const float phi = active ? a.phase[pix] : 0.0f;
    unsigned rays = 0, traced = 0;
    int entries = 0, last_span = -1;   /* samples with an entry; the still span of the last traced */
    float t_hit = INFINITY, cache = -1.0f;
    bool tracing = active;
    gi_memo memo;
    memo.valid = false;
    gi_end last;                       /* the pixel's last gather of the previous segment */
    last.g.dist = -1.0f;
    if (active && a.gi->ends_in) last = a.gi->ends_in[pix];
    const evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 = evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    float direct = 0.0f;               /* the last traced sample's, and its request */
    unsigned r = GI_NO_REQUEST;
    for (int k = 0; k < a.samples; k++) {
        const float f = ((float)k + phi) / (float)a.samples;
        const int span = evr_skip_still_span(a.plan, f);
        /* held: in the still span of the last traced sample, the same direct light and gathers */
        const bool now = tracing && !evr_skip_held(a.plan, span, last_span);
        bool want = false;
        evr_gather_point g;
        if (now) {
            r = GI_NO_REQUEST;
            direct = 0.0f;
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            evr_surface s;
            int inst = 0;
            evr_v3 org;
            if (gpu_sample_direct<LAYOUT>(a, &pose, x, y, f, &rays, &t_hit, a.coherence ? t_hit : INFINITY, &direct, &s, &inst,
                                          &org)) {
                gpu_gather_point(&a.rs, inst, &s, org, &g);
                if (gi_memo_take(&memo, inst, &g)) r = memo.req;
                else want = true;
            }
            traced++;
            last_span = span;
        }
        const unsigned slot = warp_append(d.count, want);   /* the warp's requests in one atomic */
        if (want) {
            r = slot;
            const bool known = last.g.dist >= 0.0f && gather_point_same(&last.g, &g);
            d.requests[r].g = g;
            d.requests[r].pix = pix;
            d.requests[r].ls = known ? last.le : 0.0f;
            d.requests[r].has_ls = known;
            memo.req = r;
        }
        if (tracing) {
            const size_t at = (size_t)k * (size_t)d.stride + (size_t)i;
            d.direct[at] = direct;
            d.req[at] = r;
            entries = k + 1;
        }
        if (k == 0 && tracing) {
            /* settle, as render_kernel: the first sample's rays meet nothing that moves */
            const float c = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit);
            if (c >= 0.0f) {
                tracing = false;
                cache = c;
            }
        }
    }
    if (active) {
        if (tracing) cache = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit);
        d.cache_dist[i] = cache;
        d.traced[i] = entries;
    }
    add_counts(a, lane, rays, traced);
}

/* Second kernel: the requests' gathers, a grid-stride loop over however many were made. */
__global__ void __launch_bounds__(BLOCK) gi_gather_kernel(kernel_args a, gi_deferred d)
{
    const unsigned n = *d.count;
    for (unsigned r = blockIdx.x * blockDim.x + threadIdx.x; r < n; r += gridDim.x * blockDim.x) {
        const gi_request q = d.requests[r];
        float2 l;
        gpu_gather_ends(a.gi, &a.rs.camera, &q.g, q.pix % a.width, q.pix / a.width, &l.x, &l.y, q.has_ls ? &q.ls : nullptr);
        d.lum[r] = l;
    }
}

/* Third kernel: render_kernel's pixel model over the intensities of the first two. */
template <int SENSOR>
__global__ void __launch_bounds__(BLOCK, MIN_BLOCKS) gi_pixel_kernel(kernel_args a, gi_deferred d)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int i = lp.i, pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    evr_pixel_state st;
    evr_pixel_params own;
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    const int traced = active ? d.traced[i] : 0;
    float direct = 0.0f;
    unsigned r = GI_NO_REQUEST;
    for (int k = 0; k < a.samples; k++) {
        const float f = ((float)k + phi) / (float)a.samples;
        float intensity = st.intensity;   /* kept when settled on nothing */
        if (k < traced) {
            const size_t at = (size_t)k * (size_t)d.stride + (size_t)i;
            direct = d.direct[at];
            r = d.req[at];
        }
        if (k < traced || r != GI_NO_REQUEST) {   /* settled on a surface: its last direct light, its gathers at f */
            intensity = direct;
            if (r != GI_NO_REQUEST) {
                const float2 l = d.lum[r];
                intensity += evr_gi_lerp(l.x, l.y, f);
            }
        }
        pixel_sample<SENSOR>(a, st, own, active, f, intensity, x, y, lane);
    }
    if (active) {
        st.cache_dist = d.cache_dist[i];
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.gi->ends_out) {   /* its last gather, for the next segment's start */
            gi_end e{};
            e.g.dist = -1.0f;
            if (r != GI_NO_REQUEST) {
                e.g = d.requests[r].g;
                e.le = d.lum[r].y;
            }
            a.gi->ends_out[pix] = e;
        }
    }
}

#endif
