/* What the host-side GPU BVH units share (private to src/cuda/gpu_bvh_*.c): the context that
 * flattens an Embree-built tree into gpu_bvh.h's layout, and running the build (gpu_bvh_tree.c). */
#ifndef EVR_CUDA_GPU_BVH_INTERNAL_H
#define EVR_CUDA_GPU_BVH_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <embree3/rtcore.h>
#include <embree3/rtcore_builder.h>

#include "cuda/gpu_bvh.h"

/* What the split callback needs: the group's triangles, 9 floats each (no index indirection:
 * Embree calls the callback ~100 times per triangle). */
typedef struct {
    const float *tri;
} split_source;

typedef struct {
    const void *ptr; /* build_node or build_leaf */
    uint32_t index;  /* node it becomes */
} flat_work;

typedef struct {
    int layout;
    int instances; /* items are instances (top level), */
    int deforming; /* or a deforming group's vertex-indexed triangles, else triangles */
    /* outputs, grown as needed (and kept across top-level builds) */
    evr_gpu_node4 *n4;
    evr_gpu_node8 *n8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_tri *tris;
    evr_gpu_dtri *dtris;
    evr_gpu_inst *insts;
    uint32_t num_items, cap_items;
    /* item sources, by primID */
    const float *tri9;            /* a group's triangles, 9 floats each */
    const uint32_t *tri_vidx;     /* a deforming group's triangles, 3 vertex indices each */
    const uint32_t *tri_prim;     /* their indices in their meshes */
    const int32_t *tri_inst;      /* their instance fields */
    const uint32_t *tri_filter;   /* their meshes' filter bits */
    const evr_gpu_inst *inst_src; /* the top level's groups */
    /* work list */
    flat_work *work;
    size_t num_work, cap_work;
    const char *fail; /* why flattening failed */
} flat_ctx;

/* Fills err with "what: detail" (detail may be NULL) and returns st. */
static inline evr_status fail(evr_error *err, evr_status st, const char *what, const char *detail)
{
    if (err)
        snprintf(err->msg, sizeof err->msg, "%s%s%s", what, detail ? ": " : "",
                 detail ? detail : "");
    return st;
}

/* Fills build primitive pr (item id, box lo..hi) and widens the tree's box by it. */
static inline void evr_gpu_prim_set(struct RTCBuildPrimitive *pr, size_t id, const float lo[3],
                                    const float hi[3], float box[6])
{
    pr->lower_x = lo[0];
    pr->lower_y = lo[1];
    pr->lower_z = lo[2];
    pr->upper_x = hi[0];
    pr->upper_y = hi[1];
    pr->upper_z = hi[2];
    pr->geomID = 0;
    pr->primID = (unsigned)id;
    for (int k = 0; k < 3; k++) {
        box[k] = fminf(box[k], lo[k]);
        box[k + 3] = fmaxf(box[k + 3], hi[k]);
    }
}

/* Room for n build primitives, aligned as Embree wants them. */
struct RTCBuildPrimitive *evr_gpu_tree_prims(size_t n);
/* Runs Embree's builder over prims[0..n) (capacity cap) and flattens the result into c. */
evr_status evr_gpu_tree_build(RTCDevice dev, flat_ctx *c, struct RTCBuildPrimitive *prims, size_t n,
                              size_t cap, enum RTCBuildQuality quality, unsigned max_leaf,
                              split_source *split, const float root_box[6], uint32_t *root_index,
                              evr_error *err);
/* The size of a node of the layout. */
static inline size_t evr_gpu_node_size(int layout)
{
    return layout == EVR_GPU_LAYOUT_CW8 ? sizeof(evr_gpu_node8) : sizeof(evr_gpu_node4);
}
/* Room for `nodes` more nodes and `items` more triangles in c's arrays (its counts unchanged);
 * 0: out of memory. */
int evr_gpu_tree_reserve(flat_ctx *c, uint32_t nodes, uint32_t items);
/* Moves the child and item indices of a tree's nodes [0, nn) (evr_gpu_node8 or evr_gpu_node4
 * by layout) by dn and di: where its nodes and items start in the arrays it moves into. */
void evr_gpu_tree_relocate(int layout, void *nodes, uint32_t nn, int64_t dn, int64_t di);
/* gpu_bvh_cache.c. The key of a group's tree: its build's inputs in c (tri9, tri_prim, tri_inst,
 * tri_filter of n triangles, the layout) and settings (spatial splits or not, the largest leaf). */
void evr_gpu_cache_key(const flat_ctx *c, size_t n, int high, unsigned max_leaf, uint8_t key[16]);
/* Appends the tree stored under key to c's nodes and triangles, its root the first node
 * appended: 1 when loaded; 0 when there is none, or it fails its checks (a note; c's counts
 * unchanged). */
int evr_gpu_cache_load(struct evr_gpu_bvh_cache *cache, const uint8_t key[16], flat_ctx *c);
/* Stores the tree in c's nodes [first_node, end) (its root first) and triangles [first_item,
 * end) under key; a failure leaves a note. */
void evr_gpu_cache_store(struct evr_gpu_bvh_cache *cache, const uint8_t key[16], const flat_ctx *c,
                         uint32_t first_node, uint32_t first_item);
/* Worst-case stack entries of the traversal of the tree in nodes [first, end) rooted at first
 * (children always come after their parent); -1 when out of memory. */
int evr_gpu_tree_stack_need(const flat_ctx *c, uint32_t first, uint32_t end);
/* Refits the tree in nodes [0, num_nodes) (root 0, children after their parent, every item in
 * one leaf: no spatial splits) to new item boxes (item_box: lo xyz hi xyz per item): each child
 * box made again bottom up, CW8's quantized again; node_box: room for 6 floats per node (the
 * root's box first). *cost: its surface area heuristic (the nodes' areas and each leaf's area
 * times its items, over the root's area), to tell when a refitted tree has become much worse
 * than a new one. 0: a CW8 node's boxes cannot be quantized (build it again). */
int evr_gpu_tree_refit(int layout, evr_gpu_node4 *n4, evr_gpu_node8 *n8, uint32_t num_nodes,
                       const float *item_box, float *node_box, double *cost);

#endif
