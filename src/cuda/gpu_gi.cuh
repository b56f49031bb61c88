/* Global illumination on the GPU (issue 5): the photon pass at a segment's end, the camera's
 * view of the buffer's cells, which cells changed over the segment, and the gathers of a sample
 * in the buffers of its segment's start and end, interpolated in time (evr_gi_lerp). Every
 * per-photon and per-pixel decision is src/core/photon.h, the very functions the CPU pass
 * (src/cpu/photon_pass.c, src/cpu/cpu_gi.c) runs; this file only schedules them.
 *
 * Included by cuda_backend.cu after gpu_trace (one translation unit: the kernels here trace
 * with the same traversal and take the same kernel_args).
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
#ifndef EVR_CUDA_GPU_GI_CUH
#define EVR_CUDA_GPU_GI_CUH

#include "core/photon.h"

/* A pixel's last gather of a segment, kept for the next (the deferred kernels): its gather point
 * (dist NaN or negative: none) and its luminance at the segment's end, which is the next
 * segment's start bit for bit (the same buffer, the same point, the same pixel). */
struct gi_end {
    evr_gather_point g;
    float le;
    float direct;                  /* the direct light of the same sample */
    evr_gather_sum s;              /* gp.max_photons 0: the fixed-point sums of le's gather */
};

#define GI_NO_REQUEST 0xffffffffu

/* A deferred gather: the surface point and its pixel; ls: its start gather where known (the
 * pixel's end gather of the previous segment at the same point: the requests at the front of
 * the array, gi_deferred.count). */
struct gi_request {
    evr_gather_point g;
    int pix;
    float ls;
    evr_gather_sum s;   /* gp.max_photons 0: the end's fixed-point sums (the gather kernel's) */
};

/* The shared buffers of the deferred kernels (gpu_gi_deferred.cuh; the skip kernel fills them for
 * the pixels it settles): device memory, reused by every launch (the kernels of a segment run in
 * order on the render stream). Per-sample arrays are [sample][thread]. */
struct gi_deferred {
    float *direct;        /* a traced sample's direct light */
    unsigned *req;        /* its gather request, GI_NO_REQUEST for a miss (no light) */
    int *traced;          /* per thread: samples with an entry (traced or held); later samples keep the last */
    float *cache_dist;    /* per thread: the change-driven sampling cache after the segment */
    gi_request *requests;
    float2 *lum;          /* per request: the gathers' luminance at the segment's start and end */
    /* requests made: [0] with the start known (from the front of requests), [1] without (from
     * the back); [2] pixels that made one without (listed in newpix) */
    unsigned *count;
    unsigned cap;         /* room in requests */
    int *newpix;          /* the launch's threads (pixels) that made a request without the start known */
    unsigned long long *delta;   /* gp.max_photons 0: per pixel, what the changed cells add to its last gather's sums (a, w) */
    int stride;           /* threads of a launch at most: the pixel count */
};

/* What the render kernels read (device memory, one per slot). */
struct gpu_gi_view {
    evr_photon_buffer end, start;  /* the photons at the segment's end and start (device pointers) */
    /* summed-area table, (w + 1) x (h + 1), of the cells that changed over this segment or the
     * one before: a pixel with no such cell in its window had the same indirect light all through
     * both (its intensity may be kept) */
    const uint32_t *sat;
    evr_changed_cells ch;          /* gp.max_photons 0: the cells that changed over this segment only */
    evr_gather_params gp;
    int window;                    /* cells around a pixel a gather may read */
    /* the deferred kernels' per-pixel last gathers: the previous segment's (read) and this one's
     * (written), a ring indexed by segment as the pixel states; NULL where they did not fit */
    const gi_end *ends_in;
    gi_end *ends_out;
};

