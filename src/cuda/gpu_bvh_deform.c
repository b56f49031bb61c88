/* The deforming groups' trees of the GPU acceleration structure (see gpu_bvh.h): for a segment,
 * each deforming group whose vertices moved gets its tree over boxes that hold each triangle at
 * every vertex key of the segment (the interpolation between two keys stays in their union), and
 * every tree is packed into one node array and one triangle array for the traversal. A group
 * whose vertices hold still keeps its tree as it is, bit for bit.
 *
 * Refitted, and built again when refitting has made it much worse: a tree is built (Embree's
 * binned SAH through gpu_bvh_tree.c; no spatial splits, a triangle's clipped parts would not
 * move with it) when its group first needs one, and after that its boxes are made again from
 * the segment's keys on the same topology, unless its surface area cost has grown past
 * REBUILD_COST times its cost when built (a skin that folds puts the forearm's triangles in
 * boxes that span the upper arm's). Measured on a 2-core host (a 45,000-triangle sheet that
 * bends, CW8 / BVH4): a build took 27 / 24 ms, a refit 4 / 2.5 ms; a build in every segment
 * would keep the GPU waiting for the host, which renders a segment of the eye in under 2 ms.
 * tests/test_gpu_bvh.c prints its scenes' times. */
#include "cuda/gpu_bvh_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A refitted tree whose cost grew past this factor of its cost when built is built again. */
#define REBUILD_COST 1.5

/* The builder's inputs, reused from group to group and segment to segment. */
typedef struct {
    struct RTCBuildPrimitive *prims;
    uint32_t *vidx; /* 3 per triangle */
    uint32_t *prim;
    size_t cap;
    float *vbox; /* per vertex: its box over the keys, lo xyz hi xyz (empty where not finite) */
    size_t cap_vbox;
    float *item_box, *node_box; /* a refit's: per triangle of the tree, per node */
    size_t cap_item_box, cap_node_box;
} deform_scratch;

static void tree_free(evr_gpu_dtree *t)
{
    free(t->nodes4);
    free(t->nodes8);
    free(t->tris);
    memset(t, 0, sizeof *t);
}

void evr_gpu_deform_free(evr_gpu_deform *d)
{
    int k;
    if (!d) return;
    for (k = 0; d->trees && k < d->num; k++) tree_free(&d->trees[k]);
    free(d->trees);
    free(d->nodes4);
    free(d->nodes8);
    free(d->tris);
    free(d->root);
    if (d->scratch) {
        deform_scratch *sc = d->scratch;
        free(sc->prims);
        free(sc->vidx);
        free(sc->prim);
        free(sc->vbox);
        free(sc->item_box);
        free(sc->node_box);
        free(sc);
    }
    memset(d, 0, sizeof *d);
}

/* Room for 6 floats per entry, n entries. */
static int boxes_reserve(float **p, size_t *cap, size_t n)
{
    if (n <= *cap) return 1;
    free(*p);
    *p = malloc(sizeof(float) * 6 * n);
    *cap = *p ? n : 0;
    return *p != NULL;
}

static int scratch_reserve(deform_scratch *sc, size_t n, size_t nv)
{
    if (nv > sc->cap_vbox) {
        free(sc->vbox);
        sc->vbox = malloc(sizeof(float) * 6 * nv);
        sc->cap_vbox = sc->vbox ? nv : 0;
        if (!sc->vbox) return 0;
    }
    if (n <= sc->cap) return 1;
    free(sc->prims);
    free(sc->vidx);
    free(sc->prim);
    sc->prims = evr_gpu_tree_prims(n);
    sc->vidx = malloc(sizeof(uint32_t) * 3 * n);
    sc->prim = malloc(sizeof(uint32_t) * n);
    sc->cap = sc->prims && sc->vidx && sc->prim ? n : 0;
    return sc->cap != 0;
}

/* Each vertex's box over the keys, lo xyz hi xyz (key by key: each key's array is read in
 * order). A vertex with a coordinate that is not finite at some key gets an empty box (lo > hi). */
