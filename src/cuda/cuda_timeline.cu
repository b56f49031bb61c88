/* The CUDA backend's timeline (EVR_TIMELINE): see cuda_timeline.cuh. */
#include "cuda/cuda_timeline.cuh"
#include "cuda/cuda_check.cuh"
#include "host_clock.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

evr_status timeline_open(cuda_timeline *tl, cudaStream_t s, evr_error *err)
{
    const char *path = getenv("EVR_TIMELINE");
    if (!path) return EVR_OK;
    if (!(tl->f = fopen(path, "w"))) {
        snprintf(err->msg, sizeof err->msg, "cannot write the timeline %s (EVR_TIMELINE): %s", path,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    CK(cudaEventCreate(&tl->base));
    CK(cudaEventRecord(tl->base, s));
    CK(cudaEventSynchronize(tl->base));
    tl->h0 = evr_host_seconds();
    return EVR_OK;
}

timeline_rec *timeline_at(cuda_timeline *tl, int i)
{
    if (!tl->f || tl->lost) return nullptr;
    if (i >= tl->cap) {
        int cap = tl->cap ? 2 * tl->cap : 1024;
        while (cap <= i) cap *= 2;
        void *p = realloc(tl->recs, (size_t)cap * sizeof *tl->recs);
        if (!p) {
            tl->lost = 1;
            return nullptr;
        }
        tl->recs = (timeline_rec *)p;
        memset(tl->recs + tl->cap, 0, (size_t)(cap - tl->cap) * sizeof *tl->recs);
        tl->cap = cap;
    }
    return &tl->recs[i];
}

cudaError_t timeline_gpu(const cuda_timeline *tl, timeline_rec *r, cudaEvent_t started,
                         cudaEvent_t rendered, cudaEvent_t sort_from, cudaEvent_t copied)
{
    const cudaEvent_t ev[4] = {started, rendered, sort_from, copied};
    double *g[4] = {&r->g_start, &r->g_rendered, &r->g_sort, &r->g_copied};
    for (int k = 0; k < 4; k++) {
        float ms = 0.0f;
        const cudaError_t e = cudaEventElapsedTime(&ms, tl->base, ev[k]);
        if (e != cudaSuccess) return e;
        *g[k] = 1e-3 * ms;
    }
    return cudaSuccess;
}

void timeline_close(cuda_timeline *tl)
{
    if (!tl->f) return;
    /* seconds from the base event; a segment's row once it was submitted */
    const double h0 = tl->h0;
    fprintf(tl->f, "seg sub0 sub1 col0 counted copied col1 g_start g_rendered g_sort g_copied n\n");
    for (int i = 0; i < tl->cap; i++) {
        const timeline_rec *r = &tl->recs[i];
        if (r->sub1 == 0.0) continue;
        fprintf(tl->f, "%d %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %zu\n", i,
                r->sub0 - h0, r->sub1 - h0, r->col0 - h0, r->counted - h0, r->copied - h0,
                r->col1 - h0, r->g_start, r->g_rendered, r->g_sort, r->g_copied, r->n);
    }
    if (tl->lost) fprintf(tl->f, "# incomplete: out of memory for the timeline\n");
    if (fclose(tl->f) != 0 || tl->lost)
        fprintf(stderr, "evray: warning: the timeline (EVR_TIMELINE) is incomplete\n");
    tl->f = nullptr;
    free(tl->recs);
    tl->recs = nullptr;
    if (tl->base) cudaEventDestroy(tl->base);
    tl->base = nullptr;
}
