/* Dense ground truth of one pixel from its primary hit: depth, surface normal, and optical flow
 * computed from the motion, not from images.
 *
 * A backend hands back, per pixel and label time t, the primary hit (instance, triangle,
 * barycentrics u, v) through the pixel centre. The surface point it names is the same material
 * point at every time: p(tau) = X(tau) * bary(triangle vertices at tau, u, v), X the instance's
 * world transform (its track), the vertices the mesh's own or, for a deforming mesh, its vertices
 * at tau. Projecting p(tau) through the camera at tau gives where the pixel's surface point is in
 * the image at tau; its time derivative is the image-space velocity (camera motion included),
 * and its position at t + flow_dt the DSEC-style forward displacement. The host evaluates the
 * poses (from the scene's analytic animation) at a few times around t and calls these functions
 * with them, the same for either backend's hits.
 *
 * Conventions (README "Ground truth"): pixel x's centre is x + 0.5, rows top to bottom; depth is
 * the distance along the optical axis (minus z in glTF's camera frame, which looks along -Z);
 * the normal is the shading normal in the camera's optical frame (x right, y down, z forward),
 * facing the camera. Arithmetic in double: a velocity is a difference of nearby positions. */
#ifndef EVR_CORE_LABELS_H
#define EVR_CORE_LABELS_H

#include "core/camera.h"
#include "core/vec.h"

/* Stencil slots of the velocity: the poses at t + off[k] * h, weighted w[k] / h. */
#define EVR_LABEL_STENCIL 3

typedef struct {
    double x, y, z;
} evr_label_d3;

/* One time's view of a surface point: the instance's world transform, the triangle's vertices
 * in that transform's space, and the world-to-camera transform (the inverse of the camera's
 * pose, glTF axes), in double. */
typedef struct {
    evr_m34 inst;
    float tri[9];
    double w2c[3][4];
} evr_label_pose;

/* The world-to-camera transform of a camera pose (camera to world, rigid up to scale), in
 * double. */
EVR_HD static inline void evr_label_world_to_camera(const evr_m34 *pose, double w2c[3][4])
{
    double a[3][3], inv[3][3];
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) a[i][j] = (double)pose->m[i][j];
    inv[0][0] = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    inv[0][1] = a[0][2] * a[2][1] - a[0][1] * a[2][2];
    inv[0][2] = a[0][1] * a[1][2] - a[0][2] * a[1][1];
    inv[1][0] = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    inv[1][1] = a[0][0] * a[2][2] - a[0][2] * a[2][0];
    inv[1][2] = a[0][2] * a[1][0] - a[0][0] * a[1][2];
    inv[2][0] = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    inv[2][1] = a[0][1] * a[2][0] - a[0][0] * a[2][1];
    inv[2][2] = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    double det = a[0][0] * inv[0][0] + a[0][1] * inv[1][0] + a[0][2] * inv[2][0];
    double s = det != 0.0 ? 1.0 / det : 0.0;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) w2c[i][j] = inv[i][j] * s;
        w2c[i][3] = -(w2c[i][0] * (double)pose->m[0][3] + w2c[i][1] * (double)pose->m[1][3] +
                      w2c[i][2] * (double)pose->m[2][3]);
    }
}

/* The surface point (u, v) of the pose's triangle in camera space (glTF axes). */
EVR_HD static inline evr_label_d3 evr_label_camera_point(const evr_label_pose *p, float u, float v)
{
    const double w0 = 1.0 - (double)u - (double)v;
    double o[3], wp[3];
    evr_label_d3 c;
    int i;
    for (i = 0; i < 3; i++)
        o[i] = w0 * (double)p->tri[i] + (double)u * (double)p->tri[3 + i] +
               (double)v * (double)p->tri[6 + i];
    for (i = 0; i < 3; i++)
        wp[i] = (double)p->inst.m[i][0] * o[0] + (double)p->inst.m[i][1] * o[1] +
                (double)p->inst.m[i][2] * o[2] + (double)p->inst.m[i][3];
    c.x = p->w2c[0][0] * wp[0] + p->w2c[0][1] * wp[1] + p->w2c[0][2] * wp[2] + p->w2c[0][3];
    c.y = p->w2c[1][0] * wp[0] + p->w2c[1][1] * wp[1] + p->w2c[1][2] * wp[2] + p->w2c[1][3];
    c.z = p->w2c[2][0] * wp[0] + p->w2c[2][1] * wp[1] + p->w2c[2][2] * wp[2] + p->w2c[2][3];
    return c;
}

/* Image position of a camera-space point (core/camera.h's projection, in double); 0 when it is
 * behind the camera (behind its plane z = 0, for an orthographic one). */
