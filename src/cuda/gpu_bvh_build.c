/* Host side of the GPU acceleration structure (see gpu_bvh.h): a tree per group of instances
 * (gpu_bvh_tree.c builds and flattens each) and the top level over the groups. */
#include "cuda/gpu_bvh_internal.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <embree3/rtcore_builder.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

float evr_round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}
float evr_round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

void evr_gpu_bvh_free(evr_gpu_bvh *b)
{
    if (!b) return;
    free(b->group_node);
    free(b->group_first);
    free(b->members);
    free(b->instance_group);
    free(b->group_root);
    free(b->group_instance_base);
    free(b->group_stack);
    free(b->group_bounds);
    free(b->nodes4);
    free(b->nodes8);
    free(b->tris);
    if (b->device) rtcReleaseDevice((RTCDevice)b->device);
    memset(b, 0, sizeof *b);
}

/* ---- grouping, as cpu_backend.c's build_groups ---- */

static int node_never_moves(const evr_scene *s, int node)
{
    int guard = 0;
    for (; node >= 0 && node < s->num_nodes && guard++ <= s->num_nodes; node = s->nodes[node].parent)
        if (s->nodes[node].animated) return 0;
    return 1;
}

#define EVR_STATIC_BAKE_LIMIT_DEFAULT 1000000ull
unsigned long long evr_static_bake_limit(void)
{
    const char *v = getenv("EVR_STATIC_BAKE_LIMIT");
    char *end;
    unsigned long long x;
    if (!v || !*v) return EVR_STATIC_BAKE_LIMIT_DEFAULT;
    x = strtoull(v, &end, 10);
    return *end ? EVR_STATIC_BAKE_LIMIT_DEFAULT : x;
}

/* Assigns every instance its group (numbered by first member) and lists the members. */
static int make_groups(const evr_scene *s, evr_gpu_bvh *out, int grouped)
{
    int n = s->num_instances, i, g;
    int *node_group = malloc(sizeof(int) * ((size_t)s->num_nodes + 1)), *at;
    unsigned long long static_tris = 0;
    if (!node_group) return 0;
    for (i = 0; i < s->num_nodes; i++) node_group[i] = -1;
    for (i = 0; i < n; i++) {
        int m = s->instances[i].mesh;
        if (m >= 0 && m < s->num_meshes && node_never_moves(s, s->instances[i].node))
            static_tris += s->meshes[m].num_triangles;
    }
    out->static_instanced = grouped && static_tris > evr_static_bake_limit();
    out->static_group = -1;
    out->num_groups = 0;
    for (i = 0; i < n; i++) {
        int node = s->instances[i].node, moving = !node_never_moves(s, node);
        int *grp = moving ? &node_group[node] : &out->static_group;
        if (!grouped || (!moving && out->static_instanced)) {
            /* a group of its own, in its node's space (none: the world) */
            out->instance_group[i] = out->num_groups;
            out->group_node[out->num_groups++] = node >= 0 && node < s->num_nodes ? node : -1;
            continue;
        }
        if (*grp < 0) {
            *grp = out->num_groups;
            out->group_node[out->num_groups++] = moving ? node : -1;
        }
        out->instance_group[i] = *grp;
    }
    free(node_group);
    /* members by group, ascending */
    for (i = 0; i < n; i++) out->group_first[out->instance_group[i] + 1]++;
    for (g = 0; g < out->num_groups; g++) out->group_first[g + 1] += out->group_first[g];
    at = malloc(sizeof(int) * ((size_t)out->num_groups + 1));
    if (!at) return 0;
    memcpy(at, out->group_first, sizeof(int) * (size_t)out->num_groups);
    for (i = 0; i < n; i++) out->members[at[out->instance_group[i]]++] = i;
    free(at);
    return 1;
}

/* A moving group whose members are consecutive scene instances can share its tree with another
 * such group of the same meshes: its triangles hold instances relative to the first member. */
