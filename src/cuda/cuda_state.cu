/* Helpers over the CUDA backend's state (cuda_state.cuh): event key bits, the launch arguments
 * of a slot, the kernel variant of the run, the device memory held. */
#include "cuda/cuda_state.cuh"

#include <stdlib.h>
#include <string.h>

/* Bits an event key gives x (values 0 .. n - 1). Keys are (time, y, x, polarity) packed with no
 * spare bits, so that the radix sort takes as few 8-bit passes as the segment needs (1280x720:
 * 22 bits of pixel and polarity instead of 33). */
int event_key_bits(int n)
{
    int b = 1;
    while (b < 16 && (1 << b) < n) b++;
    return b;
}

/* Bits below an event key's time: polarity, x, y (pack_event). */
int key_time_shift(int width, int height)
{
    return 1 + event_key_bits(width) + event_key_bits(height);
}

/* Microseconds after a slot's base_us its event keys can hold. */
long long slot_span_us(const cuda_backend *b, const slot *sl)
{
    return 1ll << (sl->end_bit - key_time_shift(b->setup.width, b->setup.height));
}

kernel_args make_args(cuda_backend *b, slot *sl)
{
    kernel_args a;
    memset(&a, 0, sizeof a);
    a.rs = b->host.rs;
    a.rs.meshes = b->d_meshes.p;
    a.rs.materials = b->d_materials.p;
    a.rs.bsdf_table = b->d_bsdf_table.p;
    a.rs.textures = b->d_textures.p;
    a.rs.instances = b->d_instances.p;
    a.rs.lights = b->d_lights.p;
    a.rs.deforms = sl->num_deforms ? sl->d_dviews.p : NULL;
    a.rs.num_deforms = sl->num_deforms;
    a.rs.keys = sl->d_keys.p;
    a.rs.track_offset = sl->d_tracks.p;
    a.rs.track_count = sl->d_tracks.p + sl->num_tracks;
    a.view.layout = b->bvh.layout;
    a.view.nodes4 = b->d_nodes4.p;
    a.view.nodes8 = b->d_nodes8.p;
    a.view.tris = b->d_tris.p;
    a.view.top4 = sl->d_top4.p;
    a.view.top8 = sl->d_top8.p;
    a.view.insts = sl->d_insts.p;
    a.view.num_nodes = b->bvh.num_nodes;
    a.view.num_tris = b->bvh.num_tris;
    a.view.num_top_nodes = sl->top.num_nodes;
    a.view.num_insts = sl->top.num_insts;
    a.view.dnodes4 = sl->d_dnodes4.p;
    a.view.dnodes8 = sl->d_dnodes8.p;
    a.view.dtris = sl->d_dtris.p;
    a.view.num_dnodes = sl->num_dnodes;
    a.view.num_dtris = sl->num_dtris;
    a.view.filtered = b->bvh.filtered;
    a.state_in = b->d_state[sl->index % NRING].p;
    a.state_out = b->d_state[(sl->index + 1) % NRING].p;
    a.phase = b->d_phase.p;
    a.intensity = sl->want_intensity ? sl->d_intensity.p : NULL;
    a.pos_thres = b->setup.pixel.pos_thres;
    a.neg_thres = b->setup.pixel.neg_thres;
    a.refractory = b->setup.pixel.refractory;
    a.log_floor = b->setup.pixel.log_floor;
    a.sensor = b->d_sensor.p;
    a.width = b->setup.width;
    a.height = b->setup.height;
    a.samples = b->setup.samples_per_frame;
    a.dt = (float)(sl->t1 - sl->t0);
    a.t0 = sl->t0;
    a.base_us = sl->base_us;
    a.camera_static = sl->camera_static;
    a.keys = sl->d_keys_ev.p;
    a.capacity = (unsigned)sl->d_keys_ev.cap;
    a.count = sl->d_count.p + COUNT_EVENTS;
    a.counters = sl->d_counters.p;
    a.plan = sl->d_plan.p;
    a.list = sl->reuse ? sl->d_list.p : NULL;
    a.list_count = sl->d_count.p + COUNT_LISTED;
    a.gi = b->gi ? sl->d_gi_view.p : nullptr;
    /* EVR_NO_COHERENCE (hidden, for tests and measurement): every primary ray unbounded */
    a.coherence = getenv("EVR_NO_COHERENCE") == NULL;
    a.xbits = event_key_bits(b->setup.width);
    a.ybits = event_key_bits(b->setup.height);
    a.span_us = slot_span_us(b, sl);
    /* a re-render at overflow after the camera moved on renders without them */
    a.static_hits =
        sl->static_gen >= 0 && sl->static_gen == b->static_gen ? b->d_static.p : nullptr;
    a.ids = b->setup.event_ids ? sl->d_ids_ev.p : nullptr;
    a.id_in = b->setup.event_ids ? b->d_id[sl->index % NRING].p : nullptr;
    a.id_out = b->setup.event_ids ? b->d_id[(sl->index + 1) % NRING].p : nullptr;
    return a;
}

