/* The CUDA backend's segment pipeline: submit queues a segment's upload, photon passes and render
 * on the render stream in the next free slot; when its render is done its events (64-bit keys)
 * are sorted with CUB's radix sort on the slot's copy stream while later segments render;
 * collect takes the oldest segment's events, renders it again with a larger buffer if its events
 * overflowed (its input pixel states are unchanged: ring of NRING), brings the sorted keys before
 * emit_before to the host in pieces, decoded on the thread pool and handed to the writers piece
 * by piece, and carries the rest on the device into the next segment's sort. */
#include "cuda/cuda_pipeline.cuh"
#include "cuda/cuda_gi.cuh"
#include "cuda/cuda_gi_deferred.cuh"
#include "cuda/cuda_render.cuh"
#include "cuda/cuda_state.cuh"
#include "host_clock.h"

#include <cub/device/device_radix_sort.cuh>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Renders a slot's segment on the render stream and queues the read-back of its event count. */
static evr_status launch(cuda_backend *b, slot *sl, evr_error *err)
{
    CK(cudaMemsetAsync(sl->d_count.p, 0, COUNT_N * sizeof(unsigned int), b->render));
    CK(cudaMemsetAsync(sl->d_counters.p, 0, CTR_GI_PATHS * sizeof(unsigned long long),
                       b->render)); /* the render's */
    CK(cudaMemsetAsync(sl->d_counters.p + CTR_KEY_RANGE, 0, sizeof(unsigned long long), b->render));
    kernel_args a = make_args(b, sl);
    CK(cudaEventRecord(sl->started, b->render));
    const unsigned grid =
        (tiled_threads(b->setup.width, b->setup.height) + BLOCK - 1) / BLOCK; /* >= npix threads */
    const bool ideal = evr_pixel_params_ideal(&b->setup.pixel);
    const kernel_variant v = run_variant(b);
    cudaStream_t rs = b->render;
    if (b->setup.adaptive) {
        adapt_args d;
        d.next_in = b->d_next[sl->index % NRING].p;
        d.next_out = b->d_next[(sl->index + 1) % NRING].p;
        d.plan = sl->d_adapt.p;
        d.p = b->setup.adapt;
        cuda_launch_adapt(a, d, v, grid, rs);
    } else {
        gi_deferred d{}; /* no requests: none made by the skip kernel */
        if (b->gi_deferred) {
            d = deferred_args(b);
            CK(cudaMemsetAsync(d.count, 0, REQ_COUNTS * sizeof(unsigned), rs));
        }
        refine_args r{};
        if (b->setup.refine) {
            r.plan = sl->d_adapt.p;
            r.p = b->setup.refine_params;
        }
        if (sl->reuse) {
            cuda_launch_skip(a, d, r, ideal, grid, rs);
            CK(cudaGetLastError());
        }
        evr_status st;
        if (b->setup.refine) {
            cuda_launch_refine(a, r, v, grid, rs);
        } else if (b->gi_deferred) {
            if ((st = gi_deferred_render(b, a, d, grid, err)) != EVR_OK) return st;
        } else {
            cuda_launch_render(a, v, grid, rs);
        }
    }
    CK(cudaGetLastError());
    CK(cudaEventRecord(sl->rendered, b->render));
    if (sl->num_frames > 0) { /* after the timed render: device time stays the events' */
        cuda_launch_frames(a, v, sl->d_frame_f.p, sl->num_frames, sl->d_frames.p, grid, rs);
        CK(cudaGetLastError());
        CK(cudaEventRecord(sl->framed, b->render));
    }
    if (sl->num_labels > 0) {
        cuda_launch_labels(a, v, sl->d_label_f.p, sl->num_labels, sl->d_labels.p, grid, rs);
        CK(cudaGetLastError());
        CK(cudaEventRecord(sl->framed, b->render));
    }
    CK(cudaStreamWaitEvent(sl->copy, sl->rendered, 0));
    CK(cudaMemcpyAsync(sl->h_count.p, sl->d_count.p + COUNT_EVENTS, sizeof(unsigned int),
                       cudaMemcpyDeviceToHost, sl->copy));
    CK(cudaMemcpyAsync(sl->h_counters.p, sl->d_counters.p, CTR_COUNT * sizeof(unsigned long long),
                       cudaMemcpyDeviceToHost, sl->copy));
    CK(cudaEventRecord(sl->counted, sl->copy));
    sl->copying = 0;
    return EVR_OK;
}

/* Keys carried from the segment before, moved onto this segment's time base (both bases are
 * whole microseconds, the times in range: start_copy checks them). */
__global__ void carry_keys(const unsigned long long *from, size_t n, unsigned long long delta,
                           unsigned long long *to)
{
    for (size_t i = blockIdx.x * (size_t)blockDim.x + threadIdx.x; i < n;
         i += (size_t)gridDim.x * blockDim.x)
        to[i] = from[i] - delta;
}

