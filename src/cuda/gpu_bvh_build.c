/* Host side of the GPU acceleration structure (see gpu_bvh.h): a tree per group of instances
 * (gpu_bvh_tree.c builds and flattens each; the deforming groups' per segment, gpu_bvh_deform.c)
 * and the top level over the groups. */
#include "cuda/gpu_bvh_internal.h"
#include "cuda/gpu_bvh_cache.h"
#include "backend.h"
#include "prep/instance_groups.h"
#include "prep/swept_bounds.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <embree3/rtcore_builder.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void evr_gpu_bvh_free(evr_gpu_bvh *b)
{
    if (!b) return;
    free(b->group_kind);
    free(b->group_node);
    free(b->group_first);
    free(b->members);
    free(b->instance_group);
    free(b->group_root);
    free(b->group_deform);
    free(b->group_instance_base);
    free(b->group_stack);
    free(b->group_bounds);
    free(b->nodes4);
    free(b->nodes8);
    free(b->tris);
    if (b->device) rtcReleaseDevice((RTCDevice)b->device);
    memset(b, 0, sizeof *b);
}

/* ---- groups sharing a tree ---- */

/* A moving group whose members are consecutive scene instances can share its tree with another
 * such group of the same meshes: its triangles hold instances relative to the first member. */
static int consecutive(const evr_gpu_bvh *b, int g)
{
    int first = b->group_first[g], last = b->group_first[g + 1] - 1;
    return b->group_node[g] >= 0 && b->group_kind[g] != EVR_GROUP_DEFORMING && last >= first &&
           b->members[last] - b->members[first] == last - first;
}

static uint64_t mesh_signature(const evr_scene *s, const evr_gpu_bvh *b, int g)
{
    uint64_t h = 1469598103934665603ull;
    int j;
    for (j = b->group_first[g]; j < b->group_first[g + 1]; j++) {
        h ^= (uint64_t)(uint32_t)s->instances[b->members[j]].mesh;
        h *= 1099511628211ull;
    }
    return h ^ (h >> 29);
}

static int same_meshes(const evr_scene *s, const evr_gpu_bvh *b, int g, int h)
{
    const int *mg = b->members + b->group_first[g], *mh = b->members + b->group_first[h];
    int n = b->group_first[g + 1] - b->group_first[g], j;
    if (b->group_first[h + 1] - b->group_first[h] != n) return 0;
    for (j = 0; j < n; j++)
        if (s->instances[mg[j]].mesh != s->instances[mh[j]].mesh) return 0;
    return 1;
}

static const char *group_name(const evr_scene *s, const evr_gpu_bvh *b, int g)
{
    return b->group_node[g] < 0 ? "the static instances" : s->nodes[b->group_node[g]].name;
}

/* A group's triangles for the builder (buffers reused from group to group). */
typedef struct {
    struct RTCBuildPrimitive *prims; /* room for 2 per triangle (spatial splits) */
    float *tri;                      /* 9 floats per triangle */
    uint32_t *prim;
    int32_t *inst;
    uint32_t *filter;
    size_t cap;
    float *verts; /* a baked mesh's vertices */
    size_t cap_verts;
} group_tris;

static void group_tris_free(group_tris *gt)
{
    free(gt->prims);
    free(gt->tri);
    free(gt->prim);
    free(gt->inst);
    free(gt->filter);
    free(gt->verts);
}

static int group_tris_reserve(group_tris *gt, size_t nt)
{
    if (nt <= gt->cap) return 1;
    free(gt->prims);
    free(gt->tri);
    free(gt->prim);
    free(gt->inst);
    free(gt->filter);
    gt->prims = evr_gpu_tree_prims(2 * nt);
    gt->tri = malloc(sizeof(float) * 9 * nt);
    gt->prim = malloc(sizeof(uint32_t) * nt);
    gt->inst = malloc(sizeof(int32_t) * nt);
    gt->filter = malloc(sizeof(uint32_t) * nt);
    gt->cap = gt->prims && gt->tri && gt->prim && gt->inst && gt->filter ? nt : 0;
    return gt->cap != 0;
}

