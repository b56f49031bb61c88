/* The camera's projection: pixel centre to world ray, and world point to pixel (for photon
 * splatting). Perspective (a pinhole) or orthographic (glTF camera types). Camera space looks
 * along -Z with +Y up (glTF); pixel rows go top to bottom. */
#ifndef EVR_CORE_CAMERA_H
#define EVR_CORE_CAMERA_H

#include "core/vec.h"

typedef struct {
    int width, height;
    float tan_half_y; /* perspective: tan(yfov / 2) */
    float aspect;     /* width / height of the rendered image */
    int ortho;        /* 1: orthographic, parallel rays along -Z from the plane z = 0 */
    float half_h;     /* orthographic: half the view's height in scene units (glTF ymag) */
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
    c.ortho = 0;
    c.half_h = 0.0f;
    return c;
}

/* An orthographic camera whose view is 2 half_h high (the image's aspect sets its width, as a
 * perspective camera's yfov sets its horizontal angle). */
EVR_HD static inline evr_camera_intr evr_camera_intr_ortho(int width, int height, float half_h)
{
    evr_camera_intr c = evr_camera_intr_make(width, height, 0.0f);
    c.ortho = 1;
    c.half_h = half_h;
    return c;
}

/* The angle one pixel subtends at the image centre (radians): the spread angle of the ray cone
 * through a pixel, whose width at distance t is about spread * t (core/material.h's
 * evr_texture_lod). 0 for an orthographic camera, whose rays are parallel. */
EVR_HD static inline float evr_camera_pixel_spread(const evr_camera_intr *c)
{
    if (c->ortho) return 0.0f;
    return atanf(2.0f * c->tan_half_y / (float)c->height);
}

/* The width of a pixel's ray cone at distance t along a camera ray: the pixel's footprint
 * there, which filters textures. */
EVR_HD static inline float evr_camera_cone(const evr_camera_intr *c, float t)
{
    if (c->ortho) return 2.0f * c->half_h / (float)c->height;
    return evr_camera_pixel_spread(c) * t;
}

/* The size of a pixel on a plane facing the camera at depth z (along its axis). */
EVR_HD static inline float evr_camera_pixel_size(const evr_camera_intr *c, float z)
{
    if (c->ortho) return 2.0f * c->half_h / (float)c->height;
    return 2.0f * c->tan_half_y * fmaxf(z, 1e-6f) / (float)c->height;
}

/* Ray through image position (px, py) in pixels (pixel x's centre is x + 0.5). */
EVR_HD static inline evr_ray evr_camera_ray(const evr_camera_intr *c, const evr_m34 *pose, float px,
                                            float py)
{
    evr_ray r;
    if (c->ortho) {
        float ox = (2.0f * px / (float)c->width - 1.0f) * c->half_h * c->aspect;
        float oy = (1.0f - 2.0f * py / (float)c->height) * c->half_h;
        r.org = evr_m34_point(pose, evr_v3_make(ox, oy, 0.0f));
        r.dir = evr_v3_norm(evr_m34_vector(pose, evr_v3_make(0.0f, 0.0f, -1.0f)));
        return r;
    }
    float sx = (2.0f * px / (float)c->width - 1.0f) * c->tan_half_y * c->aspect;
    float sy = (1.0f - 2.0f * py / (float)c->height) * c->tan_half_y;
    r.org = evr_v3_make(pose->m[0][3], pose->m[1][3], pose->m[2][3]);
    r.dir = evr_v3_norm(evr_m34_vector(pose, evr_v3_make(sx, sy, -1.0f)));
    return r;
}

/* Image position of a world point given the inverse pose (world to camera); returns 0 when the
 * point is behind the camera (behind its plane z = 0, for an orthographic one). */
EVR_HD static inline int evr_camera_project(const evr_camera_intr *c, const evr_m34 *world_to_cam,
                                            evr_v3 p, float *px, float *py)
{
    evr_v3 q = evr_m34_point(world_to_cam, p);
    if (q.z >= 0.0f) return 0;
    if (c->ortho) {
        *px = (q.x / (c->half_h * c->aspect) + 1.0f) * 0.5f * (float)c->width;
        *py = (1.0f - q.y / c->half_h) * 0.5f * (float)c->height;
        return 1;
    }
    float sx = q.x / -q.z, sy = q.y / -q.z;
    *px = (sx / (c->tan_half_y * c->aspect) + 1.0f) * 0.5f * (float)c->width;
    *py = (1.0f - sy / c->tan_half_y) * 0.5f * (float)c->height;
    return 1;
}

#endif