/* Grows d to hold n keys (or ids), keeping its first keep (the buffer is reallocated rarely:
 * doubling). */
template <typename T>
static cudaError_t grow_keeping(dbuf<T> &d, size_t n, size_t keep, cudaStream_t s)
{
    if (n <= d.cap) return cudaSuccess;
    dbuf<T> g;
    cudaError_t e = g.reserve(n);
    if (e == cudaSuccess && keep)
        e = cudaMemcpyAsync(g.p, d.p, keep * sizeof(unsigned long long), cudaMemcpyDeviceToDevice,
                            s);
    if (e == cudaSuccess) e = cudaStreamSynchronize(s);
    if (e != cudaSuccess) {
        g.release();
        return e;
    }
    d.release();
    d.p = g.p;
    d.cap = g.cap;
    g.p = nullptr;
    g.cap = 0;
    return cudaSuccess;
}

/* The sort of n event keys on the copy stream, their ids (when not NULL) moved with them. */
static cudaError_t sort_events(void *temp, size_t &temp_bytes, unsigned long long *keys,
                               unsigned long long *sorted, uint16_t *ids, uint16_t *ids_sorted,
                               int n, int end_bit, cudaStream_t s)
{
    if (ids)
        return cub::DeviceRadixSort::SortPairs(temp, temp_bytes, keys, sorted, ids, ids_sorted, n,
                                               0, end_bit, s);
    return cub::DeviceRadixSort::SortKeys(temp, temp_bytes, keys, sorted, n, 0, end_bit, s);
}

cudaError_t event_sort_temp_bytes(unsigned long long *keys, unsigned long long *sorted,
                                  uint16_t *ids, uint16_t *ids_sorted, int n, size_t *temp)
{
    return sort_events(nullptr, *temp, keys, sorted, ids, ids_sorted, n, 64, 0);
}

/* Queues the sort and copy to the host of a rendered segment's n events, with the keys the
 * segment before it carried (b->carry_*: its events at or after its emit_before), and of its
 * intensity and frames, on the slot's copy stream. The segment before has been collected. */
static evr_status start_copy(cuda_backend *b, slot *sl, size_t n, evr_error *err)
{
    const size_t carried = b->carry_slot >= 0 ? b->carry_n : 0;
    CK(cudaEventRecord(sl->sort_from, sl->copy));
    if (carried) {
        if (b->carry_t_lo < sl->base_us || b->carry_t_hi - sl->base_us >= slot_span_us(b, sl)) {
            snprintf(
                err->msg, sizeof err->msg,
                "internal error: events carried to the segment at %.6f s fall outside its time window",
                sl->t0);
            return EVR_ERR_BACKEND;
        }
        const int shift = key_time_shift(b->setup.width, b->setup.height);
        const unsigned long long delta = (unsigned long long)(sl->base_us - b->carry_base_us)
                                         << shift;
        CK(grow_keeping(sl->d_keys_ev, n + carried, n, sl->copy));
        const unsigned blocks =
            (unsigned)((carried + BLOCK - 1) / BLOCK < 1024 ? (carried + BLOCK - 1) / BLOCK : 1024);
        carry_keys<<<blocks, BLOCK, 0, sl->copy>>>(b->slots[b->carry_slot].d_keys_sorted.p +
                                                       b->carry_at,
                                                   carried, delta, sl->d_keys_ev.p + n);
        CK(cudaGetLastError());
        if (b->setup.event_ids) {
            CK(grow_keeping(sl->d_ids_ev, n + carried, n, sl->copy));
            CK(cudaMemcpyAsync(sl->d_ids_ev.p + n,
                               b->slots[b->carry_slot].d_ids_sorted.p + b->carry_at,
                               carried * sizeof(uint16_t), cudaMemcpyDeviceToDevice, sl->copy));
        }
    }
    n += carried;
    sl->total = n;
    if (n) {
        size_t temp = 0;
        const bool ids = b->setup.event_ids != 0;
        CK(sl->d_keys_sorted.reserve(n));
        if (ids) CK(sl->d_ids_sorted.reserve(n));
        uint16_t *ids_in = ids ? sl->d_ids_ev.p : nullptr,
                 *ids_out = ids ? sl->d_ids_sorted.p : nullptr;
        CK(sort_events(nullptr, temp, sl->d_keys_ev.p, sl->d_keys_sorted.p, ids_in, ids_out, (int)n,
                       sl->end_bit, sl->copy));
        CK(sl->d_sort_temp.reserve(temp));
        CK(sort_events(sl->d_sort_temp.p, temp, sl->d_keys_ev.p, sl->d_keys_sorted.p, ids_in,
                       ids_out, (int)n, sl->end_bit, sl->copy));
    }
    CK(cudaEventRecord(sl->sorted, sl->copy));
    if (sl->want_intensity) {
        size_t npix = (size_t)b->setup.width * b->setup.height;
        CK(sl->h_intensity.reserve(npix));
        CK(cudaMemcpyAsync(sl->h_intensity.p, sl->d_intensity.p, npix * sizeof(float),
                           cudaMemcpyDeviceToHost, sl->copy));
    }
    if (sl->num_frames) {
        size_t nf = (size_t)sl->num_frames * (size_t)b->setup.width * b->setup.height;
        CK(sl->h_frames.reserve(nf));
        CK(cudaStreamWaitEvent(sl->copy, sl->framed, 0));
        CK(cudaMemcpyAsync(sl->h_frames.p, sl->d_frames.p, nf * sizeof(float),
                           cudaMemcpyDeviceToHost, sl->copy));
    }
    if (sl->num_labels) {
        size_t nl = (size_t)sl->num_labels * (size_t)b->setup.width * b->setup.height;
        CK(sl->h_labels.reserve(nl));
        CK(cudaStreamWaitEvent(sl->copy, sl->framed, 0));
        CK(cudaMemcpyAsync(sl->h_labels.p, sl->d_labels.p, nl * sizeof(evr_hit),
                           cudaMemcpyDeviceToHost, sl->copy));
    }
    CK(cudaEventRecord(sl->copied, sl->copy));
    sl->copying = 1;
    return EVR_OK;
}

