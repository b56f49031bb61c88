/* The built-in scenes, each generated as a glTF document (demo_eye.c, demo_blink.c, ...), and the
 * small mesh-building helpers they share (demo.c). Internal to the library. */
#ifndef EVR_SCENE_DEMO_SCENES_H
#define EVR_SCENE_DEMO_SCENES_H

#include <stdint.h>
#include "evray.h"
#include "evray_experimental.h"
#include "scene/gltf_writer.h"

/* Each adds its whole scene to an empty builder; failures are recorded in the builder. */
void evr_demo_build_eye(evr_gltf *g);
void evr_demo_build_eye_drift(evr_gltf *g); /* the same with slow fixational drift */
void evr_demo_build_square(evr_gltf *g);
void evr_demo_build_disk(evr_gltf *g);
void evr_demo_build_cornell(evr_gltf *g);
void evr_demo_build_cornell_still(evr_gltf *g);
void evr_demo_build_cornell_bleed(evr_gltf *g);
void evr_demo_build_city(evr_gltf *g);
void evr_demo_build_blink(evr_gltf *g); /* morph-target lids and a skinned finger */

/* The city (demo_city.c) at a tessellation detail and a building count: EVR_CITY_DETAIL,
 * EVR_CITY_BUILDINGS and evr_demo_city_load are in evray_experimental.h. */
void evr_demo_build_city_with(evr_gltf *g, int detail, int count);
evr_status evr_demo_city_glb(int detail, int count, void **glb, size_t *size, evr_error *err);

/* A growing triangle mesh: positions, unit normals and texture coordinates per vertex. */
typedef struct {
    float *pos, *nrm, *uv;
    uint32_t *idx;
    uint32_t nv, ni, cap_v, cap_i;
    int failed; /* out of memory: further additions are ignored */
} evr_demo_mesh;

uint32_t evr_demo_mesh_vertex(evr_demo_mesh *m, const double p[3], const double n[3], double u,
                              double v);
/* The same with the position given in millimetres (stored in metres). */
uint32_t evr_demo_mesh_vertex_mm(evr_demo_mesh *m, double x, double y, double z, const double n[3],
                                 double u, double v);
/* Adds a triangle wound counter-clockwise around the mean of its vertex normals (so that the
 * geometric normal agrees with the shading normals); degenerate triangles are skipped. */
void evr_demo_mesh_triangle(evr_demo_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/* Two triangles per cell of a grid of (cols + 1) x (rows + 1) vertices added row by row
 * starting at vertex first. */
void evr_demo_mesh_grid(evr_demo_mesh *m, uint32_t first, int cols, int rows);
/* Hands the mesh to the builder (returns the mesh index, -1 on failure) and frees it. */
int evr_demo_mesh_finish(evr_gltf *g, evr_demo_mesh *m, const char *name, int material);

/* Rotation (x, y, z, w) that turns a camera or light at eye so that its -Z axis points at
 * target and its +Y axis leans towards up. */
void evr_demo_look_at(const double eye[3], const double target[3], const double up[3], float q[4]);

#endif
