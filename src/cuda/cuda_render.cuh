/* Launches of the render kernels (cuda_render.cu), each on stream s in BLOCK threads a block; the
 * caller checks cudaGetLastError. */
#ifndef EVR_CUDA_CUDA_RENDER_CUH
#define EVR_CUDA_CUDA_RENDER_CUH

#include "cuda/cuda_args.cuh"

/* Every pixel's camera ray against the static group alone (the camera holds still); layout:
 * kernel_variant.layout. */
void cuda_launch_static_hits(const kernel_args &a, int layout, gpu_static_hit *out, unsigned grid,
                             cudaStream_t s);
/* Change-driven sampling's first pass: the pixels that keep their intensity; lists the others.
 * r.plan set: refined sampling (a sensor model's kept samples at its times). */
void cuda_launch_skip(const kernel_args &a, const gi_deferred &d, const refine_args &r, bool ideal,
                      unsigned grid, cudaStream_t s);
/* The segment's samples of every pixel (or of the listed ones), uniformly... */
void cuda_launch_render(const kernel_args &a, kernel_variant v, unsigned grid, cudaStream_t s);
/* ...or adaptively. */
void cuda_launch_adapt(const kernel_args &a, const adapt_args &d, kernel_variant v, unsigned grid,
                       cudaStream_t s);
/* ...or refined (core/refine.h: the listed pixels, or every pixel). */
void cuda_launch_refine(const kernel_args &a, const refine_args &d, kernel_variant v, unsigned grid,
                        cudaStream_t s);
/* Intensity frames at normalized segment times frame_f. */
void cuda_launch_labels(const kernel_args &a, kernel_variant v, const float *label_f,
                        int num_labels, evr_hit *hits, unsigned grid, cudaStream_t s);
void cuda_launch_frames(const kernel_args &a, kernel_variant v, const float *frame_f,
                        int num_frames, float *frames, unsigned grid, cudaStream_t s);
/* Every pixel's first state and sample phase (aligned: 1, refined sampling's), on the default
 * stream. */
void cuda_launch_init_pixels(evr_pixel_state *st, float *phase, int width, int height,
                             unsigned long long seed, int aligned);

#endif
