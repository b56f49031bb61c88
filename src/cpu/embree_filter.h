/* The hit filters of core/hit_filter.h (alpha MASK holes, single-sided back faces) as Embree
 * filter functions: set only on the geometries of meshes whose evr_mesh_view.filter asks for
 * them, so that every other geometry is traced as before. The intersection filter (camera and
 * secondary rays: rtcIntersect) applies both tests, the occlusion filter (shadow rays:
 * rtcOccluded) the alpha test only. Embree may call a filter more than once for one hit (high
 * quality builds, a ray through a shared edge): the test is a function of the hit, so the answer
 * is the same. The filter finds the hit's scene instance from its instance and geometry IDs
 * through the map below, as the ray queries do. */
#ifndef EVR_CPU_EMBREE_FILTER_H
#define EVR_CPU_EMBREE_FILTER_H

#include <embree3/rtcore.h>
#include "core/render_scene.h"

typedef struct {
    const evr_render_scene *rs; /* its keys and deform views those of the segment traced */
    /* A hit's scene instance: members[group_first[instID] + geomID] (the CPU backend's grouped
     * scene), or with members NULL the geometry ID itself (a scene of one geometry per instance,
     * not instanced: evray still). */
    const int *members, *group_first;
    /* per group: EVR_GROUP_* (prep/instance_groups.h): a baked group's triangles are in world
     * space, the others' in their instance's own space, where Embree hands the filter the ray;
     * NULL: every geometry in world space */
    const int *group_kind;
} evr_cpu_filter_map;

/* Makes triangle geometry g (not yet committed) skip the hits that mesh filter bits `bits`
 * (evr_mesh_view.filter) rule out, with map (which must outlive g) as its user data. Nothing
 * when filter is 0. */
void evr_cpu_filter_set(RTCGeometry g, const evr_cpu_filter_map *map, int bits);

/* The scene instance of a hit with Embree's instance and geometry IDs, and in *local whether the
 * ray reached it in that instance's own space (1) or in world space (0). */
int evr_cpu_filter_instance(const evr_cpu_filter_map *map, unsigned inst_id, unsigned geom_id,
                            int *local);

#endif
