/* The host side of global illumination on the GPU (cuda_gi.cu): the ring of photon buffers and
 * a segment's photon passes, queued on the render stream before its render. */
#ifndef EVR_CUDA_CUDA_GI_CUH
#define EVR_CUDA_CUDA_GI_CUH

#include "cuda/cuda_state.cuh"

/* Device memory of the ring's photon buffers and the per-cell changes (shared by the slots). */
evr_status gi_ring_alloc(cuda_backend *b, int margin, evr_error *err);
/* A slot's changed-cell table and the view its kernels read. */
evr_status gi_alloc(cuda_backend *b, slot *sl, int window, evr_error *err);
/* The segment's photons on the render stream, before its render. hrs: the segment's scene with
 * host pointers. */
evr_status gi_segment(cuda_backend *b, slot *sl, const evr_segment *seg,
                      const evr_render_scene *hrs, evr_error *err);

#endif
