/* Embree's packets of N rays and hits in SOA layout (rtcore_ray.h; its accessors are C++ only):
 * a ray's fields, then a hit's, each N wide. Shared by the callbacks that read packets: the
 * deforming user geometry (deform_geometry.c) and the hit filters (embree_filter.c). */
#ifndef EVR_CPU_EMBREE_SOA_H
#define EVR_CPU_EMBREE_SOA_H

#include <stddef.h>
#include <embree3/rtcore.h>

enum { RAY_ORG = 0, RAY_TNEAR = 3, RAY_DIR = 4, RAY_TIME = 7, RAY_TFAR = 8, RAY_FIELDS = 12 };
enum { HIT_NG = 0, HIT_U = 3, HIT_V = 4, HIT_PRIM = 5, HIT_GEOM = 6, HIT_INST = 7 };

static inline float *ray_field(struct RTCRayN *ray, unsigned n, unsigned field, unsigned i)
{
    return (float *)ray + (size_t)field * n + i;
}
static inline float *hit_float(struct RTCHitN *hit, unsigned n, unsigned field, unsigned i)
{
    return (float *)hit + (size_t)field * n + i;
}
static inline unsigned *hit_uint(struct RTCHitN *hit, unsigned n, unsigned field, unsigned i)
{
    return (unsigned *)hit + (size_t)field * n + i;
}

#endif
