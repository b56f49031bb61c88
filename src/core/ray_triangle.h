/* The watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013): a ray through a shared
 * edge or vertex hits at least one of the triangles that share it, so a mesh that moves does not
 * open cracks that would flicker into events. Two-sided, barycentrics as Embree reports them
 * (the hit is (1 - u - v) v0 + u v1 + v v2). Used where we test triangles ourselves rather than
 * Embree: the CPU backend's deforming meshes. */
#ifndef EVR_CORE_RAY_TRIANGLE_H
#define EVR_CORE_RAY_TRIANGLE_H

#include "core/vec.h"

/* A ray prepared for the test: its dominant axis kz and the shear that maps it onto +z. */
typedef struct {
    float o[3];
    int kx, ky, kz;
    float sx, sy, sz;
} evr_tri_ray;

EVR_HD static inline evr_tri_ray evr_tri_ray_make(evr_v3 org, evr_v3 dir)
{
    evr_tri_ray r;
    const float d[3] = {dir.x, dir.y, dir.z};
    const float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    r.o[0] = org.x;
    r.o[1] = org.y;
    r.o[2] = org.z;
    r.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    if (d[r.kz] < 0.0f) { /* keeps the winding */
        const int t = r.kx;
        r.kx = r.ky;
        r.ky = t;
    }
    r.sx = d[r.kx] / d[r.kz];
    r.sy = d[r.ky] / d[r.kz];
    r.sz = 1.0f / d[r.kz];
    return r;
}

/* Whether the ray hits triangle (a, b, c) at t in (tnear, tfar]: *t, *u, *v. */
EVR_HD static inline int evr_tri_hit(const evr_tri_ray *r, evr_v3 a, evr_v3 b, evr_v3 c,
                                     float tnear, float tfar, float *t, float *u, float *v)
{
    const float pa[3] = {a.x - r->o[0], a.y - r->o[1], a.z - r->o[2]};
    const float pb[3] = {b.x - r->o[0], b.y - r->o[1], b.z - r->o[2]};
    const float pc[3] = {c.x - r->o[0], c.y - r->o[1], c.z - r->o[2]};
    const float akz = pa[r->kz], bkz = pb[r->kz], ckz = pc[r->kz];
    const float ax = pa[r->kx] - r->sx * akz, ay = pa[r->ky] - r->sy * akz;
    const float bx = pb[r->kx] - r->sx * bkz, by = pb[r->ky] - r->sy * bkz;
    const float cx = pc[r->kx] - r->sx * ckz, cy = pc[r->ky] - r->sy * ckz;
    float e0 = cx * by - cy * bx;                 /* weight of a */
    float e1 = ax * cy - ay * cx;                 /* weight of b */
    float e2 = bx * ay - by * ax;                 /* weight of c */
    if (e0 == 0.0f || e1 == 0.0f || e2 == 0.0f) { /* on an edge in float: decide exactly */
        e0 = (float)((double)cx * (double)by - (double)cy * (double)bx);
        e1 = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        e2 = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
    if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f)) return 0;
    const float det = e0 + e1 + e2;
    if (det == 0.0f) return 0;
    float tt = e0 * (r->sz * akz) + e1 * (r->sz * bkz) + e2 * (r->sz * ckz);
    const float adet = fabsf(det);
    if (det < 0.0f) tt = -tt;
    if (!(tt > tnear * adet && tt <= tfar * adet)) return 0;
    *t = tt / adet;
    *u = e1 / det;
    *v = e2 / det;
    return 1;
}

#endif