/* Queues the sort and copy of the oldest submitted segment when its render is done (its count is
 * on the host) and its events fit its buffer (else collect renders it again): it runs on the GPU
 * while the host is busy elsewhere, instead of after the host asks for it. */
static evr_status start_ready_copies(cuda_backend *b, evr_error *err)
{
    /* only the oldest: a sort takes the keys its segment before carries, known once collected */
    if (!b->queued) return EVR_OK;
    slot *sl = &b->slots[b->head];
    if (sl->copying) return EVR_OK;
    const cudaError_t e = cudaEventQuery(sl->counted);
    if (e == cudaErrorNotReady) return EVR_OK;
    CK(e);
    const size_t n = *sl->h_count.p;
    if (n > sl->d_keys_ev.cap) return EVR_OK; /* collect renders it again */
    return start_copy(b, sl, n, err);
}

/* The segment's deforming meshes to the slot, on the render stream through its pinned staging
 * (its last copies from there finished before its previous segment was collected): every view's
 * vertex keys and the views of them with device pointers, and the deforming groups' trees where
 * the slot does not hold their generation yet (while every mesh holds still, each slot gets them
 * once). */
static evr_status upload_deform(cuda_backend *b, slot *sl, const evr_segment *seg, evr_error *err)
{
    const evr_gpu_deform *d = &b->deform;
    const int nd = seg->num_deforms;
    cudaStream_t rs = b->render;
    sl->num_deforms = nd;
    if (nd <= 0) return EVR_OK;
    size_t nf = 0;
    for (int k = 0; k < nd; k++)
        nf += 6 * (size_t)seg->deforms[k].num_keys * (size_t)seg->deforms[k].num_vertices;
    CK(sl->h_dverts.reserve(nf + 1));
    CK(sl->d_dverts.reserve(nf + 1));
    CK(sl->h_dviews.reserve((size_t)nd));
    CK(sl->d_dviews.reserve((size_t)nd));
    size_t at = 0;
    for (int k = 0; k < nd; k++) {
        const evr_deform_view *v = &seg->deforms[k];
        const size_t n = 3 * (size_t)v->num_keys * (size_t)v->num_vertices;
        evr_deform_view *dv = &sl->h_dviews.p[k];
        *dv = *v;
        memcpy(sl->h_dverts.p + at, v->positions, n * sizeof(float));
        dv->positions = sl->d_dverts.p + at;
        at += n;
        memcpy(sl->h_dverts.p + at, v->normals, n * sizeof(float));
        dv->normals = sl->d_dverts.p + at;
        at += n;
    }
    CK(cudaMemcpyAsync(sl->d_dverts.p, sl->h_dverts.p, at * sizeof(float), cudaMemcpyHostToDevice,
                       rs));
    CK(cudaMemcpyAsync(sl->d_dviews.p, sl->h_dviews.p, (size_t)nd * sizeof(evr_deform_view),
                       cudaMemcpyHostToDevice, rs));
    if (sl->dgen == d->gen) return EVR_OK;
    sl->dgen = 0; /* until the copies below are queued */
    if (d->nodes8 && d->num_nodes) {
        CK(sl->h_dnodes8.reserve(d->num_nodes));
        CK(sl->d_dnodes8.reserve(d->num_nodes));
        memcpy(sl->h_dnodes8.p, d->nodes8, d->num_nodes * sizeof(evr_gpu_node8));
        CK(cudaMemcpyAsync(sl->d_dnodes8.p, sl->h_dnodes8.p, d->num_nodes * sizeof(evr_gpu_node8),
                           cudaMemcpyHostToDevice, rs));
    }
    if (d->nodes4 && d->num_nodes) {
        CK(sl->h_dnodes4.reserve(d->num_nodes));
        CK(sl->d_dnodes4.reserve(d->num_nodes));
        memcpy(sl->h_dnodes4.p, d->nodes4, d->num_nodes * sizeof(evr_gpu_node4));
        CK(cudaMemcpyAsync(sl->d_dnodes4.p, sl->h_dnodes4.p, d->num_nodes * sizeof(evr_gpu_node4),
                           cudaMemcpyHostToDevice, rs));
    }
    if (d->num_tris) {
        CK(sl->h_dtris.reserve(d->num_tris));
        CK(sl->d_dtris.reserve(d->num_tris));
        memcpy(sl->h_dtris.p, d->tris, d->num_tris * sizeof(evr_gpu_dtri));
        CK(cudaMemcpyAsync(sl->d_dtris.p, sl->h_dtris.p, d->num_tris * sizeof(evr_gpu_dtri),
                           cudaMemcpyHostToDevice, rs));
    }
    sl->num_dnodes = d->num_nodes;
    sl->num_dtris = d->num_tris;
    sl->dgen = d->gen;
    return EVR_OK;
}

