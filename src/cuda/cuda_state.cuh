/* The CUDA backend's state, shared by its units: the backend (scene on the device, the ring of
 * pixel states, global illumination's buffers) and its slots, one per segment in flight; and the
 * helpers that read it (launch arguments, event key bits, memory held). See cuda_backend.cu for
 * the design, cuda_pipeline.cu for the segments' way through the slots. */
#ifndef EVR_CUDA_CUDA_STATE_CUH
#define EVR_CUDA_CUDA_STATE_CUH

#include "cuda/cuda_args.cuh"
#include "cuda/cuda_check.cuh"
#include "cuda/cuda_memory.cuh"
#include "cuda/cuda_timeline.cuh"

extern "C" {
#include "backend.h"
#include "cuda/gpu_bvh.h"
#include "par_pool.h"
#include "prep/photon_emitters.h"
}

#ifndef NSLOT
#define NSLOT 4 /* segments in flight: 4 measured 5-6% faster than 3 and than 6 (H100, eye 30 s) */
#endif
#define NRING \
    (NSLOT + 1) /* pixel-state arrays: the in-flight segments' inputs and the last output */
/* Event keys a piece brings to the host (cuda_backend.h_piece), 16 MB decoded: a bound on host
 * memory whatever a burst makes (with the write queue's bytes), and a batch large enough that
 * the writers pack it in parallel (AEDAT 4.0 one packet of up to 32,768 events a thread). */
#ifndef EVENT_PIECE
#define EVENT_PIECE ((size_t)1 << 20)
#endif
#define SPLIT_N 3 /* d_split: the split index, the key there, the last key */

/* One segment in flight. */
struct slot {
    int index;
    double t0, t1;
    int camera_static, want_intensity;
    int num_frames; /* intensity frames wanted in this segment */
    long long base_us;
    int end_bit;
    hbuf<evr_motion_key> h_keys;
    hbuf<int> h_tracks; /* offsets then counts */
    dbuf<evr_motion_key> d_keys;
    dbuf<int> d_tracks;
    evr_gpu_top top; /* host top level */
    dbuf<evr_gpu_node4> d_top4;
    dbuf<evr_gpu_node8> d_top8;
    dbuf<evr_gpu_inst> d_insts;
    /* the deforming instances: the segment's vertex keys (every view's positions and normals)
     * and views of them, and the deforming groups' trees (cuda_backend.deform's packed arrays,
     * copied when their generation dgen is not the backend's) */
    int num_deforms;
    hbuf<float> h_dverts;
    dbuf<float> d_dverts;
    hbuf<evr_deform_view> h_dviews;
    dbuf<evr_deform_view> d_dviews;
    unsigned long long dgen; /* 0: none copied */
    uint32_t num_dnodes, num_dtris;
    hbuf<evr_gpu_node4> h_dnodes4;
    hbuf<evr_gpu_node8> h_dnodes8;
    hbuf<evr_gpu_dtri> h_dtris;
    dbuf<evr_gpu_node4> d_dnodes4;
    dbuf<evr_gpu_node8> d_dnodes8;
    dbuf<evr_gpu_dtri> d_dtris;
    dbuf<unsigned long long> d_keys_ev, d_keys_sorted;
    dbuf<uint16_t> d_ids_ev, d_ids_sorted; /* event ids (setup.event_ids), beside the keys */
    dbuf<unsigned char> d_sort_temp;
    dbuf<unsigned int> d_count;          /* indexed by launch_count */
    dbuf<unsigned long long> d_counters; /* indexed by segment_counter */
    dbuf<evr_skip_plan> d_plan;
    hbuf<evr_skip_plan> h_plan;
    dbuf<int> d_list;             /* pixels that trace (change-driven sampling) */
    dbuf<evr_adapt_plan> d_adapt; /* adaptive sampling's plan */
    hbuf<evr_adapt_plan> h_adapt;
    int reuse; /* the plan lets pixels reuse their intensity */
    dbuf<float> d_intensity;
    hbuf<unsigned int> h_count;
    hbuf<unsigned long long> h_counters;
    hbuf<float> h_intensity;
    hbuf<float> h_frame_f; /* normalized times of the frames */
    dbuf<float> d_frame_f;
    dbuf<float> d_frames;
    hbuf<float> h_frames;
    int num_labels;        /* label frames wanted in this segment (backend.h) */
    hbuf<float> h_label_f; /* their normalized times */
    dbuf<float> d_label_f;
    dbuf<evr_hit> d_labels; /* every pixel's primary hit at each */
    hbuf<evr_hit> h_labels;
    cudaStream_t copy = nullptr;
    cudaEvent_t framed = nullptr; /* the frame kernel is done */
    cudaEvent_t started = nullptr, rendered = nullptr, counted = nullptr, sorted = nullptr,
                copied = nullptr;
    int num_tracks, num_keys;
    /* global illumination: the changed cells, the view the kernels read (which ring buffers) */
    dbuf<uint32_t> d_sat;
    dbuf<uint32_t> d_ch_before, d_ch_base, d_ch_x; /* the cells that changed (gp.max_photons 0) */
    dbuf<gpu_gi_view> d_gi_view;
    hbuf<gpu_gi_view> h_gi_view;
    hbuf<evr_photon_emitter> h_em;
    dbuf<evr_photon_emitter> d_em;
    hbuf<float> h_cdf;
    dbuf<float> d_cdf;
    cudaEvent_t gi_started = nullptr, gi_done = nullptr;
    int gi_passes;                   /* photon passes run for this segment (0: a still copy) */
    int copying;                     /* the sort and copy of this render's events are queued */
    size_t total;                    /* keys sorted: its own, then those carried in */
    cudaEvent_t sort_from = nullptr; /* start of the sort (copy stream) */
    int static_gen = -1; /* the static hits it renders with (cuda_backend.static_gen), -1: none */
};

