/* Instance grouping for both backends (see instance_groups.h). */
#include "prep/instance_groups.h"
#include "scene/scene.h"

#include <stdlib.h>
#include <string.h>

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

void evr_instance_groups_free(evr_instance_groups *g)
{
    if (!g) return;
    free(g->group_kind);
    free(g->group_node);
    free(g->group_first);
    free(g->members);
    free(g->instance_group);
    memset(g, 0, sizeof *g);
}

int evr_instance_groups_build(const evr_scene *s, int grouped, evr_instance_groups *out)
{
    int n = s->num_instances, i, g;
    int *node_group, *at;
    unsigned long long static_tris = 0;
    memset(out, 0, sizeof *out);
    out->static_group = -1;
    if (n < 0) return 0;
    out->group_kind = malloc(sizeof(int) * ((size_t)n + 1));
    out->group_node = malloc(sizeof(int) * ((size_t)n + 1));
    out->group_first = calloc((size_t)n + 2, sizeof(int));
    out->members = malloc(sizeof(int) * ((size_t)n + 1));
    out->instance_group = malloc(sizeof(int) * ((size_t)n + 1));
    node_group = malloc(sizeof(int) * ((size_t)s->num_nodes + 1));
    if (!out->group_kind || !out->group_node || !out->group_first || !out->members ||
        !out->instance_group || !node_group) {
        free(node_group);
        evr_instance_groups_free(out);
        return 0;
    }
    for (i = 0; i < s->num_nodes; i++) node_group[i] = -1;
    for (i = 0; i < n; i++) {
        int m = s->instances[i].mesh;
        if (m >= 0 && m < s->num_meshes && !evr_instance_deforms(s, i) &&
            !evr_node_chain_animated(s, s->instances[i].node))
            static_tris += s->meshes[m].num_triangles;
    }
    out->static_instanced = grouped && static_tris > evr_static_bake_limit();
    for (i = 0; i < n; i++) {
        int node = s->instances[i].node, moving = evr_node_chain_animated(s, node);
        int *grp = moving ? &node_group[node] : &out->static_group;
        if (evr_instance_deforms(s, i)) { /* its own vertices every segment: a group of its own */
            const int skinned = s->meshes[s->instances[i].mesh].skin != NULL;
            out->instance_group[i] = out->num_groups;
            out->group_kind[out->num_groups] = EVR_GROUP_DEFORMING;
            out->group_node[out->num_groups++] =
                !skinned && node >= 0 && node < s->num_nodes ? node : -1;
            continue;
        }
        if (!grouped || (!moving && out->static_instanced)) {
            /* a group of its own, in its node's space (none: the world) */
            out->instance_group[i] = out->num_groups;
            out->group_kind[out->num_groups] = moving ? EVR_GROUP_MOVING : EVR_GROUP_STATIC;
            out->group_node[out->num_groups++] = node >= 0 && node < s->num_nodes ? node : -1;
            continue;
        }
        if (*grp < 0) {
            *grp = out->num_groups;
            out->group_kind[out->num_groups] = moving ? EVR_GROUP_MOVING : EVR_GROUP_BAKED;
            out->group_node[out->num_groups++] = moving ? node : -1;
        }
        out->instance_group[i] = *grp;
    }
    free(node_group);
    /* members by group, ascending */
    for (i = 0; i < n; i++) out->group_first[out->instance_group[i] + 1]++;
    for (g = 0; g < out->num_groups; g++) out->group_first[g + 1] += out->group_first[g];
    at = malloc(sizeof(int) * ((size_t)out->num_groups + 1));
    if (!at) {
        evr_instance_groups_free(out);
        return 0;
    }
    memcpy(at, out->group_first, sizeof(int) * (size_t)out->num_groups);
    for (i = 0; i < n; i++) out->members[at[out->instance_group[i]]++] = i;
    free(at);
    return 1;
}
