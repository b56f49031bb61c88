/* Embree's rtcBuildBVH run through our callbacks (a tree of temporary nodes in memory Embree
 * owns and frees with the RTCBVH), then flattened into the node layout the traversal reads
 * (gpu_bvh.h: BVH4 or compressed CW8), with the traversal stack each tree needs; and a flattened
 * tree refitted to new item boxes (the deforming meshes'). */
#include "cuda/gpu_bvh_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_WIDTH 8

/* ---- the temporary tree Embree builds ---- */

typedef struct {
    int leaf; /* 0 */
    unsigned n;
    void *child[MAX_WIDTH];
    float box[MAX_WIDTH][6]; /* lo xyz, hi xyz */
} build_node;

typedef struct {
    int leaf; /* 1 */
    unsigned n;
    uint32_t prim[];
} build_leaf;

static void *cb_create_node(RTCThreadLocalAllocator alloc, unsigned int n, void *user)
{
    build_node *b = rtcThreadLocalAlloc(alloc, sizeof *b, 16);
    (void)user;
    if (!b) return NULL;
    b->leaf = 0;
    b->n = n; /* more than MAX_WIDTH is caught when flattening */
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

static void *cb_create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *prims,
                            size_t n, void *user)
{
    build_leaf *l = rtcThreadLocalAlloc(alloc, sizeof *l + n * sizeof(uint32_t), 16);
    size_t i;
    (void)user;
    if (!l) return NULL;
    l->leaf = 1;
    l->n = (unsigned)n;
    for (i = 0; i < n; i++) l->prim[i] = prims[i].primID; /* geomID may carry Embree's split bits */
    return l;
}

static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

/* Spatial split: the boxes of the parts of the triangle on either side of the plane x[dim] =
 * pos, clipped to the reference's current box. Edge crossings are computed in float and the
 * boxes widened by their rounding error (a few ulps), so each box holds its part of the
 * triangle. Embree calls this for every candidate split: it must be cheap. */
static void cb_split(const struct RTCBuildPrimitive *prim, unsigned int dim, float pos,
                     struct RTCBounds *lb, struct RTCBounds *rb, void *user)
{
    const split_source *src = user;
    const float pb[6] = {prim->lower_x, prim->lower_y, prim->lower_z,
                         prim->upper_x, prim->upper_y, prim->upper_z};
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
            for (k = 0; k < 3; k++) {
                l[k] = min_f(l[k], a[k]);
                l[k + 3] = max_f(l[k + 3], a[k]);
            }
        if (ad >= pos)
            for (k = 0; k < 3; k++) {
                r[k] = min_f(r[k], a[k]);
                r[k + 3] = max_f(r[k + 3], a[k]);
            }
        if ((ad < pos && bd > pos) || (ad > pos && bd < pos)) {
            float f = (pos - ad) / (bd - ad);
            for (k = 0; k < 3; k++) {
                float x = a[k] + f * (b[k] - a[k]);
                /* |error| <= a few ulps of the larger endpoint coordinate */
                float e = 16.0f * FLT_EPSILON * max_f(fabsf(a[k]), fabsf(b[k])) + FLT_MIN;
                float lo = k == (int)dim ? pos : x - e, hi = k == (int)dim ? pos : x + e;
                l[k] = min_f(l[k], lo);
                l[k + 3] = max_f(l[k + 3], hi);
                r[k] = min_f(r[k], lo);
                r[k + 3] = max_f(r[k + 3], hi);
            }
        }
    }
    for (k = 0; k < 3; k++) { /* clip to the reference's box */
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
    lb->lower_x = l[0];
    lb->lower_y = l[1];
    lb->lower_z = l[2];
    lb->upper_x = l[3];
    lb->upper_y = l[4];
    lb->upper_z = l[5];
    rb->lower_x = r[0];
    rb->lower_y = r[1];
    rb->lower_z = r[2];
    rb->upper_x = r[3];
    rb->upper_y = r[4];
    rb->upper_z = r[5];
}

/* ---- flattening ---- */

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

int evr_gpu_tree_reserve(flat_ctx *c, uint32_t nodes, uint32_t items)
{
    uint32_t first, cap = c->cap_items;
    if (!alloc_nodes(c, nodes, &first)) return 0;
    c->num_nodes = first; /* room only */
    if (items > UINT32_MAX - c->num_items) return 0;
    if (!grow((void **)&c->tris, &cap, c->num_items + items, sizeof *c->tris)) return 0;
    c->cap_items = cap;
    return 1;
}

