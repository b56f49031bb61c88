/* A small builder for glTF 2.0 scenes, serialized to binary glTF (GLB).
 *
 * The built-in scenes are generated with it and then imported through Assimp like any user file,
 * so that the demo exercises the same path as real scenes and can be exported as-is.
 *
 *     evr_gltf *g = evr_gltf_new("my scene");
 *     int tex = evr_gltf_texture_png(g, "checker", pixels, 64, 64, 3);
 *     evr_gltf_material m;
 *     evr_gltf_material_init(&m, "paint");
 *     m.base_texture.index = tex;
 *     int mat = evr_gltf_add_material(g, &m);
 *     int mesh = evr_gltf_mesh(g, "quad", pos, nrm, uv, 4, idx, 6, mat);
 *     int node = evr_gltf_node(g, "quad", -1);
 *     evr_gltf_node_mesh(g, node, mesh);
 *     evr_gltf_node_translation(g, node, 0, 0, -2);
 *     ...
 *     st = evr_gltf_glb(g, &bytes, &size, err);
 *     evr_gltf_free(g);
 *
 * Every function returning an index returns -1 on failure; the first failure is remembered
 * (later calls do nothing) and reported by evr_gltf_glb, so callers check once at the end.
 * All arrays passed in are copied. Names are required (non-empty) on everything named.
 * Units and conventions are glTF's: metres, +Y up, right-handed, cameras and lights look along
 * their node's -Z, quaternions in x, y, z, w order, texture coordinates with (0,0) at the
 * top-left of the image, times in seconds. */
#ifndef EVR_SCENE_GLTF_WRITER_H
#define EVR_SCENE_GLTF_WRITER_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"

typedef struct evr_gltf evr_gltf;

typedef enum {
    EVR_GLTF_POINT = 0,
    EVR_GLTF_SPOT = 1,
    EVR_GLTF_DIRECTIONAL = 2
} evr_gltf_light_type;
typedef enum {
    EVR_GLTF_TRANSLATION = 0,
    EVR_GLTF_ROTATION = 1,
    EVR_GLTF_SCALE = 2,
    EVR_GLTF_WEIGHTS = 3 /* morph target weights */
} evr_gltf_path;
typedef enum { EVR_GLTF_LINEAR = 0, EVR_GLTF_STEP = 1 } evr_gltf_interp;

/* A texture as a material's slot uses it: the texture (from evr_gltf_texture_png, -1: none) and
 * its KHR_texture_transform, uv' = T(offset) R(rotation) S(scale) uv as the extension defines it
 * (rotation in radians); the identity (offset 0, rotation 0, scale 1) is not written. */
typedef struct {
    int index;
    float offset[2], rotation, scale[2];
} evr_gltf_texture_slot;

typedef enum {
    EVR_GLTF_OPAQUE = 0,
    EVR_GLTF_MASK = 1, /* alpha below alpha_cutoff is a hole */
    EVR_GLTF_BLEND = 2
} evr_gltf_alpha_mode;

/* A metallic-roughness material with the KHR_materials extensions evray reads. Colours are
 * linear; factors multiply their textures. Each extension is written (and listed in
 * extensionsUsed) only when a field differs from its default. */
typedef struct {
    const char *name;
    float base_color[4];                              /* RGBA in [0,1] */
    evr_gltf_texture_slot base_texture;               /* sRGB colour, alpha */
    float metallic, roughness;                        /* [0,1] */
    evr_gltf_texture_slot metallic_roughness_texture; /* data: roughness in G, metallic in B */
    evr_gltf_texture_slot normal_texture;             /* data: tangent-space normal */
    float normal_scale;                               /* finite (1) */
    evr_gltf_texture_slot occlusion_texture;          /* data: occlusion in R */
    float occlusion_strength;                         /* [0,1] (1) */
    float emissive[3];                                /* [0,1] */
    float emissive_strength; /* KHR_materials_emissive_strength: >= 0 (1), scales emissive */
    evr_gltf_texture_slot emissive_texture; /* sRGB */
    evr_gltf_alpha_mode alpha_mode;
    float alpha_cutoff; /* MASK: >= 0 (0.5) */
    int double_sided;
    int unlit;                                  /* KHR_materials_unlit */
    float transmission;                         /* KHR_materials_transmission: [0,1] (0) */
    evr_gltf_texture_slot transmission_texture; /* data: transmission in R */
    float ior;                                  /* KHR_materials_ior: >= 1 (1.5) */
    /* KHR_materials_volume: thickness >= 0 (0: thin-walled), attenuation_distance > 0
     * (INFINITY: none), attenuation_color in [0,1] (white) */
    float thickness, attenuation_distance, attenuation_color[3];
    /* KHR_materials_specular: factor in [0,1] (1), colour >= 0 (white) */
    float specular, specular_color[3];
} evr_gltf_material;

