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

/* A mesh's skin (glTF skin, Assimp bones): a vertex's world position is
 * sum_k weights[k] * (world(joint_nodes[j_k]) * inverse_bind[j_k]) * p over its influences, its
 * instance's node transform ignored (the glTF rule; Assimp's bones are read the same way). */
typedef struct {
    int num_joints;
    int *joint_nodes;      /* node of each joint */
    evr_m34 *inverse_bind; /* per joint: mesh space to the joint's space at bind time */
    int influences;        /* per vertex (a vertex with fewer has zero weights) */
    uint16_t *joints;      /* influences per vertex: index into joint_nodes */
    float *weights;        /* influences per vertex, summing to 1 */
} evr_skin;

/* A mesh's morph targets: p = p0 + sum_j w_j * d_positions[j]; normals likewise, then unit. */
typedef struct {
    int num_targets;
    float *d_positions;     /* num_targets * num_vertices * 3 */
    float *d_normals;       /* the same size, or NULL (normals follow the positions only) */
    float *default_weights; /* num_targets: the mesh's weights where its node gives none */
} evr_morph;

typedef struct {
    char name[64];
    uint32_t num_vertices, num_triangles;
    float *positions;  /* 3 per vertex, object space */
    float *normals;    /* 3 per vertex, unit; never NULL (generated from faces when missing) */
    float *uvs;        /* 2 per vertex, or NULL */
    float *tangents;   /* 4 per vertex (xyz unit, w = +-1 the bitangent's sign), or NULL */
    uint32_t *indices; /* 3 per triangle */
    int material;      /* index into scene materials */
    evr_v3 bounds_min, bounds_max; /* object-space bounds of the positions */
    evr_skin *skin;                /* NULL: not skinned */
    evr_morph *morph;              /* NULL: no morph targets */
} evr_mesh;

typedef struct {
    char name[64];
    evr_material_params p; /* core/material.h */
} evr_material;

typedef struct {
    int width, height;
    float *rgba; /* 4 floats per texel, row 0 at v = 0: linear (colour slots sRGB-decoded) */
    int levels;  /* mip levels in rgba after level 0 (evr_texture_view's layout); 1: level 0 */
} evr_texture;

typedef enum { EVR_INTERP_LINEAR = 0, EVR_INTERP_STEP = 1 } evr_interp;

/* One animated property of a node: times in seconds, values 3 (translation, scale), 4
 * (rotation, w x y z) or the node's num_weights (morph weights) floats per key. */
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
    int num_weights;   /* morph target weights of the meshes it places (0: none) */
    float *weights;    /* rest weights (the node's, else its mesh's defaults), num_weights */
    evr_curve w_curve; /* morph weights over time, num_weights values per key */
    int has_bounds;    /* 1 when the node places meshes */
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
    float radius; /* point and spot: radius of the emitting sphere (extras "radius"), 0: a point */
} evr_light;

typedef struct {
    char name[64];
    int node;     /* -1: fixed in world space */
    float yfov;   /* vertical field of view, radians (perspective) */
    int ortho;    /* 1: orthographic (glTF type "orthographic"; Assimp's mOrthographicWidth) */
    float ymag;   /* orthographic: half the view's height in scene units */
    float xfov;   /* > 0: the file gives the horizontal angle only (radians), and the image's
                     aspect sets yfov (evr_camera_yfov) */
    float aspect; /* width / height from the file, 0 if unknown */
    float znear;
    /* Pose in node space: position, looking along -Z, up +Y after this transform. */
    evr_m34 local;
    int automatic; /* 1 when framed automatically (scene had no camera) */
} evr_camera_desc;

/* One animation clip of the file (an aiAnimation) and whether it plays (scene/import_clips.c has
 * the rule). Every played clip starts at time 0: its keys keep the times the file gives them. */
typedef struct {
    char name[64];
    double start, end; /* its first and last key, seconds (0, 0 without keys on the scene) */
    int num_nodes;     /* nodes it animates: transforms, morph weights or mesh channels */
    int played;        /* 1 when its curves are imported */
    int conflict;      /* not played by the default rule: the first played clip that animates one
                          of its nodes; -1 otherwise */
} evr_clip;

/* How the played clips were chosen (evr_load_options.animation). */
typedef enum {
    EVR_CLIPS_DEFAULT = 0, /* the default rule */
    EVR_CLIPS_ALL = 1,     /* "all": every clip, the first clip winning where two animate a curve */
    EVR_CLIPS_ONE = 2      /* one clip by name or index */
} evr_clip_choice;