static void vertex_boxes(const evr_deform_view *v, float *vbox)
{
    const size_t per = 3 * (size_t)v->num_vertices;
    size_t i;
    int k, a;
    for (i = 0; i < v->num_vertices; i++)
        for (a = 0; a < 3; a++)
            vbox[6 * i + (size_t)a] = vbox[6 * i + 3 + (size_t)a] = v->positions[3 * i + (size_t)a];
    for (k = 1; k < v->num_keys; k++) {
        const float *p = v->positions + (size_t)k * per;
        for (i = 0; i < v->num_vertices; i++)
            for (a = 0; a < 3; a++) {
                const float x = p[3 * i + (size_t)a];
                float *b = vbox + 6 * i;
                if (x < b[a]) b[a] = x;
                if (x > b[a + 3]) b[a + 3] = x;
                if (x != x) b[a] = x; /* a NaN stays: no comparison moves it */
            }
    }
    for (i = 0; i < v->num_vertices; i++)
        for (a = 0; a < 3; a++)
            if (!isfinite(vbox[6 * i + (size_t)a]) || !isfinite(vbox[6 * i + 3 + (size_t)a])) {
                vbox[6 * i + (size_t)a] = INFINITY;
                vbox[6 * i + 3 + (size_t)a] = -INFINITY;
            }
}

/* Builds t over the triangles of scene instance inst with the segment's vertex keys, whose
 * vertex boxes sc->vbox holds: each triangle's box holds its vertices at every key. Triangles with
 * a vertex index out of range or a coordinate that is not finite at some key are left out (as
 * Embree leaves them out). */
static evr_status build_tree(RTCDevice dev, int layout, const evr_render_scene *rs, int inst,
                             deform_scratch *sc, evr_gpu_dtree *t, evr_error *err)
{
    const evr_instance_view *iv = &rs->instances[inst];
    const evr_mesh_view *m = &rs->meshes[iv->mesh];
    const evr_deform_view *v = &rs->deforms[iv->deform];
    float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    size_t n = 0, tri;
    flat_ctx c;
    uint32_t root = 0;
    evr_status st;
    int a, need;
    t->num_nodes = t->num_tris = 0;
    t->stack = 0;
    memcpy(t->bounds, box, sizeof box);
    t->built = 1;
    if (!scratch_reserve(sc, m->num_triangles, v->num_vertices))
        return fail(err, EVR_ERR_NOMEM, "out of memory for a deforming mesh's BVH", NULL);
    for (tri = 0; tri < m->num_triangles; tri++) {
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        struct RTCBuildPrimitive *pr = &sc->prims[n];
        int ok = 1, corner;
        for (corner = 0; corner < 3 && ok; corner++) {
            const uint32_t vi = m->indices[3 * tri + (size_t)corner];
            if (vi >= v->num_vertices) {
                ok = 0;
                break;
            }
            sc->vidx[3 * n + (size_t)corner] = vi;
            for (a = 0; a < 3; a++) {
                const float *b = sc->vbox + 6 * (size_t)vi;
                if (!(b[a] <= b[a + 3])) ok = 0;
                lo[a] = fminf(lo[a], b[a]);
                hi[a] = fmaxf(hi[a], b[a + 3]);
            }
        }
        if (!ok) continue;
        sc->prim[n] = (uint32_t)tri;
        evr_gpu_prim_set(pr, n, lo, hi, box);
        n++;
    }
    if (n == 0) return EVR_OK; /* nothing to hit */
    memset(&c, 0, sizeof c);
    c.layout = layout;
    c.deforming = 1;
    c.n4 = t->nodes4;
    c.n8 = t->nodes8;
    c.cap_nodes = t->cap_nodes;
    c.dtris = t->tris;
    c.cap_items = t->cap_tris;
    c.tri_vidx = sc->vidx;
    c.tri_prim = sc->prim;
    st = evr_gpu_tree_build(dev, &c, sc->prims, n, n, RTC_BUILD_QUALITY_MEDIUM,
                            layout == EVR_GPU_LAYOUT_CW8 ? 3 : 4, NULL, box, &root, err);
    free(c.work);
    t->nodes4 = c.n4;
    t->nodes8 = c.n8;
    t->cap_nodes = c.cap_nodes;
    t->tris = c.dtris;
    t->cap_tris = c.cap_items;
    t->num_nodes = c.num_nodes;
    t->num_tris = c.num_items;
    if (st != EVR_OK) return st;
    if (root != 0)
        return fail(err, EVR_ERR_BACKEND, "internal error: a tree's root is not its first node",
                    NULL);
    need = evr_gpu_tree_stack_need(&c, 0, c.num_nodes);
    if (need < 0) return fail(err, EVR_ERR_NOMEM, "out of memory for a deforming mesh's BVH", NULL);
    if (need >= EVR_GPU_STACK_SIZE)
        return fail(err, EVR_ERR_BACKEND,
                    "a deforming mesh's BVH is too deep for the traversal stack", NULL);
    t->stack = need;
    memcpy(t->bounds, box, sizeof box);
    t->built_cost = 0.0;
    return EVR_OK;
}

