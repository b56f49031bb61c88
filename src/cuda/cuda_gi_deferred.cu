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
 * bit; tests/test_cuda.py compares the two (EVR_GI_INLINE=1 selects the single kernel). */
#include "cuda/cuda_gi_deferred.cuh"
#include "cuda/cuda_pixel.cuh"

#include <stdlib.h>

/* Where a launch's thread keeps its entries in the arrays of one per pixel (direct, req, traced,
 * cache_dist; stride the pixels): its place in the skip kernel's list, or without a list its
 * pixel (a launch over every pixel in tiles has more threads than pixels). */
__device__ __forceinline__ int entry_slot(const kernel_args &a, const launch_pixel &lp)
{
    return a.list ? lp.i : lp.pix;
}

/* First kernel: render_kernel's rays and settling, without the pixel model. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK, MIN_BLOCKS) gi_trace_kernel(kernel_args a, gi_deferred d)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active =
        lp.active && !lp.indirect_only; /* the skip kernel made the others' entries */
    const int i = entry_slot(a, lp), pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    const float phi = active ? a.phase[pix] : 0.0f;
    unsigned rays = 0, traced = 0;
    int entries = 0, last_span = -1; /* samples with an entry; the still span of the last traced */
    float t_hit = INFINITY, cache = -1.0f;
    bool tracing = active;
    gi_memo memo;
    memo.valid = false;
    gi_end last; /* the pixel's last gather of the previous segment */
    last.g.dist = -1.0f;
    if (active && a.gi->ends_in) { /* its point and luminance (not the sums: the gather kernel's) */
        last.g = a.gi->ends_in[pix].g;
        last.le = a.gi->ends_in[pix].le;
    }
    bool made_new = false; /* a request without the start known */
    const evr_m34 pose_static = evr_rs_camera_pose(&a.rs, 0.0f);
    const evr_ray ray0 =
        evr_camera_ray(&a.rs.camera, &pose_static, (float)x + 0.5f, (float)y + 0.5f);
    float direct = 0.0f; /* the last traced sample's, and its request and event id */
    int deep = 0;        /* the last traced sample's path went past its primary hit */
    unsigned r = GI_NO_REQUEST, id = 0;
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
            id = 0;
            evr_m34 pose = a.camera_static ? pose_static : evr_rs_camera_pose(&a.rs, f);
            evr_surface s;
            int inst = 0;
            evr_v3 org;
            if (gpu_sample_direct<LAYOUT>(a, &pose, x, y, f, &rays, &t_hit,
                                          a.coherence ? t_hit : INFINITY, &direct, &s, &inst, &org,
                                          &deep)) {
                id = (unsigned)inst + 1u;
                gpu_gather_point(&a.rs, inst, &s, org, &g);
                if (gi_memo_take(&memo, inst, &g)) r = memo.req;
                else want = true;
            }
            traced++;
            last_span = span;
        }
        /* the warp's requests in one atomic per kind: those whose start gather is known (the
         * pixel's last, at the same point) from the front, the others from the back, each kind
         * gathered by a kernel of its own */
        const bool known = want && last.g.dist >= 0.0f && gather_point_same(&last.g, &g);
        const unsigned slot_known = warp_append(&d.count[REQ_KNOWN], known),
                       slot_new = warp_append(&d.count[REQ_NEW], want && !known);
        if (want) {
            made_new |= !known;
            r = known ? slot_known : d.cap - 1u - slot_new;
            d.requests[r].g = g;
            d.requests[r].pix = pix;
            d.requests[r].ls = known ? last.le : 0.0f;
            memo.req = r;
        }
        if (tracing) {
            const size_t at = (size_t)k * (size_t)d.stride + (size_t)i;
            d.direct[at] = direct;
            if (d.ids) d.ids[at] = id;
            d.req[at] = r;
            entries = k + 1;
        }
        if (k == 0 && tracing) {
            /* settle, as render_kernel: the first sample's rays meet nothing that moves */
            const float c = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit, deep);
            if (evr_skip_clean(c)) {
                tracing = false;
                cache = c;
            }
        }
    }
    const unsigned at = warp_append(&d.count[REQ_NEW_PIXELS], made_new);
    if (made_new) d.newpix[at] = i;
    if (active) {
        if (tracing) cache = evr_skip_cache_after_trace(&a.rs, a.plan, ray0, t_hit, deep);
        d.cache_dist[i] = cache;
        d.traced[i] = entries;
    }
    add_counts(a, lane, rays, traced);
}

