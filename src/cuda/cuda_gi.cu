/* Global illumination on the GPU: the photon pass at a segment's end, the camera's view of the
 * buffer's cells, which cells changed over the segment (the kernels and their host side); the
 * gathers of a sample in the buffers of its segment's start and end are cuda_gather.cuh's. Every
 * per-photon and per-pixel decision is src/core/photon.h, the very functions the CPU pass
 * (src/cpu/photon_pass.c, src/cpu/cpu_gi.c) runs; this file only schedules them.
 *
 * Deterministic insertion. The CPU inserts the visible photons in photon order, so a cell keeps
 * its first `layers` photons by key. Here every visible photon is appended (atomic counter) with
 * the sort key (cell << 32 | photon key); CUB sorts the keys, and each sorted photon's rank in
 * its cell (a binary search for the cell's first entry) picks its layer: the same buffer as the
 * CPU's for the same photons, whatever order the threads ran in.
 *
 * Buffers live in a ring indexed by segment, one more than the segments in flight: a segment
 * reads its own (its end) and the one before (its start), and one that overflows its event
 * buffer is rendered again at collect, after later segments' passes may have run, and must find
 * both. A still segment (nothing moved since the previous one) copies the previous buffer. */
#include "cuda/cuda_gi.cuh"
#include "cuda/cuda_trace.cuh"

#include <cub/device/device_radix_sort.cuh>
#include <string.h>

extern "C" {
#include "prep/photon_emitters.h"
}

/* Adds 1 per calling lane to counter c, one atomic per warp. */
__device__ __forceinline__ void count_lanes(unsigned long long *counters, int c)
{
    const unsigned m = __activemask(), lane = threadIdx.x & 31u;
    if (lane == (unsigned)__ffs(m) - 1u) atomicAdd(&counters[c], (unsigned long long)__popc(m));
}

/* Appends a visible photon in cell `cell` for the sort (its rank in the cell is its layer). */
__device__ __forceinline__ void photon_append(const photon_args &p, const evr_photon &ph,
                                              unsigned cell)
{
    const unsigned idx = atomicAdd(p.pending_count, 1u); /* < photons: one stay per photon */
    p.pending[idx] = ph;
    p.sort_keys[idx] = ((unsigned long long)cell << 32) | ph.key;
    p.sort_vals[idx] = idx;
}

/* Photon i's path (core/photon.h) and, where it stays, the camera's check; its rays go to trail t. */
template <int LAYOUT>
__device__ void photon_path(const kernel_args &a, const photon_args &p, unsigned i,
                            evr_photon_trail *t, evr_trail_ray *rays)
{
    const evr_render_scene *rs = &a.rs;
    evr_photon_path path;
    if (!evr_photon_path_start(rs, p.em, p.n_em, p.cdf, &p.pp, i, &path)) return;
    t->started = 1;
    count_lanes(a.counters, CTR_GI_PATHS);
    while (path.bounce < path.max_hits) {
        evr_gpu_hit h;
        evr_surface s;
        float stored[3], absorbed[3];
        uint32_t key = 0;
        const int hit =
            gpu_trace<LAYOUT>(&a.view, rs, path.pr.ray, path.tnear, 1e30f, path.f, 0, &h);
        if (rays)
            evr_photon_trail_ray(t, rays, p.trail_len, a.plan, path.pr.ray, hit ? h.t : 1e30f);
        if (!hit) return;
        const evr_material_params *mat =
            &rs->materials[rs->meshes[rs->instances[h.instance].mesh].material];
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.instance].track), path.f);
        evr_surface_at(rs, h.instance, h.prim, h.u, h.v, &xf, path.f, path.pr.ray, h.t, 0.0f, &s);
        const int ev = evr_photon_path_hit(&path, &p.pp, &s, mat, stored, absorbed, &key);
        if (ev == EVR_PHOTON_STAY) {
            evr_ray r;
            float tn, tf;
            int x, y;
            if (!evr_photon_view_ray(rs, &s, path.f, p.margin, p.pp.ray_eps, &x, &y, &r, &tn, &tf))
                return;
            const int occluded = gpu_trace<LAYOUT>(&a.view, rs, r, tn, tf, path.f, 1, &h);
            if (rays) evr_photon_trail_ray(t, rays, p.trail_len, a.plan, r, tf);
            if (occluded) return;
            t->ph = evr_photon_make(&s, stored, key);
            t->cell = (unsigned)(y + p.margin) * (unsigned)p.cells_w + (unsigned)(x + p.margin);
            photon_append(p, t->ph, t->cell);
            return;
        }
        if (ev == EVR_PHOTON_ABSORB) return;
    }
}