/* Returns NULL when out of memory. scene_name may be NULL. */
evr_gltf *evr_gltf_new(const char *scene_name);
void evr_gltf_free(evr_gltf *g);

/* Encodes 8-bit pixels (rows top to bottom, sRGB-encoded colour; channels 3 or 4) as a PNG
 * stored in the BIN chunk, with an image, and a texture that samples it with linear filtering
 * and repeat wrapping. Returns the texture index. */
int evr_gltf_texture_png(evr_gltf *g, const char *name, const uint8_t *pixels, int width,
                         int height, int channels);

/* Defaults: white, no textures (identity transforms), metallic 0, roughness 1, no emission
 * (strength 1), opaque (cutoff 0.5), double-sided, lit, no transmission, IOR 1.5, thin-walled
 * without attenuation, specular 1 white; normal scale and occlusion strength 1. */
void evr_gltf_material_init(evr_gltf_material *m, const char *name);
int evr_gltf_add_material(evr_gltf *g, const evr_gltf_material *m);

/* One triangle primitive. positions: 3 floats per vertex; normals (3, unit) and texcoords
 * (2, TEXCOORD_0) per vertex or NULL; indices: 3 per triangle, uint32. */
int evr_gltf_mesh(evr_gltf *g, const char *name, const float *positions, const float *normals,
                  const float *texcoords, uint32_t num_vertices, const uint32_t *indices,
                  uint32_t num_indices, int material);

/* One triangle primitive that may deform: evr_gltf_mesh's arrays, and
 *   tangents     TANGENT, 4 floats per vertex (unit xyz, w = +-1 the bitangent's sign), or NULL;
 *                needs normals
 *   skin         joints and weights (JOINTS_0, WEIGHTS_0), 4 per vertex: indices into the joints
 *                of the skin that the mesh's node gives (evr_gltf_node_skin), and weights >= 0
 *                summing to 1 (within 1e-5), a joint at most once with a non-zero weight; both
 *                NULL: not skinned. Joints are stored as unsigned bytes when every index of a
 *                non-zero weight is below 256, else as unsigned shorts; a joint whose weight is 0
 *                is stored as 0 (as glTF recommends).
 *   morph        num_targets targets, each a displacement of every vertex position
 *   targets      (target_positions: 3 floats per vertex, target after target) and optionally of
 *                every normal (target_normals, the same layout, or NULL); default_weights: the
 *                mesh's weights (num_targets of them, or NULL: zeros); target_names: num_targets
 *                names or NULL (written as mesh.extras.targetNames, the common convention).
 * Morph targets apply before the skin (glTF's order). */
typedef struct {
    const char *name;
    const float *positions, *normals, *texcoords;
    const float *tangents;
    uint32_t num_vertices;
    const uint32_t *indices;
    uint32_t num_indices;
    int material; /* -1: none */
    const uint16_t *joints;
    const float *weights;
    int num_targets;
    const float *target_positions, *target_normals, *default_weights;
    const char *const *target_names;
} evr_gltf_mesh_desc;

/* Defaults: nothing given, no material, not skinned, no morph targets. */
void evr_gltf_mesh_desc_init(evr_gltf_mesh_desc *d, const char *name);
int evr_gltf_add_mesh(evr_gltf *g, const evr_gltf_mesh_desc *d);

/* A skin: joints are existing node indices, distinct, with a common root node (glTF's rule);
 * inverse_bind holds 16 floats per joint (4x4, column-major as glTF stores them, last row
 * 0 0 0 1) taking the mesh's coordinates into the joint's space at bind time, or NULL
 * (identities); skeleton is the joints' closest common root or one of its ancestors, or -1. */
