/* CUDA backend: the same simulation as the CPU backend on an NVIDIA GPU.
 *
 * Per segment: the host builds the top-level BVH over the instances (bounds over the whole
 * segment) and the trees of the deforming meshes whose vertices moved, and uploads them with the
 * motion keys and the deforming meshes' vertex keys; one kernel runs every pixel's samples of the
 * segment (one thread per pixel, its samples in a loop): camera ray, our own BVH traversal with
 * motion transforms (cuda/gpu_traverse.h), shading and the pixel model from src/core, the very
 * functions the CPU backend runs. Events are appended with warp-aggregated atomics as 64-bit
 * keys (time, y, x, polarity), sorted on the GPU with CUB's radix sort on a second stream while
 * the next segments render: NSLOT segments are in flight, so that the GPU has work queued while
 * the host takes in and writes earlier ones (render times vary widely from segment to segment).
 * The sorted keys come to pinned host memory in pieces of a fixed size, each decoded and handed to
 * the writers before the next, so that a burst of events does not grow host memory.
 *
 * Pixel states live in a ring of NRING device arrays: segment i reads ring[i % NRING] and writes
 * ring[(i + 1) % NRING], so when segment i's event buffer overflows (found at collect, when the
 * segments after it may already have rendered) segment i can be rendered again from its
 * unchanged input with a larger buffer: events are never dropped.
 *
 * The units: cuda_state.cuh (the backend's state), cuda_args.cuh (what the kernels take),
 * cuda_memory.cuh (buffers), cuda_render.cu (the render kernels), cuda_gi.cu and
 * cuda_gi_deferred.cu (global illumination), cuda_pipeline.cu (submit and collect),
 * cuda_timeline.cu (EVR_TIMELINE); this file makes the backend and releases it. */
#include "cuda/cuda_gi.cuh"
#include "cuda/cuda_gi_deferred.cuh"
#include "cuda/cuda_pipeline.cuh"
#include "cuda/cuda_render.cuh"
#include "cuda/cuda_state.cuh"

#include <new>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern "C" {
#include "cuda/cuda_backend.h"
#include "cuda/gpu_bvh_cache.h"
#include "host_clock.h"
#include "prep/gi_params.h"
}