/* With reuse, first: one thread per photon takes its trail's outcome where it may, and lists the
 * photons to trace, so that photon_kernel's warps trace densely (traced inside this kernel, the
 * 15% of photons traced on the moving Cornell box left nearly every warp as slow as before). */
__global__ void __launch_bounds__(BLOCK) photon_reuse_kernel(kernel_args a, photon_args p)
{
    const unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
    bool trace = false;
    if (i < p.photons) {
        const evr_trail_ray *rays = p.trail_rays + (size_t)i * (size_t)p.trail_len;
        if (evr_photon_trail_reusable(&p.trails[i], rays, a.plan)) {
            count_lanes(a.counters, CTR_GI_REUSED);
            const evr_photon_trail t = p.trails[i];
            if (t.cell != EVR_TRAIL_NONE) photon_append(p, t.ph, t.cell);
        } else {
            trace = true;
        }
    }
    const unsigned at = warp_append(p.todo_count, trace);
    if (trace) p.todo[at] = i;
}

/* One thread per photon to trace (every photon, or the reuse kernel's list): its path, its
 * trail recorded. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK) photon_kernel(kernel_args a, photon_args p)
{
    const unsigned j = blockIdx.x * blockDim.x + threadIdx.x;
    const unsigned n = p.reuse ? *p.todo_count : p.photons;
    if (j >= n) return;
    const unsigned i = p.reuse ? p.todo[j] : j;
    evr_trail_ray *rays = p.trails ? p.trail_rays + (size_t)i * (size_t)p.trail_len : nullptr;
    evr_photon_trail t;
    evr_photon_trail_begin(&t, a.plan);
    photon_path<LAYOUT>(a, p, i, &t, rays);
    if (rays) p.trails[i] = t;
}

/* One thread per sorted photon: its layer is its rank among its cell's photons. */
__global__ void __launch_bounds__(BLOCK)
    photon_place_kernel(const unsigned long long *keys, const unsigned *vals, unsigned n,
                        const evr_photon *pending, evr_photon_buffer buf,
                        unsigned long long *counters)
{
    const unsigned j = blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= n) return;
    const unsigned long long k = keys[j];
    if (k == ~0ull) return;
    const unsigned cell = (unsigned)(k >> 32);
    const unsigned long long first_key = (unsigned long long)cell << 32;
    unsigned lo = 0, hi = j;
    while (lo < hi) { /* the cell's first entry */
        unsigned mid = (lo + hi) / 2;
        if (keys[mid] < first_key) lo = mid + 1;
        else hi = mid;
    }
    const unsigned rank = j - lo;
    if (rank < (unsigned)buf.layers) {
        buf.slots[(size_t)rank * (size_t)buf.width * (size_t)buf.height + cell] = pending[vals[j]];
        atomicAdd(&counters[CTR_GI_INSERTED], 1ull);
    } else {
        atomicAdd(&counters[CTR_GI_COLLISIONS], 1ull);
    }
    if (j + 1 == n || (unsigned)(keys[j + 1] >> 32) != cell)
        buf.count[cell] = rank + 1; /* arrivals, as the CPU counts */
}

