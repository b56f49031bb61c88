/* Device code every kernel that traces shares: our traversal in the launch's node layout and the
 * warp-aggregated append. */
#ifndef EVR_CUDA_CUDA_TRACE_CUH
#define EVR_CUDA_CUDA_TRACE_CUH

#include "cuda/cuda_args.cuh"
#include "cuda/gpu_traverse.h"

/* One traversal body for primary and shadow rays, not inlined: a kernel with four inlined copies
 * (two queries, two node layouts) stalled on instruction-cache misses (measured with ncu).
 * LAYOUT: the node layout, with EVR_GPU_TRACE_GENERAL where the scene has deforming groups or
 * filtered meshes (gpu_traverse.h's general search). */
template <int LAYOUT>
__device__ __noinline__ int gpu_trace(const evr_gpu_scene_view *view, const evr_render_scene *rs,
                                      evr_ray ray, float tnear, float tfar, float f, int any,
                                      evr_gpu_hit *hit, int groups = EVR_GROUPS_ALL)
{
    /* the dispatch of evr__trace, here with the template's constants (through evr__trace the
     * BVH4 kernels' registers came out otherwise) */
    const int general = (LAYOUT & EVR_GPU_TRACE_GENERAL) != 0;
    if (view->num_top_nodes == 0) return 0;
    if ((LAYOUT & ~EVR_GPU_TRACE_GENERAL) == EVR_GPU_LAYOUT_CW8)
        return evr__trace8(view, rs, ray, tnear, tfar, f, any, hit, groups, general);
    return evr__trace4(view, rs, ray, tnear, tfar, f, any, hit, groups, general);
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

#endif