evr_status cuda_submit(evr_backend *base, const evr_segment *seg, evr_error *err)
{
    cuda_backend *b = (cuda_backend *)base;
    evr_status st;
    const double tl_sub0 = evr_host_seconds();
    if (b->queued == NSLOT) {
        snprintf(err->msg, sizeof err->msg, "internal error: more than %d segments submitted",
                 NSLOT);
        return EVR_ERR_BACKEND;
    }
    /* the segments rendered since the last call: their sorts start now, before the host work below */
    if ((st = start_ready_copies(b, err)) != EVR_OK) return st;
    slot *sl = &b->slots[(b->head + b->queued) % NSLOT];
    /* the slot's previous segment was collected, so its copy stream is idle */
    CK(sl->d_keys_ev.reserve(b->capacity));
    if (b->setup.event_ids) CK(sl->d_ids_ev.reserve(sl->d_keys_ev.cap));
    sl->index = seg->index;
    sl->t0 = seg->t0;
    sl->t1 = seg->t1;
    sl->camera_static = seg->camera_static;
    sl->want_intensity = seg->want_intensity;
    sl->reuse = seg->skip->reuse;
    *sl->h_plan.p = *seg->skip;
    CK(cudaMemcpyAsync(sl->d_plan.p, sl->h_plan.p, sizeof(evr_skip_plan), cudaMemcpyHostToDevice,
                       b->render));
    if (b->setup.adaptive || b->setup.refine) {
        *sl->h_adapt.p = *seg->adapt;
        CK(cudaMemcpyAsync(sl->d_adapt.p, sl->h_adapt.p, sizeof(evr_adapt_plan),
                           cudaMemcpyHostToDevice, b->render));
    }
    sl->num_frames = seg->num_frames > 0 ? seg->num_frames : 0;
    if (sl->num_frames) {
        size_t nf = (size_t)sl->num_frames, npix = (size_t)b->setup.width * b->setup.height;
        CK(sl->h_frame_f.reserve(nf));
        CK(sl->d_frame_f.reserve(nf));
        CK(sl->d_frames.reserve(nf * npix));
        for (int k = 0; k < sl->num_frames; k++) {
            double f =
                seg->t1 > seg->t0 ? (seg->frame_times[k] - seg->t0) / (seg->t1 - seg->t0) : 0.0;
            sl->h_frame_f.p[k] = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
        }
        CK(cudaMemcpyAsync(sl->d_frame_f.p, sl->h_frame_f.p, nf * sizeof(float),
                           cudaMemcpyHostToDevice, b->render));
    }
    sl->num_labels = seg->num_labels > 0 ? seg->num_labels : 0;
    if (sl->num_labels) {
        size_t nl = (size_t)sl->num_labels, npix = (size_t)b->setup.width * b->setup.height;
        CK(sl->h_label_f.reserve(nl));
        CK(sl->d_label_f.reserve(nl));
        CK(sl->d_labels.reserve(nl * npix));
        for (int k = 0; k < sl->num_labels; k++) {
            double f =
                seg->t1 > seg->t0 ? (seg->label_times[k] - seg->t0) / (seg->t1 - seg->t0) : 0.0;
            sl->h_label_f.p[k] = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
        }
        CK(cudaMemcpyAsync(sl->d_label_f.p, sl->h_label_f.p, nl * sizeof(float),
                           cudaMemcpyHostToDevice, b->render));
    }
    /* events reach back to the previous segment (a pixel's last sample there; with adaptive
     * sampling up to max_dt back), and timestamp jitter and rounding move them by up to
     * EVR_JITTER_CLIP sigma plus one resolution step either way; one more segment to spare. An
     * event outside the window is counted (CTR_KEY_RANGE) and fails the run, never wraps. */
    const evr_pixel_params *px = &b->setup.pixel;
    double slack = (double)EVR_JITTER_CLIP * (double)px->time_jitter +
                   (px->time_res_us > 1 ? 1e-6 * (double)px->time_res_us : 0.0);
    double dt = seg->t1 - seg->t0, back = 2.0 * dt + slack;
    if (b->setup.adaptive)
        back += (double)b->setup.adapt.max_dt; /* a pixel's last sample: up to max_dt back */
    sl->base_us = (long long)floor((seg->t0 - back) * 1e6);
    double span_us = (back + dt + slack) * 1e6 + 2.0;
    int tbits = 1;
    while (tbits < 31 && (double)(1ull << tbits) < span_us) tbits++;
    sl->end_bit = key_time_shift(b->setup.width, b->setup.height) + tbits;
    sl->num_tracks = seg->num_tracks;
    sl->num_keys = seg->num_keys;
    CK(sl->h_keys.reserve((size_t)seg->num_keys));
    CK(sl->h_tracks.reserve(2 * (size_t)seg->num_tracks));
    memcpy(sl->h_keys.p, seg->keys, (size_t)seg->num_keys * sizeof(evr_motion_key));
    memcpy(sl->h_tracks.p, seg->track_offset, (size_t)seg->num_tracks * sizeof(int));
    memcpy(sl->h_tracks.p + seg->num_tracks, seg->track_count,
           (size_t)seg->num_tracks * sizeof(int));
    /* the deforming groups' trees (those that moved built again), the top level over the
     * groups, bounds over the whole segment; hrs (host pointers) is also what the photon pass's
     * emitter table reads */
    evr_render_scene hrs = b->host.rs;
    hrs.keys = sl->h_keys.p;
    hrs.track_offset = sl->h_tracks.p;
    hrs.track_count = sl->h_tracks.p + seg->num_tracks;
    hrs.deforms = seg->deforms;
    hrs.num_deforms = seg->num_deforms;
    if (seg->num_deforms != b->host.num_deforms) {
        snprintf(err->msg, sizeof err->msg,
                 "internal error: %d deforming meshes' vertex keys for a scene of %d",
                 seg->num_deforms, b->host.num_deforms);
        return EVR_ERR_BACKEND;
    }
    const evr_gpu_deform *dtrees = b->bvh.num_deforming ? &b->deform : NULL;
    if (dtrees &&
        (st = evr_gpu_deform_update(&b->bvh, &hrs, seg->deform_moved, &b->deform, err)) != EVR_OK)
        return st;
    if ((st = evr_gpu_top_build(&b->bvh, dtrees, &hrs, &sl->top, err)) != EVR_OK) return st;
    if ((st = upload_deform(b, sl, seg, err)) != EVR_OK) return st;
    CK(sl->d_keys.reserve((size_t)seg->num_keys));
    CK(sl->d_tracks.reserve(2 * (size_t)seg->num_tracks));
    CK(sl->d_insts.reserve(sl->top.num_insts + 1));
    CK(cudaMemcpyAsync(sl->d_keys.p, sl->h_keys.p, (size_t)seg->num_keys * sizeof(evr_motion_key),
                       cudaMemcpyHostToDevice, b->render));
    CK(cudaMemcpyAsync(sl->d_tracks.p, sl->h_tracks.p, 2 * (size_t)seg->num_tracks * sizeof(int),
                       cudaMemcpyHostToDevice, b->render));
    if (sl->top.nodes4) {
        CK(sl->d_top4.reserve(sl->top.num_nodes + 1));
        CK(cudaMemcpyAsync(sl->d_top4.p, sl->top.nodes4, sl->top.num_nodes * sizeof(evr_gpu_node4),
                           cudaMemcpyHostToDevice, b->render));
    }
    if (sl->top.nodes8) {
        CK(sl->d_top8.reserve(sl->top.num_nodes + 1));
        CK(cudaMemcpyAsync(sl->d_top8.p, sl->top.nodes8, sl->top.num_nodes * sizeof(evr_gpu_node8),
                           cudaMemcpyHostToDevice, b->render));
    }
    CK(cudaMemcpyAsync(sl->d_insts.p, sl->top.insts, sl->top.num_insts * sizeof(evr_gpu_inst),
                       cudaMemcpyHostToDevice, b->render));
    /* the host top-level arrays are reused by the next build of this slot only after collect,
     * by which time these copies are done (collect synchronizes) */
    /* a still camera: its rays' hits in the static group, made again when the camera has moved */
    sl->static_gen = -1;
    if (seg->camera_static && !b->static_off) {
        const evr_motion_key *cam = &seg->keys[seg->track_offset[b->host.rs.camera_track]];
        if (b->static_gen == 0 || memcmp(cam, &b->static_cam, sizeof *cam) != 0) {
            const int npix = b->setup.width * b->setup.height;
            CK(b->d_static.reserve((size_t)npix));
            b->static_gen++;
            kernel_args a = make_args(b, sl);
            const unsigned grid = (unsigned)((npix + BLOCK - 1) / BLOCK);
            cuda_launch_static_hits(a, run_variant(b).layout, b->d_static.p, grid, b->render);
            CK(cudaGetLastError());
            b->static_cam = *cam;
        }
        sl->static_gen = b->static_gen;
    }
    if (b->gi && (st = gi_segment(b, sl, seg, &hrs, err)) != EVR_OK) return st;
    if ((st = launch(b, sl, err)) != EVR_OK) return st;
    b->queued++;
    if (timeline_rec *r = timeline_at(&b->tl, seg->index)) {
        r->sub0 = tl_sub0;
        r->sub1 = evr_host_seconds();
    }
    return EVR_OK;
}