/* Refits t (a tree with triangles) to the segment's vertex boxes sc->vbox. 1: done; 0: it needs
 * a new build (a triangle is no longer finite, a box cannot be quantized, or the cost grew past
 * REBUILD_COST times the built tree's); -1: out of memory. The first refit after a build only
 * measures the built tree's cost (its boxes are the builder's, the same). */
static int refit_tree(int layout, deform_scratch *sc, evr_gpu_dtree *t)
{
    uint32_t i;
    double cost;
    int a, k;
    if (!boxes_reserve(&sc->item_box, &sc->cap_item_box, t->num_tris) ||
        !boxes_reserve(&sc->node_box, &sc->cap_node_box, t->num_nodes))
        return -1;
    for (i = 0; i < t->num_tris; i++) {
        float *ib = sc->item_box + 6 * (size_t)i;
        for (a = 0; a < 3; a++) {
            ib[a] = INFINITY;
            ib[a + 3] = -INFINITY;
        }
        for (k = 0; k < 3; k++) {
            const float *vb = sc->vbox + 6 * (size_t)t->tris[i].v[k];
            for (a = 0; a < 3; a++) {
                if (!(vb[a] <= vb[a + 3])) return 0;
                ib[a] = fminf(ib[a], vb[a]);
                ib[a + 3] = fmaxf(ib[a + 3], vb[a + 3]);
            }
        }
    }
    if (!evr_gpu_tree_refit(layout, t->nodes4, t->nodes8, t->num_nodes, sc->item_box, sc->node_box,
                            &cost))
        return 0;
    if (t->built_cost <= 0.0) t->built_cost = cost;
    if (cost > REBUILD_COST * t->built_cost) return 0;
    t->cost = cost;
    memcpy(t->bounds, sc->node_box, sizeof t->bounds);
    return 1;
}

static int grow_to(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    void *q;
    if (need <= *cap) return 1;
    q = realloc(*p, (size_t)need * elem);
    if (!q) return 0;
    *p = q;
    *cap = need;
    return 1;
}

/* Every tree into the packed arrays, its nodes' child and item indices moved by where its nodes
 * and triangles start there. 0: out of memory or too many. */