/* gp.max_photons 0: what the cells that changed over the segment add to every pixel's last
 * gather (a still point's sums at the segment's end are those at its start plus this), scattered
 * from the cells: a warp per changed cell, its lanes over the pixels whose window may hold it,
 * each adding the cell's new terms minus its old ones for its pixel's point (the same terms as
 * evr_photon_gather_delta's, so the same integer sums) with atomic additions (integers: the
 * order does not matter). Each pixel walking its window's rows for the changed cells instead
 * (evr_photon_gather_delta in the known requests' kernel) took 36 ms per 0.5 s of the Cornell
 * box at 1280x720 on the H100. */
__global__ void __launch_bounds__(BLOCK) gi_scatter_kernel(kernel_args a, gi_deferred d)
{
    const gpu_gi_view *v = a.gi;
    const int w = v->end.width, h = v->end.height, m = v->end.margin, reach = v->gp.max_window;
    const unsigned n = v->ch.base[h], lane = threadIdx.x & 31u,
                   warps = gridDim.x * blockDim.x / 32u;
    const int side = 2 * reach + 1;
    for (unsigned k = (blockIdx.x * blockDim.x + threadIdx.x) / 32u; k < n; k += warps) {
        int lo = 0, hi = h - 1; /* the cell's row: the last whose base <= k */
        while (lo < hi) {
            const int mid = (lo + hi + 1) / 2;
            if (v->ch.base[mid] <= k) lo = mid;
            else hi = mid - 1;
        }
        const int cy = lo, cx = (int)v->ch.x[k];
        const size_t cell = (size_t)cy * (size_t)w + (size_t)cx;
        for (int j = (int)lane; j < side * side; j += 32) {
            const int px = cx - m - reach + j % side, py = cy - m - reach + j / side;
            if (px < 0 || py < 0 || px >= a.width || py >= a.height) continue;
            const int pix = py * a.width + px;
            const evr_gather_point g = v->ends_in[pix].g;
            if (!(g.dist >= 0.0f)) continue; /* no gather kept */
            evr_sum_query q;
            const evr_gather_window win =
                evr_gather_point_query(&v->end, &a.rs.camera, &v->gp, &g, px, py, &q);
            if (abs(cx - win.cx) > win.h || abs(cy - win.cy) > win.h)
                continue; /* outside its window */
            evr_gather_sum t = {0, 0};
            evr_photon_cell_sum(&v->end, cell, &q, &t, 0);
            evr_photon_cell_sum(&v->start, cell, &q, &t, 1);
            if (t.a) atomicAdd(&d.delta[2 * (size_t)pix], (unsigned long long)t.a);
            if (t.w) atomicAdd(&d.delta[2 * (size_t)pix + 1], (unsigned long long)t.w);
        }
    }
}

/* Second kernel, first part: the requests with the start known (a pixel whose point stays), a
 * grid-stride loop over however many were made; FIXED: gp.max_photons 0 (the fixed-point sums:
 * the end's are the start's plus what gi_scatter_kernel added up for the pixel). */
template <bool FIXED>
__global__ void __launch_bounds__(BLOCK, 8) gi_gather_known_kernel(kernel_args a, gi_deferred d)
{
    const unsigned n = d.count[REQ_KNOWN];
    for (unsigned r = blockIdx.x * blockDim.x + threadIdx.x; r < n; r += gridDim.x * blockDim.x) {
        const evr_gather_point g = d.requests[r].g;
        const int pix = d.requests[r].pix, x = pix % a.width, y = pix / a.width;
        const float ls = d.requests[r].ls;
        float2 l;
        if (FIXED) {
            evr_gather_sum s = a.gi->ends_in[pix].s; /* the start's sums */
            l.x = ls;
            l.y = ls;
            if (evr_photon_window_changed(a.gi->sat, a.gi->end.width, a.gi->end.height,
                                          a.gi->end.margin, a.gi->window, x, y)) {
                s.a += d.delta[2 * (size_t)pix];
                s.w += d.delta[2 * (size_t)pix + 1];
                l.y = gpu_sum_lum(a.gi, &a.rs.camera, &g, x, y, &s);
            }
            d.requests[r].s = s;
        } else {
            evr_gather_sum s;
            gpu_gather_ends<FIXED>(a.gi, &a.rs.camera, &g, x, y, &l.x, &l.y, &ls, &s);
        }
        d.lum[r] = l;
    }
}

