/* Deforming triangles as Embree user geometry (see deform_geometry.h). */
#include "cpu/deform_geometry.h"
#include "core/ray_triangle.h"
#include "core/hit_filter.h"
#include "cpu/embree_soa.h"

#include <math.h>

static void corners(const evr_cpu_deform *d, unsigned prim, float f, evr_v3 *a, evr_v3 *b,
                    evr_v3 *c)
{
    const uint32_t *ix = d->indices + 3 * (size_t)prim;
    *a = evr_deform_lerp(&d->view, d->view.positions, ix[0], f);
    *b = evr_deform_lerp(&d->view, d->view.positions, ix[1], f);
    *c = evr_deform_lerp(&d->view, d->view.positions, ix[2], f);
}

/* A triangle's box over every key: linear interpolation between keys stays inside it. */
static void bounds(const struct RTCBoundsFunctionArguments *args)
{
    const evr_cpu_deform *d = args->geometryUserPtr;
    const evr_deform_view *v = &d->view;
    const uint32_t *ix = d->indices + 3 * (size_t)args->primID;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < v->num_keys; k++)
        for (int c = 0; c < 3; c++) {
            const float *p = v->positions + ((size_t)k * v->num_vertices + ix[c]) * 3;
            for (int a = 0; a < 3; a++) { /* finite: no libm call for NaN rules */
                lo[a] = p[a] < lo[a] ? p[a] : lo[a];
                hi[a] = p[a] > hi[a] ? p[a] : hi[a];
            }
        }
    struct RTCBounds *o = args->bounds_o;
    o->lower_x = lo[0];
    o->lower_y = lo[1];
    o->lower_z = lo[2];
    o->upper_x = hi[0];
    o->upper_y = hi[1];
    o->upper_z = hi[2];
}

/* A hit of ray i on triangle prim, unless the material rules it out (shadow: an occlusion
 * query). */
static int ray_hits(const evr_cpu_deform *d, unsigned prim, struct RTCRayN *ray, unsigned n,
                    unsigned i, int shadow, float *t, float *u, float *v, evr_v3 *ng)
{
    const evr_v3 org =
        evr_v3_make(*ray_field(ray, n, RAY_ORG, i), *ray_field(ray, n, RAY_ORG + 1, i),
                    *ray_field(ray, n, RAY_ORG + 2, i));
    const evr_v3 dir =
        evr_v3_make(*ray_field(ray, n, RAY_DIR, i), *ray_field(ray, n, RAY_DIR + 1, i),
                    *ray_field(ray, n, RAY_DIR + 2, i));
    evr_v3 a, b, c;
    corners(d, prim, *ray_field(ray, n, RAY_TIME, i), &a, &b, &c);
    const evr_tri_ray r = evr_tri_ray_make(org, dir);
    if (!evr_tri_hit(&r, a, b, c, *ray_field(ray, n, RAY_TNEAR, i), *ray_field(ray, n, RAY_TFAR, i),
                     t, u, v))
        return 0;
    /* the ray is in the instance's own space (Embree's instance transform applied) */
    if (d->filter && evr_hit_filtered(d->map->rs, d->instance, prim, *u, *v, dir, 1,
                                      *ray_field(ray, n, RAY_TIME, i), shadow))
        return 0;
    *ng = evr_v3_cross(evr_v3_sub(b, a), evr_v3_sub(c, a));
    return 1;
}

static void intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const evr_cpu_deform *d = args->geometryUserPtr;
    const unsigned n = args->N;
    struct RTCRayN *ray = (struct RTCRayN *)args->rayhit;
    struct RTCHitN *hit = (struct RTCHitN *)((float *)args->rayhit + (size_t)RAY_FIELDS * n);
    for (unsigned i = 0; i < n; i++) {
        float t, u, v;
        evr_v3 ng;
        if (args->valid[i] == 0 || !ray_hits(d, args->primID, ray, n, i, 0, &t, &u, &v, &ng))
            continue;
        *ray_field(ray, n, RAY_TFAR, i) = t;
        *hit_float(hit, n, HIT_NG, i) = ng.x;
        *hit_float(hit, n, HIT_NG + 1, i) = ng.y;
        *hit_float(hit, n, HIT_NG + 2, i) = ng.z;
        *hit_float(hit, n, HIT_U, i) = u;
        *hit_float(hit, n, HIT_V, i) = v;
        *hit_uint(hit, n, HIT_PRIM, i) = args->primID;
        *hit_uint(hit, n, HIT_GEOM, i) = args->geomID;
        for (unsigned l = 0; l < RTC_MAX_INSTANCE_LEVEL_COUNT; l++)
            *hit_uint(hit, n, HIT_INST + l, i) = args->context->instID[l];
    }
}

static void occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const evr_cpu_deform *d = args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; i++) {
        float t, u, v;
        evr_v3 ng;
        if (args->valid[i] != 0 &&
            ray_hits(d, args->primID, args->ray, args->N, i, 1, &t, &u, &v, &ng))
            *ray_field(args->ray, args->N, RAY_TFAR, i) = -INFINITY;
    }
}

RTCGeometry evr_cpu_deform_geometry_new(RTCDevice dev, evr_cpu_deform *d)
{
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    if (!g) return NULL;
    rtcSetGeometryUserPrimitiveCount(g, d->num_triangles);
    rtcSetGeometryUserData(g, d);
    rtcSetGeometryBoundsFunction(g, bounds, NULL);
    rtcSetGeometryIntersectFunction(g, intersect);
    rtcSetGeometryOccludedFunction(g, occluded);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_MEDIUM);
    return g;
}
