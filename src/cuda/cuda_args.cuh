/* What the CUDA backend's kernels take, by value: the launch configuration, the arguments of
 * every launch (kernel_args and the second arguments of the adaptive, deferred-gather and photon
 * kernels) and the names of the counters the kernels add to. Shared by the units that launch
 * kernels (cuda_render.cu, cuda_gi.cu, cuda_gi_deferred.cu) and the host code that fills them. */
#ifndef EVR_CUDA_CUDA_ARGS_CUH
#define EVR_CUDA_CUDA_ARGS_CUH

#include <cuda_runtime.h>
#include <type_traits>

extern "C" {
#include "backend.h"
#include "cuda/gpu_bvh.h"
}
#include "core/adaptive.h"
#include "core/refine.h"
#include "core/photon.h"
#include "core/skip.h"

#define BLOCK 128 /* threads a block (the summed-area columns kernel excepted) */
#ifndef MIN_BLOCKS
/* 64 registers: more warps in flight to hide the traversal's latency; faster than 80 and than
 * 48 (docs/benchmarks.md, "Render kernels' registers") */
#define MIN_BLOCKS 8
#endif
#ifndef MIN_BLOCKS_GI
#define MIN_BLOCKS_GI 4 /* with global illumination: 128 registers (the gather's state) */
#endif

/* Launches over every pixel give each warp a tile of TILE_W x TILE_H pixels (8 x 4) rather than a
 * run of 32 along a row: the warp's rays, and the cells its pixels' gathers read, then lie close
 * together in both directions. Edge tiles have lanes outside the image (inactive). The skip
 * kernel lists the pixels that trace in this order too (cuda_pixel.cuh's tiled_pixel). */
#ifndef TILE_W
#define TILE_W 8
#endif
#define TILE_H (32 / TILE_W)
static inline unsigned tiled_threads(int w, int h)
{
    return (unsigned)((w + TILE_W - 1) / TILE_W) * (unsigned)((h + TILE_H - 1) / TILE_H) * 32u;
}

/* The kernels' compile-time variant of a run: its traversal layout (the node layout,
 * EVR_GPU_LAYOUT_*, with EVR_GPU_TRACE_GENERAL where the scene has deforming meshes or meshes
 * whose hits a material may rule out: the kernels of a scene without them are the code they
 * were before), the sensor model (1) or the ideal one (0), global illumination. */
struct kernel_variant {
    int layout;
    bool sensor, gi;
};

/* Calls f with a traversal layout (kernel_variant.layout) as a compile-time constant:
 * f(std::integral_constant<int, LAYOUT>{}). */
template <typename F> static inline void with_layout(int layout, F f)
{
    const int general = layout & EVR_GPU_TRACE_GENERAL;
    if ((layout & ~EVR_GPU_TRACE_GENERAL) == EVR_GPU_LAYOUT_CW8) {
        if (general) f(std::integral_constant<int, EVR_GPU_LAYOUT_CW8 | EVR_GPU_TRACE_GENERAL>{});
        else f(std::integral_constant<int, EVR_GPU_LAYOUT_CW8>{});
    } else {
        if (general) f(std::integral_constant<int, EVR_GPU_LAYOUT_BVH4 | EVR_GPU_TRACE_GENERAL>{});
        else f(std::integral_constant<int, EVR_GPU_LAYOUT_BVH4>{});
    }
}

/* The segment's counters (kernel_args.counters, slot.d_counters): 64-bit counters the kernels
 * add to, the render kernels' first, then the photon pass's; CTR_KEY_RANGE counts events outside
 * the keys' time window (an internal error: collect fails). */