/* The event of a sorted key (pack_event's layout). */
static inline evr_event decode_key(unsigned long long k, long long base_us, int xb, int yb)
{
    evr_event e;
    e.t = base_us + (long long)(k >> (1 + xb + yb));
    e.y = (uint16_t)((k >> (1 + xb)) & ((1u << yb) - 1u));
    e.x = (uint16_t)((k >> 1) & ((1u << xb) - 1u));
    e.p = (int8_t)(k & 1u);
    e.id = 0;
    return e;
}

/* Decodes n sorted keys into dst, a segment of many events in parts on the pool: on one thread it
 * was most of the main thread's own time (the eye's 218.7 M events in 30 s at 1280x720), and
 * threads started per segment cost about as much as the work. */
struct decode_job {
    const unsigned long long *keys;
    const uint16_t *ids; /* NULL: ids off */
    size_t n, parts;
    long long base_us;
    int xb, yb;
    evr_event *dst;
};
static void decode_part(void *ctx, int k, int)
{
    const decode_job *j = (const decode_job *)ctx;
    size_t i0, i1;
    evr_par_share(j->n, (int)j->parts, k, &i0, &i1);
    if (j->ids)
        for (size_t i = i0; i < i1; i++) {
            evr_event e = decode_key(j->keys[i], j->base_us, j->xb, j->yb);
            e.id = j->ids[i];
            j->dst[i] = e;
        }
    else
        for (size_t i = i0; i < i1; i++)
            j->dst[i] = decode_key(j->keys[i], j->base_us, j->xb, j->yb);
}
static void decode_keys(evr_par_pool *pool, const unsigned long long *keys, const uint16_t *ids,
                        size_t n, long long base_us, int xb, int yb, evr_event *dst)
{
    const size_t chunk = (size_t)1 << 17; /* eight parts of a piece (EVENT_PIECE) */
    size_t parts = (n + chunk - 1) / chunk, most = (size_t)evr_par_pool_threads(pool);
    if (parts > most) parts = most;
    if (parts < 1) parts = 1;
    decode_job j = {keys, ids, n, parts, base_us, xb, yb, dst};
    evr_par_pool_run(pool, (int)parts, decode_part, &j);
}

