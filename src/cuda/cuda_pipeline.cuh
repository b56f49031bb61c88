/* The CUDA backend's segment pipeline (cuda_pipeline.cu): the backend's submit and collect. */
#ifndef EVR_CUDA_CUDA_PIPELINE_CUH
#define EVR_CUDA_CUDA_PIPELINE_CUH

#include <cuda_runtime.h>

extern "C" {
#include "backend.h"
}

evr_status cuda_submit(evr_backend *base, const evr_segment *seg, evr_error *err);
evr_status cuda_collect(evr_backend *base, evr_event_vec *out, int64_t emit_before_us,
                        const float **intensity, const float **frames, evr_error *err);
/* Bytes of temporary storage the sort of n event keys takes (for the buffers made up front);
 * with ids (not NULL), the sort that moves them with the keys. */
cudaError_t event_sort_temp_bytes(unsigned long long *keys, unsigned long long *sorted,
                                  uint16_t *ids, uint16_t *ids_sorted, int n, size_t *temp);

#endif