/* Collects the usable triangles of group g (baked into world space for the static group, as
 * the CPU backend bakes them: each vertex through evr_m34_point in float) and their box.
 * Returns their number, or (size_t)-1 when out of memory. */
static size_t gather_group(const evr_scene *s, const evr_gpu_bvh *b, int g, int32_t base,
                           group_tris *gt, float box[6])
{
    int j, k;
    size_t n = 0;
    for (k = 0; k < 3; k++) {
        box[k] = INFINITY;
        box[k + 3] = -INFINITY;
    }
    for (j = b->group_first[g]; j < b->group_first[g + 1]; j++) {
        int i = b->members[j], bake = b->group_node[g] < 0;
        const evr_mesh *mesh;
        const float *pos;
        uint32_t filter;
        size_t t;
        if (s->instances[i].mesh < 0 || s->instances[i].mesh >= s->num_meshes) continue;
        mesh = &s->meshes[s->instances[i].mesh];
        if (mesh->num_triangles == 0) continue;
        filter = (uint32_t)evr_render_mesh_filter(s, mesh);
        pos = mesh->positions;
        if (bake) {
            evr_m34 world = evr_node_world_at(s, s->instances[i].node, s->anim_start);
            uint32_t v;
            if ((size_t)mesh->num_vertices > gt->cap_verts) {
                float *nv = realloc(gt->verts, sizeof(float) * 3 * (size_t)mesh->num_vertices);
                if (!nv) return (size_t)-1;
                gt->verts = nv;
                gt->cap_verts = mesh->num_vertices;
            }
            for (v = 0; v < mesh->num_vertices; v++) {
                evr_v3 p =
                    evr_m34_point(&world, evr_v3_make(pos[3 * (size_t)v], pos[3 * (size_t)v + 1],
                                                      pos[3 * (size_t)v + 2]));
                gt->verts[3 * (size_t)v] = p.x;
                gt->verts[3 * (size_t)v + 1] = p.y;
                gt->verts[3 * (size_t)v + 2] = p.z;
            }
            pos = gt->verts;
        }
        for (t = 0; t < mesh->num_triangles; t++) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            struct RTCBuildPrimitive *pr = &gt->prims[n];
            int ok = 1, v;
            for (v = 0; v < 3; v++) {
                uint32_t vi = mesh->indices[3 * t + (size_t)v];
                if (vi >= mesh->num_vertices) {
                    ok = 0;
                    break;
                }
                for (k = 0; k < 3; k++) {
                    float x = pos[3 * (size_t)vi + (size_t)k];
                    if (!isfinite(x)) ok = 0;
                    lo[k] = fminf(lo[k], x);
                    hi[k] = fmaxf(hi[k], x);
                }
            }
            if (!ok) continue; /* Embree skips such triangles too */
            for (v = 0; v < 3; v++)
                memcpy(gt->tri + 9 * n + 3 * (size_t)v,
                       pos + 3 * (size_t)mesh->indices[3 * t + (size_t)v], 3 * sizeof(float));
            gt->prim[n] = (uint32_t)t;
            gt->inst[n] = (int32_t)i - base;
            gt->filter[n] = filter;
            evr_gpu_prim_set(pr, n, lo, hi, box);
            n++;
        }
    }
    return n;
}

