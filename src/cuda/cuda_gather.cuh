/* Device code of the gathers (global illumination's indirect light at a camera sample), shared
 * by the render kernel, which gathers inline, and the deferred kernels (cuda_gi_deferred.cu).
 * Every per-pixel decision is src/core/photon.h, the very functions the CPU runs. */
#ifndef EVR_CUDA_CUDA_GATHER_CUH
#define EVR_CUDA_CUDA_GATHER_CUH

#include "cuda/cuda_args.cuh"

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
 * (cuda_gi_deferred.cu, compiling the same function) run the very same instructions: inlined
 * into different kernels the compiler may fuse a multiply and an add in one and not the other,
 * and the events would differ in the last bit of a few samples (13 of 6.5 M events at 1280x720
 * when both were inlined). */
__device__ static __noinline__ void gpu_gather_point(const evr_render_scene *rs, int inst,
                                                     const evr_surface *s, evr_v3 cam_org,
                                                     evr_gather_point *g)
{
    (void)rs, (void)inst; /* the surface record holds what the gather needs of its material */
    evr_gather_point_at(s, inst, cam_org, g);
}

/* gp.max_photons 0 (core/photon.h's fixed-point sums): the sums of point g over buffer b, those
 * over the end buffer from those over the start buffer and the changed cells, and the luminance
 * from sums. Inlined, unlike gpu_gather_lum: no product in them is followed by an addition a
 * compiler could fuse it with (the terms' are explicit, EVR_MUL_RN), so every kernel computes the
 * same bits (tests/test_cuda.py compares the inline and deferred kernels' events); not inlined,
 * the calls spilled the gather loops' registers (gather kernels 105 -> 92 ms per 0.5 s of the
 * Cornell box at 1280x720, H100). */
__device__ __forceinline__ void gpu_gather_sum(const evr_photon_buffer *b, const gpu_gi_view *v,
                                               const evr_camera_intr *cam,
                                               const evr_gather_point *g, int x, int y,
                                               evr_gather_sum *s)
{
    evr_gather_point_sum(b, cam, &v->gp, g, x, y, s);
}

__device__ __forceinline__ void gpu_gather_delta(const gpu_gi_view *v, const evr_camera_intr *cam,
                                                 const evr_gather_point *g, int x, int y,
                                                 evr_gather_sum *s)
{
    evr_gather_point_delta(&v->end, &v->start, &v->ch, cam, &v->gp, g, x, y, s);
}

__device__ __forceinline__ float gpu_sum_lum(const gpu_gi_view *v, const evr_camera_intr *cam,
                                             const evr_gather_point *g, int x, int y,
                                             const evr_gather_sum *s)
{
    return evr_gather_sum_lum(&v->end, cam, &v->gp, g, x, y, s);
}

__device__ static __noinline__ float gpu_gather_lum(const evr_photon_buffer *b,
                                                    const gpu_gi_view *v,
                                                    const evr_camera_intr *cam,
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
__device__ __forceinline__ void gpu_gather_ends(const gpu_gi_view *v, const evr_camera_intr *cam,
                                                const evr_gather_point *g, int x, int y, float *ls,
                                                float *le, const float *known_ls, evr_gather_sum *s)
{
    if (v->end.blur) { /* --gi-blur: the lookups (a known start is made again: it is cheap) */
        evr_blur_point_lum(&v->start, &v->end, g, x, y, ls, le);
        return;
    }
    const bool changed = evr_photon_window_changed(v->sat, v->end.width, v->end.height,
                                                   v->end.margin, v->window, x, y);
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
__device__ __forceinline__ bool gather_point_same(const evr_gather_point *a,
                                                  const evr_gather_point *b)
{
    const float fa[10] = {a->p.x, a->p.y,  a->p.z,  a->n.x,  a->n.y,
                          a->n.z, a->dist, a->k[0], a->k[1], a->k[2]};
    const float fb[10] = {b->p.x, b->p.y,  b->p.z,  b->n.x,  b->n.y,
                          b->n.z, b->dist, b->k[0], b->k[1], b->k[2]};
    unsigned d = (unsigned)(a->inst ^ b->inst);
    for (int i = 0; i < 10; i++) d |= __float_as_uint(fa[i]) ^ __float_as_uint(fb[i]);
    return d == 0;
}

/* Whether the memo holds gather point g of instance inst; if not, it takes it (the caller fills
 * lum or req). The albedo is the surface's at the point: same point, same triangle side. */
__device__ __forceinline__ bool gi_memo_take(gi_memo *m, int inst, const evr_gather_point *g)
{
    const uint32_t key[7] = {__float_as_uint(g->p.x), __float_as_uint(g->p.y),
                             __float_as_uint(g->p.z), __float_as_uint(g->n.x),
                             __float_as_uint(g->n.y), __float_as_uint(g->n.z),
                             __float_as_uint(g->dist)};
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
__device__ __forceinline__ float gi_indirect(const gpu_gi_view *g, const evr_render_scene *rs,
                                             int inst, const evr_surface *s, evr_v3 cam_org, int x,
                                             int y, float f, gi_memo *m)
{
    evr_gather_point gp;
    gpu_gather_point(rs, inst, s, cam_org, &gp);
    evr_gather_sum sums;
    if (!gi_memo_take(m, inst, &gp)) {
        if (g->gp.max_photons <= 0)
            gpu_gather_ends<true>(g, &rs->camera, &gp, x, y, &m->ls, &m->le, nullptr, &sums);
        else gpu_gather_ends<false>(g, &rs->camera, &gp, x, y, &m->ls, &m->le, nullptr, &sums);
    }
    return evr_gi_lerp(m->ls, m->le, f);
}

#endif