enum segment_counter {
    CTR_RAYS = 0,          /* rays traced */
    CTR_SKIPPED = 1,       /* pixels that reused their intensity */
    CTR_TRACED = 2,        /* samples traced */
    CTR_GI_PATHS = 3,      /* photon paths started */
    CTR_GI_INSERTED = 4,   /* photons stored in the buffer */
    CTR_GI_COLLISIONS = 5, /* photons that found their cell's layers full */
    CTR_GI_CHANGED = 6,    /* cells that changed over the segment */
    CTR_GI_REUSED = 7,     /* photons that took their trail's outcome */
    CTR_KEY_RANGE = 8,
    CTR_COUNT = 9
};

/* The launch's 32-bit counts (kernel_args.count, slot.d_count). */
enum launch_count {
    COUNT_EVENTS = 0, /* event keys appended (kernel_args.count) */
    COUNT_LISTED = 1, /* pixels the skip kernel listed to trace (kernel_args.list_count) */
    COUNT_N = 2
};

/* The deferred gathers' request counts (gi_deferred.count). */
enum request_count {
    REQ_KNOWN = 0,      /* requests with the start known, from the front of the array */
    REQ_NEW = 1,        /* requests without, from the back */
    REQ_NEW_PIXELS = 2, /* pixels that made one without (listed in newpix) */
    REQ_COUNTS = 3
};

/* A camera ray's nearest hit among the static group's triangles (instance -1: none). */
struct gpu_static_hit {
    float t, u, v;
    uint32_t prim;
    int32_t instance;
};

/* Everything one launch reads, by value. */
struct kernel_args {
    evr_render_scene rs;     /* device pointers */
    evr_gpu_scene_view view; /* device pointers */
    const evr_pixel_state *state_in;
    evr_pixel_state *state_out;
    const float *phase;
    float *intensity; /* NULL unless the segment's intensities are wanted */
    float pos_thres, neg_thres, refractory, log_floor; /* the ideal pixel's parameters */
    int width, height, samples;
    float dt;          /* segment length, seconds */
    double t0;         /* segment start, seconds */
    long long base_us; /* event keys hold t_us - base_us */
    int camera_static;
    unsigned long long *keys; /* event keys */
    unsigned int capacity;
    unsigned int *count;          /* [COUNT_EVENTS] */
    unsigned long long *counters; /* the segment's counters, indexed by segment_counter */
    /* change-driven sampling: the segment's plan; with reuse, the skip kernel lists the pixels
     * that must trace (list, list_count) and the render kernel runs those only */
    const evr_skip_plan *plan;
    int *list;
    unsigned int *list_count; /* [COUNT_LISTED] of the same array as count */
    /* the sensor kernel's full parameters stay in device memory: this struct is copied per
     * thread (the traversal takes its address), so it is kept small, and this comes last so
     * that the ideal kernel sees the same layout as before the sensor model */
    const evr_pixel_params *sensor;
    const struct gpu_gi_view *gi; /* global illumination (cuda_gi.cu), NULL when off */
    int coherence;                /* primary rays start with tfar just past the pixel's last hit */
    int xbits, ybits;             /* event keys: bits of x and of y (event_key_bits) */
    long long span_us;            /* event keys hold t_us - base_us in [0, span_us) */
    /* per pixel, its camera ray's hit in the static group while the camera holds still (NULL:
     * not this segment): primary rays search the other groups only */
    const gpu_static_hit *static_hits;
    /* event ids (evr_event.id; NULL when off): ids[k] is keys[k]'s; id_in / id_out each pixel's
     * last traced sample's, a ring as the states */
    uint16_t *ids;
    const unsigned *id_in;
    unsigned *id_out;
};

/* Adaptive sampling's own arguments: a second kernel parameter, so that kernel_args (and the
 * uniform kernels) keep their layout. */
struct adapt_args {
    const float
        *next_in; /* each pixel's next sample time, segment-relative (a ring as the states) */
    float *next_out;
    const evr_adapt_plan *plan; /* the segment's motion bounds (device memory) */
    evr_adapt_params p;
};

/* Refined sampling's own arguments (a second kernel parameter, as adapt_args). */
struct refine_args {
    const evr_adapt_plan *plan; /* the segment's motion bounds (device memory) */
    evr_refine_params p;
};