evr_status evr_gpu_bvh_build(const evr_scene *s, int layout, evr_gpu_bvh_cache *cache,
                             evr_gpu_bvh *out, evr_error *err)
{
    flat_ctx c;
    group_tris gt;
    evr_instance_groups groups;
    evr_status st = EVR_OK;
    RTCDevice dev;
    int n = s->num_instances, g, *table = NULL;
    size_t table_mask = 0;
    memset(out, 0, sizeof *out);
    memset(&c, 0, sizeof c);
    memset(&gt, 0, sizeof gt);
    out->grouped = !(layout & EVR_GPU_BVH_UNGROUPED);
    layout &= ~EVR_GPU_BVH_UNGROUPED;
    if (layout == 0) layout = EVR_GPU_LAYOUT_DEFAULT;
    if (layout != EVR_GPU_LAYOUT_BVH4 && layout != EVR_GPU_LAYOUT_CW8)
        return fail(err, EVR_ERR_ARG, "unknown GPU BVH layout", NULL);
    if (n < 0) return fail(err, EVR_ERR_ARG, "a negative instance count", NULL);
    out->layout = layout;
    out->num_scene_instances = n;
    for (g = 0; g < n && !out->filtered; g++) /* then the kernels' general search */
        if (s->instances[g].mesh >= 0 && s->instances[g].mesh < s->num_meshes)
            out->filtered = evr_render_mesh_filter(s, &s->meshes[s->instances[g].mesh]) != 0;
    if (evr_instance_groups_build(s, out->grouped, &groups)) { /* its arrays are ours from here */
        out->num_groups = groups.num_groups;
        out->static_group = groups.static_group;
        out->static_instanced = groups.static_instanced;
        out->group_kind = groups.group_kind;
        out->group_node = groups.group_node;
        out->group_first = groups.group_first;
        out->members = groups.members;
        out->instance_group = groups.instance_group;
    }
    out->group_root = malloc(sizeof(int32_t) * ((size_t)n + 1));
    out->group_deform = malloc(sizeof(int) * ((size_t)n + 1));
    out->group_instance_base = calloc((size_t)n + 1, sizeof(int32_t));
    out->group_stack = calloc((size_t)n + 1, sizeof(int));
    out->group_bounds = malloc(sizeof(float) * 6 * ((size_t)n + 1));
    if (!out->group_kind || !out->group_node || !out->group_first || !out->members ||
        !out->instance_group || !out->group_root || !out->group_deform ||
        !out->group_instance_base || !out->group_stack || !out->group_bounds) {
        evr_gpu_bvh_free(out);
        return fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
    }
    /* moving groups that may share a tree, by their meshes: an open-addressing table */
    for (table_mask = 1; table_mask < 2 * (size_t)out->num_groups; table_mask *= 2) {}
    table = malloc(sizeof(int) * table_mask);
    if (!table) {
        evr_gpu_bvh_free(out);
        return fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
    }
    memset(table, 0xff, sizeof(int) * table_mask); /* -1: empty */
    table_mask--;
    dev = rtcNewDevice(NULL);
    if (!dev) {
        free(table);
        evr_gpu_bvh_free(out);
        return fail(err, EVR_ERR_BACKEND, "cannot create the Embree device", NULL);
    }
    out->device = dev;
    c.layout = layout;
    for (g = 0; g < out->num_groups && st == EVR_OK; g++) {
        float box[6];
        size_t nt = 0, cnt;
        uint32_t root, first = c.num_nodes;
        int32_t base = 0;
        int j, need;
        split_source split;
        out->group_root[g] = -1;
        out->group_deform[g] = -1;
        if (out->group_kind[g] == EVR_GROUP_DEFORMING) {
            /* its tree is made per segment (evr_gpu_deform_update); its one member is its
             * triangles' instance */
            out->group_deform[g] = out->num_deforming++;
            out->group_instance_base[g] = out->members[out->group_first[g]];
            for (j = 0; j < 6; j++) out->group_bounds[6 * g + j] = j < 3 ? INFINITY : -INFINITY;
            continue;
        }
        if (consecutive(out, g)) {
            size_t h = (size_t)mesh_signature(s, out, g) & table_mask;
            base = out->members[out->group_first[g]];
            out->group_instance_base[g] = base;
            while (table[h] >= 0 && !same_meshes(s, out, g, table[h])) h = (h + 1) & table_mask;
            if (table[h] >= 0) { /* the same meshes as an earlier group: its tree */
                int o = table[h];
                out->group_root[g] = out->group_root[o];
                out->group_stack[g] = out->group_stack[o];
                memcpy(out->group_bounds + 6 * g, out->group_bounds + 6 * o, 6 * sizeof(float));
                continue;
            }
            table[h] = g;
        }
        for (j = 0; j < 6; j++) out->group_bounds[6 * g + j] = j < 3 ? INFINITY : -INFINITY;
        for (j = out->group_first[g]; j < out->group_first[g + 1]; j++) {
            int m = s->instances[out->members[j]].mesh;
            if (m >= 0 && m < s->num_meshes) nt += s->meshes[m].num_triangles;
        }
        if (nt == 0) continue;
        if (nt > 0x3fffffff) {
            st = fail(err, EVR_ERR_ARG,
                      "a group of instances has too many triangles for the GPU BVH",
                      group_name(s, out, g));
            break;
        }
        if (!group_tris_reserve(&gt, nt)) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        cnt = gather_group(s, out, g, base, &gt, box);
        if (cnt == (size_t)-1) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        if (cnt == 0) continue;
        c.tri9 = gt.tri;
        c.tri_prim = gt.prim;
        c.tri_inst = gt.inst;
        c.tri_filter = gt.filter;
        split.tri = gt.tri;
        /* spatial splits (HIGH) for trees up to evr_tree_high_quality's size, as on the CPU */
        const int high = evr_tree_high_quality(cnt);
        const unsigned max_leaf = layout == EVR_GPU_LAYOUT_CW8 ? 3 : 4;
        const int keep = cache && cache->dir && cnt >= cache->min_tris;
        const uint32_t first_item = c.num_items;
        int loaded = 0;
        uint8_t key[16];
        if (keep) {
            evr_gpu_cache_key(&c, cnt, high, max_leaf, key);
            loaded = evr_gpu_cache_load(cache, key, &c);
        }
        if (loaded) {
            root = first;
        } else {
            st = evr_gpu_tree_build(dev, &c, gt.prims, cnt, high ? 2 * cnt : cnt,
                                    high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM,
                                    max_leaf, high ? &split : NULL, box, &root, err);
            if (st != EVR_OK) break;
        }
        out->num_trees++;
        need = evr_gpu_tree_stack_need(&c, first, c.num_nodes);
        if (need < 0) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        if (need >= EVR_GPU_STACK_SIZE) {
            st = fail(err, EVR_ERR_BACKEND, "a group's BVH is too deep for the traversal stack",
                      group_name(s, out, g));
            break;
        }
        if (keep && !loaded) evr_gpu_cache_store(cache, key, &c, first, first_item);
        out->group_root[g] = (int32_t)root;
        out->group_stack[g] = need;
        if (need > out->max_stack) out->max_stack = need;
        memcpy(out->group_bounds + 6 * g, box, sizeof box);
    }
    free(table);
    group_tris_free(&gt);
    free(c.work);
    out->nodes4 = c.n4;
    out->nodes8 = c.n8;
    out->num_nodes = c.num_nodes;
    out->tris = c.tris;
    out->num_tris = c.num_items;
    if (st != EVR_OK) evr_gpu_bvh_free(out);
    return st;
}