/* Where the sorted keys reach limit (the first at or after it), the key there and the last key:
 * one thread's binary search, so that the keys need not come to the host to be split. */
__global__ void split_keys(const unsigned long long *keys, size_t n, unsigned long long limit,
                           unsigned long long *out)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < limit) lo = mid + 1;
        else hi = mid;
    }
    out[0] = lo;
    out[1] = lo < n ? keys[lo] : 0ull;
    out[2] = n ? keys[n - 1] : 0ull;
}

/* Keys in piece k of the split first keys. */
static size_t piece_keys(const cuda_backend *b, size_t k, size_t split)
{
    const size_t at = k * b->piece;
    return split - at < b->piece ? split - at : b->piece;
}

/* Queues the copy of piece k of the slot's sorted keys before split (and their ids) into
 * b->h_piece[k % 2], with the next piece's first key after it, on the slot's copy stream. */
static cudaError_t copy_piece(cuda_backend *b, slot *sl, size_t k, size_t split)
{
    const int buf = (int)(k & 1);
    const size_t at = k * b->piece, m = piece_keys(b, k, split);
    const size_t with_next = at + m < split ? m + 1 : m;
    cudaError_t e = cudaEventRecord(b->piece_from[buf], sl->copy);
    if (e == cudaSuccess)
        e = cudaMemcpyAsync(b->h_piece[buf].p, sl->d_keys_sorted.p + at,
                            with_next * sizeof(unsigned long long), cudaMemcpyDeviceToHost,
                            sl->copy);
    if (e == cudaSuccess && b->setup.event_ids)
        e = cudaMemcpyAsync(b->h_piece_ids[buf].p, sl->d_ids_sorted.p + at, m * sizeof(uint16_t),
                            cudaMemcpyDeviceToHost, sl->copy);
    if (e == cudaSuccess) e = cudaEventRecord(b->piece_copied[buf], sl->copy);
    return e;
}

