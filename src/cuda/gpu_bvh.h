/* Our own ray-tracing acceleration structure, for the CUDA backend (and for host tests that
 * check it against Embree where there is no GPU).
 *
 * Two levels, as in the CPU backend:
 *   bottom  one BVH per mesh, in object space, built once per run by Embree's rtcBuildBVH
 *           (SAH with spatial splits, RTC_BUILD_QUALITY_HIGH) and flattened into wide nodes;
 *           every mesh's nodes and triangles live in one node array and one triangle array.
 *   top     one BVH over the scene's instances, rebuilt on the host for every segment (Embree's
 *           binned SAH, one instance per leaf; about 0.1 ms for the eye scene, 0.25 s for 100k
 *           instances half of them moving, on 2 cores); an instance's box encloses its mesh's
 *           box moved by the instance's motion keys over the WHOLE segment (a proven bound, not
 *           samples only), so a ray at any time inside the segment finds every instance it can
 *           hit.
 * Everything is flat arrays of plain structs that refer to each other by index: one memcpy
 * per array puts them on the device, and evr_gpu_scene_view (a struct of const pointers) is
 * what the traversal in gpu_traverse.h reads, filled with host pointers here and with device
 * pointers by the CUDA backend.
 *
 * Node layouts (chosen per build, recorded in every struct, so both can be measured):
 *   EVR_GPU_LAYOUT_BVH4  4-wide nodes with float child boxes, SoA, 128 bytes (one cache line);
 *                        nearest-first traversal with a distance per stack entry. Simple.
 *   EVR_GPU_LAYOUT_CW8   8-wide compressed nodes of Ylitie, Karras and Laine (2017), 80 bytes:
 *                        child boxes quantized to 8 bits on a power-of-two grid anchored at the
 *                        parent's corner, children ordered by ray octant, leaves of <= 3 items,
 *                        a stack of (node group, hit mask) pairs: one entry per level. Less
 *                        memory traffic per ray, which is what limits GPU traversal on large
 *                        scenes. The default (EVR_GPU_LAYOUT_DEFAULT).
 * Leaves refer to a contiguous run of items stored in leaf order: triangles (three vertices,
 * ready for the watertight test, plus the original triangle index; leaves of <= 3 for CW8,
 * <= 4 for BVH4) at the bottom, instance records (one per leaf) at the top. Quantized boxes
 * are rounded outwards, checked in float arithmetic as the traversal decodes them, so they
 * always contain the exact child box. */
#ifndef EVR_CUDA_GPU_BVH_H
#define EVR_CUDA_GPU_BVH_H

#include <stdint.h>
#include "evray.h"
#include "core/motion.h"
#include "core/render_scene.h"

