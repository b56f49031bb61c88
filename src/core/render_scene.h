/* The render-ready scene both backends read: flat arrays (host or device pointers) of meshes,
 * materials, textures, instances and lights, plus the motion keys of the current segment. */
#ifndef EVR_CORE_RENDER_SCENE_H
#define EVR_CORE_RENDER_SCENE_H

#include <stdint.h>
#include "core/motion.h"
#include "core/camera.h"

typedef struct {
    const float *positions, *normals, *uvs; /* uvs may be NULL */
    const uint32_t *indices;
    uint32_t num_triangles;
    int material;
} evr_mesh_view;

/* A material's parameters, defined with the model that reads them in core/material.h. */
typedef struct evr_material_params evr_material_params;

typedef struct {
    int width, height;
    const float *rgba; /* linear, 4 floats per texel */
} evr_texture_view;

typedef struct {
    int type;  /* evr_light_type */
    int track; /* motion track index, -1: fixed (pos/dir are world) */
    float color[3];
    evr_v3 pos, dir; /* in the track's space */
    float cos_inner, cos_outer;
} evr_light_view;

typedef struct {
    int mesh;
    int track; /* motion track of the instance's node */
} evr_instance_view;

typedef struct {
    const evr_mesh_view *meshes;
    const evr_material_params *materials;
    const evr_texture_view *textures;
    const evr_instance_view *instances;
    const evr_light_view *lights;
    int num_instances, num_lights;
    /* Motion of the current segment: track i has track_count[i] keys at keys + track_offset[i]. */
    const evr_motion_key *keys;
    const int *track_offset, *track_count;
    int camera_track;
    evr_m34 camera_local; /* camera pose in its track's space */
    evr_camera_intr camera;
    float ambient; /* ambient irradiance as a fraction of pi (radiance = albedo * ambient) */
    float ray_eps; /* offset for secondary rays, scaled to the scene */
} evr_render_scene;

EVR_HD static inline evr_motion_track evr_rs_track(const evr_render_scene *rs, int i)
{
    evr_motion_track t;
    t.keys = rs->keys + rs->track_offset[i];
    t.n = rs->track_count[i];
    return t;
}

/* Camera pose at normalized segment time f. */
EVR_HD static inline evr_m34 evr_rs_camera_pose(const evr_render_scene *rs, float f)
{
    evr_m34 w = evr_motion_eval(evr_rs_track(rs, rs->camera_track), f);
    return evr_m34_mul(w, rs->camera_local);
}

#endif
