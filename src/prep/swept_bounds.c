/* Swept bounds of boxes carried by motion tracks (see swept_bounds.h). */
#include "prep/swept_bounds.h"

#include <math.h>
#include <stddef.h>

float evr_round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}
float evr_round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

static void extend_corners(const evr_m34 *m, const float lo[3], const float hi[3], double blo[3],
                           double bhi[3])
{
    int c, k;
    for (c = 0; c < 8; c++) {
        evr_v3 p =
            evr_v3_make((c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]);
        evr_v3 q = evr_m34_point(m, p);
        double x[3] = {q.x, q.y, q.z};
        for (k = 0; k < 3; k++) {
            if (x[k] < blo[k]) blo[k] = x[k];
            if (x[k] > bhi[k]) bhi[k] = x[k];
        }
    }
}

/* |U p| for the upper-triangular part of a key. */
static double upper_apply_len(const evr_motion_key *k, const double p[3], int diff,
                              const evr_motion_key *b)
{
    double s0 = k->scale[0], s1 = k->scale[1], s2 = k->scale[2];
    double k0 = k->skew[0], k1 = k->skew[1], k2 = k->skew[2];
    double x, y, z;
    if (diff) {
        s0 = b->scale[0] - s0;
        s1 = b->scale[1] - s1;
        s2 = b->scale[2] - s2;
        k0 = b->skew[0] - k0;
        k1 = b->skew[1] - k1;
        k2 = b->skew[2] - k2;
    }
    x = s0 * p[0] + k0 * p[1] + k1 * p[2];
    y = s1 * p[1] + k2 * p[2];
    z = s2 * p[2];
    return sqrt(x * x + y * y + z * z);
}

void evr_swept_bounds(const float lo[3], const float hi[3], evr_motion_track tr, float out_lo[3],
                      float out_hi[3])
{
    double blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double mag = 0.0;
    int i, j, k;
    if (tr.n <= 1) {
        evr_m34 m = evr_motion_key_matrix(&tr.keys[0]);
        extend_corners(&m, lo, hi, blo, bhi);
    }
    for (i = 0; i + 1 < tr.n; i++) {
        /* x(s) = T(s) + Q(s) c, Q = R U, for s in [0, 1] and c in the box. Between two samples
         * s0 < s1: T is linear, so T(s) lies in the box of T(s0), T(s1); Q(s) c lies within
         * L h / 2 (h = s1 - s0) of Q(s0) c or Q(s1) c, L a bound on its speed:
         * |d(Q c)/ds| <= w max|U(s) c| + |dU c|, w the rotation's angular speed (slerp:
         * constant, the angle between the keys; normalized lerp for close keys: at most 1.0003
         * times that); |U(s) c| is convex in s and c, so its maximum is at an end key and a
         * corner of the box. Each step's box is the sum of the two; the result their union.
         * Translation needs no samples: the samples follow the rotation and scaling only. */
        evr_motion_key a = tr.keys[i], b = tr.keys[i + 1];
        double plo[3], phi[3], pt[3]; /* previous sample: Q box and T */
        double d = fabs((double)evr_quat_dot(a.rot, b.rot));
        double qa = sqrt((double)evr_quat_dot(a.rot, a.rot)),
               qb = sqrt((double)evr_quat_dot(b.rot, b.rot));
        double w, umax = 0.0, dumax = 0.0, L, margin;
        evr_v3 ta = a.trans, tb = b.trans;
        int steps, c;
        d = qa > 0.0 && qb > 0.0 ? d / (qa * qb) : 1.0;
        w = 2.0 * acos(d > 1.0 ? 1.0 : d) * 1.01 + 1e-6;
        for (c = 0; c < 8; c++) {
            double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1],
                           (c & 4) ? hi[2] : lo[2]};
            umax =
                fmax(umax, fmax(upper_apply_len(&a, p, 0, NULL), upper_apply_len(&b, p, 0, NULL)));
            dumax = fmax(dumax, upper_apply_len(&a, p, 1, &b));
        }
        L = w * umax + dumax;
        /* samples close enough that the widening is 1% of the object's size */
        steps = (int)ceil(L / (2e-2 * (umax > 0.0 ? umax : 1.0)));
        if (steps < 1) steps = 1;
        if (steps > 64) steps = 64;
        margin = L / (2.0 * steps);
        a.trans = b.trans = evr_v3_make(0.0f, 0.0f, 0.0f);
        for (j = 0; j <= steps; j++) {
            float f = (float)j / (float)steps;
            evr_motion_key key = evr_motion_key_lerp(&a, &b, f);
            evr_m34 m = evr_motion_key_matrix(&key);
            evr_v3 t = evr_v3_lerp(ta, tb, f);
            double qlo[3] = {INFINITY, INFINITY, INFINITY},
                   qhi[3] = {-INFINITY, -INFINITY, -INFINITY};
            double tt[3] = {t.x, t.y, t.z};
            extend_corners(&m, lo, hi, qlo, qhi);
            if (j > 0)
                for (k = 0; k < 3; k++) {
                    blo[k] = fmin(blo[k], fmin(pt[k], tt[k]) + fmin(plo[k], qlo[k]) - margin);
                    bhi[k] = fmax(bhi[k], fmax(pt[k], tt[k]) + fmax(phi[k], qhi[k]) + margin);
                }
            for (k = 0; k < 3; k++) {
                plo[k] = qlo[k];
                phi[k] = qhi[k];
                pt[k] = tt[k];
            }
        }
    }
    for (k = 0; k < 3; k++) mag = fmax(mag, fmax(fabs(blo[k]), fabs(bhi[k])));
    for (k = 0; k < 3; k++) {
        /* float evaluation of the transforms (in the traversal and here) is off by a few ulps */
        double slack = 1e-6 * mag + 1e-30;
        out_lo[k] = evr_round_down(blo[k] - slack);
        out_hi[k] = evr_round_up(bhi[k] + slack);
    }
}
