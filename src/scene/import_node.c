/* The node hierarchy: flattened depth-first with each node's rest transform, one instance per
 * (node, mesh) pair, nodes found by Assimp name, and the scene's rest-pose bounds. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/cimport.h>
#include <assimp/scene.h>

#include "scene/import_internal.h"

static int name_index_cmp(const void *pa, const void *pb)
{
    const name_index *a = pa, *b = pb;
    int c = strcmp(a->name, b->name);
    return c ? c : (a->index > b->index) - (a->index < b->index);
}

/* The position in by_name of the first node named `name` (where it would be when none is). */
static int first_by_name(const importer *im, const char *name)
{
    int lo = 0, hi = im->s->num_nodes;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (strcmp(im->by_name[mid].name, name) < 0) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* The first node (in depth-first order) with Assimp name `name`, or -1. Assimp attaches
 * animation channels, bones, cameras and lights to nodes by name. */
int evr_import_find_node(const importer *im, const char *name)
{
    int at;
    if (!im->by_name) return -1;
    at = first_by_name(im, name);
    return (at < im->s->num_nodes && !strcmp(im->by_name[at].name, name)) ? im->by_name[at].index
                                                                          : -1;
}

int evr_import_name_count(const importer *im, const char *name)
{
    int at, n = 0;
    if (!im->by_name) return 0;
    at = first_by_name(im, name);
    while (at + n < im->s->num_nodes && !strcmp(im->by_name[at + n].name, name)) n++;
    return n;
}

evr_m34 evr_import_m34(const struct aiMatrix4x4 *a)
{
    evr_m34 m;
    m.m[0][0] = a->a1;
    m.m[0][1] = a->a2;
    m.m[0][2] = a->a3;
    m.m[0][3] = a->a4;
    m.m[1][0] = a->b1;
    m.m[1][1] = a->b2;
    m.m[1][2] = a->b3;
    m.m[1][3] = a->b4;
    m.m[2][0] = a->c1;
    m.m[2][1] = a->c2;
    m.m[2][2] = a->c3;
    m.m[2][3] = a->c4;
    return m;
}

/* Flattens the node tree depth-first (parents before children) and makes the instances. */
evr_status evr_import_nodes(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    const struct aiNode **stack = NULL;
    int *stack_parent = NULL;
    int sp = 0, cap = 0, count = 0, ninst = 0, i;
    unsigned c;

    if (!ai->mRootNode)
        return evr_import_fail(im->err, EVR_ERR_FORMAT, "the scene has no node hierarchy");
    /* Count the nodes (iteratively: hierarchies can be deep). */
    cap = 64;
    stack = malloc((size_t)cap * sizeof *stack);
    stack_parent = malloc((size_t)cap * sizeof *stack_parent);
    if (!stack || !stack_parent) goto nomem;
    stack[sp++] = ai->mRootNode;
    while (sp) {
        const struct aiNode *n = stack[--sp];
        count++;
        ninst += (int)n->mNumMeshes;
        for (c = 0; c < n->mNumChildren; c++) {
            if (sp == cap) {
                const struct aiNode **ns;
                int *np;
                cap *= 2;
                ns = realloc(stack, (size_t)cap * sizeof *stack);
                if (ns) stack = ns;
                np = ns ? realloc(stack_parent, (size_t)cap * sizeof *stack_parent) : NULL;
                if (np) stack_parent = np;
                if (!ns || !np) goto nomem;
            }
            stack[sp++] = n->mChildren[c];
        }
        if (count > (1 << 26)) {
            free(stack);
            free(stack_parent);
            return evr_import_fail(im->err, EVR_ERR_FORMAT,
                                   "the node hierarchy is too large or cyclic");
        }
    }

    s->nodes = calloc((size_t)count, sizeof *s->nodes);
    im->ai_nodes = calloc((size_t)count, sizeof *im->ai_nodes);
    s->instances = calloc((size_t)ninst + 1, sizeof *s->instances);
    if (!s->nodes || !im->ai_nodes || !s->instances) goto nomem;
    s->num_nodes = count;

    sp = 0;
    stack[sp] = ai->mRootNode;
    stack_parent[sp++] = -1;
    count = 0;
    while (sp) {
        const struct aiNode *an = stack[--sp];
        int parent = stack_parent[sp], self = count++;
        evr_node *n = &s->nodes[self];
        struct aiVector3D sc, pos;
        struct aiQuaternion q;
        im->ai_nodes[self] = an;
        evr_import_copy_name(n->name, sizeof n->name, an->mName.data);
        n->parent = parent;
        n->rest_matrix = evr_import_m34(&an->mTransformation);
        aiDecomposeMatrix(&an->mTransformation, &sc, &q, &pos);
        n->translation = evr_v3_make(pos.x, pos.y, pos.z);
        n->scale = evr_v3_make(sc.x, sc.y, sc.z);
        n->rotation = evr_quat_normalize(evr_quat_make(q.w, q.x, q.y, q.z));
        for (c = 0; c < an->mNumMeshes; c++) {
            if (an->mMeshes[c] >= (unsigned)s->num_meshes) continue;
            s->instances[s->num_instances].mesh = (int)an->mMeshes[c];
            s->instances[s->num_instances].node = self;
            s->num_instances++;
        }
        /* children in reverse so that they come out in file order */
        for (c = an->mNumChildren; c-- > 0;) {
            stack[sp] = an->mChildren[c];
            stack_parent[sp++] = self;
        }
    }
    free(stack);
    free(stack_parent);

    im->by_name = malloc((size_t)s->num_nodes * sizeof *im->by_name);
    if (!im->by_name)
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading the node hierarchy");
    for (i = 0; i < s->num_nodes; i++) {
        im->by_name[i].name = im->ai_nodes[i]->mName.data;
        im->by_name[i].index = i;
    }
    qsort(im->by_name, (size_t)s->num_nodes, sizeof *im->by_name, name_index_cmp);

    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        evr_node *n = &s->nodes[s->instances[i].node];
        if (!n->has_bounds) {
            n->bounds_min = m->bounds_min;
            n->bounds_max = m->bounds_max;
            n->has_bounds = 1;
        } else {
            n->bounds_min = evr_v3_make(fminf(n->bounds_min.x, m->bounds_min.x),
                                        fminf(n->bounds_min.y, m->bounds_min.y),
                                        fminf(n->bounds_min.z, m->bounds_min.z));
            n->bounds_max = evr_v3_make(fmaxf(n->bounds_max.x, m->bounds_max.x),
                                        fmaxf(n->bounds_max.y, m->bounds_max.y),
                                        fmaxf(n->bounds_max.z, m->bounds_max.z));
        }
    }
    return EVR_OK;
nomem:
    free(stack);
    free(stack_parent);
    return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading the node hierarchy");
}

