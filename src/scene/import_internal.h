/* What the importer's units share (private to src/scene/import*.c). The entry points are
 * include/evray.h's evr_scene_load, evr_scene_load_memory and evr_scene_describe; import.c
 * says which of Assimp 5.2's quirks each unit corrects.
 *
 *   import.c           loading a file or memory through Assimp, the order of the steps, release
 *   import_gltf.c      the glTF JSON read directly, for what Assimp drops
 *   import_texture.c   base colour textures: finding, decoding and linearizing them
 *   import_mesh.c      materials and triangle meshes
 *   import_node.c      the node hierarchy, instances and rest-pose bounds
 *   import_clips.c     which animation clips play (the default rule or the caller's choice)
 *   import_anim.c      animation curves
 *   import_camera.c    cameras (or one framing the scene)
 *   import_light.c     punctual lights (or a headlight)
 *   import_describe.c  what `evray info` prints */
#ifndef EVR_SCENE_IMPORT_INTERNAL_H
#define EVR_SCENE_IMPORT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene.h"

struct aiScene;
struct aiNode;
struct aiAnimation;

#define EVR_PI_D 3.14159265358979323846

/* ---- glTF side information: what Assimp 5.2 drops (import_gltf.c) ---- */

enum { PATH_T = 0, PATH_R = 1, PATH_S = 2 };
enum { GL_LINEAR = 0, GL_STEP = 1, GL_CUBIC = 2 };

#define T_ABSENT -1e30f

/* One glTF animation channel that targets a node's translation, rotation or scale. */
typedef struct {
    const char *node; /* the node's name as Assimp gives it (points into node_names) */
    int anim, path, interp;
} side_channel;

typedef struct {
    int num_nodes;
    char **node_names; /* as Assimp names them: the name, or "nodes[i]" when empty */
    int num_anims;
    side_channel *ch; /* sorted by node name, animation, path */
    int num_ch;
    int num_materials;
    float *emissive_strength; /* KHR_materials_emissive_strength, 1 when absent */
    float *t_extras; /* per material: extras.t_diffuse, extras.t_specular (T_ABSENT when absent) */
} gltf_side;

/* Reads the side information from a .gltf or a GLB (data: the file's bytes, a GLB's header and
 * JSON chunk at least). */
evr_status evr_gltf_side_parse(const unsigned char *data, size_t size, gltf_side *g,
                               evr_error *err);
void evr_gltf_side_free(gltf_side *g);
/* The interpolation of the glTF channel (animation anim, node named `name`, path): GL_*, or -1
 * when the file has no such channel (Assimp synthesized the keys). anim < 0: any animation. */
int evr_gltf_side_interp(const gltf_side *g, int anim, const char *name, int path);

/* ---- the importer's state while it converts one aiScene ---- */

typedef struct {
    const char *name; /* Assimp's full name (evr names are cut at 63 characters) */
    int index;
} name_index;

typedef struct {
    const struct aiScene *ai;
    evr_scene *s;
    evr_error *err;
    char dir[512]; /* folder of the scene file with a trailing '/', "" for memory */
    int gltf;      /* Assimp's glTF 2.0 quirks apply */
    int have_side;
    gltf_side side;
    char **tex_keys; /* per scene texture: what it was loaded from (to share it) */
    int tex_cap;
    int *mat_uv;                    /* per material: UV channel of its base colour texture */
    const struct aiNode **ai_nodes; /* per evr node */
    unsigned char *clip_played;     /* per aiAnimation: 1 when its curves are imported (NULL:
                                       every clip plays) */
    name_index *by_name;            /* nodes sorted by Assimp name */
} importer;

/* ---- shared helpers (import.c) ---- */

/* Fills err with one line (newlines from library messages become spaces) and returns st. */
evr_status evr_import_fail(evr_error *err, evr_status st, const char *fmt, ...);
void evr_import_copy_name(char *dst, size_t cap, const char *src);
/* Reads at most max bytes of a file (the whole file when max is 0), 0-ended. */
evr_status evr_import_read_file(const char *path, size_t max, unsigned char **data, size_t *size,
                                evr_error *err);

/* ---- the steps, in the order import.c runs them ---- */

/* Materials (with their textures) and then meshes: a mesh's UVs are its material's channel. */
evr_status evr_import_materials(importer *im);
evr_status evr_import_meshes(importer *im, uint64_t *total_tris);
/* Loads (or shares) the texture Assimp names ai_path for material mat_name: *out its index. */
evr_status evr_import_texture(importer *im, const char *ai_path, const char *mat_name, int *out);
/* Flattens the node tree depth-first (parents before children) and makes the instances. */
evr_status evr_import_nodes(importer *im);
/* The first node (in depth-first order) with Assimp name `name`, or -1. */
int evr_import_find_node(const importer *im, const char *name);
/* Which clips play: s->clips, s->clip_choice, im->clip_played and s->notice from `choice`
 * (evr_load_options.animation). Runs after the nodes and before any curve is imported. */
evr_status evr_import_clips(importer *im, const char *choice);
/* 1 when the curves of aiAnimation a are imported (every importer of curves asks this). */
int evr_import_clip_played(const importer *im, unsigned a);
/* Ticks per second of a clip's key times (quirk (a) in import.c): mTicksPerSecond, 25 when 0. */
double evr_import_ticks_per_second(const struct aiAnimation *an);
/* The interpolation (GL_*) of clip a's channel for node's property path (PATH_*): what the glTF
 * JSON says, GL_LINEAR without it, or -1 when Assimp synthesized those keys (quirk (e)). */
int evr_import_channel_interp(const importer *im, unsigned a, const char *node, int path);
/* Curves of the played clips (evr_import_clip_played). */
evr_status evr_import_animation(importer *im);
void evr_import_curve_free(evr_curve *c);
/* The scene's world bounds at rest pose. */
void evr_import_bounds(evr_scene *s);
evr_status evr_import_cameras(importer *im);
evr_status evr_import_lights(importer *im);

#endif