/* ---- top level ---- */

void evr_gpu_top_free(evr_gpu_top *top)
{
    if (!top) return;
    free(top->nodes4);
    free(top->nodes8);
    free(top->insts);
    free(top->group_bounds);
    memset(top, 0, sizeof *top);
}

evr_status evr_gpu_top_build(const evr_gpu_bvh *b, const evr_gpu_deform *d,
                             const evr_render_scene *rs, evr_gpu_top *top, evr_error *err)
{
    int ng = b->num_groups, g, k, need, bottom_stack = b->max_stack;
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
    if (rs->num_instances != b->num_scene_instances)
        return fail(err, EVR_ERR_ARG,
                    "the render scene's instances are not those the GPU BVH was built for", NULL);
    if (b->num_deforming && (!d || d->num != b->num_deforming || d->layout != b->layout))
        return fail(err, EVR_ERR_ARG,
                    "internal error: the deforming groups' trees are not those of the GPU BVH",
                    NULL);
    if (d && d->max_stack > bottom_stack) bottom_stack = d->max_stack;
    if (ng > top->cap_groups || !top->group_bounds) {
        float *gb = realloc(top->group_bounds, sizeof(float) * 6 * ((size_t)ng + 1));
        if (!gb) return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
        top->group_bounds = gb;
        top->cap_groups = ng;
    }
    top->num_groups = ng;
    src = malloc(sizeof *src * ((size_t)ng + 1));
    prims = evr_gpu_tree_prims((size_t)ng);
    if (!src || !prims) {
        free(src);
        free(prims);
        return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
    }
    for (g = 0; g < ng; g++) {
        const int dk = b->group_deform[g]; /* a deforming group: its tree in d */
        const float *gb = dk >= 0 ? d->trees[dk].bounds : b->group_bounds + 6 * g;
        const int32_t group_root = dk >= 0 ? d->root[dk] : b->group_root[g];
        float *ib = top->group_bounds + 6 * g, lo[3], hi[3];
        evr_gpu_inst *in = &src[count];
        int ok = 1;
        for (k = 0; k < 3; k++) {
            ib[k] = INFINITY;
            ib[k + 3] = -INFINITY;
        }
        if (group_root < 0) continue;
        memset(in, 0, sizeof *in);
        in->root = dk >= 0 ? -1 - group_root : group_root;
        in->instance_base = b->group_instance_base[g];
        if (b->group_node[g] < 0 && dk < 0) { /* world space (the static group) */
            for (k = 0; k < 3; k++) {
                lo[k] = gb[k];
                hi[k] = gb[k + 3];
            }
            in->track = -1;
            in->moving = 0;
            in->inv = evr_m34_identity();
        } else {
            /* every member is on the group's node: the first one's track is the group's (a
             * skinned mesh's, in world space, is the fixed world frame's: never track -1, which
             * would make it part of the static hits of a still camera) */
            int track = rs->instances[b->members[b->group_first[g]]].track;
            evr_motion_track tr = evr_rs_track(rs, track);
            evr_swept_bounds(gb, gb + 3, tr, lo, hi);
            in->track = track;
            in->moving = tr.n > 1;
            if (!in->moving) {
                evr_m34 xf = evr_motion_eval(tr, 0.0f);
                in->inv = evr_m34_inverse(&xf);
            }
        }
        for (k = 0; k < 3; k++)
            if (!isfinite(lo[k]) || !isfinite(hi[k])) ok = 0;
        if (!ok) continue;
        for (k = 0; k < 3; k++) {
            ib[k] = lo[k];
            ib[k + 3] = hi[k];
            box[k] = fminf(box[k], lo[k]);
            box[k + 3] = fmaxf(box[k + 3], hi[k]);
        }
        prims[count].lower_x = lo[0];
        prims[count].lower_y = lo[1];
        prims[count].lower_z = lo[2];
        prims[count].upper_x = hi[0];
        prims[count].upper_y = hi[1];
        prims[count].upper_z = hi[2];
        prims[count].geomID = 0;
        prims[count].primID = (unsigned)count;
        count++;
    }
    if (count == 0) {
        free(src);
        free(prims);
        return EVR_OK; /* nothing to hit */
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
    /* one group per leaf: entering a group costs far more than a box test (and the CW8 traversal
     * finds a top-level leaf's group through its slot, evr__trace8) */
    st = evr_gpu_tree_build((RTCDevice)b->device, &c, prims, count, count, RTC_BUILD_QUALITY_MEDIUM,
                            1, NULL, box, &root, err);
    free(c.work);
    top->nodes4 = c.n4;
    top->nodes8 = c.n8;
    top->cap_nodes = c.cap_nodes;
    top->insts = c.insts;
    top->cap_insts = c.cap_items;
    free(src);
    free(prims);
    if (st != EVR_OK) return st;
    need = evr_gpu_tree_stack_need(&c, 0, c.num_nodes);
    if (need < 0) return fail(err, EVR_ERR_NOMEM, "out of memory for the top-level BVH", NULL);
    need += bottom_stack;
    if (need >= EVR_GPU_STACK_SIZE)
        return fail(err, EVR_ERR_BACKEND, "the scene's BVH is too deep for the traversal stack",
                    NULL);
    top->num_nodes = c.num_nodes;
    top->num_insts = c.num_items;
    top->stack_need = need;
    return EVR_OK;
}

void evr_gpu_scene_view_host(const evr_gpu_bvh *b, const evr_gpu_deform *d, const evr_gpu_top *top,
                             evr_gpu_scene_view *v)
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
    v->filtered = b->filtered;
    if (d) {
        v->dnodes4 = d->nodes4;
        v->dnodes8 = d->nodes8;
        v->dtris = d->tris;
        v->num_dnodes = d->num_nodes;
        v->num_dtris = d->num_tris;
    }
}
