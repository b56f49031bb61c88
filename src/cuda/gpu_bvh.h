/* Our own ray-tracing acceleration structure, for the CUDA backend (and for host tests that
 * check it against Embree where there is no GPU).
 *
 * Two levels over the groups of instances that both backends use (prep/instance_groups.h: the
 * never-moving instances baked into world space, or past the bake limit each in its node's
 * space with one tree per mesh; the instances of each moving node in that node's object space;
 * each deforming instance on its own).
 *   bottom  one BVH per group, built once per run by Embree's rtcBuildBVH (SAH with spatial
 *           splits, RTC_BUILD_QUALITY_HIGH; a binned SAH, MEDIUM, past evr_tree_high_quality's
 *           size) and flattened into wide nodes; every group's nodes and triangles live in one
 *           node array and one triangle array. Moving groups whose members are consecutive
 *           scene instances with the same sequence of meshes (many instances of one mesh, each
 *           on its own node) share one BVH.
 *   deforming  a deforming group's vertices change from segment to segment (evr_deform_view:
 *           vertex keys over the segment): its BVH is made for a segment (evr_gpu_deform: built
 *           once, then refitted, built again when refits have made it much worse), over boxes
 *           that hold each triangle at every key (the interpolation between two keys stays
 *           inside their union), so a ray at any time of the segment finds it; its
 *           triangles (evr_gpu_dtri) carry vertex indices, and the traversal interpolates the
 *           vertices at the ray's time (evr_deform_lerp_in, as shading does). Made again only
 *           when the vertices moved: while they hold still the tree stays the same bits, so the
 *           same rays meet the same triangles in the same order (change-driven sampling). The
 *           trees of all deforming groups are packed into arrays of their own, one copy per
 *           segment in flight on the device. A scene without deforming meshes is searched by the
 *           code that searched it before them (gpu_traverse.h).
 *   top     one BVH over the groups, rebuilt on the host for every segment (Embree's binned
 *           SAH, one group per leaf); a moving group's box encloses its object-space box moved
 *           by its track's motion keys over the WHOLE segment (a proven bound, not samples
 *           only), so a ray at any time inside the segment finds every group it can hit; a
 *           deforming group's object-space box is that of its vertex keys. The
 *           traversal searches a node's groups in a fixed order, set at the build: smallest box
 *           first, so that their hits shorten the ray before the large groups around them.
 * Each triangle carries its scene instance (relative to its group's first member in a BVH that
 * groups share) and its index in that instance's mesh, so a hit reports the instance and
 * triangle as Embree does.
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
 * ready for the watertight test, plus instance and triangle index; leaves of <= 3 for CW8,
 * <= 4 for BVH4) at the bottom, group records (one per leaf) at the top. Quantized boxes
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
/* Or'ed into a traversal's layout (the CUDA backend's kernels' LAYOUT): the general search, for
 * a scene with deforming groups or with meshes whose hits a material may rule out
 * (core/hit_filter.h: alpha MASK, single-sided). gpu_traverse.h: a search without either is
 * the code it was before them; one general kind for both keeps the kernels' instantiations (and
 * the compile time) as they were. */
#define EVR_GPU_TRACE_GENERAL 0x10
/* Or'ed into evr_gpu_bvh_build's layout: no grouping, every instance a group of its own in its
 * node's object space (the trees of one mesh shared), as before grouping; for comparisons. */
#define EVR_GPU_BVH_UNGROUPED 0x100

/* Entries of the traversal stack (one array per ray, shared by both levels). Builds check that
 * every tree fits: the top level's worst case plus the deepest group's worst case. */
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

/* A triangle in leaf order, in its group's space, 48 bytes: vertices (as the mesh gives them,
 * or baked into world space for the static group; the watertight test needs the vertices
 * themselves, not edges), the triangle's index in its mesh, its scene instance (plus the
 * group's evr_gpu_inst.instance_base) and its mesh's filter bits (evr_mesh_view.filter, read
 * only by the general search). With spatial splits one triangle may appear in several leaves. */
typedef struct {
    EVR_ALIGN16 float v0[3];
    uint32_t prim; /* triangle index in the instance's mesh */
    float v1[3];
    int32_t instance; /* scene instance, minus the group's instance_base */
    float v2[3];
    uint32_t filter; /* EVR_FILTER_* of its mesh (core/hit_filter.h), 0: none */
} evr_gpu_tri;

