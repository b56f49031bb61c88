/* A deforming instance's triangles as Embree user geometry: Embree builds a static tree over each
 * triangle's box across the segment's vertex keys (a fast build every segment the mesh moves,
 * where triangles with time steps cost a motion-blur build of every key interval), and the rays
 * that reach a triangle test it interpolated to their own time (evr_deform_lerp, the GPU's rule)
 * with the watertight test of core/ray_triangle.h; the hits its material rules out
 * (core/hit_filter.h) are skipped in the same callbacks. */
#ifndef EVR_CPU_DEFORM_GEOMETRY_H
#define EVR_CPU_DEFORM_GEOMETRY_H

#include <embree3/rtcore.h>
#include "core/render_scene.h"
#include "cpu/embree_filter.h"

/* What the callbacks read: the mesh's triangles and the current segment's keys. */
typedef struct {
    const uint32_t *indices;
    uint32_t num_triangles;
    evr_deform_view view; /* set every segment before rendering (its arrays live that long) */
    /* the hits its mesh's material rules out (core/hit_filter.h): filter bits (0: none) and what
     * the test reads (map->rs, the segment's) for the group's one instance */
    int filter, instance;
    const evr_cpu_filter_map *map;
} evr_cpu_deform;

/* A user geometry over d's triangles (d must outlive it); NULL when Embree refuses. */
RTCGeometry evr_cpu_deform_geometry_new(RTCDevice dev, evr_cpu_deform *d);

#endif
