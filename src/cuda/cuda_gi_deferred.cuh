/* Global illumination with the gathers deferred to kernels of their own (cuda_gi_deferred.cu):
 * their buffers and the render of a segment through them. */
#ifndef EVR_CUDA_CUDA_GI_DEFERRED_CUH
#define EVR_CUDA_CUDA_GI_DEFERRED_CUH

#include "cuda/cuda_state.cuh"

/* The deferred gathers' buffers (b->gi_deferred 0 where they do not fit: the render kernel
 * gathers inline), and their release. */
void gi_deferred_alloc(cuda_backend *b, const cudaDeviceProp *prop);
void gi_deferred_release(cuda_backend *b);
/* The deferred kernels' shared buffers, as launch arguments. */
gi_deferred deferred_args(const cuda_backend *b);
/* The segment's render on the render stream after the skip kernel: the trace, gather and pixel
 * kernels. */
evr_status gi_deferred_render(const cuda_backend *b, const kernel_args &a, const gi_deferred &d,
                              unsigned grid, evr_error *err);

#endif
