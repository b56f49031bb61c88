/* The render-ready scene both backends read: flat arrays (host or device pointers) of meshes,
 * materials, textures, instances and lights, plus the motion keys of the current segment. */
#ifndef EVR_CORE_RENDER_SCENE_H
#define EVR_CORE_RENDER_SCENE_H

#include <stdint.h>
#include "core/motion.h"
#include "core/camera.h"

typedef struct {
    const float *positions, *normals, *uvs; /* uvs may be NULL */
    const float *tangents; /* 4 per vertex (xyz unit, w the bitangent's sign), or NULL */
    const uint32_t *indices;
    uint32_t num_triangles;
    int material;
    int filter; /* tests its hits need (EVR_FILTER_* of core/hit_filter.h), 0: none */
} evr_mesh_view;

/* A material's parameters, defined with the model that reads them in core/material.h. */
typedef struct evr_material_params evr_material_params;

/* A texture and its mip levels: level 0 is width x height texels, level k+1 halves level k
 * (rounded down, at least 1: evr_mip_size) and follows it in rgba, levels in all (down to 1 x 1
 * when built at import: scene/texture_mips.c); 4 floats per texel, rows from v = 0. Level k
 * starts at 4 * (the texels of levels 0 .. k-1): evr_texture_level_view. */
typedef struct {
    int width, height, levels; /* levels >= 1 */
    const float *rgba;
} evr_texture_view;

/* The size along one axis of level k of a texture n texels wide: floor(n / 2^k), at least 1. */
EVR_HD static inline int evr_mip_size(int n, int k)
{
    int m = k < 31 ? n >> k : 0;
    return m > 0 ? m : 1;
}

/* The texels of t's levels 0 .. k-1: where level k starts, in texels (k = t->levels: all). */
EVR_HD static inline long evr_texture_texels(const evr_texture_view *t, int k)
{
    long n = 0;
    for (int i = 0; i < k; i++)
        n += (long)evr_mip_size(t->width, i) * (long)evr_mip_size(t->height, i);
    return n;
}

/* Level k (0 <= k < t->levels) of t as a texture of one level. */
EVR_HD static inline evr_texture_view evr_texture_level_view(const evr_texture_view *t, int k)
{
    evr_texture_view l;
    const long off = evr_texture_texels(t, k);
    l.width = evr_mip_size(t->width, k);
    l.height = evr_mip_size(t->height, k);
    l.levels = 1;
    l.rgba = t->rgba + 4 * off;
    return l;
}

typedef struct {
    int type;  /* evr_light_type */
    int track; /* motion track index, -1: fixed (pos/dir are world) */
    float color[3];
    evr_v3 pos, dir; /* in the track's space */
    float cos_inner, cos_outer;
    float radius; /* point and spot: the emitting sphere's radius (0: a point) */
} evr_light_view;

typedef struct {
    int mesh;
    int track;  /* motion track of the instance's node (a skinned mesh: the world frame) */
    int deform; /* index into evr_render_scene.deforms, -1: the mesh's own vertices */
} evr_instance_view;

/* A deforming instance's vertices over the current segment: num_keys >= 1 keys at uniform
 * times 0, 1/(num_keys-1), ..., 1, each num_vertices positions and unit normals (3 floats each,
 * key-major), in the instance's track space. A ray at time f sees every vertex linearly
 * interpolated between the keys around f (evr_deform_lerp, on both backends). */
typedef struct {
    int num_keys;
    uint32_t num_vertices;
    const float *positions, *normals;
} evr_deform_view;