/* Second kernel, second part: the requests without the start known (a new point: the moving
 * object's pixels make one at every sample), both gathers walking the window. The lanes of a
 * warp take the samples of one pixel (or of 32 / samples pixels), so that they walk the same
 * window in step and read the same cells: one load serves them all. (One request a thread in
 * the order made, neighbouring lanes reading neighbouring windows: 138 ms against 107 ms per
 * 0.5 s of the Cornell box at 1280x720 on the H100 with the fixed-point sums, 81 against 78 ms
 * with --gather-max 64.) */
template <bool FIXED>
__global__ void __launch_bounds__(BLOCK, 8) gi_gather_new_kernel(kernel_args a, gi_deferred d)
{
    const unsigned n = d.count[REQ_NEW_PIXELS], lane = threadIdx.x & 31u,
                   warps = gridDim.x * blockDim.x / 32u;
    const unsigned span = a.samples < 32 ? (unsigned)a.samples : 32u,
                   per_warp = 32u / span;           /* lanes a pixel, pixels a warp */
    const unsigned back = d.cap - d.count[REQ_NEW]; /* the first request without the start known */
    if (lane >= per_warp * span) return;
    for (unsigned w = (blockIdx.x * blockDim.x + threadIdx.x) / 32u; w * per_warp < n; w += warps) {
        const unsigned at = w * per_warp + lane / span;
        if (at >= n) break;
        const int i = d.newpix[at], entries = d.traced[i];
        unsigned prev = GI_NO_REQUEST;
        for (int k = (int)(lane % span); k < entries; k += (int)span) {
            const unsigned r = d.req[(size_t)k * (size_t)d.stride + (size_t)i];
            if (k > 0) prev = d.req[(size_t)(k - 1) * (size_t)d.stride + (size_t)i];
            if (r == GI_NO_REQUEST || r < back || r == prev)
                continue; /* a miss, a known start, or the sample before's */
            const evr_gather_point g = d.requests[r].g;
            const int pix = d.requests[r].pix;
            float2 l;
            evr_gather_sum s;
            gpu_gather_ends<FIXED>(a.gi, &a.rs.camera, &g, pix % a.width, pix / a.width, &l.x, &l.y,
                                   nullptr, &s);
            d.lum[r] = l;
            if (FIXED) d.requests[r].s = s;
        }
    }
}

/* Third kernel: render_kernel's pixel model over the intensities of the first two. */
template <int SENSOR>
__global__ void __launch_bounds__(BLOCK, MIN_BLOCKS) gi_pixel_kernel(kernel_args a, gi_deferred d)
{
    launch_pixel lp;
    if (!launch_pixel_of(a, &lp)) return;
    const bool active = lp.active;
    const int i = entry_slot(a, lp), pix = lp.pix, x = lp.x, y = lp.y;
    const unsigned lane = lp.lane;
    evr_pixel_state st;
    evr_pixel_params own;
    const float phi = pixel_begin<SENSOR>(a, active, pix, x, y, st, own);
    const int traced = active ? d.traced[i] : 0;
    float direct = 0.0f;
    unsigned r = GI_NO_REQUEST, id = active && a.id_in ? a.id_in[pix] : 0u;
    for (int k = 0; k < a.samples; k++) {
        const float f = ((float)k + phi) / (float)a.samples;
        float intensity = st.intensity; /* kept when settled on nothing */
        if (k < traced) {
            const size_t at = (size_t)k * (size_t)d.stride + (size_t)i;
            direct = d.direct[at];
            r = d.req[at];
            if (d.ids) id = d.ids[at];
        }
        if (k < traced ||
            r !=
                GI_NO_REQUEST) { /* settled on a surface: its last direct light, its gathers at f */
            intensity = direct;
            if (r != GI_NO_REQUEST) {
                const float2 l = d.lum[r];
                intensity += evr_gi_lerp(l.x, l.y, f);
            }
        }
        pixel_sample<SENSOR>(a, st, own, active, f, intensity, x, y, lane, id);
    }
    if (active) {
        st.cache_dist = d.cache_dist[i];
        evr_pixel_end_segment(&st, a.dt);
        store_state<SENSOR>(a, pix, st);
        if (a.id_out) a.id_out[pix] = id;
        if (a.gi->ends_out) { /* its last gather, for the next segment's start */
            gi_end e{};
            e.g.dist = -1.0f;
            if (r != GI_NO_REQUEST) {
                e.g = d.requests[r].g;
                e.le = d.lum[r].y;
                e.direct = direct;
                /* the sums only where the gather kernels made them (gi_gather_known_kernel) */
                if (a.gi->gp.max_photons <= 0 && !a.gi->end.blur) e.s = d.requests[r].s;
            }
            a.gi->ends_out[pix] = e;
        }
    }
}