/* A pixel's last gather in this launch: the same point, normal, distance and instance in the
 * same buffers give the same estimates bit for bit (a traced pixel on a still surface). ls, le:
 * the estimates at the segment's start and end (gathers inside the render kernel); req: the
 * deferred gathers' request (gi_trace_kernel). */
struct gi_memo {
    uint32_t key[7];
    int inst;
    float ls, le;
    unsigned req;
    bool valid;
};

/* The gather point of surface s (instance inst) seen from cam_org, and a gather's luminance at
 * one: not inlined, so that the render kernel (gathers inline) and the deferred kernels
 * (gpu_gi_deferred.cuh) run the very same instructions: inlined into different kernels the
 * compiler may fuse a multiply and an add in one and not the other, and the events would differ
 * in the last bit of a few samples (13 of 6.5 M events at 1280x720 when both were inlined). */
__device__ __noinline__ void gpu_gather_point(const evr_render_scene *rs, int inst, const evr_surface *s, evr_v3 cam_org,
                                              evr_gather_point *g)
{
    evr_gather_point_at(s, &rs->materials[rs->meshes[rs->instances[inst].mesh].material], cam_org, g);
}

/* gp.max_photons 0 (core/photon.h's fixed-point sums): the sums of point g over buffer b, those
 * over the end buffer from those over the start buffer and the changed cells, and the luminance
 * from sums. Inlined, unlike gpu_gather_lum: no product in them is followed by an addition a
 * compiler could fuse it with (the terms' are explicit, EVR_MUL_RN), so every kernel computes the
 * same bits (tests/test_cuda.py compares the inline and deferred kernels' events); not inlined,
 * the calls spilled the gather loops' registers (gather kernels 105 -> 92 ms per 0.5 s of the
 * Cornell box at 1280x720, H100). */
__device__ __forceinline__ void gpu_gather_sum(const evr_photon_buffer *b, const gpu_gi_view *v, const evr_camera_intr *cam,
                                            const evr_gather_point *g, int x, int y, evr_gather_sum *s)
{
    evr_gather_point_sum(b, cam, &v->gp, g, x, y, s);
}

__device__ __forceinline__ void gpu_gather_delta(const gpu_gi_view *v, const evr_camera_intr *cam, const evr_gather_point *g, int x,
                                              int y, evr_gather_sum *s)
{
    evr_gather_point_delta(&v->end, &v->start, &v->ch, cam, &v->gp, g, x, y, s);
}

__device__ __forceinline__ float gpu_sum_lum(const gpu_gi_view *v, const evr_camera_intr *cam, const evr_gather_point *g, int x, int y,
                                          const evr_gather_sum *s)
{
    return evr_gather_sum_lum(&v->end, cam, &v->gp, g, x, y, s);
}

__device__ __noinline__ float gpu_gather_lum(const evr_photon_buffer *b, const gpu_gi_view *v, const evr_camera_intr *cam,
                                             const evr_gather_point *g, int x, int y)
{
    return evr_gather_point_lum(b, cam, &v->gp, g, x, y);
}

/* The gathers of point g (pixel (x, y)) at the segment's start and end; one where the window saw
 * no change (the same cells give the same estimate), none at the start where it is known
 * (known_ls: the previous segment's end gather of the same point). Two walks: walking both
 * buffers together, cell by cell, made the gather kernel 12% slower (H200, Cornell box at
 * 1280x720, 0.5 s: 0.237 s against 0.210 s). With gp.max_photons 0 (FIXED) the start is
 * never given here (a known start's end is its sums plus gi_scatter_kernel's, in
 * gi_gather_known_kernel), and the end's sums (s, out) are the start's plus the changed cells'
 * terms, a walk over the few changed cells of the window instead of all of it. */