typedef struct {
    const evr_mesh_view *meshes;
    const evr_material_params *materials;
    const evr_texture_view *textures;
    const evr_instance_view *instances;
    const evr_light_view *lights;
    const evr_deform_view *deforms; /* of the current segment, like the keys */
    int num_instances, num_lights, num_deforms;
    /* Motion of the current segment: track i has track_count[i] keys at keys + track_offset[i]. */
    const evr_motion_key *keys;
    const int *track_offset, *track_count;
    int camera_track;
    evr_m34 camera_local; /* camera pose in its track's space */
    evr_camera_intr camera;
    float ambient; /* ambient irradiance as a fraction of pi (radiance = albedo * ambient) */
    float ray_eps; /* offset for secondary rays, scaled to the scene */
    const float *bsdf_table; /* core/bsdf.h's albedo table (NULL: single scattering only) */
    int max_bounces;         /* reflections and refractions a camera ray may take */
    int translucent;         /* some material transmits or blends: shadow rays pass them */
} evr_render_scene;

EVR_HD static inline evr_motion_track evr_rs_track(const evr_render_scene *rs, int i)
{
    evr_motion_track t;
    t.keys = rs->keys + rs->track_offset[i];
    t.n = rs->track_count[i];
    return t;
}

/* The key interval of time f over n keys: *a is the first key, the return value the fraction. */
EVR_HD static inline float evr_key_interval(int n, float f, int *a)
{
    if (n <= 1) {
        *a = 0;
        return 0.0f;
    }
    float x = f * (float)(n - 1);
    int i = (int)floorf(x);
    if (i < 0) i = 0;
    if (i > n - 2) i = n - 2;
    *a = i;
    return x - (float)i;
}

/* Vertex v of a deforming instance in key interval a at fraction fr (evr_key_interval of the
 * time: what a ray traversal works out once for all the vertices it reads); 3 floats at base:
 * positions or normals. Between equal keys the key itself, bit for bit, so that a still stretch
 * stays still. */
EVR_HD static inline evr_v3 evr_deform_lerp_in(const evr_deform_view *d, const float *base,
                                               uint32_t v, int a, float fr)
{
    const float *p = base + ((size_t)a * d->num_vertices + v) * 3;
    evr_v3 pa = evr_v3_make(p[0], p[1], p[2]);
    if (d->num_keys <= 1) return pa;
    const float *q = p + (size_t)d->num_vertices * 3;
    if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) return pa;
    return evr_v3_make(p[0] + (q[0] - p[0]) * fr, p[1] + (q[1] - p[1]) * fr,
                       p[2] + (q[2] - p[2]) * fr);
}

/* Vertex v of a deforming instance at time f (evr_deform_lerp_in). */
EVR_HD static inline evr_v3 evr_deform_lerp(const evr_deform_view *d, const float *base, uint32_t v,
                                            float f)
{
    int a;
    const float fr = evr_key_interval(d->num_keys, f, &a);
    return evr_deform_lerp_in(d, base, v, a, fr);
}

/* Position and normal (not unit between keys) of vertex v of mesh view m as instance inst shows
 * it at time f. */
EVR_HD static inline evr_v3 evr_rs_vertex(const evr_render_scene *rs, int inst,
                                          const evr_mesh_view *m, uint32_t v, float f)
{
    const int d = rs->instances[inst].deform;
    if (d >= 0) return evr_deform_lerp(&rs->deforms[d], rs->deforms[d].positions, v, f);
    return evr_v3_make(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]);
}
EVR_HD static inline evr_v3 evr_rs_normal(const evr_render_scene *rs, int inst,
                                          const evr_mesh_view *m, uint32_t v, float f)
{
    const int d = rs->instances[inst].deform;
    if (d >= 0) return evr_deform_lerp(&rs->deforms[d], rs->deforms[d].normals, v, f);
    return evr_v3_make(m->normals[3 * v], m->normals[3 * v + 1], m->normals[3 * v + 2]);
}

/* A ray's closest hit: distance, barycentrics, triangle and scene instance. */
typedef struct {
    float t, u, v;
    unsigned prim;
    int inst;
} evr_hit;

/* Camera pose at normalized segment time f. */
EVR_HD static inline evr_m34 evr_rs_camera_pose(const evr_render_scene *rs, float f)
{
    evr_m34 w = evr_motion_eval(evr_rs_track(rs, rs->camera_track), f);
    return evr_m34_mul(w, rs->camera_local);
}

#endif