/* One thread per cell: what the camera sees through the cell's centre at normalized segment time f. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK)
    photon_view_kernel(kernel_args a, evr_photon_buffer buf, float f)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= buf.width * buf.height) return;
    const evr_render_scene *rs = &a.rs;
    const evr_m34 pose = evr_rs_camera_pose(rs, f);
    const evr_v3 fwd = evr_v3_norm(evr_m34_vector(&pose, evr_v3_make(0.0f, 0.0f, -1.0f)));
    const evr_ray ray = evr_photon_cell_ray(rs, &pose, &buf, cell % buf.width, cell / buf.width);
    float g[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    evr_gpu_hit h;
    int seen = -1;
    if (gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, 1e30f, f, 0, &h)) {
        seen = h.instance;
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.instance].track), f);
        evr_surface s;
        evr_surface_at(rs, h.instance, h.prim, h.u, h.v, &xf, f, ray, h.t,
                       evr_camera_cone(&rs->camera, h.t), &s);
        evr_photon_cell_view(rs, fwd, &s, ray, h.t, g);
    }
    for (int k = 0; k < 8; k++) buf.gbuf[8 * (size_t)cell + k] = g[k];
    if (buf.view_inst) buf.view_inst[cell] = seen;
}

/* --gi-blur (core/photon_blur.h), one thread per cell that sees a surface: its flux and area into
 * dst (k -1), step k of the blur from src into dst, or the ratio from src into buf.blur (dst
 * NULL). */
__global__ void __launch_bounds__(BLOCK)
    photon_blur_kernel(kernel_args a, evr_photon_buffer buf, evr_v3 org, float sigma,
                       evr_gather_params gp, const float *src, float *dst, int k)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= buf.width * buf.height || buf.view_inst[cell] < 0) return;
    const int x = cell % buf.width, y = cell / buf.width;
    if (!dst) evr_blur_cell_finish(&buf, src, (size_t)cell);
    else if (k < 0) evr_blur_cell_splat(&buf, &gp, (size_t)cell, dst + EVR_BLUR_CH * (size_t)cell);
    else evr_blur_cell(&buf, &a.rs.camera, org, sigma, src, dst, x, y, k);
}

/* Changed cells into the summed-area table's interior (row 0 and column 0 stay zero): 1 where
 * the photons or the view at the segment's end differ from its start's, or did over the segment
 * before (last, per cell: updated to this segment's). */
__global__ void __launch_bounds__(BLOCK)
    photon_changed_kernel(evr_photon_buffer end, evr_photon_buffer start, uint8_t *last,
                          uint32_t *sat, unsigned long long *counters)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= end.width * end.height) return;
    const int x = cell % end.width, y = cell / end.width;
    const uint8_t photons = !evr_photon_cell_same(&end, &start, (size_t)cell);
    /* --gi-blur: what changes a pixel's light is its cells' lookups */
    const uint8_t now = end.blur ? !evr_blur_cell_same(&end, &start, (size_t)cell) : photons;
    sat[(size_t)(y + 1) * (size_t)(end.width + 1) + (size_t)(x + 1)] = now | last[cell];
    last[cell] = now;
    if (photons)
        count_lanes(counters, CTR_GI_CHANGED); /* this segment's changes, as the CPU counts them */
}

/* The list of the cells that changed over the segment (core/photon.h's evr_changed_cells, for
 * gp.max_photons 0) from the per-cell flags photon_changed_kernel left in last: per row the
 * count before each column (one warp a row, as sat_rows_kernel), then the rows' bases (one warp),
 * then each changed cell's column at its entry. */
__global__ void __launch_bounds__(BLOCK)
    changed_rows_kernel(const uint8_t *last, int w, int h, uint32_t *before)
{
    const int y = (int)((blockIdx.x * blockDim.x + threadIdx.x) / 32u);
    const unsigned lane = threadIdx.x & 31u;
    if (y >= h) return; /* the whole warp */
    uint32_t *row = before + (size_t)y * (size_t)(w + 1);
    uint32_t carry = 0;
    for (int x0 = 0; x0 < w; x0 += 32) {
        const int x = x0 + (int)lane;
        const uint32_t f = x < w ? (uint32_t)last[(size_t)y * (size_t)w + (size_t)x] : 0u;
        uint32_t v = f;
        for (int o = 1; o < 32; o <<= 1) {
            const uint32_t u = __shfl_up_sync(0xffffffffu, v, (unsigned)o);
            if (lane >= (unsigned)o) v += u;
        }
        if (x < w) row[x] = carry + v - f; /* exclusive */
        carry += __shfl_sync(0xffffffffu, v, 31);
    }
    if (lane == 0) row[w] = carry;
}

