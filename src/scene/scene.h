/* The in-memory scene every backend renders: meshes in object space, materials, textures,
 * lights, one camera, and a flattened node hierarchy whose transforms are animated. Built by
 * the importer (scene/import.c, through Assimp) from a file or from a generated glTF. */
#ifndef EVR_SCENE_SCENE_H
#define EVR_SCENE_SCENE_H

#include <stddef.h>
#include <stdint.h>
#include "core/vec.h"
#include "core/motion.h"
#include "core/material.h"
#include "evray.h"

typedef struct {
    char name[64];
    uint32_t num_vertices, num_triangles;
    float *positions;  /* 3 per vertex, object space */
    float *normals;    /* 3 per vertex, unit; never NULL (generated from faces when missing) */
    float *uvs;        /* 2 per vertex, or NULL */
    uint32_t *indices; /* 3 per triangle */
    int material;      /* index into scene materials */
    evr_v3 bounds_min, bounds_max; /* object-space bounds of the positions */
} evr_mesh;

typedef struct {
    char name[64];
    evr_material_params p; /* core/material.h */
} evr_material;

typedef struct {
    int width, height;
    float *rgba; /* linear (sRGB decoded), 4 floats per texel, row 0 at v = 0 */
} evr_texture;

typedef enum { EVR_INTERP_LINEAR = 0, EVR_INTERP_STEP = 1 } evr_interp;

/* One animated property of a node: times in seconds, values 3 (translation, scale) or 4
 * (rotation, w x y z) floats per key. */
typedef struct {
    int num_keys;
    double *times;
    float *values;
    evr_interp interp;
} evr_curve;

typedef struct {
    char name[64];
    int parent;                /* index of the parent node, -1 for a root */
    evr_v3 translation, scale; /* rest pose (used where a curve is absent) */
    evr_quat rotation;
    evr_m34 rest_matrix; /* rest pose as a matrix (nodes given by a matrix keep it exactly) */
    int animated;        /* any curve present */
    evr_curve t_curve, r_curve, s_curve; /* num_keys == 0 when absent */
    int has_bounds;                      /* 1 when the node places meshes */
    evr_v3 bounds_min, bounds_max; /* union of the object-space bounds of the meshes it places */
} evr_node;

typedef struct {
    int mesh; /* index into meshes */
    int node; /* node whose world transform places the mesh */
} evr_instance;

typedef enum { EVR_LIGHT_POINT = 0, EVR_LIGHT_SPOT = 1, EVR_LIGHT_DIRECTIONAL = 2 } evr_light_type;

typedef struct {
    char name[64];
    evr_light_type type;
    int node;         /* -1: fixed in world space */
    float color[3];   /* linear RGB times intensity (candela for point/spot, lux for directional) */
    evr_v3 position;  /* in node space */
    evr_v3 direction; /* in node space, the way light travels (spot, directional) */
    float inner_cone, outer_cone; /* spot: half angles in radians */
} evr_light;

typedef struct {
    char name[64];
    int node;     /* -1: fixed in world space */
    float yfov;   /* vertical field of view, radians */
    float aspect; /* width / height from the file, 0 if unknown */
    float znear;
    /* Pose in node space: position, looking along -Z, up +Y after this transform. */
    evr_m34 local;
    int automatic; /* 1 when framed automatically (scene had no camera) */
} evr_camera_desc;

struct evr_scene {
    char source[512];
    char format[32];    /* the Assimp importer that read it, e.g. "glTF2 Importer" */
    int num_animations; /* animation clips in the file; all play together from time 0 */
    int num_meshes, num_materials, num_textures, num_nodes, num_instances, num_lights, num_cameras;
    evr_mesh *meshes;
    evr_material *materials;
    evr_texture *textures;
    evr_node *nodes;
    evr_instance *instances;
    evr_light *lights;
    evr_camera_desc *cameras;    /* all cameras of the file; at least one after import */
    int default_light;           /* 1 when the scene had no light and one was added */
    double anim_start, anim_end; /* time range covered by the animation curves (0,0 if static) */
    double frame_rate;           /* frames per second of the animation when the file says, else 0 */
    evr_v3 bounds_min, bounds_max; /* world bounds at rest pose */
};

/* Animation evaluation (scene/anim.c). */
evr_m34 evr_node_local_at(const evr_node *n, double t);
evr_m34 evr_node_world_at(const evr_scene *s, int node, double t);
/* 1 when the node or one of its ancestors has animation curves (0 for -1, no node). */
int evr_node_chain_animated(const evr_scene *s, int node);

/* Motion keys of a node's world transform over [t0, t1]: the fewest uniformly spaced keys
 * (2^k + 1, at most max_keys) such that interpolating them matches the curves within tol
 * (relative to the scene's size) and neighbouring rotations differ by less than 120 degrees.
 * Returns the number of keys written (1 for a node that does not move in the segment). */
int evr_node_motion_keys(const evr_scene *s, int node, double t0, double t1, float tol,
                         evr_motion_key *keys, int max_keys);

/* Index of the camera whose name is `name`, or -1; NULL or "" gives 0 (the first camera). */
int evr_scene_find_camera(const evr_scene *s, const char *name);

/* Frees everything a scene owns. */
void evr_scene_free_contents(evr_scene *s);

#endif
