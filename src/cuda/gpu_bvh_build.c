/* Host side of the GPU acceleration structure (see gpu_bvh.h): Embree's rtcBuildBVH builds a
 * tree of temporary nodes through our callbacks (in memory Embree owns and frees with the
 * RTCBVH), which is then flattened into the layout the traversal reads. */
#include "cuda/gpu_bvh.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <embree3/rtcore_builder.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_WIDTH 8

/* ---- the temporary tree Embree builds ---- */

typedef struct {
    int leaf;                      /* 0 */
    unsigned n;
    void *child[MAX_WIDTH];
    float box[MAX_WIDTH][6];       /* lo xyz, hi xyz */
} build_node;

typedef struct {
    int leaf;                      /* 1 */
    unsigned n;
    uint32_t prim[];
} build_leaf;

/* What the split callback needs: the mesh's triangles, 9 floats each (no index indirection:
 * Embree calls the callback ~100 times per triangle). */
typedef struct {
    const float *tri;
} split_source;

static void *cb_create_node(RTCThreadLocalAllocator alloc, unsigned int n, void *user)
{
    build_node *b = rtcThreadLocalAlloc(alloc, sizeof *b, 16);
    (void)user;
    if (!b) return NULL;
    b->leaf = 0;
    b->n = n;   /* more than MAX_WIDTH is caught when flattening */
    return b;
}

static void cb_set_children(void *node, void **children, unsigned int n, void *user)
{
    build_node *b = node;
    unsigned i;
    (void)user;
    for (i = 0; i < n && i < MAX_WIDTH; i++) b->child[i] = children[i];
}

static void cb_set_bounds(void *node, const struct RTCBounds **bounds, unsigned int n, void *user)
{
    build_node *b = node;
    unsigned i;
    (void)user;
    for (i = 0; i < n && i < MAX_WIDTH; i++) {
        b->box[i][0] = bounds[i]->lower_x;
        b->box[i][1] = bounds[i]->lower_y;
        b->box[i][2] = bounds[i]->lower_z;
        b->box[i][3] = bounds[i]->upper_x;
        b->box[i][4] = bounds[i]->upper_y;
        b->box[i][5] = bounds[i]->upper_z;
    }
}

static void *cb_create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *prims, size_t n, void *user)
{
    build_leaf *l = rtcThreadLocalAlloc(alloc, sizeof *l + n * sizeof(uint32_t), 16);
    size_t i;
    (void)user;
    if (!l) return NULL;
    l->leaf = 1;
    l->n = (unsigned)n;
    for (i = 0; i < n; i++) l->prim[i] = prims[i].primID;   /* geomID may carry Embree's split bits */
    return l;
}

/* Float bounds that hold a double value: lo rounded down, hi rounded up. */
static float round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}
static float round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

/* Spatial split: the boxes of the parts of the triangle on either side of the plane x[dim] =
 * pos, clipped to the reference's current box. Edge crossings are computed in float and the
 * boxes widened by their rounding error (a few ulps), so each box holds its part of the
 * triangle. Embree calls this for every candidate split: it must be cheap. */