#ifdef __cplusplus
#define EVR_ALIGN16 alignas(16)
extern "C" {
#else
#define EVR_ALIGN16 _Alignas(16)
#endif

#define EVR_GPU_LAYOUT_BVH4 4
#define EVR_GPU_LAYOUT_CW8 8
#ifndef EVR_GPU_LAYOUT_DEFAULT
#define EVR_GPU_LAYOUT_DEFAULT EVR_GPU_LAYOUT_CW8
#endif

/* Entries of the traversal stack (one array per ray, shared by both levels). Builds check that
 * every tree fits: the top level's worst case plus the deepest mesh's worst case. */
#define EVR_GPU_STACK_SIZE 64

/* 4-wide node, 128 bytes. Child i: count[i] == 0: an inner node, child[i] its index;
 * count[i] > 0: a leaf of count[i] items from child[i] on; child[i] < 0: an empty slot (its box
 * is empty: lo = +inf, hi = -inf). */
typedef struct {
    EVR_ALIGN16 float lo_x[4];
    float hi_x[4], lo_y[4], hi_y[4], lo_z[4], hi_z[4];
    int32_t child[4];
    uint32_t count[4];
} evr_gpu_node4;

/* 8-wide compressed node, 80 bytes. Child boxes: lo = p + qlo * 2^(e - 127), hi likewise, per
 * axis, each product and sum computed as one fused multiply-add (fmaf) in float.
 * meta[s] of slot s: 0 empty; inner child: 0x20 | (24 + s), its node is child_base plus the
 * number of inner children in slots below s (bits of imask); leaf: (0x1, 0x3 or 0x7 for 1, 2 or
 * 3 items) << 5 | offset of its first item from item_base. Slot s is filled with the child
 * nearest to rays of octant s (bit 0 set: x direction negative, bit 1: y, bit 2: z). */
typedef struct {
    EVR_ALIGN16 float p[3];
    uint8_t e[3];
    uint8_t imask;
    uint32_t child_base;
    uint32_t item_base;
    uint8_t meta[8];
    uint8_t qlo[3][8];
    uint8_t qhi[3][8];
} evr_gpu_node8;

/* A triangle in leaf order, object space, 48 bytes: vertices as the mesh gives them (the
 * watertight test needs the vertices themselves, not edges) and the triangle's index in its
 * mesh. With spatial splits one triangle may appear in several leaves. */
typedef struct {
    EVR_ALIGN16 float v0[3];
    uint32_t prim;
    float v1[3];
    uint32_t pad1;
    float v2[3];
    uint32_t pad2;
} evr_gpu_tri;

/* An instance in the top level's leaf order, 64 bytes. */
typedef struct {
    EVR_ALIGN16 evr_m34 inv;   /* world to object; valid when moving == 0 */
    int32_t root;              /* root node of the mesh's bottom-level BVH */
    int32_t track;             /* motion track (evr_render_scene) */
    int32_t instance;          /* index into the scene's instances (and evr_render_scene's) */
    int32_t moving;            /* 1: the transform changes in the segment, evaluate per ray */
} evr_gpu_inst;

/* What the traversal reads; all pointers host or all device. */
typedef struct {
    int layout;                          /* EVR_GPU_LAYOUT_* */
    const evr_gpu_node4 *nodes4;         /* bottom level, layout BVH4 (else NULL) */
    const evr_gpu_node8 *nodes8;         /* bottom level, layout CW8 (else NULL) */
    const evr_gpu_tri *tris;
    const evr_gpu_node4 *top4;           /* top level, root at 0 */
    const evr_gpu_node8 *top8;
    const evr_gpu_inst *insts;
    uint32_t num_nodes, num_tris, num_top_nodes, num_insts;   /* num_top_nodes 0: nothing to hit */
} evr_gpu_scene_view;

/* ---- host side ---- */

/* Bottom level of every mesh of a scene. */
typedef struct {
    int layout;
    int num_meshes;
    int32_t *mesh_root;        /* per mesh: root node, -1 for a mesh without usable triangles */
    int *mesh_stack;           /* per mesh: stack entries its traversal needs at most */
    float *mesh_bounds;        /* per mesh: object-space box of its triangles, lo xyz hi xyz */
    int max_stack;             /* largest of mesh_stack */
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes;
    evr_gpu_tri *tris;
    uint32_t num_tris;         /* triangle references (>= the meshes' triangles with splits) */
    void *device;              /* the Embree device (RTCDevice) its builds use */
} evr_gpu_bvh;

/* Top level of one segment. Zero it before the first build; later builds reuse its memory. */
typedef struct {
    int layout;
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_inst *insts;
    uint32_t num_insts, cap_insts;
    float *inst_bounds;        /* per scene instance: world box over the segment, lo xyz hi xyz
                                  (empty, lo > hi, for an instance left out) */
    int num_scene_instances;
    int stack_need;            /* top level's worst case plus the deepest mesh's */
} evr_gpu_top;

/* Builds the bottom level of every mesh of s with the given layout (0: EVR_GPU_LAYOUT_DEFAULT).
 * On failure *out is left empty (safe to free). */
evr_status evr_gpu_bvh_build(const evr_scene *s, int layout, evr_gpu_bvh *out, evr_error *err);
void evr_gpu_bvh_free(evr_gpu_bvh *b);

/* Builds the top level for the segment whose motion keys rs holds (rs->instances[i].mesh and
 * .track, rs->keys, rs->track_offset, rs->track_count; rs->num_instances). */
evr_status evr_gpu_top_build(const evr_gpu_bvh *b, const evr_render_scene *rs, evr_gpu_top *top, evr_error *err);
void evr_gpu_top_free(evr_gpu_top *top);

/* A view of host arrays, for host traversal. */
void evr_gpu_scene_view_host(const evr_gpu_bvh *b, const evr_gpu_top *top, evr_gpu_scene_view *v);

/* World box that holds the object-space box [lo, hi] moved by track tr at every time of the
 * segment, f in [0, 1], with the interpolation of evr_motion_eval. Conservative: between
 * samples of the rotation and scaling, the box of the (linear) translation plus the boxes at
 * the two samples widened by a bound on how far a point can turn or stretch in between (slerp
 * at its angular speed, scale/skew change); the union over all steps. Samples are spaced so
 * that the widening is about 1% of the object's size (at most 64 per key interval). */
void evr_gpu_segment_bounds(const float lo[3], const float hi[3], evr_motion_track tr, float out_lo[3],
                            float out_hi[3]);

#ifdef __cplusplus
}
#endif
#endif
