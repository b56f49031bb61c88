/* Pinhole camera: pixel centre to world ray, and world point to pixel (for photon splatting).
 * Camera space looks along -Z with +Y up (glTF); pixel rows go top to bottom. */
#ifndef EVR_CORE_CAMERA_H
#define EVR_CORE_CAMERA_H

#include "core/vec.h"

typedef struct {
    int width, height;
    float tan_half_y; /* tan(yfov / 2) */
    float aspect;     /* width / height of the rendered image */
} evr_camera_intr;

typedef struct {
    evr_v3 org, dir;
} evr_ray;

EVR_HD static inline evr_camera_intr evr_camera_intr_make(int width, int height, float yfov)
{
    evr_camera_intr c;
    c.width = width;
    c.height = height;
    c.tan_half_y = tanf(0.5f * yfov);
    c.aspect = (float)width / (float)height;
    return c;
}

/* The angle one pixel subtends at the image centre (radians): the spread angle of the ray cone
 * through a pixel, whose width at distance t is about spread * t (core/material.h's
 * evr_texture_lod). */
EVR_HD static inline float evr_camera_pixel_spread(const evr_camera_intr *c)
{
    return atanf(2.0f * c->tan_half_y / (float)c->height);
}

/* Ray through image position (px, py) in pixels (pixel x's centre is x + 0.5). */
EVR_HD static inline evr_ray evr_camera_ray(const evr_camera_intr *c, const evr_m34 *pose, float px,
                                            float py)
{
    float sx = (2.0f * px / (float)c->width - 1.0f) * c->tan_half_y * c->aspect;
    float sy = (1.0f - 2.0f * py / (float)c->height) * c->tan_half_y;
    evr_ray r;
    r.org = evr_v3_make(pose->m[0][3], pose->m[1][3], pose->m[2][3]);
    r.dir = evr_v3_norm(evr_m34_vector(pose, evr_v3_make(sx, sy, -1.0f)));
    return r;
}

/* Image position of a world point given the inverse pose (world to camera); returns 0 when the
 * point is behind the camera. */
EVR_HD static inline int evr_camera_project(const evr_camera_intr *c, const evr_m34 *world_to_cam,
                                            evr_v3 p, float *px, float *py)
{
    evr_v3 q = evr_m34_point(world_to_cam, p);
    if (q.z >= 0.0f) return 0;
    float sx = q.x / -q.z, sy = q.y / -q.z;
    *px = (sx / (c->tan_half_y * c->aspect) + 1.0f) * 0.5f * (float)c->width;
    *py = (1.0f - sy / c->tan_half_y) * 0.5f * (float)c->height;
    return 1;
}

#endif
