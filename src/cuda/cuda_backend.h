/* The CUDA backend (built when nvcc is found). */
#ifndef EVR_CUDA_CUDA_BACKEND_H
#define EVR_CUDA_CUDA_BACKEND_H

#include "backend.h"

/* Fails with a clear message when there is no usable device or not enough device memory. */
evr_status evr_cuda_backend_new(const evr_scene *s, const evr_render_host *h,
                                const evr_run_setup *setup, evr_backend **out, evr_error *err);
/* Name of the device a CUDA backend runs on. */
const char *evr_cuda_device_name(const evr_backend *b);

#endif