kernel_variant run_variant(const cuda_backend *b)
{
    kernel_variant v;
    v.layout =
        b->bvh.layout | (b->bvh.num_deforming || b->bvh.filtered ? EVR_GPU_TRACE_GENERAL : 0);
    v.sensor = !evr_pixel_params_ideal(&b->setup.pixel);
    v.gi = b->gi != 0;
    return v;
}

uint64_t device_bytes(const cuda_backend *b)
{
    uint64_t n = bytes(b->d_floats) + bytes(b->d_indices) + bytes(b->d_meshes) +
                 bytes(b->d_materials) + bytes(b->d_bsdf_table) + bytes(b->d_textures) +
                 bytes(b->d_texels) + bytes(b->d_instances) + bytes(b->d_lights) +
                 bytes(b->d_nodes4) + bytes(b->d_nodes8) + bytes(b->d_tris) + bytes(b->d_phase) +
                 bytes(b->d_sensor);
    for (int i = 0; i < NRING; i++)
        n += bytes(b->d_state[i]) + bytes(b->d_next[i]) + bytes(b->d_id[i]);
    for (int i = 0; i < NSLOT; i++) {
        const slot *sl = &b->slots[i];
        n += bytes(sl->d_keys) + bytes(sl->d_tracks) + bytes(sl->d_top4) + bytes(sl->d_top8) +
             bytes(sl->d_insts) + bytes(sl->d_keys_ev) + bytes(sl->d_keys_sorted) +
             bytes(sl->d_ids_ev) + bytes(sl->d_ids_sorted) + bytes(sl->d_sort_temp) +
             bytes(sl->d_count) + bytes(sl->d_counters) + bytes(sl->d_plan) + bytes(sl->d_list) +
             bytes(sl->d_intensity) + bytes(sl->d_frame_f) + bytes(sl->d_frames) +
             bytes(sl->d_sat) + bytes(sl->d_ch_before) + bytes(sl->d_ch_base) + bytes(sl->d_ch_x) +
             bytes(sl->d_em) + bytes(sl->d_cdf) + bytes(sl->d_dverts) + bytes(sl->d_dviews) +
             bytes(sl->d_dnodes4) + bytes(sl->d_dnodes8) + bytes(sl->d_dtris);
    }
    for (int i = 0; i < NRING; i++)
        n += bytes(b->gi_ring[i].slots) + bytes(b->gi_ring[i].count) + bytes(b->gi_ring[i].gbuf);
    n += bytes(b->d_gi_last);
    for (int i = 0; i < NRING; i++) n += bytes(b->d_gi_ends[i]);
    n += bytes(b->d_pending) + bytes(b->d_pkeys) + bytes(b->d_pkeys_sorted) + bytes(b->d_pvals) +
         bytes(b->d_pvals_sorted) + bytes(b->d_pcount) + bytes(b->d_ptemp) + bytes(b->d_trails) +
         bytes(b->d_trail_rays) + bytes(b->d_todo) + bytes(b->d_gd_direct) + bytes(b->d_gd_ids) +
         bytes(b->d_gd_cache) + bytes(b->d_gd_lum) + bytes(b->d_gd_req) + bytes(b->d_gd_traced) +
         bytes(b->d_gd_requests) + bytes(b->d_gd_newpix) + bytes(b->d_gd_delta);
    return n;
}