static void cb_split(const struct RTCBuildPrimitive *prim, unsigned int dim, float pos, struct RTCBounds *lb,
                     struct RTCBounds *rb, void *user)
{
    const split_source *src = user;
    const float pb[6] = {prim->lower_x, prim->lower_y, prim->lower_z, prim->upper_x, prim->upper_y, prim->upper_z};
    const float *t = src->tri + 9 * (size_t)prim->primID, *v[3];
    float l[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    float r[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    int i, k;
    v[0] = t;
    v[1] = t + 3;
    v[2] = t + 6;
    for (i = 0; i < 3; i++) {
        const float *a = v[i], *b = v[i == 2 ? 0 : i + 1];
        float ad = a[dim], bd = b[dim];
        if (ad <= pos)
            for (k = 0; k < 3; k++) { l[k] = min_f(l[k], a[k]); l[k + 3] = max_f(l[k + 3], a[k]); }
        if (ad >= pos)
            for (k = 0; k < 3; k++) { r[k] = min_f(r[k], a[k]); r[k + 3] = max_f(r[k + 3], a[k]); }
        if ((ad < pos && bd > pos) || (ad > pos && bd < pos)) {
            float f = (pos - ad) / (bd - ad);
            for (k = 0; k < 3; k++) {
                float x = a[k] + f * (b[k] - a[k]);
                /* |error| <= a few ulps of the larger endpoint coordinate */
                float e = 16.0f * FLT_EPSILON * max_f(fabsf(a[k]), fabsf(b[k])) + FLT_MIN;
                float lo = k == (int)dim ? pos : x - e, hi = k == (int)dim ? pos : x + e;
                l[k] = min_f(l[k], lo); l[k + 3] = max_f(l[k + 3], hi);
                r[k] = min_f(r[k], lo); r[k + 3] = max_f(r[k + 3], hi);
            }
        }
    }
    for (k = 0; k < 3; k++) {   /* clip to the reference's box */
        l[k] = max_f(l[k], pb[k]);
        l[k + 3] = min_f(l[k + 3], pb[k + 3]);
        r[k] = max_f(r[k], pb[k]);
        r[k + 3] = min_f(r[k + 3], pb[k + 3]);
    }
    l[dim + 3] = min_f(l[dim + 3], pos);
    r[dim] = max_f(r[dim], pos);
    /* a side the clipped triangle does not reach: the reference's box cut at the plane, which
     * is larger than needed but never wrong */
    if (!(l[0] <= l[3] && l[1] <= l[4] && l[2] <= l[5])) {
        memcpy(l, pb, sizeof l);
        l[dim + 3] = min_f(pos, pb[dim + 3]);
        if (l[dim] > l[dim + 3]) l[dim] = l[dim + 3];
    }
    if (!(r[0] <= r[3] && r[1] <= r[4] && r[2] <= r[5])) {
        memcpy(r, pb, sizeof r);
        r[dim] = max_f(pos, pb[dim]);
        if (r[dim + 3] < r[dim]) r[dim + 3] = r[dim];
    }
    lb->lower_x = l[0]; lb->lower_y = l[1]; lb->lower_z = l[2];
    lb->upper_x = l[3]; lb->upper_y = l[4]; lb->upper_z = l[5];
    rb->lower_x = r[0]; rb->lower_y = r[1]; rb->lower_z = r[2];
    rb->upper_x = r[3]; rb->upper_y = r[4]; rb->upper_z = r[5];
}

/* ---- flattening ---- */

typedef struct {
    const void *ptr;               /* build_node or build_leaf */
    uint32_t index;                /* node it becomes */
} flat_work;

typedef struct {
    int layout;
    int instances;                 /* items are instances (top level), else triangles */
    /* outputs, grown as needed (and kept across top-level builds) */
    evr_gpu_node4 *n4;
    evr_gpu_node8 *n8;
    uint32_t num_nodes, cap_nodes;
    evr_gpu_tri *tris;
    evr_gpu_inst *insts;
    uint32_t num_items, cap_items;
    /* item sources */
    const float *positions;
    const uint32_t *indices;
    const evr_gpu_inst *inst_src;  /* by scene instance index */
    /* work list */
    flat_work *work;
    size_t num_work, cap_work;
    const char *fail;              /* why flattening failed */
} flat_ctx;

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    uint32_t c = *cap ? *cap : 64;
    void *q;
    if (need <= *cap) return 1;
    while (c < need) {
        if (c > UINT32_MAX / 2) return 0;
        c *= 2;
    }
    q = realloc(*p, (size_t)c * elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

static int alloc_nodes(flat_ctx *c, uint32_t n, uint32_t *first)
{
    uint32_t need = c->num_nodes + n;
    if (need < c->num_nodes) return 0;
    if (need > c->cap_nodes) {
        uint32_t cap = c->cap_nodes;
        if (c->layout == EVR_GPU_LAYOUT_CW8) {
            if (!grow((void **)&c->n8, &cap, need, sizeof *c->n8)) return 0;
        } else {
            if (!grow((void **)&c->n4, &cap, need, sizeof *c->n4)) return 0;
        }
        c->cap_nodes = cap;
    }
    *first = c->num_nodes;
    c->num_nodes = need;
    return 1;
}

static int push_work(flat_ctx *c, const void *ptr, uint32_t index)
{
    if (c->num_work == c->cap_work) {
        size_t cap = c->cap_work ? 2 * c->cap_work : 64;
        flat_work *w = realloc(c->work, cap * sizeof *w);
        if (!w) return 0;
        c->work = w;
        c->cap_work = cap;
    }
    c->work[c->num_work].ptr = ptr;
    c->work[c->num_work].index = index;
    c->num_work++;
    return 1;
}

/* Appends a leaf's items; returns the index of the first. */
static int emit_items(flat_ctx *c, const build_leaf *l, uint32_t *first)
{
    uint32_t need = c->num_items + l->n, i;
    if (need < c->num_items) return 0;
    if (need > c->cap_items) {
        uint32_t cap = c->cap_items;
        if (c->instances) {
            if (!grow((void **)&c->insts, &cap, need, sizeof *c->insts)) return 0;
        } else {
            if (!grow((void **)&c->tris, &cap, need, sizeof *c->tris)) return 0;
        }
        c->cap_items = cap;
    }
    *first = c->num_items;
    for (i = 0; i < l->n; i++) {
        uint32_t p = l->prim[i];
        if (c->instances) {
            c->insts[c->num_items + i] = c->inst_src[p];
        } else {
            evr_gpu_tri *t = &c->tris[c->num_items + i];
            const uint32_t *ix = c->indices + 3 * (size_t)p;
            memset(t, 0, sizeof *t);
            memcpy(t->v0, c->positions + 3 * (size_t)ix[0], 3 * sizeof(float));
            memcpy(t->v1, c->positions + 3 * (size_t)ix[1], 3 * sizeof(float));
            memcpy(t->v2, c->positions + 3 * (size_t)ix[2], 3 * sizeof(float));
            t->prim = p;
        }
    }
    c->num_items = need;
    return 1;
}

/* Children of a temporary node (a leaf at the root counts as a node with itself as only child). */
static unsigned node_children(const void *p, const float root_box[6], const void **kid, float box[][6])
{
    const build_node *b = p;
    unsigned i;
    if (b->leaf) {
        kid[0] = p;
        memcpy(box[0], root_box, 6 * sizeof(float));
        return 1;
    }
    for (i = 0; i < b->n && i < MAX_WIDTH; i++) {
        kid[i] = b->child[i];
        memcpy(box[i], b->box[i], 6 * sizeof(float));
    }
    return b->n;
}

static int flatten_node4(flat_ctx *c, const void *p, uint32_t index, const float root_box[6])
{
    const void *kid[MAX_WIDTH];
    float box[MAX_WIDTH][6];
    unsigned n = node_children(p, root_box, kid, box), i;
    evr_gpu_node4 nd;
    if (n > 4) {
        c->fail = "the builder made a node wider than 4";
        return 0;
    }
    for (i = 0; i < 4; i++) {
        nd.lo_x[i] = nd.lo_y[i] = nd.lo_z[i] = INFINITY;
        nd.hi_x[i] = nd.hi_y[i] = nd.hi_z[i] = -INFINITY;
        nd.child[i] = -1;
        nd.count[i] = 0;
    }
    for (i = 0; i < n; i++) {
        const build_leaf *l = kid[i];
        uint32_t at;
        nd.lo_x[i] = box[i][0]; nd.lo_y[i] = box[i][1]; nd.lo_z[i] = box[i][2];
        nd.hi_x[i] = box[i][3]; nd.hi_y[i] = box[i][4]; nd.hi_z[i] = box[i][5];
        if (l->leaf) {
            if (l->n == 0 || l->n > 0x7fffffffu || !emit_items(c, l, &at)) {
                c->fail = "out of memory";
                return 0;
            }
            nd.count[i] = l->n;
        } else {
            if (!alloc_nodes(c, 1, &at) || !push_work(c, kid[i], at)) {
                c->fail = "out of memory";
                return 0;
            }
        }
        if (at > 0x7fffffffu) {
            c->fail = "too many nodes or items";
            return 0;
        }
        nd.child[i] = (int32_t)at;
    }
    c->n4[index] = nd;
    return 1;
}

/* Smallest exponent e (scale 2^e, a normal float) such that p + 255 * 2^e >= hi in float. */
static int quant_exponent(float p, float hi)
{
    double ext = (double)hi - (double)p;
    int e = ext > 0.0 ? (int)ceil(log2(ext / 255.0)) : -126;
    if (e < -126) e = -126;
    if (e > 100) e = 100;
    while (e < 100 && p + 255.0f * ldexpf(1.0f, e) < hi) e++;
    while (e > -126 && p + 255.0f * ldexpf(1.0f, e - 1) >= hi) e--;
    return e;
}

static int quantize_node8(evr_gpu_node8 *nd, float box[][6], const int *slot_kid, const float pbox[6])
{
    int a, s;
    for (a = 0; a < 3; a++) {
        float p = pbox[a];
        int e = quant_exponent(p, pbox[a + 3]);
        float sc = ldexpf(1.0f, e);
        if (!(p + 255.0f * sc >= pbox[a + 3])) return 0;
        nd->p[a] = p;
        nd->e[a] = (uint8_t)(e + 127);
        for (s = 0; s < 8; s++) {
            int k = slot_kid[s], qlo, qhi;
            if (k < 0) {
                nd->qlo[a][s] = 0;
                nd->qhi[a][s] = 0;
                continue;
            }
            /* rounded outwards and checked as the traversal decodes them: p + q * 2^e in float
             * (q * 2^e is exact, so that is one rounding, with or without a fused multiply-add) */
            qlo = (int)floor(((double)box[k][a] - (double)p) / (double)sc);
            qhi = (int)ceil(((double)box[k][a + 3] - (double)p) / (double)sc);
            if (qlo < 0) qlo = 0;
            if (qlo > 255) qlo = 255;
            if (qhi < 0) qhi = 0;
            if (qhi > 255) qhi = 255;
            while (qlo > 0 && p + (float)qlo * sc > box[k][a]) qlo--;
            while (qhi < 255 && p + (float)qhi * sc < box[k][a + 3]) qhi++;
            if (p + (float)qlo * sc > box[k][a] || p + (float)qhi * sc < box[k][a + 3]) return 0;
            nd->qlo[a][s] = (uint8_t)qlo;
            nd->qhi[a][s] = (uint8_t)qhi;
        }
    }
    return 1;
}

static int flatten_node8(flat_ctx *c, const void *p, uint32_t index, const float root_box[6])
{
    static const uint8_t unary[4] = {0, 1, 3, 7};
    const void *kid[MAX_WIDTH];
    float box[MAX_WIDTH][6], pbox[6], cost[MAX_WIDTH][8];
    int slot_kid[8], kid_slot[MAX_WIDTH];
    unsigned n = node_children(p, root_box, kid, box), i, a, inner = 0;
    uint32_t child_base = 0, item_base = c->num_items, next_item_offset = 0;
    int s, k, done;
    evr_gpu_node8 nd;
    if (n > 8) {
        c->fail = "the builder made a node wider than 8";
        return 0;
    }
    memset(&nd, 0, sizeof nd);
    for (a = 0; a < 3; a++) {
        pbox[a] = INFINITY;
        pbox[a + 3] = -INFINITY;
    }
    for (i = 0; i < n; i++)
        for (a = 0; a < 3; a++) {
            pbox[a] = fminf(pbox[a], box[i][a]);
            pbox[a + 3] = fmaxf(pbox[a + 3], box[i][a + 3]);
        }
    /* Slot s gets the child nearest to rays of octant s: the smallest centroid offset along
     * the octant's direction; greedy over the cheapest (child, slot) pairs. */
    for (i = 0; i < n; i++) {
        float d[3];
        for (a = 0; a < 3; a++) d[a] = 0.5f * (box[i][a] + box[i][a + 3]) - 0.5f * (pbox[a] + pbox[a + 3]);
        for (s = 0; s < 8; s++)
            cost[i][s] = ((s & 1) ? -d[0] : d[0]) + ((s & 2) ? -d[1] : d[1]) + ((s & 4) ? -d[2] : d[2]);
        kid_slot[i] = -1;
    }
    for (s = 0; s < 8; s++) slot_kid[s] = -1;
    for (done = 0; done < (int)n; done++) {
        int bi = -1, bs = -1;
        for (i = 0; i < n; i++) {
            if (kid_slot[i] >= 0) continue;
            for (s = 0; s < 8; s++)
                if (slot_kid[s] < 0 && (bi < 0 || cost[i][s] < cost[bi][bs])) {
                    bi = (int)i;
                    bs = s;
                }
        }
        kid_slot[bi] = bs;
        slot_kid[bs] = bi;
    }
    for (i = 0; i < n; i++)
        if (!((const build_leaf *)kid[i])->leaf) inner++;
    if (inner && !alloc_nodes(c, inner, &child_base)) {
        c->fail = "out of memory";
        return 0;
    }
    nd.child_base = child_base;
    nd.item_base = item_base;
    inner = 0;
    for (s = 0; s < 8; s++) {
        const build_leaf *l;
        k = slot_kid[s];
        if (k < 0) continue;
        l = kid[k];
        if (l->leaf) {
            uint32_t at;
            if (l->n == 0 || l->n > 3) {
                c->fail = "the builder made a leaf of more than 3 items";
                return 0;
            }
            if (!emit_items(c, l, &at)) {
                c->fail = "out of memory";
                return 0;
            }
            nd.meta[s] = (uint8_t)((unary[l->n] << 5) | next_item_offset);
            next_item_offset += l->n;
        } else {
            nd.meta[s] = (uint8_t)(0x20 | (24 + s));
            nd.imask |= (uint8_t)(1u << s);
            if (!push_work(c, l, child_base + inner)) {
                c->fail = "out of memory";
                return 0;
            }
            inner++;
        }
    }
    if (!quantize_node8(&nd, box, slot_kid, pbox)) {
        c->fail = "a node's box cannot be quantized (coordinates out of range)";
        return 0;
    }
    c->n8[index] = nd;
    return 1;
}

/* Flattens the tree under root (whose box is root_box); returns the root's node index. */
static int flatten(flat_ctx *c, const void *root, const float root_box[6], uint32_t *root_index)
{
    uint32_t at;
    c->num_work = 0;
    if (!alloc_nodes(c, 1, &at) || !push_work(c, root, at)) {
        c->fail = "out of memory";
        return 0;
    }
    *root_index = at;
    while (c->num_work) {
        flat_work w = c->work[--c->num_work];
        int ok = c->layout == EVR_GPU_LAYOUT_CW8 ? flatten_node8(c, w.ptr, w.index, root_box)
                                                 : flatten_node4(c, w.ptr, w.index, root_box);
        if (!ok) return 0;
    }
    return 1;
}

/* Worst-case stack entries of the traversal of the tree in nodes [first, end) rooted at first
 * (children always come after their parent). BVH4 pushes every inner child hit but the
 * nearest; CW8 pushes a node's remaining hits as one entry. */
static int stack_need(const flat_ctx *c, uint32_t first, uint32_t end)
{
    uint32_t n = end - first, i;
    int *need = calloc(n ? n : 1, sizeof(int)), r;
    if (!need) return -1;
    for (i = n; i-- > 0;) {
        int best = 0, k = 0, j, m = 0;
        if (c->layout == EVR_GPU_LAYOUT_CW8) {
            const evr_gpu_node8 *nd = &c->n8[first + i];
            for (j = 0; j < 8; j++)
                if (nd->imask & (1u << j)) {
                    int v = need[nd->child_base + (uint32_t)k - first];
                    if (v > best) best = v;
                    k++;
                }
            m = k >= 2 ? 1 : 0;
        } else {
            const evr_gpu_node4 *nd = &c->n4[first + i];
            for (j = 0; j < 4; j++)
                if (nd->child[j] >= 0 && nd->count[j] == 0) {
                    int v = need[(uint32_t)nd->child[j] - first];
                    if (v > best) best = v;
                    k++;
                }
            m = k >= 1 ? k - 1 : 0;
        }
        need[i] = k ? best + m : 0;
    }
    r = need[0];
    free(need);
    return r;
}

static evr_status fail(evr_error *err, evr_status st, const char *what, const char *detail)
{
    if (err) snprintf(err->msg, sizeof err->msg, "%s%s%s", what, detail ? ": " : "", detail ? detail : "");
    return st;
}

static struct RTCBuildPrimitive *alloc_prims(size_t n)
{
    size_t bytes = (n ? n : 1) * sizeof(struct RTCBuildPrimitive);
    bytes = (bytes + 31) & ~(size_t)31;
    return aligned_alloc(32, bytes);
}

/* Runs Embree's builder over prims[0..n) (capacity cap) and flattens the result. */
static evr_status build_tree(RTCDevice dev, flat_ctx *c, struct RTCBuildPrimitive *prims, size_t n, size_t cap,
                             enum RTCBuildQuality quality, unsigned max_leaf, split_source *split,
                             const float root_box[6], uint32_t *root_index, evr_error *err)
{
    struct RTCBuildArguments args = rtcDefaultBuildArguments();
    RTCBVH bvh = rtcNewBVH(dev);
    void *root;
    evr_status st = EVR_OK;
    if (!bvh) return fail(err, EVR_ERR_BACKEND, "Embree cannot create a BVH", NULL);
    args.byteSize = sizeof args;
    args.buildQuality = quality;
    args.maxBranchingFactor = c->layout == EVR_GPU_LAYOUT_CW8 ? 8 : 4;
    args.maxDepth = 48;
    args.minLeafSize = 1;
    args.maxLeafSize = max_leaf;
    args.traversalCost = 1.0f;
    args.intersectionCost = 1.0f;
    args.bvh = bvh;
    args.primitives = prims;
    args.primitiveCount = n;
    args.primitiveArrayCapacity = cap;
    args.createNode = cb_create_node;
    args.setNodeChildren = cb_set_children;
    args.setNodeBounds = cb_set_bounds;
    args.createLeaf = cb_create_leaf;
    args.splitPrimitive = split ? cb_split : NULL;
    args.userPtr = split;
    root = rtcBuildBVH(&args);
    if (!root || rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        st = fail(err, EVR_ERR_BACKEND, "Embree's BVH builder failed", NULL);
    } else if (!flatten(c, root, root_box, root_index)) {
        st = fail(err, strcmp(c->fail, "out of memory") == 0 ? EVR_ERR_NOMEM : EVR_ERR_BACKEND,
                  "cannot flatten the BVH", c->fail);
    }
    rtcReleaseBVH(bvh);
    return st;
}

void evr_gpu_bvh_free(evr_gpu_bvh *b)
{
    if (!b) return;
    free(b->mesh_root);
    free(b->mesh_stack);
    free(b->mesh_bounds);
    free(b->nodes4);
    free(b->nodes8);
    free(b->tris);
    if (b->device) rtcReleaseDevice((RTCDevice)b->device);
    memset(b, 0, sizeof *b);
}

evr_status evr_gpu_bvh_build(const evr_scene *s, int layout, evr_gpu_bvh *out, evr_error *err)
{
    flat_ctx c;
    evr_status st = EVR_OK;
    RTCDevice dev;
    int m;
    memset(out, 0, sizeof *out);
    memset(&c, 0, sizeof c);
    if (layout == 0) layout = EVR_GPU_LAYOUT_DEFAULT;
    if (layout != EVR_GPU_LAYOUT_BVH4 && layout != EVR_GPU_LAYOUT_CW8)
        return fail(err, EVR_ERR_ARG, "unknown GPU BVH layout", NULL);
    out->layout = layout;
    out->num_meshes = s->num_meshes;
    out->mesh_root = malloc(sizeof(int32_t) * ((size_t)s->num_meshes + 1));
    out->mesh_stack = calloc((size_t)s->num_meshes + 1, sizeof(int));
    out->mesh_bounds = malloc(sizeof(float) * 6 * ((size_t)s->num_meshes + 1));
    if (!out->mesh_root || !out->mesh_stack || !out->mesh_bounds) {
        evr_gpu_bvh_free(out);
        return fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
    }
    dev = rtcNewDevice(NULL);
    if (!dev) {
        evr_gpu_bvh_free(out);
        return fail(err, EVR_ERR_BACKEND, "cannot create the Embree device", NULL);
    }
    out->device = dev;
    c.layout = layout;
    for (m = 0; m < s->num_meshes && st == EVR_OK; m++) {
        const evr_mesh *mesh = &s->meshes[m];
        size_t nt = mesh->num_triangles, n = 0, t;
        float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        struct RTCBuildPrimitive *prims;
        float *tri;
        split_source split;
        uint32_t root, first = c.num_nodes;
        int k, need;
        out->mesh_root[m] = -1;
        memcpy(out->mesh_bounds + 6 * m, box, sizeof box);
        if (nt == 0) continue;
        if (nt > 0x3fffffff) {
            st = fail(err, EVR_ERR_ARG, "a mesh has too many triangles for the GPU BVH", mesh->name);
            break;
        }
        prims = alloc_prims(2 * nt);   /* room for spatial splits */
        tri = malloc(sizeof(float) * 9 * nt);
        if (!prims || !tri) {
            free(prims);
            free(tri);
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        for (t = 0; t < nt; t++) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            int ok = 1, v;
            for (v = 0; v < 3; v++) {
                uint32_t vi = mesh->indices[3 * t + (size_t)v];
                if (vi >= mesh->num_vertices) { ok = 0; break; }
                for (k = 0; k < 3; k++) {
                    float x = mesh->positions[3 * (size_t)vi + (size_t)k];
                    if (!isfinite(x)) ok = 0;
                    lo[k] = fminf(lo[k], x);
                    hi[k] = fmaxf(hi[k], x);
                }
            }
            if (!ok) continue;   /* Embree skips such triangles too */
            for (v = 0; v < 3; v++)
                memcpy(tri + 9 * t + 3 * (size_t)v, mesh->positions + 3 * (size_t)mesh->indices[3 * t + (size_t)v],
                       3 * sizeof(float));
            prims[n].lower_x = lo[0]; prims[n].lower_y = lo[1]; prims[n].lower_z = lo[2];
            prims[n].upper_x = hi[0]; prims[n].upper_y = hi[1]; prims[n].upper_z = hi[2];
            prims[n].geomID = 0;
            prims[n].primID = (unsigned)t;
            for (k = 0; k < 3; k++) {
                box[k] = fminf(box[k], lo[k]);
                box[k + 3] = fmaxf(box[k + 3], hi[k]);
            }
            n++;
        }
        if (n == 0) {
            free(prims);
            free(tri);
            continue;
        }
        c.positions = mesh->positions;
        c.indices = mesh->indices;
        split.tri = tri;
        st = build_tree(dev, &c, prims, n, 2 * n, RTC_BUILD_QUALITY_HIGH, layout == EVR_GPU_LAYOUT_CW8 ? 3 : 4,
                        &split, box, &root, err);
        free(prims);
        free(tri);
        if (st != EVR_OK) break;
        need = stack_need(&c, first, c.num_nodes);
        if (need < 0) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        if (need >= EVR_GPU_STACK_SIZE) {
            st = fail(err, EVR_ERR_BACKEND, "a mesh's BVH is too deep for the traversal stack", mesh->name);
            break;
        }
        out->mesh_root[m] = (int32_t)root;
        out->mesh_stack[m] = need;
        if (need > out->max_stack) out->max_stack = need;
        memcpy(out->mesh_bounds + 6 * m, box, sizeof box);
    }
    free(c.work);
    out->nodes4 = c.n4;
    out->nodes8 = c.n8;
    out->num_nodes = c.num_nodes;
    out->tris = c.tris;
    out->num_tris = c.num_items;
    if (st != EVR_OK) evr_gpu_bvh_free(out);
    return st;
}

/* ---- motion bounds ---- */

static void extend_corners(const evr_m34 *m, const float lo[3], const float hi[3], double blo[3], double bhi[3])
{
    int c, k;
    for (c = 0; c < 8; c++) {
        evr_v3 p = evr_v3_make((c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]);
        evr_v3 q = evr_m34_point(m, p);
        double x[3] = {q.x, q.y, q.z};
        for (k = 0; k < 3; k++) {
            if (x[k] < blo[k]) blo[k] = x[k];
            if (x[k] > bhi[k]) bhi[k] = x[k];
        }
    }
}

/* |U p| for the upper-triangular part of a key. */
static double upper_apply_len(const evr_motion_key *k, const double p[3], int diff, const evr_motion_key *b)
{
    double s0 = k->scale[0], s1 = k->scale[1], s2 = k->scale[2];
    double k0 = k->skew[0], k1 = k->skew[1], k2 = k->skew[2];
    double x, y, z;
    if (diff) {
        s0 = b->scale[0] - s0; s1 = b->scale[1] - s1; s2 = b->scale[2] - s2;
        k0 = b->skew[0] - k0; k1 = b->skew[1] - k1; k2 = b->skew[2] - k2;
    }
    x = s0 * p[0] + k0 * p[1] + k1 * p[2];
    y = s1 * p[1] + k2 * p[2];
    z = s2 * p[2];
    return sqrt(x * x + y * y + z * z);
}

void evr_gpu_segment_bounds(const float lo[3], const float hi[3], evr_motion_track tr, float out_lo[3],
                            float out_hi[3])
{
    double blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double mag = 0.0;
    int i, j, k;
    if (tr.n <= 1) {
        evr_m34 m = evr_motion_key_matrix(&tr.keys[0]);
        extend_corners(&m, lo, hi, blo, bhi);
    }
    for (i = 0; i + 1 < tr.n; i++) {
        /* x(s) = T(s) + Q(s) c, Q = R U, for s in [0, 1] and c in the box. Between two samples
         * s0 < s1: T is linear, so T(s) lies in the box of T(s0), T(s1); Q(s) c lies within
         * L h / 2 (h = s1 - s0) of Q(s0) c or Q(s1) c, L a bound on its speed:
         * |d(Q c)/ds| <= w max|U(s) c| + |dU c|, w the rotation's angular speed (slerp:
         * constant, the angle between the keys; normalized lerp for close keys: at most 1.0003
         * times that); |U(s) c| is convex in s and c, so its maximum is at an end key and a
         * corner of the box. Each step's box is the sum of the two; the result their union.
         * Translation needs no samples: the samples follow the rotation and scaling only. */
        evr_motion_key a = tr.keys[i], b = tr.keys[i + 1];
        double plo[3], phi[3], pt[3];   /* previous sample: Q box and T */
        double d = fabs((double)evr_quat_dot(a.rot, b.rot));
        double qa = sqrt((double)evr_quat_dot(a.rot, a.rot)), qb = sqrt((double)evr_quat_dot(b.rot, b.rot));
        double w, umax = 0.0, dumax = 0.0, L, margin;
        evr_v3 ta = a.trans, tb = b.trans;
        int steps, c;
        d = qa > 0.0 && qb > 0.0 ? d / (qa * qb) : 1.0;
        w = 2.0 * acos(d > 1.0 ? 1.0 : d) * 1.01 + 1e-6;
        for (c = 0; c < 8; c++) {
            double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
            umax = fmax(umax, fmax(upper_apply_len(&a, p, 0, NULL), upper_apply_len(&b, p, 0, NULL)));
            dumax = fmax(dumax, upper_apply_len(&a, p, 1, &b));
        }
        L = w * umax + dumax;
        /* samples close enough that the widening is 1% of the object's size */
        steps = (int)ceil(L / (2e-2 * (umax > 0.0 ? umax : 1.0)));
        if (steps < 1) steps = 1;
        if (steps > 64) steps = 64;
        margin = L / (2.0 * steps);
        a.trans = b.trans = evr_v3_make(0.0f, 0.0f, 0.0f);
        for (j = 0; j <= steps; j++) {
            float f = (float)j / (float)steps;
            evr_motion_key key = evr_motion_key_lerp(&a, &b, f);
            evr_m34 m = evr_motion_key_matrix(&key);
            evr_v3 t = evr_v3_lerp(ta, tb, f);
            double qlo[3] = {INFINITY, INFINITY, INFINITY}, qhi[3] = {-INFINITY, -INFINITY, -INFINITY};
            double tt[3] = {t.x, t.y, t.z};
            extend_corners(&m, lo, hi, qlo, qhi);
            if (j > 0)
                for (k = 0; k < 3; k++) {
                    blo[k] = fmin(blo[k], fmin(pt[k], tt[k]) + fmin(plo[k], qlo[k]) - margin);
                    bhi[k] = fmax(bhi[k], fmax(pt[k], tt[k]) + fmax(phi[k], qhi[k]) + margin);
                }
            for (k = 0; k < 3; k++) {
                plo[k] = qlo[k];
                phi[k] = qhi[k];
                pt[k] = tt[k];
            }
        }
    }
    for (k = 0; k < 3; k++) mag = fmax(mag, fmax(fabs(blo[k]), fabs(bhi[k])));
    for (k = 0; k < 3; k++) {
        /* float evaluation of the transforms (in the traversal and here) is off by a few ulps */
        double slack = 1e-6 * mag + 1e-30;
        out_lo[k] = round_down(blo[k] - slack);
        out_hi[k] = round_up(bhi[k] + slack);
    }
}

/* ---- top level ---- */

void evr_gpu_top_free(evr_gpu_top *top)
{
    if (!top) return;
    free(top->nodes4);
    free(top->nodes8);
    free(top->insts);
    free(top->inst_bounds);
    memset(top, 0, sizeof *top);
}

evr_status evr_gpu_top_build(const evr_gpu_bvh *b, const evr_render_scene *rs, evr_gpu_top *top, evr_error *err)
{
    int n = rs->num_instances, i, k, need;
    size_t count = 0;
    evr_gpu_inst *src = NULL;
    struct RTCBuildPrimitive *prims = NULL;
    float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    flat_ctx c;
    evr_status st = EVR_OK;
    uint32_t root;

    if (top->layout && top->layout != b->layout) evr_gpu_top_free(top);
    top->layout = b->layout;
    top->num_nodes = 0;
    top->num_insts = 0;
    top->stack_need = 0;
    if (n > top->num_scene_instances || !top->inst_bounds) {
        float *ib = realloc(top->inst_bounds, sizeof(float) * 6 * ((size_t)n + 1));
        if (!ib) return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
        top->inst_bounds = ib;
    }
    top->num_scene_instances = n;
    src = malloc(sizeof *src * ((size_t)n + 1));
    prims = alloc_prims((size_t)n);
    if (!src || !prims) {
        free(src);
        free(prims);
        return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
    }
    for (i = 0; i < n; i++) {
        const evr_instance_view *iv = &rs->instances[i];
        float *ib = top->inst_bounds + 6 * i, lo[3], hi[3];
        evr_motion_track tr;
        int ok = 1;
        for (k = 0; k < 3; k++) {
            ib[k] = INFINITY;
            ib[k + 3] = -INFINITY;
        }
        if (iv->mesh < 0 || iv->mesh >= b->num_meshes || b->mesh_root[iv->mesh] < 0) continue;
        tr = evr_rs_track(rs, iv->track);
        evr_gpu_segment_bounds(b->mesh_bounds + 6 * iv->mesh, b->mesh_bounds + 6 * iv->mesh + 3, tr, lo, hi);
        for (k = 0; k < 3; k++)
            if (!isfinite(lo[k]) || !isfinite(hi[k])) ok = 0;
        if (!ok) continue;
        for (k = 0; k < 3; k++) {
            ib[k] = lo[k];
            ib[k + 3] = hi[k];
            box[k] = fminf(box[k], lo[k]);
            box[k + 3] = fmaxf(box[k + 3], hi[k]);
        }
        memset(&src[i], 0, sizeof src[i]);
        src[i].root = b->mesh_root[iv->mesh];
        src[i].track = iv->track;
        src[i].instance = i;
        src[i].moving = tr.n > 1;
        if (!src[i].moving) {
            evr_m34 xf = evr_motion_eval(tr, 0.0f);
            src[i].inv = evr_m34_inverse(&xf);
        }
        prims[count].lower_x = lo[0]; prims[count].lower_y = lo[1]; prims[count].lower_z = lo[2];
        prims[count].upper_x = hi[0]; prims[count].upper_y = hi[1]; prims[count].upper_z = hi[2];
        prims[count].geomID = 0;
        prims[count].primID = (unsigned)i;
        count++;
    }
    if (count == 0) {
        free(src);
        free(prims);
        return EVR_OK;   /* nothing to hit */
    }
    memset(&c, 0, sizeof c);
    c.layout = b->layout;
    c.instances = 1;
    c.inst_src = src;
    c.n4 = top->nodes4;
    c.n8 = top->nodes8;
    c.cap_nodes = top->cap_nodes;
    c.insts = top->insts;
    c.cap_items = top->cap_insts;
    /* one instance per leaf: entering an instance costs far more than a box test */
    st = build_tree((RTCDevice)b->device, &c, prims, count, count, RTC_BUILD_QUALITY_MEDIUM, 1, NULL, box, &root,
                    err);
    free(c.work);
    top->nodes4 = c.n4;
    top->nodes8 = c.n8;
    top->cap_nodes = c.cap_nodes;
    top->insts = c.insts;
    top->cap_insts = c.cap_items;
    free(src);
    free(prims);
    if (st != EVR_OK) return st;
    need = stack_need(&c, 0, c.num_nodes);
    if (need < 0) return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
    need += b->max_stack;
    if (need >= EVR_GPU_STACK_SIZE)
        return fail(err, EVR_ERR_BACKEND, "the scene's BVH is too deep for the traversal stack", NULL);
    top->num_nodes = c.num_nodes;
    top->num_insts = c.num_items;
    top->stack_need = need;
    return EVR_OK;
}

void evr_gpu_scene_view_host(const evr_gpu_bvh *b, const evr_gpu_top *top, evr_gpu_scene_view *v)
{
    memset(v, 0, sizeof *v);
    v->layout = b->layout;
    v->nodes4 = b->nodes4;
    v->nodes8 = b->nodes8;
    v->tris = b->tris;
    v->num_nodes = b->num_nodes;
    v->num_tris = b->num_tris;
    v->top4 = top->nodes4;
    v->top8 = top->nodes8;
    v->insts = top->insts;
    v->num_top_nodes = top->num_nodes;
    v->num_insts = top->num_insts;
}