/* World transform of a node at its rest pose. */
static evr_m34 rest_world(const evr_scene *s, int node)
{
    evr_m34 m = evr_m34_identity();
    while (node >= 0) {
        m = evr_m34_mul(s->nodes[node].rest_matrix, m);
        node = s->nodes[node].parent;
    }
    return m;
}

/* A deforming instance's world bounds at the animation's start (a skinned mesh's rest
 * positions mean nothing without its joints: the mesh node's transform is ignored); 0 when
 * memory ran out. */
static int deformed_bounds(const evr_scene *s, int inst, evr_v3 *lo, evr_v3 *hi)
{
    const evr_mesh *m = &s->meshes[s->instances[inst].mesh];
    float *p = malloc(sizeof(float) * 3 * (size_t)m->num_vertices + 1);
    evr_m34 w = m->skin ? evr_m34_identity() : rest_world(s, s->instances[inst].node);
    uint32_t v;
    if (!p || !evr_instance_deformed_at(s, inst, s->anim_start, p, NULL)) {
        free(p);
        return 0;
    }
    for (v = 0; v < m->num_vertices; v++) {
        evr_v3 q = evr_m34_point(&w, evr_v3_make(p[3 * v], p[3 * v + 1], p[3 * v + 2]));
        *lo = evr_v3_make(fminf(lo->x, q.x), fminf(lo->y, q.y), fminf(lo->z, q.z));
        *hi = evr_v3_make(fmaxf(hi->x, q.x), fmaxf(hi->y, q.y), fmaxf(hi->z, q.z));
    }
    free(p);
    return 1;
}

void evr_import_bounds(evr_scene *s)
{
    int i, c, any = 0;
    evr_v3 lo = evr_v3_make(INFINITY, INFINITY, INFINITY),
           hi = evr_v3_make(-INFINITY, -INFINITY, -INFINITY);
    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        evr_m34 w;
        if (!m->num_triangles) continue;
        any = 1;
        if (evr_instance_deforms(s, i) && deformed_bounds(s, i, &lo, &hi)) continue;
        w = rest_world(s, s->instances[i].node);
        for (c = 0; c < 8; c++) {
            evr_v3 p = evr_v3_make((c & 1) ? m->bounds_max.x : m->bounds_min.x,
                                   (c & 2) ? m->bounds_max.y : m->bounds_min.y,
                                   (c & 4) ? m->bounds_max.z : m->bounds_min.z);
            p = evr_m34_point(&w, p);
            lo = evr_v3_make(fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z));
            hi = evr_v3_make(fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z));
        }
    }
    if (!any) lo = hi = evr_v3_make(0, 0, 0);
    s->bounds_min = lo;
    s->bounds_max = hi;
}