/* A photon buffer in device memory (cuda_gi.cu): a ring of them, indexed by segment. */
struct gi_buffer {
    dbuf<evr_photon> slots;
    dbuf<uint32_t> count;
    dbuf<float> gbuf;
    dbuf<int> view_inst; /* --gi-blur: the cells' instances and blurred estimates */
    dbuf<float> blur;
    evr_photon_buffer ph; /* the shape and the device pointers */
};

struct cuda_backend {
    evr_backend base;
    const evr_hit *labels_hits; /* the label hits of the segment collected last, or NULL */
    const evr_scene *scene;
    /* every pixel's camera ray in the static group, for a still camera at static_cam (the
     * camera track's key); static_gen counts the times it was made (0: not yet); static_off:
     * never (EVR_NO_STATIC_HITS, for measurements) */
    dbuf<gpu_static_hit> d_static;
    evr_motion_key static_cam;
    int static_gen, static_off;
    evr_par_pool *par; /* decodes the sorted keys (NULL: on the main thread) */
    evr_render_host host;
    evr_run_setup setup;
    evr_gpu_bvh bvh;
    evr_gpu_deform deform; /* the deforming groups' trees of the last submitted segment (host) */
    int device;
    char device_name[256];
    /* scene on the device */
    dbuf<float> d_floats; /* all vertex data */
    dbuf<uint32_t> d_indices;
    dbuf<evr_mesh_view> d_meshes;
    dbuf<evr_material_params> d_materials;
    dbuf<float> d_bsdf_table; /* core/bsdf.h's albedo table */
    dbuf<evr_texture_view> d_textures;
    dbuf<float> d_texels;
    dbuf<evr_instance_view> d_instances;
    dbuf<evr_light_view> d_lights;
    dbuf<evr_gpu_node4> d_nodes4;
    dbuf<evr_gpu_node8> d_nodes8;
    dbuf<evr_gpu_tri> d_tris;
    dbuf<evr_pixel_state> d_state[NRING];
    dbuf<float> d_next[NRING];  /* adaptive sampling: next sample times, a ring as d_state */
    dbuf<unsigned> d_id[NRING]; /* event ids: each pixel's last traced sample's, as d_state */
    dbuf<float> d_phase;
    dbuf<evr_pixel_params> d_sensor; /* the run's pixel parameters, for the sensor kernel */
    cudaStream_t render = nullptr;
    slot slots[NSLOT];
    int head, queued;
    size_t capacity; /* event keys per segment */
    /* the collected segment's sorted keys at or after its emit_before, still on the device
     * (slots[carry_slot].d_keys_sorted from carry_at, carry_n of them, keys on carry_base_us,
     * times carry_t_lo .. carry_t_hi): sorted again with the next segment's (carry_slot -1: none) */
    int carry_slot;
    size_t carry_at, carry_n;
    long long carry_base_us, carry_t_lo, carry_t_hi;
    evr_event_vec scratch;
    /* The collected segment's keys come to the host in pieces of EVENT_PIECE, through two pinned
     * buffers (one copied while the other is decoded and written), so that host memory holds a
     * piece however many events a segment makes. d_split/h_split: where emit_before splits the
     * sorted keys, the key there and the last key. */
    size_t piece; /* EVENT_PIECE, or the hidden EVR_EVENT_PIECE's (tests: many pieces) */
    hbuf<unsigned long long> h_piece[2];
    hbuf<uint16_t> h_piece_ids[2];
    cudaEvent_t piece_from[2] = {nullptr, nullptr}, piece_copied[2] = {nullptr, nullptr};
    dbuf<unsigned long long> d_split;
    hbuf<unsigned long long> h_split;
    /* global illumination (cuda_gi.cu): the pass's photons and their sort, shared by the slots
     * (one pass at a time on the render stream) */
    int gi, gi_have_prev;
    gi_buffer gi_ring[NRING]; /* segment i ends in gi_ring[i % NRING], starts in the one before */
    dbuf<uint8_t> d_gi_last;  /* per cell: changed over the last segment */
    float blur_sigma;         /* --gi-blur: its sigma in world units (0: off) */
    dbuf<float> d_blur_tmp;   /* the blur's two working arrays (EVR_BLUR_CH a cell) */
    dbuf<gi_end>
        d_gi_ends[NRING]; /* deferred gathers: each pixel's last gather, a ring as d_state */
    uint32_t photons;
    evr_photon_params pp;
    evr_gather_params gp;
    evr_photon_emitters em; /* host: rebuilt per segment */
    dbuf<evr_photon> d_pending;
    dbuf<unsigned long long> d_pkeys, d_pkeys_sorted;
    dbuf<unsigned> d_pvals, d_pvals_sorted, d_pcount;
    dbuf<unsigned char> d_ptemp;
    /* the photons' trails (core/photon.h) and the emitter table of the pass that recorded them */
    dbuf<evr_photon_trail> d_trails;
    dbuf<evr_trail_ray> d_trail_rays;
    dbuf<unsigned> d_todo,
        d_todo_count; /* the photons a pass traces when others reuse their trails */
    int trails_valid, trails_off;
    evr_photon_emitters trail_em;
    /* GI with deferred gathers (cuda_gi_deferred.cu): off when its buffers do not fit, or with
     * adaptive sampling (its kernel gathers inline) */
    int gi_deferred;
    unsigned gather_grid;
    dbuf<float> d_gd_direct, d_gd_cache;
    dbuf<unsigned> d_gd_ids;
    dbuf<float2> d_gd_lum;
    dbuf<unsigned> d_gd_req, d_gd_count;
    dbuf<int> d_gd_traced, d_gd_newpix;
    dbuf<unsigned long long> d_gd_delta;
    dbuf<gi_request> d_gd_requests;
    cuda_timeline tl; /* EVR_TIMELINE (hidden, for measurement) */
};

/* Bits an event key gives a coordinate of n values, and those below an event key's time. */
int event_key_bits(int n);
int key_time_shift(int width, int height);
/* Microseconds after a slot's base_us its event keys can hold. */
long long slot_span_us(const cuda_backend *b, const slot *sl);
/* The arguments of a launch for slot sl's segment. */
kernel_args make_args(cuda_backend *b, slot *sl);
/* The kernel variant of the run. */
kernel_variant run_variant(const cuda_backend *b);
/* Device memory the backend holds, bytes. */
uint64_t device_bytes(const cuda_backend *b);

#endif
