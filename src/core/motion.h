/* Per-segment motion keys: an affine transform decomposed as T * R * U, where U is upper
 * triangular (scale on the diagonal, skew above it), R a unit quaternion and T a translation.
 * It is the decomposition Embree's rtcSetGeometryTransformQuaternion interpolates, and these are
 * the same interpolation rules (lerp U and T, slerp R along the shortest arc), so a camera or an
 * instance moves identically on the CPU (inside Embree) and on the GPU (through this file). */
#ifndef EVR_CORE_MOTION_H
#define EVR_CORE_MOTION_H

#include <stdint.h>

#include "core/vec.h"

typedef struct {
    float scale[3]; /* U diagonal */
    float skew[3];  /* U[0][1], U[0][2], U[1][2] */
    evr_quat rot;
    evr_v3 trans;
} evr_motion_key;

/* Keys of one moving thing over one segment: n >= 1 keys at uniform times 0, 1/(n-1), ..., 1,
 * n at most EVR_MAX_KEYS (the cap the segment loop gives the key fitting, src/sim.c). */
#define EVR_MAX_KEYS 65
typedef struct {
    const evr_motion_key *keys;
    int n;
} evr_motion_track;

EVR_HD static inline evr_m34 evr_motion_key_matrix(const evr_motion_key *k)
{
    float r[3][3];
    float u[3][3] = {{k->scale[0], k->skew[0], k->skew[1]},
                     {0.0f, k->scale[1], k->skew[2]},
                     {0.0f, 0.0f, k->scale[2]}};
    evr_m34 m;
    int i, j;
    evr_quat_to_m33(k->rot, r);
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++)
            m.m[i][j] = r[i][0] * u[0][j] + r[i][1] * u[1][j] + r[i][2] * u[2][j];
    }
    m.m[0][3] = k->trans.x;
    m.m[1][3] = k->trans.y;
    m.m[2][3] = k->trans.z;
    return m;
}

EVR_HD static inline evr_motion_key evr_motion_key_lerp(const evr_motion_key *a,
                                                        const evr_motion_key *b, float f)
{
    evr_motion_key k;
    int i;
    for (i = 0; i < 3; i++) {
        k.scale[i] = a->scale[i] + (b->scale[i] - a->scale[i]) * f;
        k.skew[i] = a->skew[i] + (b->skew[i] - a->skew[i]) * f;
    }
    k.rot = evr_quat_slerp(a->rot, b->rot, f);
    k.trans = evr_v3_lerp(a->trans, b->trans, f);
    return k;
}

EVR_HD static inline uint32_t evr_motion_bits_diff(float a, float b)
{
    union {
        float f;
        uint32_t u;
    } x, y;
    x.f = a;
    y.f = b;
    return x.u ^ y.u;
}

/* Whether two keys are the same bit for bit. */
EVR_HD static inline int evr_motion_key_same(const evr_motion_key *a, const evr_motion_key *b)
{
    uint32_t d =
        evr_motion_bits_diff(a->rot.w, b->rot.w) | evr_motion_bits_diff(a->rot.x, b->rot.x) |
        evr_motion_bits_diff(a->rot.y, b->rot.y) | evr_motion_bits_diff(a->rot.z, b->rot.z) |
        evr_motion_bits_diff(a->trans.x, b->trans.x) |
        evr_motion_bits_diff(a->trans.y, b->trans.y) | evr_motion_bits_diff(a->trans.z, b->trans.z);
    for (int i = 0; i < 3; i++)
        d |= evr_motion_bits_diff(a->scale[i], b->scale[i]) |
             evr_motion_bits_diff(a->skew[i], b->skew[i]);
    return d == 0;
}

/* Transform at normalized segment time f in [0,1]. Between two keys that are the same, the key
 * itself: the same bits at every time of the interval (an interpolation of equal ends rounds
 * differently at different times), so that a sample there may take another's intensity
 * (evr_skip_still_span). */