static int consecutive(const evr_gpu_bvh *b, int g)
{
    int first = b->group_first[g], last = b->group_first[g + 1] - 1;
    return b->group_node[g] >= 0 && last >= first && b->members[last] - b->members[first] == last - first;
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
    struct RTCBuildPrimitive *prims;   /* room for 2 per triangle (spatial splits) */
    float *tri;                        /* 9 floats per triangle */
    uint32_t *prim;
    int32_t *inst;
    size_t cap;
    float *verts;                      /* a baked mesh's vertices */
    size_t cap_verts;
} group_tris;

static void group_tris_free(group_tris *gt)
{
    free(gt->prims);
    free(gt->tri);
    free(gt->prim);
    free(gt->inst);
    free(gt->verts);
}

static int group_tris_reserve(group_tris *gt, size_t nt)
{
    if (nt <= gt->cap) return 1;
    free(gt->prims);
    free(gt->tri);
    free(gt->prim);
    free(gt->inst);
    gt->prims = evr_gpu_tree_prims(2 * nt);
    gt->tri = malloc(sizeof(float) * 9 * nt);
    gt->prim = malloc(sizeof(uint32_t) * nt);
    gt->inst = malloc(sizeof(int32_t) * nt);
    gt->cap = gt->prims && gt->tri && gt->prim && gt->inst ? nt : 0;
    return gt->cap != 0;
}

/* Collects the usable triangles of group g (baked into world space for the static group, as
 * the CPU backend bakes them: each vertex through evr_m34_point in float) and their box.
 * Returns their number, or (size_t)-1 when out of memory. */
static size_t gather_group(const evr_scene *s, const evr_gpu_bvh *b, int g, int32_t base, group_tris *gt,
                           float box[6])
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
        size_t t;
        if (s->instances[i].mesh < 0 || s->instances[i].mesh >= s->num_meshes) continue;
        mesh = &s->meshes[s->instances[i].mesh];
        if (mesh->num_triangles == 0) continue;
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
                evr_v3 p = evr_m34_point(&world, evr_v3_make(pos[3 * (size_t)v], pos[3 * (size_t)v + 1],
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
                if (vi >= mesh->num_vertices) { ok = 0; break; }
                for (k = 0; k < 3; k++) {
                    float x = pos[3 * (size_t)vi + (size_t)k];
                    if (!isfinite(x)) ok = 0;
                    lo[k] = fminf(lo[k], x);
                    hi[k] = fmaxf(hi[k], x);
                }
            }
            if (!ok) continue;   /* Embree skips such triangles too */
            for (v = 0; v < 3; v++)
                memcpy(gt->tri + 9 * n + 3 * (size_t)v, pos + 3 * (size_t)mesh->indices[3 * t + (size_t)v],
                       3 * sizeof(float));
            gt->prim[n] = (uint32_t)t;
            gt->inst[n] = (int32_t)i - base;
            pr->lower_x = lo[0]; pr->lower_y = lo[1]; pr->lower_z = lo[2];
            pr->upper_x = hi[0]; pr->upper_y = hi[1]; pr->upper_z = hi[2];
            pr->geomID = 0;
            pr->primID = (unsigned)n;
            for (k = 0; k < 3; k++) {
                box[k] = fminf(box[k], lo[k]);
                box[k + 3] = fmaxf(box[k + 3], hi[k]);
            }
            n++;
        }
    }
    return n;
}