__global__ void changed_base_kernel(const uint32_t *before, int w, int h, uint32_t *base)
{
    const unsigned lane = threadIdx.x & 31u;
    uint32_t carry = 0;
    if (lane == 0) base[0] = 0;
    for (int y0 = 0; y0 < h; y0 += 32) {
        const int y = y0 + (int)lane;
        uint32_t v = y < h ? before[(size_t)y * (size_t)(w + 1) + (size_t)w] : 0u;
        for (int o = 1; o < 32; o <<= 1) {
            const uint32_t u = __shfl_up_sync(0xffffffffu, v, (unsigned)o);
            if (lane >= (unsigned)o) v += u;
        }
        if (y < h) base[y + 1] = carry + v;
        carry += __shfl_sync(0xffffffffu, v, 31);
    }
}

__global__ void __launch_bounds__(BLOCK)
    changed_list_kernel(const uint8_t *last, int w, int h, evr_changed_cells ch, uint32_t *xs)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= w * h || !last[cell]) return;
    const int x = cell % w, y = cell / w;
    xs[ch.base[y] + ch.before[(size_t)y * (size_t)(w + 1) + (size_t)x]] = (uint32_t)x;
}

/* The summed-area table: prefix sums along rows, then columns. Rows: one warp per row, 32 cells
 * at a time (a shuffle scan plus the carry of the cells before): one thread per row walking its
 * row read memory 1,300 cells apart per lane, 0.24 ms a segment at 1280x720 on the H100. */
__global__ void __launch_bounds__(BLOCK) sat_rows_kernel(uint32_t *sat, int w, int h)
{
    const int y = (int)((blockIdx.x * blockDim.x + threadIdx.x) / 32u);
    const unsigned lane = threadIdx.x & 31u;
    if (y >= h) return; /* the whole warp */
    uint32_t *row = sat + (size_t)(y + 1) * (size_t)(w + 1) + 1;
    uint32_t carry = 0;
    for (int x0 = 0; x0 < w; x0 += 32) {
        const int x = x0 + (int)lane;
        uint32_t v = x < w ? row[x] : 0u;
        for (int o = 1; o < 32; o <<= 1) {
            const uint32_t u = __shfl_up_sync(0xffffffffu, v, (unsigned)o);
            if (lane >= (unsigned)o) v += u;
        }
        v += carry;
        if (x < w) row[x] = v;
        carry = __shfl_sync(0xffffffffu, v, 31);
    }
}

/* Columns: a block of SAT_CHUNKS warps takes 32 neighbouring columns (each warp's loads one row
 * of them), each warp a chunk of the rows; the chunks' sums are carried in a second pass. One
 * thread walking a whole column took 0.29 ms a segment at 1280x720 on the H100 (1,312 threads,
 * each 752 dependent steps). */
