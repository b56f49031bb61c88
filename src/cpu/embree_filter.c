/* Embree filter functions over core/hit_filter.h (see embree_filter.h). */
#include "cpu/embree_filter.h"
#include "core/hit_filter.h"
#include "cpu/embree_soa.h"
#include "prep/instance_groups.h"

int evr_cpu_filter_instance(const evr_cpu_filter_map *map, unsigned inst_id, unsigned geom_id,
                            int *local)
{
    if (!map->members) {
        *local = 0;
        return (int)geom_id;
    }
    *local = map->group_kind && map->group_kind[inst_id] != EVR_GROUP_BAKED;
    return map->members[map->group_first[inst_id] + (int)geom_id];
}

static void filter(const struct RTCFilterFunctionNArguments *args, int shadow)
{
    const evr_cpu_filter_map *map = args->geometryUserPtr;
    const unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        int local;
        if (args->valid[i] == 0) continue;
        const int inst = evr_cpu_filter_instance(map, *hit_uint(args->hit, n, HIT_INST, i),
                                                 *hit_uint(args->hit, n, HIT_GEOM, i), &local);
        const evr_v3 dir = evr_v3_make(*ray_field(args->ray, n, RAY_DIR, i),
                                       *ray_field(args->ray, n, RAY_DIR + 1, i),
                                       *ray_field(args->ray, n, RAY_DIR + 2, i));
        if (evr_hit_filtered(map->rs, inst, *hit_uint(args->hit, n, HIT_PRIM, i),
                             *hit_float(args->hit, n, HIT_U, i), *hit_float(args->hit, n, HIT_V, i),
                             dir, local, *ray_field(args->ray, n, RAY_TIME, i), shadow))
            args->valid[i] = 0;
    }
}

static void intersect_filter(const struct RTCFilterFunctionNArguments *args) { filter(args, 0); }
static void occluded_filter(const struct RTCFilterFunctionNArguments *args) { filter(args, 1); }

void evr_cpu_filter_set(RTCGeometry g, const evr_cpu_filter_map *map, int bits)
{
    if (!bits) return;
    rtcSetGeometryUserData(g, (void *)map);
    rtcSetGeometryIntersectFilterFunction(g, intersect_filter);
    /* shadow rays see back faces: only holes let them through */
    if (bits & EVR_FILTER_MASK) rtcSetGeometryOccludedFilterFunction(g, occluded_filter);
}