evr_status evr_gpu_bvh_build(const evr_scene *s, int layout, evr_gpu_bvh *out, evr_error *err)
{
    flat_ctx c;
    group_tris gt;
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
    out->group_node = malloc(sizeof(int) * ((size_t)n + 1));
    out->group_first = calloc((size_t)n + 2, sizeof(int));
    out->members = malloc(sizeof(int) * ((size_t)n + 1));
    out->instance_group = malloc(sizeof(int) * ((size_t)n + 1));
    out->group_root = malloc(sizeof(int32_t) * ((size_t)n + 1));
    out->group_instance_base = calloc((size_t)n + 1, sizeof(int32_t));
    out->group_stack = calloc((size_t)n + 1, sizeof(int));
    out->group_bounds = malloc(sizeof(float) * 6 * ((size_t)n + 1));
    if (!out->group_node || !out->group_first || !out->members || !out->instance_group || !out->group_root ||
        !out->group_instance_base || !out->group_stack || !out->group_bounds || !make_groups(s, out, out->grouped)) {
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
    memset(table, 0xff, sizeof(int) * table_mask);   /* -1: empty */
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
        if (consecutive(out, g)) {
            size_t h = (size_t)mesh_signature(s, out, g) & table_mask;
            base = out->members[out->group_first[g]];
            out->group_instance_base[g] = base;
            while (table[h] >= 0 && !same_meshes(s, out, g, table[h])) h = (h + 1) & table_mask;
            if (table[h] >= 0) {   /* the same meshes as an earlier group: its tree */
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
            st = fail(err, EVR_ERR_ARG, "a group of instances has too many triangles for the GPU BVH",
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
        split.tri = gt.tri;
        st = evr_gpu_tree_build(dev, &c, gt.prims, cnt, 2 * cnt, RTC_BUILD_QUALITY_HIGH,
                                layout == EVR_GPU_LAYOUT_CW8 ? 3 : 4, &split, box, &root, err);
        if (st != EVR_OK) break;
        out->num_trees++;
        need = evr_gpu_tree_stack_need(&c, first, c.num_nodes);
        if (need < 0) {
            st = fail(err, EVR_ERR_NOMEM, "out of memory for the GPU BVH", NULL);
            break;
        }
        if (need >= EVR_GPU_STACK_SIZE) {
            st = fail(err, EVR_ERR_BACKEND, "a group's BVH is too deep for the traversal stack", group_name(s, out, g));
            break;
        }
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
        out_lo[k] = evr_round_down(blo[k] - slack);
        out_hi[k] = evr_round_up(bhi[k] + slack);
    }
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

evr_status evr_gpu_top_build(const evr_gpu_bvh *b, const evr_render_scene *rs, evr_gpu_top *top, evr_error *err)
{
    int ng = b->num_groups, g, k, need;
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
        return fail(err, EVR_ERR_ARG, "the render scene's instances are not those the GPU BVH was built for", NULL);
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
        const float *gb = b->group_bounds + 6 * g;
        float *ib = top->group_bounds + 6 * g, lo[3], hi[3];
        evr_gpu_inst *in = &src[count];
        int ok = 1;
        for (k = 0; k < 3; k++) {
            ib[k] = INFINITY;
            ib[k + 3] = -INFINITY;
        }
        if (b->group_root[g] < 0) continue;
        memset(in, 0, sizeof *in);
        in->root = b->group_root[g];
        in->instance_base = b->group_instance_base[g];
        if (b->group_node[g] < 0) {   /* world space (the static group) */
            for (k = 0; k < 3; k++) {
                lo[k] = gb[k];
                hi[k] = gb[k + 3];
            }
            in->track = -1;
            in->moving = 0;
            in->inv = evr_m34_identity();
        } else {   /* every member is on the group's node: the first one's track is the group's */
            int track = rs->instances[b->members[b->group_first[g]]].track;
            evr_motion_track tr = evr_rs_track(rs, track);
            evr_gpu_segment_bounds(gb, gb + 3, tr, lo, hi);
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
        prims[count].lower_x = lo[0]; prims[count].lower_y = lo[1]; prims[count].lower_z = lo[2];
        prims[count].upper_x = hi[0]; prims[count].upper_y = hi[1]; prims[count].upper_z = hi[2];
        prims[count].geomID = 0;
        prims[count].primID = (unsigned)count;
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
    /* one group per leaf: entering a group costs far more than a box test (and the CW8 traversal
     * finds a top-level leaf's group through its slot, evr__trace8) */
    st = evr_gpu_tree_build((RTCDevice)b->device, &c, prims, count, count, RTC_BUILD_QUALITY_MEDIUM, 1, NULL, box,
                            &root, err);
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