static int pack(evr_gpu_deform *d)
{
    uint32_t nn = 0, nt = 0;
    int k;
    for (k = 0; k < d->num; k++) {
        const evr_gpu_dtree *t = &d->trees[k];
        if (t->num_nodes > 0x7fffffffu - nn || t->num_tris > 0x7fffffffu - nt) return 0;
        nn += t->num_nodes;
        nt += t->num_tris;
    }
    if (d->layout == EVR_GPU_LAYOUT_CW8) {
        if (!grow_to((void **)&d->nodes8, &d->cap_nodes, nn, sizeof *d->nodes8)) return 0;
    } else {
        if (!grow_to((void **)&d->nodes4, &d->cap_nodes, nn, sizeof *d->nodes4)) return 0;
    }
    if (!grow_to((void **)&d->tris, &d->cap_tris, nt, sizeof *d->tris)) return 0;
    d->max_stack = 0;
    for (k = 0, nn = 0, nt = 0; k < d->num; k++) {
        const evr_gpu_dtree *t = &d->trees[k];
        d->root[k] = t->num_nodes ? (int32_t)nn : -1;
        if (t->num_nodes) {
            void *to = d->layout == EVR_GPU_LAYOUT_CW8 ? (void *)(d->nodes8 + nn)
                                                       : (void *)(d->nodes4 + nn);
            memcpy(to,
                   d->layout == EVR_GPU_LAYOUT_CW8 ? (const void *)t->nodes8
                                                   : (const void *)t->nodes4,
                   evr_gpu_node_size(d->layout) * t->num_nodes);
            evr_gpu_tree_relocate(d->layout, to, t->num_nodes, nn, nt);
        }
        if (t->num_tris) memcpy(d->tris + nt, t->tris, sizeof *t->tris * t->num_tris);
        nn += t->num_nodes;
        nt += t->num_tris;
        if (t->stack > d->max_stack) d->max_stack = t->stack;
    }
    d->num_nodes = nn;
    d->num_tris = nt;
    return 1;
}

evr_status evr_gpu_deform_update(const evr_gpu_bvh *b, const evr_render_scene *rs, const int *moved,
                                 evr_gpu_deform *d, evr_error *err)
{
    int g;
    evr_status st = EVR_OK;
    if (d->num != b->num_deforming || d->layout != b->layout || !d->scratch) {
        evr_gpu_deform_free(d);
        d->layout = b->layout;
        d->num = b->num_deforming;
        d->trees = calloc((size_t)d->num + 1, sizeof *d->trees);
        d->root = malloc(sizeof *d->root * ((size_t)d->num + 1));
        d->scratch = calloc(1, sizeof(deform_scratch));
        if (!d->trees || !d->root || !d->scratch) {
            evr_gpu_deform_free(d);
            return fail(err, EVR_ERR_NOMEM, "out of memory for the deforming meshes' BVHs", NULL);
        }
    }
    d->rebuilt = d->refitted = 0;
    for (g = 0; g < b->num_groups && st == EVR_OK; g++) {
        const int k = b->group_deform[g], inst = b->members[b->group_first[g]];
        deform_scratch *sc = d->scratch;
        evr_gpu_dtree *t = &d->trees[k];
        const evr_deform_view *v;
        int di, r = 0;
        if (k < 0) continue;
        di = rs->instances[inst].deform;
        if (di < 0 || di >= rs->num_deforms || !rs->deforms) {
            st = fail(err, EVR_ERR_ARG,
                      "internal error: a deforming instance without the segment's vertex keys",
                      NULL);
            break;
        }
        if (t->built && moved && !moved[di]) continue; /* still: the same tree */
        v = &rs->deforms[di];
        if (!scratch_reserve(sc, 0, v->num_vertices)) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for a deforming mesh's BVH", NULL);
            break;
        }
        vertex_boxes(v, sc->vbox);
        if (t->built && t->num_tris) r = refit_tree(b->layout, sc, t);
        if (r == 1) {
            d->refitted++;
            continue;
        }
        if (r == 0) {
            st = build_tree((RTCDevice)b->device, b->layout, rs, inst, sc, t, err);
            d->rebuilt++;
            if (st == EVR_OK && t->num_tris) r = refit_tree(b->layout, sc, t); /* its cost */
        }
        if (r < 0) st = fail(err, EVR_ERR_NOMEM, "out of memory for a deforming mesh's BVH", NULL);
    }
    if (st == EVR_OK && (d->rebuilt || d->refitted || d->gen == 0)) {
        if (!pack(d))
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the deforming meshes' BVHs", NULL);
        d->gen++;
    }
    if (st != EVR_OK) evr_gpu_deform_free(d);
    return st;
}