gi_deferred deferred_args(const cuda_backend *b)
{
    gi_deferred d;
    d.direct = b->d_gd_direct.p;
    d.ids = b->setup.event_ids ? b->d_gd_ids.p : nullptr;
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

void gi_deferred_release(cuda_backend *b)
{
    b->d_gd_direct.release();
    b->d_gd_ids.release();
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
            cudaMemset(b->d_gi_ends[i].p, 0xff, npix * sizeof(gi_end)) !=
                cudaSuccess) { /* dist NaN: none */
            (void)cudaGetLastError();
            for (int j = 0; j < NRING; j++) b->d_gi_ends[j].release();
            return;
        }
    }
}

/* The deferred gathers' buffers: every sample of every pixel may make a request (the moving
 * object's pixels do). Where they do not fit in device memory the render kernel gathers inline,
 * with a notice. EVR_GI_INLINE=1 (hidden, for tests and measurement) chooses that too. */
void gi_deferred_alloc(cuda_backend *b, const cudaDeviceProp *prop)
{
    b->gi_deferred = 0;
    if (!b->gi || b->setup.adaptive || getenv("EVR_GI_INLINE")) return;
    const size_t npix = (size_t)b->setup.width * b->setup.height,
                 n = npix * (size_t)b->setup.samples_per_frame;
    if (b->d_gd_direct.reserve(n, true) == cudaSuccess &&
        (!b->setup.event_ids || b->d_gd_ids.reserve(n, true) == cudaSuccess) &&
        b->d_gd_req.reserve(n, true) == cudaSuccess &&
        b->d_gd_lum.reserve(n, true) == cudaSuccess &&
        b->d_gd_requests.reserve(n, true) == cudaSuccess &&
        b->d_gd_traced.reserve(npix, true) == cudaSuccess &&
        b->d_gd_cache.reserve(npix, true) == cudaSuccess &&
        b->d_gd_count.reserve(REQ_COUNTS) == cudaSuccess &&
        b->d_gd_newpix.reserve(npix, true) == cudaSuccess &&
        b->d_gd_delta.reserve(2 * npix, true) == cudaSuccess) {
        b->gi_deferred = 1;
        gi_ends_alloc(b, npix);
        b->gather_grid =
            (unsigned)prop->multiProcessorCount *
            64u; /* grid-stride: 64 blocks an SM balanced the gathers best (16: 9% slower) */
        return;
    }
    (void)cudaGetLastError(); /* the failed allocation: not sticky, cleared */
    gi_deferred_release(b);
    fprintf(stderr,
            "evray: notice: not enough GPU memory to defer the gathers of %zu samples a segment; "
            "gathering inside the render kernel (slower)\n",
            n);
}

evr_status gi_deferred_render(const cuda_backend *b, const kernel_args &a, const gi_deferred &d,
                              unsigned grid, evr_error *err)
{
    cudaStream_t rs = b->render;
    with_layout(run_variant(b).layout,
                [&](auto l) { gi_trace_kernel<decltype(l)::value><<<grid, BLOCK, 0, rs>>>(a, d); });
    CK(cudaGetLastError());
    if (b->gp.max_photons <= 0 && b->blur_sigma <= 0.0f) {
        if (b->d_gi_ends[0].p) { /* what the changed cells add to the pixels' last gathers */
            CK(cudaMemsetAsync(d.delta, 0,
                               2 * (size_t)b->setup.width * (size_t)b->setup.height *
                                   sizeof(unsigned long long),
                               rs));
            gi_scatter_kernel<<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
        }
        gi_gather_known_kernel<true><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
        gi_gather_new_kernel<true><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
    } else {
        gi_gather_known_kernel<false><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
        gi_gather_new_kernel<false><<<b->gather_grid, BLOCK, 0, rs>>>(a, d);
    }
    CK(cudaGetLastError());
    if (evr_pixel_params_ideal(&b->setup.pixel)) gi_pixel_kernel<0><<<grid, BLOCK, 0, rs>>>(a, d);
    else gi_pixel_kernel<1><<<grid, BLOCK, 0, rs>>>(a, d);
    return EVR_OK;
}
