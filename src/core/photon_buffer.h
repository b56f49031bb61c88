/* The image-space photon buffer: its layout, where a stored photon lands and what the camera
 * must see for it to count, lock-free insertion with a canonical order, and the camera's view of
 * each cell. */
#ifndef EVR_CORE_PHOTON_BUFFER_H
#define EVR_CORE_PHOTON_BUFFER_H

#include <stddef.h>
#include <stdint.h>
#include "core/shading.h"

#if defined(__CUDA_ARCH__) /* nvcc's device pass; its host pass is the host compiler's */
#define EVR_ATOMIC_INC_U32(p) atomicAdd((unsigned int *)(p), 1u)
/* a product that is never fused with an addition (nvcc fuses a * b + c into one rounding where
 * it likes; the C compiler here, ISO C without FMA, never does) */
#define EVR_MUL_RN(a, b) __fmul_rn((a), (b))
#else
#define EVR_ATOMIC_INC_U32(p) __atomic_fetch_add((p), 1u, __ATOMIC_RELAXED)
#define EVR_MUL_RN(a, b) ((a) * (b))
#endif

typedef struct {
    float p[3], n[3]; /* world position, normal on the side the photon came from */
    float flux[3];    /* incident flux the photon stands for (RGB) */
    uint32_t key;     /* photon number * 16 + bounce: a canonical order */
} evr_photon;

/* The image plus a guard band of `margin` pixels on every side (so that pixels near the image's
 * border have photons all round them): width x height cells, width = image width + 2 margin,
 * of `layers` photons each. Image pixel (x, y), -margin <= x < image width + margin, is cell
 * i = (y + margin) * width + x + margin; layer k of cell i is slots[k * width * height + i];
 * count[i] is how many photons arrived at cell i (those beyond `layers` were dropped and counted
 * in *collisions). Host or device pointers; the owner zeroes count and *collisions. */
typedef struct {
    int width, height, layers, margin;
    evr_photon *slots;
    uint32_t *count;
    uint32_t *collisions;
    /* Optional (NULL: none): what the camera sees through each cell's centre, 8 floats per cell:
     * position (3), normal facing the camera (3), the surface area the cell covers there, the
     * variance of that footprint (evr_photon_cell_view); a cell that sees nothing has area 0.
     * evr_photon_gather then normalizes its kernel over the part of the disk that lies on
     * surfaces like the query's, not the whole disk (no darkening at creases and silhouettes). */
    float *gbuf;
    /* Optional (NULL: none; --gi-blur, core/photon_blur.h): per cell, the scene instance seen
     * through its centre (-1: none) and the blurred irradiance estimate there (RGB). */
    int *view_inst;
    float *blur;
} evr_photon_buffer;

/* Image pixel of world point p for the camera (world_to_cam = inverse pose), which may lie up
 * to margin pixels outside the image; 0 when behind the camera or farther out. */
EVR_HD static inline int evr_photon_pixel(const evr_camera_intr *c, const evr_m34 *world_to_cam,
                                          evr_v3 p, int margin, int *x, int *y)
{
    float px = -1e9f, py = -1e9f, m = (float)margin;
    if (!evr_camera_project(c, world_to_cam, p, &px, &py)) return 0;
    if (!(px >= -m && py >= -m && px < (float)c->width + m && py < (float)c->height + m)) return 0;
    *x = (int)floorf(px);
    *y = (int)floorf(py);
    if (*x >= c->width + margin) *x = c->width + margin - 1;
    if (*y >= c->height + margin) *y = c->height + margin - 1;
    return 1;
}

/* A photon that stays at s at time f is kept where the camera sees it: the cell (x, y) it
 * lands in, and the ray r from s towards the camera that must be free over [*tnear, *tfar).
 * 0 when the camera is behind the surface or the point projects outside the image and its band. */
EVR_HD static inline int evr_photon_view_ray(const evr_render_scene *rs, const evr_surface *s,
                                             float f, int margin, float eps, int *x, int *y,
                                             evr_ray *r, float *tnear, float *tfar)
{
    evr_m34 pose = evr_rs_camera_pose(rs, f), inv = evr_m34_inverse(&pose);
    evr_v3 cam = evr_v3_make(pose.m[0][3], pose.m[1][3], pose.m[2][3]);
    evr_v3 d = evr_v3_sub(cam, s->p);
    float dist = evr_v3_len(d);
    if (rs->camera.ortho) { /* the camera's ray through s: straight back to its plane */
        const evr_v3 back = evr_v3_norm(evr_m34_vector(&pose, evr_v3_make(0.0f, 0.0f, 1.0f)));
        dist = evr_v3_dot(d, back);
        d = evr_v3_scale(back, dist);
    }
    if (!(dist > 0.0f) || evr_v3_dot(d, s->n) <= 0.0f) return 0;
    if (!evr_photon_pixel(&rs->camera, &inv, s->p, margin, x, y)) return 0;
    r->org = s->p;
    r->dir = evr_v3_scale(d, 1.0f / dist);
    *tnear = evr_shadow_tnear(s, r->dir, eps);
    *tfar = dist * (1.0f - 1e-4f);
    return 1;
}