template <bool FIXED>
__device__ __forceinline__ void gpu_gather_ends(const gpu_gi_view *v, const evr_camera_intr *cam, const evr_gather_point *g, int x,
                                                int y, float *ls, float *le, const float *known_ls, evr_gather_sum *s)
{
    const bool changed = evr_photon_window_changed(v->sat, v->end.width, v->end.height, v->end.margin, v->window, x, y);
    if (FIXED) {
        gpu_gather_sum(&v->start, v, cam, g, x, y, s);
        *ls = gpu_sum_lum(v, cam, g, x, y, s);
        if (changed) gpu_gather_delta(v, cam, g, x, y, s);
        *le = changed ? gpu_sum_lum(v, cam, g, x, y, s) : *ls;
        return;
    }
    *ls = known_ls ? *known_ls : gpu_gather_lum(&v->start, v, cam, g, x, y);
    *le = changed ? gpu_gather_lum(&v->end, v, cam, g, x, y) : *ls;
}

/* Whether two gather points are the same bit for bit (the same estimates). */
__device__ __forceinline__ bool gather_point_same(const evr_gather_point *a, const evr_gather_point *b)
{
    const float fa[10] = {a->p.x, a->p.y, a->p.z, a->n.x, a->n.y, a->n.z, a->dist, a->k[0], a->k[1], a->k[2]};
    const float fb[10] = {b->p.x, b->p.y, b->p.z, b->n.x, b->n.y, b->n.z, b->dist, b->k[0], b->k[1], b->k[2]};
    unsigned d = 0;
    for (int i = 0; i < 10; i++) d |= __float_as_uint(fa[i]) ^ __float_as_uint(fb[i]);
    return d == 0;
}

/* Whether the memo holds gather point g of instance inst; if not, it takes it (the caller fills
 * lum or req). The albedo is the surface's at the point: same point, same triangle side. */
__device__ __forceinline__ bool gi_memo_take(gi_memo *m, int inst, const evr_gather_point *g)
{
    const uint32_t key[7] = {__float_as_uint(g->p.x), __float_as_uint(g->p.y), __float_as_uint(g->p.z), __float_as_uint(g->n.x),
                             __float_as_uint(g->n.y), __float_as_uint(g->n.z), __float_as_uint(g->dist)};
    bool same = m->valid && m->inst == inst;
    for (int k = 0; k < 7 && same; k++) same = m->key[k] == key[k];
    if (same) return true;
    for (int k = 0; k < 7; k++) m->key[k] = key[k];
    m->inst = inst;
    m->valid = true;
    return false;
}

/* The indirect light of a sample at surface s of instance inst at normalized segment time f: the
 * pixel's memo, or gathers (the pixel's own thread walks its window; a version spreading each
 * window's cells over the warp's lanes was slower, measured on an H200: 2.07 s against 1.80 s of
 * render kernels for the Cornell box at 1280x720, 2 s: most windows are searched to the same
 * size, so the lanes of a warp were already busy in step). */
__device__ __forceinline__ float gi_indirect(const gpu_gi_view *g, const evr_render_scene *rs, int inst, const evr_surface *s,
                                             evr_v3 cam_org, int x, int y, float f, gi_memo *m)
{
    evr_gather_point gp;
    gpu_gather_point(rs, inst, s, cam_org, &gp);
    evr_gather_sum sums;
    if (!gi_memo_take(m, inst, &gp)) {
        if (g->gp.max_photons <= 0) gpu_gather_ends<true>(g, &rs->camera, &gp, x, y, &m->ls, &m->le, nullptr, &sums);
        else gpu_gather_ends<false>(g, &rs->camera, &gp, x, y, &m->ls, &m->le, nullptr, &sums);
    }
    return evr_gi_lerp(m->ls, m->le, f);
}

/* Counters of a pass in the slot's counter array (after the render kernels' three). */
/* the segment's counters (kernel_args.rays): 0 .. 2 rays, pixels skipped, samples traced (cuda_backend.cu);
 * then the photon pass's; KEY_RANGE: events outside the keys' time window (an internal error) */
