/* A CUDA runtime call's failure as the backend's status, with its message in err (the calling
 * host function has an `evr_error *err` and returns evr_status). */
#ifndef EVR_CUDA_CUDA_CHECK_CUH
#define EVR_CUDA_CUDA_CHECK_CUH

#include <cuda_runtime.h>
#include <stdio.h>

#define CK(call)                                                                      \
    do {                                                                              \
        cudaError_t e_ = (call);                                                      \
        if (e_ != cudaSuccess) {                                                      \
            snprintf(err->msg, sizeof err->msg, "CUDA: %s failed: %s", #call,         \
                     cudaGetErrorString(e_));                                         \
            return e_ == cudaErrorMemoryAllocation ? EVR_ERR_NOMEM : EVR_ERR_BACKEND; \
        }                                                                             \
    } while (0)

#endif
