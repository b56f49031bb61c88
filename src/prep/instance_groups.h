/* How both backends group a scene's instances before building their trees over the groups.
 *   baked   every instance whose node never moves (no animated node on its parent chain), its
 *           mesh's triangles baked into world space with the node's transform at
 *           evr_scene.anim_start; one group, no motion. Unless baking would copy more than
 *           evr_static_bake_limit() triangles: then every such instance is a group of its own,
 *   static  one never-moving instance in its node's space (the node's fixed transform), whose
 *           tree a backend shares among the instances of one mesh (a city of thousands of
 *           instances of a dozen buildings stores each building once);
 *   moving  the instances of one moving node, in that node's object space, moved by its track;
 *   deforming  one instance whose mesh deforms (skin, morph targets), its vertices given per
 *           segment (evr_deform_view) in its node's space, or in world space when skinned (node
 *           -1), moved by the node's track when that node moves.
 * A ray that crosses overlapping instances (skin and orbit around an eyeball) then searches one
 * tree instead of one per instance. Groups are numbered in the order of their first member and
 * list their members in ascending order: the backends' trees, and so their hits, follow both. */
#ifndef EVR_PREP_INSTANCE_GROUPS_H
#define EVR_PREP_INSTANCE_GROUPS_H

#include "evray.h"

#define EVR_GROUP_BAKED 0
#define EVR_GROUP_STATIC 1
#define EVR_GROUP_MOVING 2
#define EVR_GROUP_DEFORMING 3

typedef struct {
    int num_groups;
    int static_group;     /* the baked group, -1: none (every instance moves, or the static
                                  instances are past the bake limit) */
    int static_instanced; /* 1: the static instances were past the bake limit (static groups) */
    int *group_kind;      /* per group: EVR_GROUP_* */
    int *group_node;      /* per group: the node whose space it is in (a moving group's node
                                  is also its motion track), -1: world space */
    int *group_first;     /* per group + 1: its members are members[group_first[g] ..
                                  group_first[g + 1]), scene instance indices, ascending */
    int *members;
    int *instance_group; /* per scene instance: its group */
} evr_instance_groups;

/* Groups the instances of s as above; grouped 0: no grouping, every instance a group of its own
 * in its node's space (static or moving), for comparisons. Returns 0 when out of memory (out is
 * then empty, safe to free). */
int evr_instance_groups_build(const evr_scene *s, int grouped, evr_instance_groups *out);
void evr_instance_groups_free(evr_instance_groups *g);

/* Past this many triangles baked into world space (counted per instance) the never-moving
 * instances are kept as instances instead: 1,000,000, or the environment variable
 * EVR_STATIC_BAKE_LIMIT (a triangle count; 0: always instance, for tests and comparisons). */
unsigned long long evr_static_bake_limit(void);

/* Whether both backends build a tree made once (every group's but a deforming one's) over this
 * many triangles with spatial splits (Embree's HIGH quality): up to 262,144, and past that as a
 * binned SAH (MEDIUM), several times faster to build at a few per cent of tracing speed
 * (docs/benchmarks.md, "Set-up of a big static model"). */
static inline int evr_tree_high_quality(unsigned long long triangles)
{
    return triangles <= 262144u;
}

#endif