evr_status cuda_collect(evr_backend *base, evr_event_vec *out, int64_t emit_before_us,
                        const float **intensity, const float **frames, evr_error *err)
{
    cuda_backend *b = (cuda_backend *)base;
    evr_status st;
    if (!b->queued) {
        snprintf(err->msg, sizeof err->msg, "internal error: collect without a submitted segment");
        return EVR_ERR_BACKEND;
    }
    slot *sl = &b->slots[b->head];
    double tw = evr_host_seconds();
    const double tl_col0 = tw;
    CK(cudaEventSynchronize(sl->counted));
    const double tl_counted = evr_host_seconds();
    base->wait_seconds += evr_host_seconds() - tw;
    size_t n = *sl->h_count.p;
    while (n > sl->d_keys_ev.cap) {
        /* overflow: grow and render this segment again from its unchanged input states (the
         * next segment, if rendering, reads states this re-run rewrites identically: wait) */
        CK(cudaDeviceSynchronize());
        CK(sl->d_keys_ev.reserve(n + n / 4));
        if (b->setup.event_ids) CK(sl->d_ids_ev.reserve(sl->d_keys_ev.cap));
        if (sl->d_keys_ev.cap > b->capacity)
            b->capacity = sl->d_keys_ev.cap; /* the other slots grow at their next submit */
        if ((st = launch(b, sl, err)) != EVR_OK) return st;
        CK(cudaEventSynchronize(sl->counted));
        n = *sl->h_count.p;
    }
    if (sl->h_counters.p[CTR_KEY_RANGE]) {
        snprintf(
            err->msg, sizeof err->msg,
            "internal error: %llu events of the segment at %.6f s fell outside its time window",
            (unsigned long long)sl->h_counters.p[CTR_KEY_RANGE], sl->t0);
        return EVR_ERR_BACKEND;
    }
    base->rays += sl->h_counters.p[CTR_RAYS];
    base->pixels_skipped += sl->h_counters.p[CTR_SKIPPED];
    base->samples_traced += sl->h_counters.p[CTR_TRACED];
    if (b->gi && sl->gi_passes) {
        float gi_ms = 0.0f;
        CK(cudaEventElapsedTime(&gi_ms, sl->gi_started, sl->gi_done));
        base->photon_seconds += 1e-3 * (double)gi_ms;
        base->photons_traced += sl->h_counters.p[CTR_GI_PATHS];
        base->photons_reused += sl->h_counters.p[CTR_GI_REUSED];
        base->photons_stored += sl->h_counters.p[CTR_GI_INSERTED];
        base->photon_collisions += sl->h_counters.p[CTR_GI_COLLISIONS];
        base->photon_cells_changed += sl->h_counters.p[CTR_GI_CHANGED];
        base->photon_passes += (uint64_t)sl->gi_passes;
        sl->gi_passes = 0; /* a re-render at overflow does not run the passes again */
    }
    float ms = 0.0f;
    CK(cudaEventElapsedTime(&ms, sl->started, sl->rendered));
    base->device_seconds += 1e-3 * (double)ms;
    if (b->setup.adaptive)
        base->samples += sl->h_counters.p[CTR_TRACED]; /* the samples taken, all traced */
    else
        base->samples += (uint64_t)b->setup.width * (uint64_t)b->setup.height *
                         (uint64_t)b->setup.samples_per_frame;
    if (!sl->copying && (st = start_copy(b, sl, n, err)) != EVR_OK) return st;
    tw = evr_host_seconds();
    CK(cudaStreamSynchronize(sl->copy));
    base->wait_seconds += evr_host_seconds() - tw;
    const double tl_copied = evr_host_seconds();
    if (timeline_rec *r = timeline_at(&b->tl, sl->index)) {
        CK(timeline_gpu(&b->tl, r, sl->started, sl->rendered, sl->sort_from, sl->copied));
        r->col0 = tl_col0;
        r->counted = tl_counted;
        r->copied = tl_copied;
        r->n = n;
    }
    if (n) {
        float sort_ms = 0.0f, copy_ms = 0.0f;
        CK(cudaEventElapsedTime(&sort_ms, sl->sort_from, sl->sorted));
        CK(cudaEventElapsedTime(&copy_ms, sl->sorted, sl->copied));
        base->sort_seconds += 1e-3 * (double)sort_ms;
        base->copy_seconds += 1e-3 * (double)copy_ms;
    }
    /* The keys before emit_before are decoded; the rest stay on the device and are sorted again
     * with the next segment's, which can precede them (a pixel's first sample there reaches back
     * to its last one here). On the host they had to be merged with the next segment's events:
     * 0.21 s of the main thread for the 30 s eye, and a copy of them at every hand-over. */
    const int xb = event_key_bits(b->setup.width), yb = event_key_bits(b->setup.height);
    const int shift = key_time_shift(b->setup.width, b->setup.height);
    const size_t total = sl->total; /* its own n and those carried in */
    size_t split = total;
    unsigned long long key_split = 0, key_last = 0;
    if (total && emit_before_us != INT64_MAX) {
        const long long rel = (long long)emit_before_us - sl->base_us;
        const unsigned long long limit =
            rel <= 0 ? 0ull : (unsigned long long)rel << shift; /* the first key at or after it */
        if (rel < slot_span_us(b, sl)) {
            split_keys<<<1, 1, 0, sl->copy>>>(sl->d_keys_sorted.p, total, limit, b->d_split.p);
            CK(cudaGetLastError());
            CK(cudaMemcpyAsync(b->h_split.p, b->d_split.p, SPLIT_N * sizeof(unsigned long long),
                               cudaMemcpyDeviceToHost, sl->copy));
            CK(cudaStreamSynchronize(sl->copy));
            split = (size_t)b->h_split.p[0];
            key_split = b->h_split.p[1];
            key_last = b->h_split.p[2];
        }
    }
    b->carry_slot = split < total ? b->head : -1;
    b->carry_at = split;
    b->carry_n = total - split;
    b->carry_base_us = sl->base_us;
    if (split < total) {
        b->carry_t_lo = decode_key(key_split, sl->base_us, xb, yb).t;
        b->carry_t_hi = decode_key(key_last, sl->base_us, xb, yb).t;
    }
    /* The keys before the split come over piece by piece, the next piece copied while this one
     * is decoded (straight after any events held back in out, the two runs merged where they
     * overlap) and handed to the writers: each piece brings the next one's first key, before
     * which every event of the segment is then on the host. */
    const size_t pieces = (split + b->piece - 1) / b->piece;
    if (pieces) CK(copy_piece(b, sl, 0, split));
    for (size_t k = 0; k < pieces; k++) {
        const int buf = (int)(k & 1);
        const size_t m = piece_keys(b, k, split);
        tw = evr_host_seconds();
        CK(cudaEventSynchronize(b->piece_copied[buf]));
        base->wait_seconds += evr_host_seconds() - tw;
        float piece_ms = 0.0f;
        CK(cudaEventElapsedTime(&piece_ms, b->piece_from[buf], b->piece_copied[buf]));
        base->copy_seconds += 1e-3 * (double)piece_ms;
        if (k + 1 < pieces) CK(copy_piece(b, sl, k + 1, split));
        const size_t held = out->n;
        if (!evr_event_vec_reserve(out, m)) {
            snprintf(err->msg, sizeof err->msg, "out of memory for events");
            return EVR_ERR_NOMEM;
        }
        decode_keys(b->par, b->h_piece[buf].p, b->setup.event_ids ? b->h_piece_ids[buf].p : nullptr,
                    m, sl->base_us, xb, yb, out->data + held);
        out->n += m;
        if (!evr_events_merge_runs(out, held, &b->scratch)) {
            snprintf(err->msg, sizeof err->msg, "out of memory for events");
            return EVR_ERR_NOMEM;
        }
        if (k + 1 < pieces && base->emit_piece) {
            const long long next_t = decode_key(b->h_piece[buf].p[m], sl->base_us, xb, yb).t;
            if ((st = base->emit_piece(base->emit_user, next_t, err)) != EVR_OK) return st;
        }
    }
    *intensity = sl->want_intensity ? sl->h_intensity.p : NULL;
    *frames = sl->num_frames ? sl->h_frames.p : NULL;
    b->labels_hits = sl->num_labels ? sl->h_labels.p : NULL;
    base->device_bytes = device_bytes(b);
    if (timeline_rec *r = timeline_at(&b->tl, sl->index)) r->col1 = evr_host_seconds();
    b->head = (b->head + 1) % NSLOT;
    b->queued--;
    return start_ready_copies(b, err);
}