enum { GI_PATHS = 3, GI_INSERTED = 4, GI_COLLISIONS = 5, GI_CHANGED = 6, GI_REUSED = 7, KEY_RANGE = 8, GI_COUNTERS = 9 };

struct photon_args {
    const evr_photon_emitter *em;
    int n_em;
    const float *cdf;
    evr_photon_params pp;
    unsigned photons;
    int margin, cells_w;
    unsigned long long *sort_keys; /* (cell << 32) | photon key; all ones where no photon */
    unsigned *sort_vals;           /* index into pending */
    evr_photon *pending;
    unsigned *pending_count;
    /* trails (core/photon.h): NULL when they did not fit in memory */
    evr_photon_trail *trails;
    evr_trail_ray *trail_rays;
    int trail_len;
    int reuse;                     /* the trails are the previous pass's, with the same emitters */
    unsigned *todo;                /* with reuse: the photons to trace (photon_reuse_kernel lists them) */
    unsigned *todo_count;
};

/* Adds 1 per calling lane to counter c, one atomic per warp. */
__device__ __forceinline__ void count_lanes(unsigned long long *counters, int c)
{
    const unsigned m = __activemask(), lane = threadIdx.x & 31u;
    if (lane == (unsigned)__ffs(m) - 1u) atomicAdd(&counters[c], (unsigned long long)__popc(m));
}

/* Appends a visible photon in cell `cell` for the sort (its rank in the cell is its layer). */
__device__ __forceinline__ void photon_append(const photon_args &p, const evr_photon &ph, unsigned cell)
{
    const unsigned idx = atomicAdd(p.pending_count, 1u);   /* < photons: one stay per photon */
    p.pending[idx] = ph;
    p.sort_keys[idx] = ((unsigned long long)cell << 32) | ph.key;
    p.sort_vals[idx] = idx;
}

/* Photon i's path (core/photon.h) and, where it stays, the camera's check; its rays go to trail t. */
template <int LAYOUT>
__device__ void photon_path(const kernel_args &a, const photon_args &p, unsigned i, evr_photon_trail *t, evr_trail_ray *rays)
{
    const evr_render_scene *rs = &a.rs;
    evr_photon_path path;
    if (!evr_photon_path_start(rs, p.em, p.n_em, p.cdf, &p.pp, i, &path)) return;
    t->started = 1;
    count_lanes(a.rays, GI_PATHS);
    while (path.bounce < path.max_hits) {
        evr_gpu_hit h;
        evr_surface s;
        float stored[3], absorbed[3];
        uint32_t key = 0;
        const int hit = gpu_trace<LAYOUT>(&a.view, rs, path.pr.ray, path.tnear, 1e30f, path.f, 0, &h);
        if (rays) evr_photon_trail_ray(t, rays, p.trail_len, a.plan, path.pr.ray, hit ? h.t : 1e30f);
        if (!hit) return;
        const evr_material_params *mat = &rs->materials[rs->meshes[rs->instances[h.instance].mesh].material];
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.instance].track), path.f);
        evr_surface_at(rs, h.instance, h.prim, h.u, h.v, &xf, path.pr.ray, h.t, &s);
        const int ev = evr_photon_path_hit(&path, &p.pp, &s, mat, stored, absorbed, &key);
        if (ev == EVR_PHOTON_STAY) {
            evr_ray r;
            float tn, tf;
            int x, y;
            if (!evr_photon_view_ray(rs, &s, path.f, p.margin, p.pp.ray_eps, &x, &y, &r, &tn, &tf)) return;
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
            count_lanes(a.rays, GI_REUSED);
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
__global__ void __launch_bounds__(BLOCK) photon_place_kernel(const unsigned long long *keys, const unsigned *vals, unsigned n,
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
    while (lo < hi) {   /* the cell's first entry */
        unsigned mid = (lo + hi) / 2;
        if (keys[mid] < first_key) lo = mid + 1;
        else hi = mid;
    }
    const unsigned rank = j - lo;
    if (rank < (unsigned)buf.layers) {
        buf.slots[(size_t)rank * (size_t)buf.width * (size_t)buf.height + cell] = pending[vals[j]];
        atomicAdd(&counters[GI_INSERTED], 1ull);
    } else {
        atomicAdd(&counters[GI_COLLISIONS], 1ull);
    }
    if (j + 1 == n || (unsigned)(keys[j + 1] >> 32) != cell) buf.count[cell] = rank + 1;   /* arrivals, as the CPU counts */
}

/* One thread per cell: what the camera sees through the cell's centre at normalized segment time f. */
template <int LAYOUT>
__global__ void __launch_bounds__(BLOCK) photon_view_kernel(kernel_args a, evr_photon_buffer buf, float f)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= buf.width * buf.height) return;
    const evr_render_scene *rs = &a.rs;
    const evr_m34 pose = evr_rs_camera_pose(rs, f);
    const evr_v3 fwd = evr_v3_norm(evr_m34_vector(&pose, evr_v3_make(0.0f, 0.0f, -1.0f)));
    const evr_ray ray = evr_photon_cell_ray(rs, &pose, &buf, cell % buf.width, cell / buf.width);
    float g[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    evr_gpu_hit h;
    if (gpu_trace<LAYOUT>(&a.view, rs, ray, 0.0f, 1e30f, f, 0, &h)) {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[h.instance].track), f);
        evr_surface s;
        evr_surface_at(rs, h.instance, h.prim, h.u, h.v, &xf, ray, h.t, &s);
        evr_photon_cell_view(rs, fwd, &s, ray, h.t, g);
    }
    for (int k = 0; k < 8; k++) buf.gbuf[8 * (size_t)cell + k] = g[k];
}