void evr_gpu_tree_relocate(int layout, void *nodes, uint32_t nn, int64_t dn, int64_t di)
{
    for (uint32_t i = 0; i < nn; i++) {
        if (layout == EVR_GPU_LAYOUT_CW8) {
            evr_gpu_node8 *nd = (evr_gpu_node8 *)nodes + i;
            nd->child_base = (uint32_t)(nd->child_base + dn);
            nd->item_base = (uint32_t)(nd->item_base + di);
        } else {
            evr_gpu_node4 *nd = (evr_gpu_node4 *)nodes + i;
            for (int j = 0; j < 4; j++)
                if (nd->child[j] >= 0)
                    nd->child[j] = (int32_t)(nd->child[j] + (nd->count[j] ? di : dn));
        }
    }
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
        } else if (c->deforming) {
            if (!grow((void **)&c->dtris, &cap, need, sizeof *c->dtris)) return 0;
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
        } else if (c->deforming) {
            evr_gpu_dtri *t = &c->dtris[c->num_items + i];
            memcpy(t->v, c->tri_vidx + 3 * (size_t)p, sizeof t->v);
            t->prim = c->tri_prim[p];
        } else {
            evr_gpu_tri *t = &c->tris[c->num_items + i];
            const float *v = c->tri9 + 9 * (size_t)p;
            memset(t, 0, sizeof *t);
            memcpy(t->v0, v, 3 * sizeof(float));
            memcpy(t->v1, v + 3, 3 * sizeof(float));
            memcpy(t->v2, v + 6, 3 * sizeof(float));
            t->prim = c->tri_prim[p];
            t->instance = c->tri_inst[p];
            t->filter = c->tri_filter[p];
        }
    }
    c->num_items = need;
    return 1;
}

/* Children of a temporary node (a leaf at the root counts as a node with itself as only child). */
static unsigned node_children(const void *p, const float root_box[6], const void **kid,
                              float box[][6])
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

static float half_area(const float b[6])
{
    float x = b[3] - b[0], y = b[4] - b[1], z = b[5] - b[2];
    return x * y + y * z + z * x;
}

/* Top level: the traversal searches a node's groups in the order of their slots (BVH4) or
 * from the last item to the first (CW8), before descending. A group searched early meets the
 * whole ray; one searched late only what is left of it. Small groups first: the large ones
 * (the static group encloses the scene) then find the ray shortened by the small ones' hits.
 * Returns the kids' indices by increasing box area. */