static evr_status upload_scene(cuda_backend *b, evr_error *err)
{
    const evr_scene *s = b->scene;
    size_t nf = 0, ni = 0, nt = 0;
    int i;
    for (i = 0; i < s->num_meshes; i++) {
        const evr_mesh *m = &s->meshes[i];
        nf += (size_t)m->num_vertices * (6 + (m->uvs ? 2 : 0) + (m->tangents ? 4 : 0));
        ni += (size_t)m->num_triangles * 3;
    }
    for (i = 0; i < s->num_textures; i++) /* every mip level */
        nt += (size_t)evr_texture_texels(&b->host.textures[i], b->host.textures[i].levels) * 4;
    CK(b->d_floats.reserve(nf + 1));
    CK(b->d_indices.reserve(ni + 1));
    CK(b->d_texels.reserve(nt + 1));
    evr_mesh_view *mv = (evr_mesh_view *)calloc((size_t)s->num_meshes + 1, sizeof *mv);
    evr_texture_view *tv = (evr_texture_view *)calloc((size_t)s->num_textures + 1, sizeof *tv);
    if (!mv || !tv) {
        free(mv);
        free(tv);
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    size_t of = 0, oi = 0, ot = 0;
    cudaError_t e = cudaSuccess;
    for (i = 0; i < s->num_meshes && e == cudaSuccess; i++) {
        const evr_mesh *m = &s->meshes[i];
        size_t nv = m->num_vertices;
        mv[i] = b->host.meshes[i];
        e = cudaMemcpy(b->d_floats.p + of, m->positions, nv * 3 * sizeof(float),
                       cudaMemcpyHostToDevice);
        mv[i].positions = b->d_floats.p + of;
        of += nv * 3;
        if (e == cudaSuccess)
            e = cudaMemcpy(b->d_floats.p + of, m->normals, nv * 3 * sizeof(float),
                           cudaMemcpyHostToDevice);
        mv[i].normals = b->d_floats.p + of;
        of += nv * 3;
        mv[i].uvs = NULL;
        if (m->uvs && e == cudaSuccess) {
            e = cudaMemcpy(b->d_floats.p + of, m->uvs, nv * 2 * sizeof(float),
                           cudaMemcpyHostToDevice);
            mv[i].uvs = b->d_floats.p + of;
            of += nv * 2;
        }
        mv[i].tangents = NULL; /* a normal map's frames */
        if (m->tangents && e == cudaSuccess) {
            e = cudaMemcpy(b->d_floats.p + of, m->tangents, nv * 4 * sizeof(float),
                           cudaMemcpyHostToDevice);
            mv[i].tangents = b->d_floats.p + of;
            of += nv * 4;
        }
        if (e == cudaSuccess)
            e = cudaMemcpy(b->d_indices.p + oi, m->indices,
                           (size_t)m->num_triangles * 3 * sizeof(uint32_t), cudaMemcpyHostToDevice);
        mv[i].indices = b->d_indices.p + oi;
        oi += (size_t)m->num_triangles * 3;
    }
    for (i = 0; i < s->num_textures && e == cudaSuccess; i++) {
        size_t n = (size_t)evr_texture_texels(&b->host.textures[i], b->host.textures[i].levels) * 4;
        tv[i] = b->host.textures[i];
        e = cudaMemcpy(b->d_texels.p + ot, s->textures[i].rgba, n * sizeof(float),
                       cudaMemcpyHostToDevice);
        tv[i].rgba = b->d_texels.p + ot;
        ot += n;
    }
    if (e == cudaSuccess) e = b->d_meshes.reserve((size_t)s->num_meshes + 1);
    if (e == cudaSuccess)
        e = cudaMemcpy(b->d_meshes.p, mv, ((size_t)s->num_meshes + 1) * sizeof *mv,
                       cudaMemcpyHostToDevice);
    if (e == cudaSuccess) e = b->d_textures.reserve((size_t)s->num_textures + 1);
    if (e == cudaSuccess)
        e = cudaMemcpy(b->d_textures.p, tv, ((size_t)s->num_textures + 1) * sizeof *tv,
                       cudaMemcpyHostToDevice);
    free(mv);
    free(tv);
    CK(e);
    CK(b->d_materials.reserve((size_t)s->num_materials + 1));
    CK(cudaMemcpy(b->d_materials.p, b->host.materials,
                  ((size_t)s->num_materials + 1) * sizeof(evr_material_params),
                  cudaMemcpyHostToDevice));
    CK(b->d_bsdf_table.reserve(2 * EVR_BSDF_MU * EVR_BSDF_ROUGH));
    CK(cudaMemcpy(b->d_bsdf_table.p, b->host.bsdf_table,
                  2 * EVR_BSDF_MU * EVR_BSDF_ROUGH * sizeof(float), cudaMemcpyHostToDevice));
    CK(b->d_instances.reserve((size_t)s->num_instances + 1));
    CK(cudaMemcpy(b->d_instances.p, b->host.instances,
                  ((size_t)s->num_instances + 1) * sizeof(evr_instance_view),
                  cudaMemcpyHostToDevice));
    CK(b->d_lights.reserve((size_t)s->num_lights + 1));
    CK(cudaMemcpy(b->d_lights.p, b->host.lights,
                  ((size_t)s->num_lights + 1) * sizeof(evr_light_view), cudaMemcpyHostToDevice));
    if (b->bvh.nodes4) {
        CK(b->d_nodes4.reserve(b->bvh.num_nodes + 1));
        CK(cudaMemcpy(b->d_nodes4.p, b->bvh.nodes4, b->bvh.num_nodes * sizeof(evr_gpu_node4),
                      cudaMemcpyHostToDevice));
    }
    if (b->bvh.nodes8) {
        CK(b->d_nodes8.reserve(b->bvh.num_nodes + 1));
        CK(cudaMemcpy(b->d_nodes8.p, b->bvh.nodes8, b->bvh.num_nodes * sizeof(evr_gpu_node8),
                      cudaMemcpyHostToDevice));
    }
    CK(b->d_tris.reserve(b->bvh.num_tris + 1));
    CK(cudaMemcpy(b->d_tris.p, b->bvh.tris, b->bvh.num_tris * sizeof(evr_gpu_tri),
                  cudaMemcpyHostToDevice));
    return EVR_OK;
}

static const evr_hit *cuda_label_hits(evr_backend *base)
{
    return ((cuda_backend *)base)->labels_hits;
}

static void cuda_release(evr_backend *base)
{
    cuda_backend *b = (cuda_backend *)base;
    if (!b) return;
    cudaDeviceSynchronize();
    timeline_close(&b->tl);
    for (int i = 0; i < NSLOT; i++) {
        slot *sl = &b->slots[i];
        sl->h_keys.release();
        sl->h_tracks.release();
        sl->d_keys.release();
        sl->d_tracks.release();
        evr_gpu_top_free(&sl->top);
        sl->d_top4.release();
        sl->d_top8.release();
        sl->d_insts.release();
        sl->h_dverts.release();
        sl->d_dverts.release();
        sl->h_dviews.release();
        sl->d_dviews.release();
        sl->h_dnodes4.release();
        sl->h_dnodes8.release();
        sl->h_dtris.release();
        sl->d_dnodes4.release();
        sl->d_dnodes8.release();
        sl->d_dtris.release();
        sl->d_keys_ev.release();
        sl->d_keys_sorted.release();
        sl->d_ids_ev.release();
        sl->d_ids_sorted.release();
        sl->d_sort_temp.release();
        sl->d_count.release();
        sl->d_counters.release();
        sl->d_intensity.release();
        sl->d_plan.release();
        sl->h_plan.release();
        sl->d_list.release();
        sl->d_adapt.release();
        sl->h_adapt.release();
        sl->h_count.release();
        sl->h_counters.release();
        sl->h_intensity.release();
        sl->h_frame_f.release();
        sl->d_frame_f.release();
        sl->d_frames.release();
        sl->h_frames.release();
        sl->d_sat.release();
        sl->d_ch_before.release();
        sl->d_ch_base.release();
        sl->d_ch_x.release();
        sl->h_gi_view.release();
        sl->d_gi_view.release();
        sl->h_em.release();
        sl->d_em.release();
        sl->h_cdf.release();
        sl->d_cdf.release();
        if (sl->gi_started) cudaEventDestroy(sl->gi_started);
        if (sl->gi_done) cudaEventDestroy(sl->gi_done);
        if (sl->framed) cudaEventDestroy(sl->framed);
        if (sl->copy) cudaStreamDestroy(sl->copy);
        if (sl->started) cudaEventDestroy(sl->started);
        if (sl->rendered) cudaEventDestroy(sl->rendered);
        if (sl->counted) cudaEventDestroy(sl->counted);
        if (sl->sorted) cudaEventDestroy(sl->sorted);
        if (sl->copied) cudaEventDestroy(sl->copied);
        if (sl->sort_from) cudaEventDestroy(sl->sort_from);
    }
    for (int k = 0; k < 2; k++) {
        b->h_piece[k].release();
        b->h_piece_ids[k].release();
        if (b->piece_from[k]) cudaEventDestroy(b->piece_from[k]);
        if (b->piece_copied[k]) cudaEventDestroy(b->piece_copied[k]);
    }
    b->d_split.release();
    b->h_split.release();
    b->d_floats.release();
    b->d_indices.release();
    b->d_meshes.release();
    b->d_materials.release();
    b->d_bsdf_table.release();
    b->d_textures.release();
    b->d_texels.release();
    b->d_instances.release();
    b->d_lights.release();
    b->d_nodes4.release();
    b->d_nodes8.release();
    b->d_tris.release();
    b->d_phase.release();
    b->d_static.release();
    evr_par_pool_free(b->par);
    b->par = nullptr;
    b->d_sensor.release();
    for (int i = 0; i < NRING; i++) {
        b->d_state[i].release();
        b->d_next[i].release();
        b->d_id[i].release();
        b->gi_ring[i].slots.release();
        b->gi_ring[i].count.release();
        b->gi_ring[i].gbuf.release();
    }
    b->d_gi_last.release();
    b->d_pending.release();
    b->d_pkeys.release();
    b->d_pkeys_sorted.release();
    b->d_pvals.release();
    b->d_pvals_sorted.release();
    b->d_pcount.release();
    b->d_ptemp.release();
    b->d_trails.release();
    b->d_trail_rays.release();
    b->d_todo.release();
    b->d_todo_count.release();
    evr_photon_emitters_free(&b->trail_em);
    gi_deferred_release(b);
    evr_photon_emitters_free(&b->em);
    if (b->render) cudaStreamDestroy(b->render);
    evr_gpu_deform_free(&b->deform);
    evr_gpu_bvh_free(&b->bvh);
    evr_event_vec_free(&b->scratch);
    delete b;
}

static evr_status init(cuda_backend *b, evr_error *err)
{
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess || count == 0) {
        /* without an NVIDIA driver the runtime says "driver version is insufficient": say it plainly */
        const char *why = e == cudaSuccess || e == cudaErrorNoDevice ? "no NVIDIA GPU found"
                          : e == cudaErrorInsufficientDriver
                              ? "no NVIDIA driver, or one too old for CUDA 13"
                              : cudaGetErrorString(e);
        snprintf(err->msg, sizeof err->msg, "no usable CUDA device (%s)", why);
        return EVR_ERR_BACKEND;
    }
    CK(cudaGetDevice(&b->device));
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, b->device));
    snprintf(b->device_name, sizeof b->device_name, "%s", prop.name);
    evr_status st;
    evr_gpu_bvh_cache cache;
    evr_gpu_bvh_cache_init(&cache, b->setup.bvh_cache);
    const double t_bvh = evr_host_seconds();
    st = evr_gpu_bvh_build(b->scene, b->setup.gpu_bvh, &cache, &b->bvh, err);
    b->base.bvh_seconds = evr_host_seconds() - t_bvh;
    b->base.bvh_trees = b->bvh.num_trees;
    b->base.bvh_trees_cached = cache.loaded;
    snprintf(b->base.notice, sizeof b->base.notice, "%s", cache.note);
    if (st != EVR_OK) return st;
    if ((st = upload_scene(b, err)) != EVR_OK) return st;
    size_t npix = (size_t)b->setup.width * b->setup.height;
    for (int i = 0; i < NRING; i++) CK(b->d_state[i].reserve(npix));
    if (b->setup.adaptive) {
        for (int i = 0; i < NRING; i++) {
            CK(b->d_next[i].reserve(npix));
            CK(cudaMemset(b->d_next[i].p, 0, npix * sizeof(float)));
        }
    }
    if (b->setup.event_ids) {
        for (int i = 0; i < NRING; i++) {
            CK(b->d_id[i].reserve(npix));
            CK(cudaMemset(b->d_id[i].p, 0, npix * sizeof(unsigned)));
        }
    }
    CK(b->d_phase.reserve(npix));
    CK(b->d_sensor.reserve(1));
    CK(cudaMemcpy(b->d_sensor.p, &b->setup.pixel, sizeof(evr_pixel_params),
                  cudaMemcpyHostToDevice));
    cuda_launch_init_pixels(b->d_state[0].p, b->d_phase.p, b->setup.width, b->setup.height,
                            (unsigned long long)b->setup.seed, b->setup.refine);
    CK(cudaGetLastError());
    CK(cudaStreamCreateWithFlags(&b->render, cudaStreamNonBlocking));
    /* four events a pixel per segment: the eye's busiest segments at 1280x720 take 3.3 (a segment
     * that needs more grows every slot's buffers, after rendering it again); but the slots' key,
     * sorted-key and sort buffers (24 bytes a key each) take at most an eighth of the free device
     * memory up front, so that a large image on a small GPU still starts (and grows as needed) */
    size_t free_bytes = 0, total_bytes = 0;
    CK(cudaMemGetInfo(&free_bytes, &total_bytes));
    const size_t fit = free_bytes / 8 / (NSLOT * 24);
    b->capacity = npix * 4 < fit ? npix * 4 : fit;
    if (b->capacity < (1u << 20)) b->capacity = 1u << 20;
    b->carry_slot = -1;
    int gi_margin = 0, gi_window = 0;
    b->gi = b->setup.gi;
    if (b->gi)
        evr_gi_run_params(&b->setup, b->scene, &b->photons, &b->gp, &b->pp, &gi_margin, &gi_window);
    b->blur_sigma = b->gi ? b->setup.gi_blur * b->gp.radius : 0.0f;
    b->trails_off = getenv("EVR_NO_PHOTON_REUSE") !=
                    NULL; /* hidden, for tests and measurement: every photon traced */
    b->static_off = getenv("EVR_NO_STATIC_HITS") != NULL;
    b->par = evr_par_pool_new(evr_par_threads(8)); /* NULL: keys decoded on this thread */
    if (b->setup.gpu_event_capacity > 0) b->capacity = (size_t)b->setup.gpu_event_capacity;
    if (b->gi && (st = gi_ring_alloc(b, gi_margin, err)) != EVR_OK) return st;
    for (int i = 0; i < NSLOT; i++) {
        slot *sl = &b->slots[i];
        /* the sort and copy of segment i run while segment i + 1 renders: at the highest
         * priority, so that their few blocks go first and the host can take in segment i's
         * events while the GPU is still busy (at equal priority the sort waited for the whole
         * render kernel and the GPU then idled while the host worked) */
        int least = 0, greatest = 0;
        CK(cudaDeviceGetStreamPriorityRange(&least, &greatest));
        CK(cudaStreamCreateWithPriority(&sl->copy, cudaStreamNonBlocking, greatest));
        CK(cudaEventCreate(&sl->started));
        CK(cudaEventCreate(&sl->rendered));
        CK(cudaEventCreate(&sl->counted));
        CK(cudaEventCreate(&sl->sorted));
        CK(cudaEventCreate(&sl->copied));
        CK(cudaEventCreate(&sl->sort_from));
        CK(cudaEventCreate(&sl->framed));
        CK(sl->d_keys_ev.reserve(b->capacity));
        /* the sort's buffers too, up front: allocated as segments first need them, the frees
         * and pinned allocations stalled the GPU for 0.2 s of the eye's first second */
        CK(sl->d_keys_sorted.reserve(b->capacity));
        if (b->setup.event_ids) {
            CK(sl->d_ids_ev.reserve(b->capacity));
            CK(sl->d_ids_sorted.reserve(b->capacity));
        }
        size_t temp = 0;
        CK(event_sort_temp_bytes(
            sl->d_keys_ev.p, sl->d_keys_sorted.p, b->setup.event_ids ? sl->d_ids_ev.p : nullptr,
            b->setup.event_ids ? sl->d_ids_sorted.p : nullptr, (int)sl->d_keys_sorted.cap, &temp));
        CK(sl->d_sort_temp.reserve(temp));
        CK(sl->d_count.reserve(COUNT_N));
        CK(sl->d_counters.reserve(CTR_COUNT));
        CK(sl->d_plan.reserve(1));
        CK(sl->h_plan.reserve(1));
        if (b->setup.adaptive || b->setup.refine) {
            CK(sl->d_adapt.reserve(1));
            CK(sl->h_adapt.reserve(1));
        }
        CK(sl->d_list.reserve((size_t)b->setup.width * (size_t)b->setup.height));
        CK(sl->d_intensity.reserve(npix));
        CK(sl->h_count.reserve(1));
        CK(sl->h_counters.reserve(CTR_COUNT));
        CK(cudaMemset(sl->d_counters.p, 0, CTR_COUNT * sizeof(unsigned long long)));
        if (b->gi && (st = gi_alloc(b, sl, gi_window, err)) != EVR_OK) return st;
    }
    b->piece = EVENT_PIECE;
    if (const char *v = getenv("EVR_EVENT_PIECE")) {
        const long long n = atoll(v);
        if (n > 0 && n < (1ll << 30)) b->piece = (size_t)n;
    }
    for (int k = 0; k < 2; k++) {
        CK(b->h_piece[k].reserve(b->piece + 1, true));
        if (b->setup.event_ids) CK(b->h_piece_ids[k].reserve(b->piece, true));
        CK(cudaEventCreate(&b->piece_from[k]));
        CK(cudaEventCreate(&b->piece_copied[k]));
    }
    CK(b->d_split.reserve(SPLIT_N));
    CK(b->h_split.reserve(SPLIT_N));
    if (b->gi) CK(b->d_pcount.reserve(1));
    gi_deferred_alloc(b, &prop);
    CK(cudaDeviceSynchronize());
    return timeline_open(&b->tl, b->render, err);
}

extern "C" evr_status evr_cuda_backend_new(const evr_scene *s, const evr_render_host *h,
                                           const evr_run_setup *setup, evr_backend **out,
                                           evr_error *err)
{
    cuda_backend *b = new (std::nothrow) cuda_backend();
    if (!b) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    b->base.name = "cuda";
    b->base.depth = NSLOT;
    b->base.submit = cuda_submit;
    b->base.collect = cuda_collect;
    b->base.release = cuda_release;
    b->base.label_hits = cuda_label_hits;
    b->base.samples = 0;
    b->base.rays = 0;
    b->base.device_seconds = 0.0;
    b->scene = s;
    b->host = *h;
    b->setup = *setup;
    evr_status st = init(b, err);
    if (st != EVR_OK) {
        cuda_release(&b->base);
        return st;
    }
    *out = &b->base;
    return EVR_OK;
}

extern "C" const char *evr_cuda_device_name(const evr_backend *base)
{
    return ((const cuda_backend *)base)->device_name;
}