#define SAT_CHUNKS 8
__global__ void __launch_bounds__(32 * SAT_CHUNKS) sat_cols_kernel(uint32_t *sat, int w, int h)
{
    __shared__ uint32_t chunk_sum[SAT_CHUNKS][32];
    const int lane = (int)(threadIdx.x & 31u), c = (int)(threadIdx.x / 32u);
    const int x = (int)blockIdx.x * 32 + lane + 1;
    const int rows = (h + SAT_CHUNKS - 1) / SAT_CHUNKS, y0 = 1 + c * rows,
              y1 = min(h + 1, y0 + rows);
    const size_t W = (size_t)w + 1;
    uint32_t run = 0;
    if (x <= w)
        for (int y = y0; y < y1; y++) {
            run += sat[(size_t)y * W + (size_t)x];
            sat[(size_t)y * W + (size_t)x] = run;
        }
    chunk_sum[c][lane] = run;
    __syncthreads();
    uint32_t carry = 0;
    for (int k = 0; k < c; k++) carry += chunk_sum[k][lane];
    if (x <= w && carry)
        for (int y = y0; y < y1; y++) sat[(size_t)y * W + (size_t)x] += carry;
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
        if (b->d_trails.reserve(n, true) != cudaSuccess ||
            b->d_trail_rays.reserve((size_t)n * len, true) != cudaSuccess) {
            (void)cudaGetLastError(); /* not sticky: cleared */
            b->d_trails.release();
            b->d_trail_rays.release();
            b->trails_off = 1;
            return;
        }
    }
    if (b->d_todo.reserve(n) != cudaSuccess || b->d_todo_count.reserve(1) != cudaSuccess) {
        (void)cudaGetLastError();
        b->trails_valid = 0;
        return; /* no reuse this pass, no trails recorded */
    }
    p->trails = b->d_trails.p;
    p->trail_rays = b->d_trail_rays.p;
    p->todo = b->d_todo.p;
    p->todo_count = b->d_todo_count.p;
    p->reuse = evr_photon_trails_pass(&b->trail_em, &b->trails_valid, &b->em);
}

/* One photon pass at normalized segment time f into buffer out, on the render stream:
 * the photons, traced at f, and the camera's view of the cells at f. hrs: the segment's scene
 * with host pointers (the emitters are built on the host). */
static evr_status gi_pass(cuda_backend *b, slot *sl, const evr_render_scene *hrs, float f,
                          const evr_photon_buffer *out, evr_error *err)
{
    const size_t cells = (size_t)out->width * (size_t)out->height;
    const unsigned cgrid = (unsigned)((cells + BLOCK - 1) / BLOCK);
    cudaStream_t rs = b->render;
    evr_status st;
    if ((st = evr_photon_emitters_build(hrs, f, b->pp.bounds, b->photons, &b->em, err)) != EVR_OK)
        return st;
    if (b->gp.flux_scale == 0.0f)
        b->gp.flux_scale = evr_gather_flux_scale(b->em.total_power, b->photons); /* the run's */
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
    CK(cudaMemcpyAsync(sl->d_em.p, sl->h_em.p, ((size_t)b->em.n + 1) * sizeof(evr_photon_emitter),
                       cudaMemcpyHostToDevice, rs));
    CK(cudaMemcpyAsync(sl->d_cdf.p, sl->h_cdf.p, ((size_t)b->em.cdf_n + 1) * sizeof(float),
                       cudaMemcpyHostToDevice, rs));
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
        /* the sort moves every value, the unused ones' too (after every used key) */
        CK(cudaMemsetAsync(b->d_pvals.p, 0xff, (size_t)n * sizeof(unsigned), rs));
        const unsigned pgrid = (n + BLOCK - 1) / BLOCK;
        if (p.reuse) {
            CK(cudaMemsetAsync(p.todo_count, 0, sizeof(unsigned), rs));
            photon_reuse_kernel<<<pgrid, BLOCK, 0, rs>>>(a, p);
            CK(cudaGetLastError());
        }
        with_layout(run_variant(b).layout, [&](auto l) {
            photon_kernel<decltype(l)::value><<<pgrid, BLOCK, 0, rs>>>(a, p);
        });
        CK(cudaGetLastError());
        /* the cell in the high bits (up to 2^end - 1), the photon key in the low 32 */
        int end_bit = 33;
        while (end_bit < 64 && (1ull << (end_bit - 32)) <= cells) end_bit++;
        size_t temp = 0;
        CK(cub::DeviceRadixSort::SortPairs(nullptr, temp, b->d_pkeys.p, b->d_pkeys_sorted.p,
                                           b->d_pvals.p, b->d_pvals_sorted.p, (int)n, 0, end_bit,
                                           rs));
        CK(b->d_ptemp.reserve(temp));
        CK(cub::DeviceRadixSort::SortPairs(b->d_ptemp.p, temp, b->d_pkeys.p, b->d_pkeys_sorted.p,
                                           b->d_pvals.p, b->d_pvals_sorted.p, (int)n, 0, end_bit,
                                           rs));
        photon_place_kernel<<<pgrid, BLOCK, 0, rs>>>(b->d_pkeys_sorted.p, b->d_pvals_sorted.p, n,
                                                     b->d_pending.p, *out, sl->d_counters.p);
        CK(cudaGetLastError());
    }
    with_layout(run_variant(b).layout, [&](auto l) {
        photon_view_kernel<decltype(l)::value><<<cgrid, BLOCK, 0, rs>>>(a, *out, f);
    });
    CK(cudaGetLastError());
    if (b->blur_sigma > 0.0f) { /* every step: a cell past its own keeps its value */
        const float sg = b->blur_sigma;
        const evr_m34 pose = evr_rs_camera_pose(hrs, f); /* the camera at the pass, on the host */
        const evr_v3 org = evr_m34_point(&pose, evr_v3_make(0.0f, 0.0f, 0.0f));
        float *work[2] = {b->d_blur_tmp.p, b->d_blur_tmp.p + EVR_BLUR_CH * cells};
        for (int k = -1; k < EVR_BLUR_MAX_STEPS; k++)
            photon_blur_kernel<<<cgrid, BLOCK, 0, rs>>>(a, *out, org, sg, b->gp, work[(k + 2) % 2],
                                                        work[(k + 1) % 2], k);
        photon_blur_kernel<<<cgrid, BLOCK, 0, rs>>>(a, *out, org, sg, b->gp,
                                                    work[EVR_BLUR_MAX_STEPS % 2], nullptr, 0);
        CK(cudaGetLastError());
    }
    sl->gi_passes++;
    return EVR_OK;
}