/* A deforming group's triangle in leaf order, 16 bytes: its vertices' indices into the group's
 * evr_deform_view (interpolated at the ray's time) and its index in the mesh; its instance is the
 * group's one member (evr_gpu_inst.instance_base). */
typedef struct {
    EVR_ALIGN16 uint32_t v[3];
    uint32_t prim;
} evr_gpu_dtri;

/* A group in the top level's leaf order, 64 bytes. */
typedef struct {
    EVR_ALIGN16 evr_m34 inv; /* world to group space; valid when moving == 0 */
    int32_t root;            /* root node of the group's bottom-level BVH; a deforming group's:
                                -1 - its root in the deforming trees (dnodes) */
    int32_t track;           /* motion track (evr_render_scene), -1 in world space (static) */
    int32_t instance_base;   /* added to a triangle's instance: the scene instance index */
    int32_t moving;          /* 1: the transform changes in the segment, evaluate per ray */
} evr_gpu_inst;

/* What the traversal reads; all pointers host or all device. */
typedef struct {
    int layout;   /* EVR_GPU_LAYOUT_* */
    int filtered; /* some mesh's hits may be ruled out (evr_gpu_bvh.filtered); in the padding
                     after layout: the kernels' arguments keep their size and offsets */
    const evr_gpu_node4 *nodes4; /* bottom level, layout BVH4 (else NULL) */
    const evr_gpu_node8 *nodes8; /* bottom level, layout CW8 (else NULL) */
    const evr_gpu_tri *tris;
    const evr_gpu_node4 *top4; /* top level, root at 0 */
    const evr_gpu_node8 *top8;
    const evr_gpu_inst *insts;
    uint32_t num_nodes, num_tris, num_top_nodes, num_insts; /* num_top_nodes 0: nothing to hit */
    /* the deforming groups' trees of the segment (evr_gpu_deform's packed arrays; num_dtris 0:
     * no deforming group to search) */
    const evr_gpu_node4 *dnodes4;
    const evr_gpu_node8 *dnodes8;
    const evr_gpu_dtri *dtris;
    uint32_t num_dnodes, num_dtris;
} evr_gpu_scene_view;

/* ---- host side ---- */

/* Bottom level of every group of a scene (the groups of prep/instance_groups.h, in their order). */
typedef struct {
    int layout;
    int grouped; /* 0: built with EVR_GPU_BVH_UNGROUPED */
    int num_groups;
    int num_scene_instances;
    /* the grouping (evr_instance_groups: its arrays, owned here) */
    int static_group;     /* index of the baked static group, -1: none */
    int static_instanced; /* 1: the static instances were past the bake limit: each is a group
                                  of its own in its node's space, the trees shared by mesh */
    int *group_kind;      /* per group: EVR_GROUP_* (prep/instance_groups.h) */
    int *group_node;      /* per group: the node whose object space it is in and whose track
                                  moves it, -1: world space (the static group, a skinned mesh) */
    int *group_first;     /* per group + 1: its members are members[group_first[g] ..
                                  group_first[g + 1]), scene instance indices, ascending */
    int *members;
    int *instance_group; /* per scene instance: its group */
    int32_t *group_root; /* per group: root node, -1 for a group without usable triangles (and
                                  for a deforming group: its tree is evr_gpu_deform's) */
    int *group_deform;   /* per group: its index among the deforming groups, -1: none */
    int num_deforming;   /* deforming groups */
    int filtered;        /* some instance's mesh has filter bits (evr_mesh_view.filter): the
                            general search */
    int32_t *group_instance_base; /* per group: evr_gpu_inst.instance_base */
    int *group_stack;             /* per group: stack entries its traversal needs at most */
    float *group_bounds;          /* per group: box of its triangles in its space, lo xyz hi xyz */
    int num_trees;                /* bottom-level BVHs built (groups that share one count once) */
    int max_stack;                /* largest of group_stack */
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes;
    evr_gpu_tri *tris;
    uint32_t num_tris; /* triangle references (>= the meshes' triangles with splits) */
    void *device;      /* the Embree device (RTCDevice) its builds use */
} evr_gpu_bvh;