/* The buffer's record of a photon stored at s. */
EVR_HD static inline evr_photon evr_photon_make(const evr_surface *s, const float flux[3],
                                                uint32_t key)
{
    evr_photon ph;
    ph.p[0] = s->p.x;
    ph.p[1] = s->p.y;
    ph.p[2] = s->p.z;
    ph.n[0] = s->n.x;
    ph.n[1] = s->n.y;
    ph.n[2] = s->n.z;
    ph.flux[0] = flux[0];
    ph.flux[1] = flux[1];
    ph.flux[2] = flux[2];
    ph.key = key;
    return ph;
}

/* Lock-free insertion: an atomic increment claims a layer; a photon arriving at a full cell is
 * dropped and counted as a collision. Returns 1 when stored. Threads inserting concurrently
 * store the same set of photons whenever no cell overflows (the order of a cell's layers may
 * differ: evr_photon_buffer_sort_cell restores the canonical order). */
EVR_HD static inline int evr_photon_buffer_insert(evr_photon_buffer *b, int x, int y,
                                                  const evr_photon *ph)
{
    size_t i = (size_t)(y + b->margin) * (size_t)b->width + (size_t)(x + b->margin);
    uint32_t k = EVR_ATOMIC_INC_U32(&b->count[i]);
    if (k >= (uint32_t)b->layers) {
        EVR_ATOMIC_INC_U32(b->collisions);
        return 0;
    }
    b->slots[(size_t)k * (size_t)b->width * (size_t)b->height + i] = *ph;
    return 1;
}

/* Sorts one cell's layers by key (insertion sort over a handful). */
EVR_HD static inline void evr_photon_buffer_sort_cell(evr_photon_buffer *b, size_t i)
{
    size_t npix = (size_t)b->width * (size_t)b->height;
    int n = b->count[i] < (uint32_t)b->layers ? (int)b->count[i] : b->layers, a, c;
    for (a = 1; a < n; a++) {
        evr_photon v = b->slots[(size_t)a * npix + i];
        for (c = a; c > 0 && b->slots[(size_t)(c - 1) * npix + i].key > v.key; c--)
            b->slots[(size_t)c * npix + i] = b->slots[(size_t)(c - 1) * npix + i];
        b->slots[(size_t)c * npix + i] = v;
    }
}

/* The camera's ray (pose) through the centre of buffer cell (cx, cy), guard band included. */
EVR_HD static inline evr_ray evr_photon_cell_ray(const evr_render_scene *rs, const evr_m34 *pose,
                                                 const evr_photon_buffer *b, int cx, int cy)
{
    return evr_camera_ray(&rs->camera, pose, (float)(cx - b->margin) + 0.5f,
                          (float)(cy - b->margin) + 0.5f);
}

/* A cell's view (gbuf, 8 floats) from the surface s met at distance t along its ray; fwd: the
 * camera's forward axis. The area is the pixel's at unit distance * depth^2 * cos(off-axis
 * angle) / |cos of the incidence| (the cosine at least 0.1); an orthographic camera's pixel has
 * the same area at every depth. The footprint is a strip w wide and w / cos long (w^2 = area *
 * cos); its variance (w^2 + (w / cos)^2) / 12 = area (cos + 1 / cos) / 12 lets a gather take the
 * kernel's integral over the strip rather than its value at the centre (evr_cell_area_weight):
 * on a surface seen at a grazing angle a strip is as long as the kernel is wide, and centre
 * values alone swing as a moving point's kernel passes over the strips. */
EVR_HD static inline void evr_photon_cell_view(const evr_render_scene *rs, evr_v3 fwd,
                                               const evr_surface *s, evr_ray ray, float t,
                                               float g[8])
{
    const float a = 4.0f * rs->camera.tan_half_y * rs->camera.tan_half_y /
                    ((float)rs->camera.height * (float)rs->camera.height);
    float ca = evr_v3_dot(ray.dir, fwd), z = t * ca;
    float ct = fmaxf(fabsf(evr_v3_dot(s->n, ray.dir)), 0.1f);
    g[0] = s->p.x;
    g[1] = s->p.y;
    g[2] = s->p.z;
    g[3] = s->n.x;
    g[4] = s->n.y;
    g[5] = s->n.z;
    if (rs->camera.ortho) {
        const float px = evr_camera_pixel_size(&rs->camera, t);
        g[6] = px * px / ct;
    } else {
        g[6] = a * z * z * ca / ct;
    }
    g[7] = g[6] * (ct + 1.0f / ct) * (1.0f / 12.0f);
}

/* A cell's share of the kernel's integral over the surfaces the camera sees, for a query at
 * squared distance d2 from the cell's view g with the kernel's variance s2 (sigma^2): the
 * Gaussian convolved with the footprint taken as a Gaussian of variance g[7] (the integral over
 * the plane stays the area's), counted while the footprint reaches within r^2 = lim2
 * (evr_cell_area_reaches). Products unfused (EVR_MUL_RN: the same bits wherever computed). */
EVR_HD static inline int evr_cell_area_reaches(const float *g, float d2, float lim2)
{
    return g[6] > 0.0f && d2 <= lim2 + 4.0f * g[7];
}

EVR_HD static inline float evr_cell_area_weight(const float *g, float d2, float s2)
{
    const float se = s2 + g[7];
    return EVR_MUL_RN(EVR_MUL_RN(expf(EVR_MUL_RN(d2, -0.5f / se)), s2 / se), g[6]);
}

#endif