int evr_gltf_skin(evr_gltf *g, const char *name, const int *joints, int num_joints,
                  const float *inverse_bind, int skeleton);

/* Perspective camera; yfov in radians; aspect <= 0: not given; zfar <= 0: infinite. */
int evr_gltf_camera(evr_gltf *g, const char *name, float yfov, float aspect, float znear,
                    float zfar);

/* KHR_lights_punctual light. color: linear RGB (NULL: white); intensity in candela (point,
 * spot) or lux (directional); cone half-angles in radians (spot only; 0 <= inner < outer <= pi/2). */
int evr_gltf_light(evr_gltf *g, const char *name, evr_gltf_light_type type, const float color[3],
                   float intensity, float inner_cone, float outer_cone);

/* The same with every field, and a radius (metres, >= 0, point and spot lights only) written as
 * the light's "extras": {"radius": r} when > 0: the emitter's size, so that a smooth surface
 * reflects it as a disc (evr_light.radius). */
typedef struct {
    const char *name;
    evr_gltf_light_type type;
    float color[3];
    float intensity, inner_cone, outer_cone, radius;
} evr_gltf_light_desc;

/* Defaults: white, intensity 1, cones 0 and pi/4, radius 0. */
void evr_gltf_light_desc_init(evr_gltf_light_desc *d, const char *name, evr_gltf_light_type type);
int evr_gltf_add_light(evr_gltf *g, const evr_gltf_light_desc *d);

/* A node; parent is an existing node index or -1 for a root of the scene. */
int evr_gltf_node(evr_gltf *g, const char *name, int parent);
void evr_gltf_node_translation(evr_gltf *g, int node, float x, float y, float z);
void evr_gltf_node_rotation(evr_gltf *g, int node, float x, float y, float z, float w); /* unit */
void evr_gltf_node_scale(evr_gltf *g, int node, float x, float y, float z);
void evr_gltf_node_mesh(evr_gltf *g, int node, int mesh);
void evr_gltf_node_camera(evr_gltf *g, int node, int camera);
void evr_gltf_node_light(evr_gltf *g, int node, int light);
/* Skins the node's mesh, which must be skinned (evr_gltf_mesh_desc.joints) with joint indices
 * below the skin's joint count; glTF ignores the transform of a skinned mesh's node (the joints
 * place it), so leave it at the identity. A skinned mesh's node needs a skin. */
void evr_gltf_node_skin(evr_gltf *g, int node, int skin);
/* The node's morph weights, one per target of its mesh; without them the mesh's default
 * weights apply. */
void evr_gltf_node_weights(evr_gltf *g, int node, const float *weights, int count);

/* An animation, then its channels: one sampler each, count keys with strictly increasing times
 * (seconds, >= 0) and values 3 (translation, scale), 4 (rotation x y z w) or, for weights, one
 * per morph target of the node's mesh (set before the channel) floats per key. */
int evr_gltf_animation(evr_gltf *g, const char *name);
void evr_gltf_channel(evr_gltf *g, int animation, int node, evr_gltf_path path, const float *times,
                      const float *values, int count, evr_gltf_interp interp);

/* Records a failure found by the caller (e.g. out of memory while generating data) unless one
 * is already recorded. */
void evr_gltf_fail(evr_gltf *g, evr_status status, const char *msg);

/* The first failure so far (EVR_OK if none), its message copied into err when err is not NULL. */
evr_status evr_gltf_status(const evr_gltf *g, evr_error *err);

/* A built-in scene's variant (0: the scene as it always is): a seed its builder draws what
 * varies from (the eye: its gaze plan and its iris). */
void evr_gltf_set_variant(evr_gltf *g, uint64_t seed);
uint64_t evr_gltf_variant(const evr_gltf *g);

/* Serializes to GLB: 12-byte header, JSON chunk (space-padded), BIN chunk (zero-padded), all
 * 4-byte aligned. *glb is malloc'ed; free() it. The builder stays usable afterwards. */
evr_status evr_gltf_glb(evr_gltf *g, void **glb, size_t *size, evr_error *err);

#endif