/* One deforming group's tree (node and item indices from 0, its root at node 0). */
typedef struct {
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_dtri *tris;
    uint32_t num_tris, cap_tris;
    int stack;         /* traversal stack it needs */
    float bounds[6];   /* box of its triangles at every key of the segment it was built for, in
                        its group's space, lo xyz hi xyz */
    int built;         /* 0: not yet built */
    double built_cost; /* its surface area cost when built (relative to the root's area) */
    double cost;       /* and now, refitted to the segment's keys */
} evr_gpu_dtree;

/* The deforming groups' trees for the current segment (host). Zero it before the first update;
 * updates reuse its memory. */
typedef struct {
    int layout;
    int num;              /* deforming groups (evr_gpu_bvh.num_deforming) */
    evr_gpu_dtree *trees; /* per deforming group */
    /* every tree packed, node and item indices relocated: what evr_gpu_scene_view's dnodes4,
     * dnodes8 and dtris hold */
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_dtri *tris;
    uint32_t num_tris, cap_tris;
    int32_t *root;          /* per deforming group: its root in the packed nodes, -1: nothing */
    int max_stack;          /* largest of the trees' stacks */
    int rebuilt, refitted;  /* trees the last update built, and refitted */
    unsigned long long gen; /* counts the updates that changed the packed arrays */
    void *scratch;          /* the builder's inputs (private) */
} evr_gpu_deform;

/* Top level of one segment. Zero it before the first build; later builds reuse its memory. */
typedef struct {
    int layout;
    evr_gpu_node4 *nodes4;
    evr_gpu_node8 *nodes8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_inst *insts; /* one per group with triangles, in leaf order */
    uint32_t num_insts, cap_insts;
    float *group_bounds; /* per group: world box over the segment, lo xyz hi xyz (empty,
                                  lo > hi, for a group left out) */
    int num_groups, cap_groups;
    int stack_need; /* top level's worst case plus the deepest group's */
} evr_gpu_top;

/* Groups the instances of s (evr_instance_groups_build) and builds the bottom level of every
 * group with the given layout (0: EVR_GPU_LAYOUT_DEFAULT; EVR_GPU_BVH_UNGROUPED or'ed in: no
 * grouping). Reads the meshes, the instances and the nodes (parent, animated, transforms at
 * anim_start). cache (NULL: none): trees kept across runs (gpu_bvh_cache.h), loaded where it
 * has them, written where it has not; its counts and note say what happened. On failure *out
 * is left empty (safe to free). */
struct evr_gpu_bvh_cache; /* gpu_bvh_cache.h */
evr_status evr_gpu_bvh_build(const evr_scene *s, int layout, struct evr_gpu_bvh_cache *cache,
                             evr_gpu_bvh *out, evr_error *err);
void evr_gpu_bvh_free(evr_gpu_bvh *b);

/* Makes the deforming groups' trees for the segment whose vertex keys rs->deforms holds (host
 * views, rs->num_deforms of them; rs->meshes and rs->instances for the triangles): a group whose
 * vertices moved (moved[k] of its deform view k, evr_segment.deform_moved; NULL: all moved) gets
 * its tree refitted to each triangle's box at every key, or built (Embree's binned SAH) where it
 * has none yet or a refit made it much worse; the others keep theirs, bit for bit. Segments in
 * order. On failure d is left empty. */
evr_status evr_gpu_deform_update(const evr_gpu_bvh *b, const evr_render_scene *rs, const int *moved,
                                 evr_gpu_deform *d, evr_error *err);
void evr_gpu_deform_free(evr_gpu_deform *d);

/* Builds the top level for the segment whose motion keys rs holds (rs->num_instances, equal to
 * the scene's; rs->instances[i].track, the same for every member of a moving group; rs->keys,
 * rs->track_offset, rs->track_count) and whose deforming groups' trees d holds (updated for
 * this segment; NULL where b has no deforming groups). */
evr_status evr_gpu_top_build(const evr_gpu_bvh *b, const evr_gpu_deform *d,
                             const evr_render_scene *rs, evr_gpu_top *top, evr_error *err);
void evr_gpu_top_free(evr_gpu_top *top);

/* A view of host arrays, for host traversal (d: NULL where b has no deforming groups). */
void evr_gpu_scene_view_host(const evr_gpu_bvh *b, const evr_gpu_deform *d, const evr_gpu_top *top,
                             evr_gpu_scene_view *v);

#ifdef __cplusplus
}
#endif
#endif