static void order_by_area(unsigned n, float box[][6], unsigned *order)
{
    unsigned i, j;
    for (i = 0; i < n; i++) {
        unsigned k = i;
        float a = half_area(box[i]);
        for (j = i; j > 0 && half_area(box[order[j - 1]]) > a; j--) order[j] = order[j - 1];
        order[j] = k;
    }
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
    if (c->instances) { /* slots by increasing area (inner children are sorted by distance anyway) */
        const void *k2[MAX_WIDTH];
        float b2[MAX_WIDTH][6];
        unsigned order[MAX_WIDTH];
        order_by_area(n, box, order);
        for (i = 0; i < n; i++) {
            k2[i] = kid[order[i]];
            memcpy(b2[i], box[order[i]], sizeof b2[i]);
        }
        memcpy(kid, k2, sizeof(kid[0]) * n);
        memcpy(box, b2, sizeof(box[0]) * n);
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
        nd.lo_x[i] = box[i][0];
        nd.lo_y[i] = box[i][1];
        nd.lo_z[i] = box[i][2];
        nd.hi_x[i] = box[i][3];
        nd.hi_y[i] = box[i][4];
        nd.hi_z[i] = box[i][5];
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

static int quantize_node8(evr_gpu_node8 *nd, float box[][6], const int *slot_kid,
                          const float pbox[6])
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
    int slot_kid[8], kid_slot[MAX_WIDTH], leaf_order[MAX_WIDTH];
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
        for (a = 0; a < 3; a++)
            d[a] = 0.5f * (box[i][a] + box[i][a + 3]) - 0.5f * (pbox[a] + pbox[a + 3]);
        for (s = 0; s < 8; s++)
            cost[i][s] =
                ((s & 1) ? -d[0] : d[0]) + ((s & 2) ? -d[1] : d[1]) + ((s & 4) ? -d[2] : d[2]);
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
    /* leaves in slot order, at the top level by decreasing area (the traversal takes the last
     * item first: the smallest group) */
    if (c->instances) {
        unsigned order[MAX_WIDTH];
        order_by_area(n, box, order);
        for (i = 0; i < n; i++) leaf_order[i] = (int)order[n - 1 - i];
    } else {
        for (i = 0, s = 0; s < 8; s++)
            if (slot_kid[s] >= 0) leaf_order[i++] = slot_kid[s];
    }
    for (i = 0; i < n; i++) { /* leaves */
        const build_leaf *l = kid[leaf_order[i]];
        uint32_t at;
        if (!l->leaf) continue;
        if (l->n == 0 || l->n > 3) {
            c->fail = "the builder made a leaf of more than 3 items";
            return 0;
        }
        if (!emit_items(c, l, &at)) {
            c->fail = "out of memory";
            return 0;
        }
        nd.meta[kid_slot[leaf_order[i]]] = (uint8_t)((unary[l->n] << 5) | next_item_offset);
        next_item_offset += l->n;
    }
    for (s = 0; s < 8; s++) { /* inner children */
        const build_leaf *l;
        k = slot_kid[s];
        if (k < 0) continue;
        l = kid[k];
        if (l->leaf) continue;
        nd.meta[s] = (uint8_t)(0x20 | (24 + s));
        nd.imask |= (uint8_t)(1u << s);
        if (!push_work(c, l, child_base + inner)) {
            c->fail = "out of memory";
            return 0;
        }
        inner++;
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
int evr_gpu_tree_stack_need(const flat_ctx *c, uint32_t first, uint32_t end)
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

/* ---- refitting ---- */

static void box_empty(float b[6])
{
    b[0] = b[1] = b[2] = INFINITY;
    b[3] = b[4] = b[5] = -INFINITY;
}

static void box_add(float b[6], const float *o)
{
    int a;
    for (a = 0; a < 3; a++) {
        b[a] = min_f(b[a], o[a]);
        b[a + 3] = max_f(b[a + 3], o[a + 3]);
    }
}

/* The box of items [first, first + n) and their share of the cost (n times its area). */
static void leaf_box(const float *item_box, uint32_t first, uint32_t n, float b[6], double *cost)
{
    uint32_t i;
    box_empty(b);
    for (i = 0; i < n; i++) box_add(b, item_box + 6 * (size_t)(first + i));
    *cost += (double)n * half_area(b);
}

int evr_gpu_tree_refit(int layout, evr_gpu_node4 *n4, evr_gpu_node8 *n8, uint32_t num_nodes,
                       const float *item_box, float *node_box, double *cost)
{
    uint32_t i;
    double sum = 0.0;
    int s, k;
    for (i = num_nodes; i-- > 0;) { /* children come after their parent */
        float *nb = node_box + 6 * (size_t)i;
        box_empty(nb);
        if (layout == EVR_GPU_LAYOUT_CW8) {
            evr_gpu_node8 *nd = &n8[i];
            float box[8][6];
            int slot_kid[8];
            for (s = 0; s < 8; s++) {
                const unsigned m = nd->meta[s];
                slot_kid[s] = -1;
                if (!m) continue;
                if ((m & 31u) >= 24u) { /* an inner child: after the inner ones of lower slots */
                    const uint32_t c =
                        nd->child_base + (uint32_t)__builtin_popcount(nd->imask & ((1u << s) - 1u));
                    memcpy(box[s], node_box + 6 * (size_t)c, sizeof box[s]);
                } else { /* a leaf: (0x1, 0x3, 0x7 for 1, 2, 3 items) << 5 | offset */
                    leaf_box(item_box, nd->item_base + (m & 31u),
                             (uint32_t)__builtin_popcount(m >> 5), box[s], &sum);
                }
                slot_kid[s] = s;
                box_add(nb, box[s]);
            }
            if (!quantize_node8(nd, box, slot_kid, nb)) return 0;
        } else {
            evr_gpu_node4 *nd = &n4[i];
            for (k = 0; k < 4; k++) {
                float b[6];
                if (nd->child[k] < 0) continue;
                if (nd->count[k]) leaf_box(item_box, (uint32_t)nd->child[k], nd->count[k], b, &sum);
                else memcpy(b, node_box + 6 * (size_t)nd->child[k], sizeof b);
                nd->lo_x[k] = b[0];
                nd->lo_y[k] = b[1];
                nd->lo_z[k] = b[2];
                nd->hi_x[k] = b[3];
                nd->hi_y[k] = b[4];
                nd->hi_z[k] = b[5];
                box_add(nb, b);
            }
        }
        sum += half_area(nb);
    }
    *cost = num_nodes && half_area(node_box) > 0.0f ? sum / (double)half_area(node_box) : 0.0;
    return 1;
}

struct RTCBuildPrimitive *evr_gpu_tree_prims(size_t n)
{
    size_t bytes = (n ? n : 1) * sizeof(struct RTCBuildPrimitive);
    bytes = (bytes + 31) & ~(size_t)31;
    return aligned_alloc(32, bytes);
}

/* Runs Embree's builder over prims[0..n) (capacity cap) and flattens the result. */
evr_status evr_gpu_tree_build(RTCDevice dev, flat_ctx *c, struct RTCBuildPrimitive *prims, size_t n,
                              size_t cap, enum RTCBuildQuality quality, unsigned max_leaf,
                              split_source *split, const float root_box[6], uint32_t *root_index,
                              evr_error *err)
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