/* The segment's photons on the render stream, before its render: the pass at its end (the first
 * segment's at its start too), the cells that changed, the view its kernels read. A still segment
 * (nothing moved in it or since the previous one) copies the previous segment's buffer. */
evr_status gi_segment(cuda_backend *b, slot *sl, const evr_segment *seg,
                      const evr_render_scene *hrs, evr_error *err)
{
    const gi_buffer *end = &b->gi_ring[sl->index % NRING],
                    *start = &b->gi_ring[(sl->index + NRING - 1) % NRING];
    const evr_photon_buffer *eb = &end->ph, *sb = &start->ph;
    const size_t cells = (size_t)eb->width * (size_t)eb->height;
    const unsigned cgrid = (unsigned)((cells + BLOCK - 1) / BLOCK);
    cudaStream_t rs = b->render;
    evr_status st;
    sl->gi_passes = 0;
    CK(cudaMemsetAsync(sl->d_counters.p + CTR_GI_PATHS, 0,
                       (CTR_COUNT - CTR_GI_PATHS) * sizeof(unsigned long long), rs));
    if (evr_skip_plan_still(seg->skip) && b->gi_have_prev) {
        CK(cudaMemcpyAsync(eb->count, sb->count, cells * sizeof(uint32_t), cudaMemcpyDeviceToDevice,
                           rs));
        CK(cudaMemcpyAsync(eb->slots, sb->slots, cells * (size_t)eb->layers * sizeof(evr_photon),
                           cudaMemcpyDeviceToDevice, rs));
        CK(cudaMemcpyAsync(eb->gbuf, sb->gbuf, cells * 8 * sizeof(float), cudaMemcpyDeviceToDevice,
                           rs));
        if (eb->blur) {
            CK(cudaMemcpyAsync(eb->view_inst, sb->view_inst, cells * sizeof(int),
                               cudaMemcpyDeviceToDevice, rs));
            CK(cudaMemcpyAsync(eb->blur, sb->blur, cells * 3 * sizeof(float),
                               cudaMemcpyDeviceToDevice, rs));
        }
    } else {
        CK(cudaEventRecord(sl->gi_started, rs));
        if (!b->gi_have_prev) {
            if ((st = gi_pass(b, sl, hrs, 0.0f, sb, err)) != EVR_OK) return st;
            CK(cudaStreamSynchronize(rs)); /* the emitters' staging is the slot's: its copy done */
        }
        if ((st = gi_pass(b, sl, hrs, 1.0f, eb, err)) != EVR_OK) return st;
    }
    photon_changed_kernel<<<cgrid, BLOCK, 0, rs>>>(*eb, *sb, b->d_gi_last.p, sl->d_sat.p,
                                                   sl->d_counters.p);
    sat_rows_kernel<<<(unsigned)((32 * (size_t)eb->height + BLOCK - 1) / BLOCK), BLOCK, 0, rs>>>(
        sl->d_sat.p, eb->width, eb->height);
    sat_cols_kernel<<<(unsigned)((eb->width + 31) / 32), 32 * SAT_CHUNKS, 0, rs>>>(
        sl->d_sat.p, eb->width, eb->height);
    if (b->gp.max_photons <= 0 && b->blur_sigma <= 0.0f) {
        const evr_changed_cells ch = sl->h_gi_view.p->ch;
        changed_rows_kernel<<<(unsigned)((32 * (size_t)eb->height + BLOCK - 1) / BLOCK), BLOCK, 0,
                              rs>>>(b->d_gi_last.p, eb->width, eb->height, sl->d_ch_before.p);
        changed_base_kernel<<<1, 32, 0, rs>>>(sl->d_ch_before.p, eb->width, eb->height,
                                              sl->d_ch_base.p);
        changed_list_kernel<<<cgrid, BLOCK, 0, rs>>>(b->d_gi_last.p, eb->width, eb->height, ch,
                                                     sl->d_ch_x.p);
    }
    CK(cudaGetLastError());
    if (sl->gi_passes) CK(cudaEventRecord(sl->gi_done, rs));
    /* the slot's last copy from its staging finished before its previous segment was collected */
    gpu_gi_view *v = sl->h_gi_view.p;
    v->end = *eb;
    v->start = *sb;
    v->gp = b->gp; /* with the run's flux scale, known after the first pass */
    v->ends_in = b->d_gi_ends[0].p ? b->d_gi_ends[sl->index % NRING].p : nullptr;
    v->ends_out = b->d_gi_ends[0].p ? b->d_gi_ends[(sl->index + 1) % NRING].p : nullptr;
    CK(cudaMemcpyAsync(sl->d_gi_view.p, v, sizeof *v, cudaMemcpyHostToDevice, rs));
    b->gi_have_prev = 1;
    return EVR_OK;
}

