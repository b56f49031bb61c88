/* EVR_TIMELINE=path (hidden, for measurement): per segment, host times (evr_host_seconds) and GPU
 * times (seconds after a base event, recorded at h0 on the host), written when the backend is
 * released. */
#ifndef EVR_CUDA_CUDA_TIMELINE_CUH
#define EVR_CUDA_CUDA_TIMELINE_CUH

#include <cuda_runtime.h>
#include <stddef.h>
#include <stdio.h>

extern "C" {
#include "backend.h"
}

/* One segment's times. */
struct timeline_rec {
    double sub0, sub1, col0, counted, copied, col1, g_start, g_rendered, g_sort, g_copied;
    size_t n;
};

struct cuda_timeline {
    FILE *f; /* NULL: no timeline */
    cudaEvent_t base;
    double h0;
    timeline_rec *recs;
    int cap, lost;
};

/* Opens the timeline EVR_TIMELINE names (none when unset) and records its base on stream s. */
evr_status timeline_open(cuda_timeline *tl, cudaStream_t s, evr_error *err);
/* Segment i's record (NULL: no timeline, or no memory for it, which the file then says). */
timeline_rec *timeline_at(cuda_timeline *tl, int i);
/* The GPU times of a record: events started, rendered, sort started, copied (all complete). */
cudaError_t timeline_gpu(const cuda_timeline *tl, timeline_rec *r, cudaEvent_t started,
                         cudaEvent_t rendered, cudaEvent_t sort_from, cudaEvent_t copied);
/* Writes the timeline and frees it (the device synchronized). */
void timeline_close(cuda_timeline *tl);

#endif