EVR_HD static inline int evr_label_project(const evr_camera_intr *c, evr_label_d3 q, double *px,
                                           double *py)
{
    if (!(q.z < 0.0)) return 0;
    if (c->ortho) {
        const double hy = (double)c->half_h, hx = hy * (double)c->aspect;
        *px = (q.x / hx + 1.0) * 0.5 * (double)c->width;
        *py = (1.0 - q.y / hy) * 0.5 * (double)c->height;
        return 1;
    }
    const double ty = (double)c->tan_half_y, tx = ty * (double)c->aspect;
    *px = (q.x / -q.z / tx + 1.0) * 0.5 * (double)c->width;
    *py = (1.0 - q.y / -q.z / ty) * 0.5 * (double)c->height;
    return 1;
}

/* One pixel's labels; NaN where undefined (the point behind the camera at a time). */
typedef struct {
    float depth;     /* along the optical axis */
    float normal[3]; /* optical frame, unit, facing the camera */
    float flow[2];   /* image velocity, px/s */
    float disp[2];   /* image displacement from t to t + flow_dt, px */
} evr_label_px;

/* The labels of surface point (u, v): pose[0] at t, pose[1 .. EVR_LABEL_STENCIL] at the
 * velocity stencil's times (weights w, step h seconds: velocity = sum w[k] x(pose[1 + k]) / h),
 * pose[EVR_LABEL_STENCIL + 1] at t + flow_dt. nrm: the triangle's vertex normals at t in the
 * instance's space (9 floats). */
EVR_HD static inline void evr_label_pixel(const evr_camera_intr *c, const evr_label_pose *pose,
                                          const float *nrm, float u, float v, const double *w,
                                          double h, evr_label_px *out)
{
    const float nan = NAN;
    double x0 = 0.0, y0 = 0.0, x = 0.0, y = 0.0, vx = 0.0, vy = 0.0;
    int k, ok;
    evr_label_d3 q = evr_label_camera_point(&pose[0], u, v);
    out->depth = (float)-q.z;
    out->flow[0] = out->flow[1] = out->disp[0] = out->disp[1] = nan;
    ok = evr_label_project(c, q, &x0, &y0);
    for (k = 0; ok && k < EVR_LABEL_STENCIL; k++) {
        if (w[k] == 0.0) continue;
        ok = evr_label_project(c, evr_label_camera_point(&pose[1 + k], u, v), &x, &y);
        vx += w[k] * x;
        vy += w[k] * y;
    }
    if (ok) {
        out->flow[0] = (float)(vx / h);
        out->flow[1] = (float)(vy / h);
    }
    if (ok &&
        evr_label_project(c, evr_label_camera_point(&pose[EVR_LABEL_STENCIL + 1], u, v), &x, &y)) {
        out->disp[0] = (float)(x - x0);
        out->disp[1] = (float)(y - y0);
    }
    /* the shading normal: interpolated, to world, to camera (glTF axes), then the optical frame */
    const float w0 = 1.0f - u - v;
    evr_v3 n =
        evr_v3_make(w0 * nrm[0] + u * nrm[3] + v * nrm[6], w0 * nrm[1] + u * nrm[4] + v * nrm[7],
                    w0 * nrm[2] + u * nrm[5] + v * nrm[8]);
    n = evr_m34_normal(&pose[0].inst, n);
    double cn[3];
    for (k = 0; k < 3; k++)
        cn[k] = pose[0].w2c[k][0] * n.x + pose[0].w2c[k][1] * n.y + pose[0].w2c[k][2] * n.z;
    double l = sqrt(cn[0] * cn[0] + cn[1] * cn[1] + cn[2] * cn[2]);
    if (l > 0.0) {
        /* facing the camera: against the direction from the camera to the point */
        if (cn[0] * q.x + cn[1] * q.y + cn[2] * q.z > 0.0) l = -l;
        out->normal[0] = (float)(cn[0] / l);
        out->normal[1] = (float)(-cn[1] / l); /* optical frame: y down, z forward */
        out->normal[2] = (float)(-cn[2] / l);
    } else {
        out->normal[0] = out->normal[1] = out->normal[2] = nan;
    }
}

/* A velocity stencil for a label at t whose motion is defined on [lo, hi] (the curves hold
 * still outside; a central difference across an end would halve the velocity there): central
 * where t +- h lie inside, else one-sided of second order. off: offsets in steps of h. */
EVR_HD static inline void evr_label_stencil(double t, double h, double lo, double hi, double *off,
                                            double *w)
{
    if (t - h < lo && t + 2.0 * h <= hi) { /* forward */
        off[0] = 0.0, off[1] = 1.0, off[2] = 2.0;
        w[0] = -1.5, w[1] = 2.0, w[2] = -0.5;
    } else if (t + h > hi && t - 2.0 * h >= lo) { /* backward */
        off[0] = 0.0, off[1] = -1.0, off[2] = -2.0;
        w[0] = 1.5, w[1] = -2.0, w[2] = 0.5;
    } else {
        off[0] = -1.0, off[1] = 1.0, off[2] = 0.0;
        w[0] = -0.5, w[1] = 0.5, w[2] = 0.0;
    }
}

#endif