/* Device memory of the ring's photon buffers and the per-cell changes (shared by the slots). */
evr_status gi_ring_alloc(cuda_backend *b, int margin, evr_error *err)
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
        if (b->blur_sigma > 0.0f) {
            CK(g->view_inst.reserve(cells));
            CK(g->blur.reserve(cells * 3));
            CK(cudaMemset(g->view_inst.p, 0xff, cells * sizeof(int)));
            CK(cudaMemset(g->blur.p, 0, cells * 3 * sizeof(float)));
            buf->view_inst = g->view_inst.p;
            buf->blur = g->blur.p;
        }
        buf->collisions = nullptr; /* the place kernel counts them (CTR_GI_COLLISIONS) */
    }
    const size_t cells = (size_t)b->gi_ring[0].ph.width * (size_t)b->gi_ring[0].ph.height;
    CK(b->d_gi_last.reserve(cells));
    CK(cudaMemset(b->d_gi_last.p, 0, cells));
    if (b->blur_sigma > 0.0f) CK(b->d_blur_tmp.reserve(cells * 2 * EVR_BLUR_CH));
    return EVR_OK;
}

/* A slot's changed-cell table and the view its kernels read. */
evr_status gi_alloc(cuda_backend *b, slot *sl, int window, evr_error *err)
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