/* A listed pixel whose direct light stays while its indirect light changes (deferred gathers):
 * the skip kernel makes its samples, the trace kernel leaves it alone. */
#define LIST_INDIRECT_ONLY 0x80000000u

/* A pixel's last gather of a segment, kept for the next (the deferred kernels): its gather point
 * (dist NaN or negative: none) and its luminance at the segment's end, which is the next
 * segment's start bit for bit (the same buffer, the same point, the same pixel). */
struct gi_end {
    evr_gather_point g;
    float le;
    float direct;     /* the direct light of the same sample */
    evr_gather_sum s; /* gp.max_photons 0: the fixed-point sums of le's gather */
};

#define GI_NO_REQUEST 0xffffffffu

/* A deferred gather: the surface point and its pixel; ls: its start gather where known (the
 * pixel's end gather of the previous segment at the same point: the requests at the front of
 * the array, gi_deferred.count). */
struct gi_request {
    evr_gather_point g;
    int pix;
    float ls;
    evr_gather_sum s; /* gp.max_photons 0: the end's fixed-point sums (the gather kernel's) */
};

/* The shared buffers of the deferred kernels (cuda_gi_deferred.cu; the skip kernel fills them for
 * the pixels it settles): device memory, reused by every launch (the kernels of a segment run in
 * order on the render stream). Per-sample arrays are [sample][thread]. */
struct gi_deferred {
    float *direct; /* a traced sample's direct light */
    unsigned *ids; /* its event id (NULL: ids off) */
    unsigned *req; /* its gather request, GI_NO_REQUEST for a miss (no light) */
    int *
        traced; /* per thread: samples with an entry (traced or held); later samples keep the last */
    float *cache_dist; /* per thread: the change-driven sampling cache after the segment */
    gi_request *requests;
    float2 *lum;     /* per request: the gathers' luminance at the segment's start and end */
    unsigned *count; /* requests made, indexed by request_count */
    unsigned cap;    /* room in requests */
    int *newpix;     /* the launch's threads (pixels) that made a request without the start known */
    unsigned long long *
        delta; /* gp.max_photons 0: per pixel, what the changed cells add to its last gather's sums (a, w) */
    int stride; /* threads of a launch at most: the pixel count */
};

/* What the render kernels read (device memory, one per slot). */
struct gpu_gi_view {
    evr_photon_buffer end, start; /* the photons at the segment's end and start (device pointers) */
    /* summed-area table, (w + 1) x (h + 1), of the cells that changed over this segment or the
     * one before: a pixel with no such cell in its window had the same indirect light all through
     * both (its intensity may be kept) */
    const uint32_t *sat;
    evr_changed_cells ch; /* gp.max_photons 0: the cells that changed over this segment only */
    evr_gather_params gp;
    int window; /* cells around a pixel a gather may read */
    /* the deferred kernels' per-pixel last gathers: the previous segment's (read) and this one's
     * (written), a ring indexed by segment as the pixel states; NULL where they did not fit */
    const gi_end *ends_in;
    gi_end *ends_out;
};

struct photon_args {
    const evr_photon_emitter *em;
    int n_em;
    const float *cdf;
    evr_photon_params pp;
    unsigned photons;
    int margin, cells_w;
    unsigned long long *sort_keys; /* (cell << 32) | photon key; all ones where no photon */
    unsigned *sort_vals;           /* index into pending */
    evr_photon *pending;
    unsigned *pending_count;
    /* trails (core/photon.h): NULL when they did not fit in memory */
    evr_photon_trail *trails;
    evr_trail_ray *trail_rays;
    int trail_len;
    int reuse;      /* the trails are the previous pass's, with the same emitters */
    unsigned *todo; /* with reuse: the photons to trace (photon_reuse_kernel lists them) */
    unsigned *todo_count;
};

#endif