/* Changed cells into the summed-area table's interior (row 0 and column 0 stay zero): 1 where
 * the photons or the view at the segment's end differ from its start's, or did over the segment
 * before (last, per cell: updated to this segment's). */
__global__ void __launch_bounds__(BLOCK) photon_changed_kernel(evr_photon_buffer end, evr_photon_buffer start, uint8_t *last,
                                                               uint32_t *sat, unsigned long long *counters)
{
    const int cell = blockIdx.x * blockDim.x + threadIdx.x;
    if (cell >= end.width * end.height) return;
    const int x = cell % end.width, y = cell / end.width;
    const uint8_t now = !evr_photon_cell_same(&end, &start, (size_t)cell);
    sat[(size_t)(y + 1) * (size_t)(end.width + 1) + (size_t)(x + 1)] = now | last[cell];
    last[cell] = now;
    if (now) count_lanes(counters, GI_CHANGED);   /* this segment's changes, as the CPU counts them */
}

/* The list of the cells that changed over the segment (core/photon.h's evr_changed_cells, for
 * gp.max_photons 0) from the per-cell flags photon_changed_kernel left in last: per row the
 * count before each column (one warp a row, as sat_rows_kernel), then the rows' bases (one warp),
 * then each changed cell's column at its entry. */
__global__ void __launch_bounds__(BLOCK) changed_rows_kernel(const uint8_t *last, int w, int h, uint32_t *before)
{
    const int y = (int)((blockIdx.x * blockDim.x + threadIdx.x) / 32u);
    const unsigned lane = threadIdx.x & 31u;
    if (y >= h) return;   /* the whole warp */
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
        if (x < w) row[x] = carry + v - f;   /* exclusive */
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

__global__ void __launch_bounds__(BLOCK) changed_list_kernel(const uint8_t *last, int w, int h, evr_changed_cells ch, uint32_t *xs)
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
    if (y >= h) return;   /* the whole warp */
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
    const int rows = (h + SAT_CHUNKS - 1) / SAT_CHUNKS, y0 = 1 + c * rows, y1 = min(h + 1, y0 + rows);
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

#endif