EVR_HD static inline evr_m34 evr_motion_eval(evr_motion_track tr, float f)
{
    if (tr.n <= 1) return evr_motion_key_matrix(&tr.keys[0]);
    float x = f * (float)(tr.n - 1);
    int i = (int)floorf(x);
    if (i < 0) i = 0;
    if (i > tr.n - 2) i = tr.n - 2;
    if (evr_motion_key_same(&tr.keys[i], &tr.keys[i + 1]))
        return evr_motion_key_matrix(&tr.keys[i]);
    evr_motion_key k = evr_motion_key_lerp(&tr.keys[i], &tr.keys[i + 1], x - (float)i);
    return evr_motion_key_matrix(&k);
}

/* Quaternion of a proper rotation matrix (Shepperd's method). */
EVR_HD static inline evr_quat evr_quat_from_m33(const float r[3][3])
{
    float tr = r[0][0] + r[1][1] + r[2][2];
    evr_quat q;
    if (tr > 0.0f) {
        float s = sqrtf(tr + 1.0f) * 2.0f;
        q = evr_quat_make(0.25f * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s,
                          (r[1][0] - r[0][1]) / s);
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        float s = sqrtf(1.0f + r[0][0] - r[1][1] - r[2][2]) * 2.0f;
        q = evr_quat_make((r[2][1] - r[1][2]) / s, 0.25f * s, (r[0][1] + r[1][0]) / s,
                          (r[0][2] + r[2][0]) / s);
    } else if (r[1][1] > r[2][2]) {
        float s = sqrtf(1.0f + r[1][1] - r[0][0] - r[2][2]) * 2.0f;
        q = evr_quat_make((r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25f * s,
                          (r[1][2] + r[2][1]) / s);
    } else {
        float s = sqrtf(1.0f + r[2][2] - r[0][0] - r[1][1]) * 2.0f;
        q = evr_quat_make((r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s,
                          0.25f * s);
    }
    return evr_quat_normalize(q);
}

/* Decomposes an affine matrix into a key by QR (Gram-Schmidt on the columns). A mirroring
 * matrix keeps a proper rotation and puts the sign into scale[2]. */
EVR_HD static inline evr_motion_key evr_motion_key_from_matrix(const evr_m34 *m)
{
    evr_v3 a0 = evr_v3_make(m->m[0][0], m->m[1][0], m->m[2][0]);
    evr_v3 a1 = evr_v3_make(m->m[0][1], m->m[1][1], m->m[2][1]);
    evr_v3 a2 = evr_v3_make(m->m[0][2], m->m[1][2], m->m[2][2]);
    evr_motion_key k;
    float u00 = evr_v3_len(a0);
    evr_v3 q0 = u00 > 0 ? evr_v3_scale(a0, 1.0f / u00) : evr_v3_make(1, 0, 0);
    float u01 = evr_v3_dot(q0, a1);
    evr_v3 b1 = evr_v3_sub(a1, evr_v3_scale(q0, u01));
    float u11 = evr_v3_len(b1);
    evr_v3 q1 = u11 > 0 ? evr_v3_scale(b1, 1.0f / u11)
                        : evr_v3_norm(evr_v3_cross(evr_v3_make(0, 0, 1), q0));
    float u02 = evr_v3_dot(q0, a2), u12 = evr_v3_dot(q1, a2);
    evr_v3 b2 = evr_v3_sub(evr_v3_sub(a2, evr_v3_scale(q0, u02)), evr_v3_scale(q1, u12));
    evr_v3 q2 = evr_v3_cross(q0, q1); /* proper rotation by construction */
    float u22 = evr_v3_dot(q2, b2);   /* negative for a mirroring matrix */
    float r[3][3] = {{q0.x, q1.x, q2.x}, {q0.y, q1.y, q2.y}, {q0.z, q1.z, q2.z}};
    k.scale[0] = u00;
    k.scale[1] = u11;
    k.scale[2] = u22;
    k.skew[0] = u01;
    k.skew[1] = u02;
    k.skew[2] = u12;
    k.rot = evr_quat_from_m33(r);
    k.trans = evr_v3_make(m->m[0][3], m->m[1][3], m->m[2][3]);
    return k;
}

#endif
