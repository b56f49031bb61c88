/* Small vector, quaternion and affine-matrix math shared by CPU and GPU. */
#ifndef EVR_CORE_VEC_H
#define EVR_CORE_VEC_H

#include <math.h>
#include "core/hd.h"

typedef struct {
    float x, y, z;
} evr_v3;
typedef struct {
    float w, x, y, z;
} evr_quat; /* w + xi + yj + zk, unit for rotations */
/* Affine transform, row-major 3x4: p' = m[r][0..2] . p + m[r][3]. */
typedef struct {
    float m[3][4];
} evr_m34;

EVR_HD static inline evr_v3 evr_v3_make(float x, float y, float z)
{
    evr_v3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}
EVR_HD static inline evr_v3 evr_v3_add(evr_v3 a, evr_v3 b)
{
    return evr_v3_make(a.x + b.x, a.y + b.y, a.z + b.z);
}
EVR_HD static inline evr_v3 evr_v3_sub(evr_v3 a, evr_v3 b)
{
    return evr_v3_make(a.x - b.x, a.y - b.y, a.z - b.z);
}
EVR_HD static inline evr_v3 evr_v3_mul(evr_v3 a, evr_v3 b)
{
    return evr_v3_make(a.x * b.x, a.y * b.y, a.z * b.z);
}
EVR_HD static inline evr_v3 evr_v3_scale(evr_v3 a, float s)
{
    return evr_v3_make(a.x * s, a.y * s, a.z * s);
}
EVR_HD static inline float evr_v3_dot(evr_v3 a, evr_v3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
EVR_HD static inline evr_v3 evr_v3_cross(evr_v3 a, evr_v3 b)
{
    return evr_v3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
EVR_HD static inline float evr_v3_len(evr_v3 a) { return sqrtf(evr_v3_dot(a, a)); }
EVR_HD static inline evr_v3 evr_v3_norm(evr_v3 a)
{
    float l = evr_v3_len(a);
    return l > 0.0f ? evr_v3_scale(a, 1.0f / l) : a;
}
EVR_HD static inline evr_v3 evr_v3_lerp(evr_v3 a, evr_v3 b, float f)
{
    return evr_v3_make(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f);
}

EVR_HD static inline evr_quat evr_quat_make(float w, float x, float y, float z)
{
    evr_quat q;
    q.w = w;
    q.x = x;
    q.y = y;
    q.z = z;
    return q;
}
EVR_HD static inline float evr_quat_dot(evr_quat a, evr_quat b)
{
    return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
}
EVR_HD static inline evr_quat evr_quat_normalize(evr_quat q)
{
    float l = sqrtf(evr_quat_dot(q, q));
    if (l <= 0.0f) return evr_quat_make(1, 0, 0, 0);
    return evr_quat_make(q.w / l, q.x / l, q.y / l, q.z / l);
}
EVR_HD static inline evr_quat evr_quat_mul(evr_quat a, evr_quat b)
{
    return evr_quat_make(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
                         a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                         a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                         a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w);
}
/* Spherical linear interpolation along the shortest arc. */
EVR_HD static inline evr_quat evr_quat_slerp(evr_quat a, evr_quat b, float f)
{
    float d = evr_quat_dot(a, b);
    if (d < 0.0f) {
        b = evr_quat_make(-b.w, -b.x, -b.y, -b.z);
        d = -d;
    }
    float wa, wb;
    if (d > 0.9995f) { /* nearly parallel: lerp is exact to float precision */
        wa = 1.0f - f;
        wb = f;
    } else {
        float th = acosf(d), s = sinf(th);
        wa = sinf((1.0f - f) * th) / s;
        wb = sinf(f * th) / s;
    }
    return evr_quat_normalize(evr_quat_make(wa * a.w + wb * b.w, wa * a.x + wb * b.x,
                                            wa * a.y + wb * b.y, wa * a.z + wb * b.z));
}
/* Rotation matrix of a unit quaternion, written into the 3x3 part of m. */
EVR_HD static inline void evr_quat_to_m33(evr_quat q, float r[3][3])
{
    float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    r[0][0] = 1 - 2 * (yy + zz);
    r[0][1] = 2 * (xy - wz);
    r[0][2] = 2 * (xz + wy);
    r[1][0] = 2 * (xy + wz);
    r[1][1] = 1 - 2 * (xx + zz);
    r[1][2] = 2 * (yz - wx);
    r[2][0] = 2 * (xz - wy);
    r[2][1] = 2 * (yz + wx);
    r[2][2] = 1 - 2 * (xx + yy);
}

EVR_HD static inline evr_m34 evr_m34_identity(void)
{
    evr_m34 r;
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++) r.m[i][j] = (i == j) ? 1.0f : 0.0f;
    return r;
}
EVR_HD static inline evr_m34 evr_m34_mul(evr_m34 a, evr_m34 b)
{
    evr_m34 r;
    int i, j;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 4; j++)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
        r.m[i][3] += a.m[i][3];
    }
    return r;
}
EVR_HD static inline evr_v3 evr_m34_point(const evr_m34 *a, evr_v3 p)
{
    return evr_v3_make(a->m[0][0] * p.x + a->m[0][1] * p.y + a->m[0][2] * p.z + a->m[0][3],
                       a->m[1][0] * p.x + a->m[1][1] * p.y + a->m[1][2] * p.z + a->m[1][3],
                       a->m[2][0] * p.x + a->m[2][1] * p.y + a->m[2][2] * p.z + a->m[2][3]);
}
EVR_HD static inline evr_v3 evr_m34_vector(const evr_m34 *a, evr_v3 v)
{
    return evr_v3_make(a->m[0][0] * v.x + a->m[0][1] * v.y + a->m[0][2] * v.z,
                       a->m[1][0] * v.x + a->m[1][1] * v.y + a->m[1][2] * v.z,
                       a->m[2][0] * v.x + a->m[2][1] * v.y + a->m[2][2] * v.z);
}
/* Normal transform: inverse transpose of the linear part, via cofactors (scale-free). */
EVR_HD static inline evr_v3 evr_m34_normal(const evr_m34 *a, evr_v3 n)
{
    evr_v3 c0 = evr_v3_make(a->m[0][0], a->m[1][0], a->m[2][0]);
    evr_v3 c1 = evr_v3_make(a->m[0][1], a->m[1][1], a->m[2][1]);
    evr_v3 c2 = evr_v3_make(a->m[0][2], a->m[1][2], a->m[2][2]);
    evr_v3 r0 = evr_v3_cross(c1, c2), r1 = evr_v3_cross(c2, c0), r2 = evr_v3_cross(c0, c1);
    float det = evr_v3_dot(c0, r0);
    evr_v3 out =
        evr_v3_add(evr_v3_add(evr_v3_scale(r0, n.x), evr_v3_scale(r1, n.y)), evr_v3_scale(r2, n.z));
    return evr_v3_norm(det < 0.0f ? evr_v3_scale(out, -1.0f) : out);
}
/* Inverse of an affine transform, through the adjugate of the linear part. A singular matrix
 * (a zero scale) gives the zero matrix: nothing maps onto it, so rays through it hit nothing. */
EVR_HD static inline evr_m34 evr_m34_inverse(const evr_m34 *a)
{
    evr_v3 c0 = evr_v3_make(a->m[0][0], a->m[1][0], a->m[2][0]);
    evr_v3 c1 = evr_v3_make(a->m[0][1], a->m[1][1], a->m[2][1]);
    evr_v3 c2 = evr_v3_make(a->m[0][2], a->m[1][2], a->m[2][2]);
    evr_v3 r[3];
    evr_m34 inv;
    int i;
    r[0] = evr_v3_cross(c1, c2); /* rows of the inverse, times det */
    r[1] = evr_v3_cross(c2, c0);
    r[2] = evr_v3_cross(c0, c1);
    float det = evr_v3_dot(c0, r[0]);
    float s = det != 0.0f ? 1.0f / det : 0.0f;
    for (i = 0; i < 3; i++) {
        evr_v3 row = evr_v3_scale(r[i], s);
        inv.m[i][0] = row.x;
        inv.m[i][1] = row.y;
        inv.m[i][2] = row.z;
        inv.m[i][3] = -(row.x * a->m[0][3] + row.y * a->m[1][3] + row.z * a->m[2][3]);
    }
    return inv;
}

#endif