struct evr_scene {
    char source[512];
    char format[32];    /* the Assimp importer that read it, e.g. "glTF2 Importer" */
    int num_animations; /* animation clips in the file (clips: one per clip) */
    evr_clip *clips;
    evr_clip_choice clip_choice;
    char notice[512]; /* one line for the user (evr_scene_notice), "" when nothing to say */
    int num_meshes, num_materials, num_textures, num_nodes, num_instances, num_lights, num_cameras;
    evr_mesh *meshes;
    evr_material *materials;
    evr_texture *textures;
    evr_node *nodes;
    evr_instance *instances;
    evr_light *lights;
    evr_camera_desc *cameras;    /* all cameras of the file; at least one after import */
    int default_light;           /* 1 when the scene had no light and one was added */
    double anim_start, anim_end; /* time range of the played clips' curves (0,0 if static) */
    double frame_rate;           /* frames per second of the animation when the file says, else 0 */
    evr_v3 bounds_min, bounds_max; /* world bounds at rest pose */
    char *warnings;   /* what evray does not render of the file: lines ending in '\n', or NULL */
    int num_warnings; /* how many there were (the text keeps the first EVR_MAX_WARNINGS) */
    evr_load_times times; /* where the load's time went (evr_scene_load_times) */
};

#define EVR_MAX_WARNINGS 16
#define EVR_PI_D 3.14159265358979323846

/* Animation evaluation (scene/anim.c). */
evr_m34 evr_node_local_at(const evr_node *n, double t);
evr_m34 evr_node_world_at(const evr_scene *s, int node, double t);
/* 1 when the node or one of its ancestors has animation curves (0 for -1, no node). */
int evr_node_chain_animated(const evr_scene *s, int node);

/* Deformation (scene/deform.c). An instance deforms when its mesh has a skin or morph targets;
 * evr_instance_deformed_at writes its vertices at time t: in world space for a skinned mesh (its
 * node ignored), else in its node's space; normals unit (NULL: not wanted). */
int evr_instance_deforms(const evr_scene *s, int instance);
/* Whether the deformation can change over time: a joint's or the weights' curves. */
int evr_instance_deform_animated(const evr_scene *s, int instance);
int evr_instance_deformed_at(const evr_scene *s, int instance, double t, float *positions,
                             float *normals); /* 0: out of memory */
/* The same for vertices [first, end) only (positions and normals still indexed by vertex), for
 * evaluating one instance on several threads. */
int evr_instance_deformed_range(const evr_scene *s, int instance, double t, uint32_t first,
                                uint32_t end, float *positions, float *normals);
/* The morph weights of node n at time t into w (n->num_weights of them). */
void evr_node_weights_at(const evr_node *n, double t, float *w);

/* Fitting motion keys to a moving frame (a node's world transform, the camera's pose): the
 * fewest uniformly spaced keys (2^k + 1, at most max_keys) such that interpolating them moves
 * every probe point (in the frame's space) within limit of where pose puts it, at the quarter
 * points of every key interval and at the inner times (where the motion bends, inside
 * (t0, t1)), and neighbouring rotations differ by less than 120 degrees. moves 0: one key, pose
 * at t0. One key too when the frame holds still over the segment. Returns the keys written. */
typedef evr_m34 (*evr_pose_fn)(const void *user, double t);
typedef struct {
    evr_pose_fn pose;
    const void *user;
    int moves;
    const evr_v3 *probes;
    int num_probes;
    const double *inner;
    int num_inner;
    float limit;
} evr_motion_fit;
int evr_motion_fit_keys(const evr_motion_fit *fit, double t0, double t1, evr_motion_key *keys,
                        int max_keys);
/* The scene's size the key tolerance is relative to (its rest bounds' diagonal, 1 if none). */
float evr_motion_fit_size(const evr_scene *s);
/* A frame's probe points without geometry: its origin and unit axes scaled by size, so that a
 * rotation is checked as the motion of points at that distance. Returns 4. */
int evr_motion_frame_probes(float size, evr_v3 *p);

/* Appends the key times of a node's curves and its ancestors' curves that lie strictly inside
 * (t0, t1) to out[n..cap): where a piecewise curve bends, a fit must look. Returns the new
 * count. */
int evr_node_inner_key_times(const evr_scene *s, int node, double t0, double t1, double *out, int n,
                             int cap);
#define EVR_MAX_INNER_TIMES 256

/* Motion keys of a node's world transform over [t0, t1]: the fewest uniformly spaced keys
 * (2^k + 1, at most max_keys) such that interpolating them matches the curves within tol
 * (relative to the scene's size) and neighbouring rotations differ by less than 120 degrees.
 * Returns the number of keys written (1 for a node that does not move in the segment). */
int evr_node_motion_keys(const evr_scene *s, int node, double t0, double t1, float tol,
                         evr_motion_key *keys, int max_keys);

/* The vertical field of view of camera c on an image of the given aspect (width / height). */
float evr_camera_yfov(const evr_camera_desc *c, float aspect);

/* Index of the camera whose name is `name`, or -1; NULL or "" gives 0 (the first camera). */
int evr_scene_find_camera(const evr_scene *s, const char *name);

/* Frees everything a scene owns. */
void evr_scene_free_contents(evr_scene *s);

#endif
