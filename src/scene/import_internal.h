/* What the importer's units share (private to src/scene/import*.c). The entry points are
 * include/evray.h's evr_scene_load, evr_scene_load_memory and evr_scene_describe; import.c
 * says which of Assimp 5.2's quirks each unit corrects.
 *
 *   import.c           loading a file or memory through Assimp, the order of the steps, release
 *   import_gltf.c      the glTF JSON read directly, for what Assimp drops
 *   import_gltf_data.c glTF buffers and accessors read directly (data: URIs, files, GLB BIN)
 *   import_gltf_deform.c  glTF skins and morph targets checked before Assimp reads them
 *   import_gltf_geometry.c  glTF quantized attributes and GPU instancing, patched for Assimp
 *   import_gltf_patch.c   the patched copy of a glTF that Assimp reads
 *   import_memfile.c   an aiFileIO that serves Assimp a patched copy of the scene file
 *   import_texture.c   textures: finding, decoding (sRGB for colour, as is for data), sharing
 *   import_material.c  materials as Assimp gives them (every format but glTF)
 *   import_gltf_material.c  glTF materials read from the JSON (checked before Assimp reads it)
 *   import_mesh.c      triangle meshes (and their tangents: tangents.c)
 *   import_node.c      the node hierarchy, instances and rest-pose bounds
 *   import_clips.c     which animation clips play (the default rule or the caller's choice)
 *   import_anim.c      animation curves
 *   import_deform.c    skins, morph targets, morph weights and their curves
 *   import_camera.c    cameras (or one framing the scene)
 *   import_light.c     punctual lights (or a headlight)
 *   import_describe.c  what `evray info` prints */
#ifndef EVR_SCENE_IMPORT_INTERNAL_H
#define EVR_SCENE_IMPORT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "io/json_read.h"
#include "scene/scene.h"

struct aiScene;
struct aiNode;
struct aiAnimation;

#define EVR_PI_D 3.14159265358979323846

/* ---- glTF side information: what Assimp 5.2 drops (import_gltf.c) ---- */

enum { PATH_T = 0, PATH_R = 1, PATH_S = 2, PATH_W = 3 };
enum { GL_LINEAR = 0, GL_STEP = 1, GL_CUBIC = 2 };

/* One glTF animation channel that targets a node's translation, rotation, scale or morph
 * weights. */
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
    int *node_num_weights; /* per node: the morph weights it gives (node.weights), 0: none */
    float **node_weights;  /* per node: those weights, or NULL */
    int num_lights;
    float *light_radius; /* per KHR_lights_punctual light: extras.radius (>= 0; 0 when absent) */
} gltf_side;

/* A glTF index (a non-negative integer number), or -1. */
int evr_gltf_index(const evr_jdoc *d, int v);
/* The JSON text of a .gltf or of a GLB's first chunk: 0 when a GLB has none. */
int evr_gltf_json_span(const unsigned char *data, size_t size, const char **json, size_t *len);
/* Reads the side information from a .gltf or a GLB (data: the file's bytes, a GLB's header and
 * JSON chunk at least). */
evr_status evr_gltf_side_parse(const unsigned char *data, size_t size, gltf_side *g,
                               evr_error *err);
void evr_gltf_side_free(gltf_side *g);
/* The interpolation of the glTF channel (animation anim, node named `name`, path): GL_*, or -1
 * when the file has no such channel (Assimp synthesized the keys). anim < 0: any animation. */
int evr_gltf_side_interp(const gltf_side *g, int anim, const char *name, int path);

/* ---- glTF binary data (import_gltf_data.c) ---- */

/* Where a glTF's data is: its bytes (a .gltf's text, or a GLB: whole, or its header and JSON
 * chunk only, the BIN chunk then read from path), and the folder of relative URIs. */
typedef struct {
    const unsigned char *bytes;
    size_t nbytes;
    const char *path;   /* the file, NULL for memory */
    const char *dir;    /* folder with a trailing '/' ("" the current one); NULL: none (memory) */
    int allow_external; /* files outside dir may be read (evr_load_options.allow_external) */
} gltf_source;

/* Accessors of one parsed glTF document; buffers are loaded when first read. */
typedef struct {
    const evr_jdoc *d;
    const gltf_source *src;
    int accessors; /* the JSON array */
    int num_accessors, num_views, num_buffers;
    int *acc_v, *view_v, *buf_v; /* the JSON value of each accessor, view and buffer */
    unsigned char **buf;         /* per buffer: its bytes once loaded */
    size_t *buf_len;
} gltf_data;

evr_status evr_gltf_data_init(gltf_data *g, const evr_jdoc *d, int root, const gltf_source *src,
                              evr_error *err);
void evr_gltf_data_free(gltf_data *g);
/* The JSON value of accessor a, or -1. */
int evr_gltf_accessor(const gltf_data *g, int a);
/* Accessor a's element count (-1 when there is no such accessor) and components per element. */
int evr_gltf_accessor_count(const gltf_data *g, int a, int *ncomp);
/* A URI's percent escapes decoded (file names with spaces are written %20) into out. */
void evr_gltf_uri_decode(const char *in, char *out, size_t cap);
/* Image value img's encoded bytes: *data (free()) for a data: URI or a buffer view; else *data
 * NULL and path the file (dir + its decoded uri). */
evr_status evr_gltf_image_source(gltf_data *g, int img, unsigned char **data, size_t *n, char *path,
                                 size_t cap, evr_error *err);
/* Reads accessor a (SCALAR to VEC4, float matrices; strides, normalized integers and sparse
 * values applied)
 * into *out, count * ncomp doubles (free()). */
evr_status evr_gltf_accessor_read(gltf_data *g, int a, double **out, int *count, int *ncomp,
                                  evr_error *err);

/* ---- the glTF checked before anything else reads it (import_gltf_validate.c) ---- */

/* Checks a glTF 2.0 file against its own structure before Assimp (or any other stage) reads
 * it: the GLB container against the file's size, every index (buffers, views, accessors,
 * meshes, nodes, skins, animations, cameras, lights, textures, images) in range, accessors
 * inside their views and views inside their buffers, vertex indices below the vertex count, a
 * node tree without loops, every number finite (vertices, transforms, keys, quaternions not
 * zero) and cameras and lights with valid parameters, buffers that may be read
 * (evr_import_file_check). One line naming the first problem. */
evr_status evr_gltf_validate(const gltf_source *src, evr_error *err);

/* ---- glTF skins and morph targets before Assimp (import_gltf_deform.c) ---- */

/* Checks what Assimp 5.2 would misread or crash on (quirks (j) to (n) in import.c): one error
 * naming the mesh. When a used skin has no inverseBindMatrices or a mesh is placed with two
 * skins, *patched is a copy of the file for Assimp to read instead (identity matrices added, a
 * copy of the mesh per further skin; free()); else NULL. A document that is not glTF 2.0 JSON
 * passes unchecked (Assimp reports it). */
evr_status evr_gltf_deform_check(const gltf_source *src, unsigned char **patched, size_t *npatched,
                                 evr_error *err);

/* ---- the patched copy of a glTF (import_gltf_patch.c) ---- */

/* Replace text[at, at + len) of the JSON by `text` (len 0: insert). */
typedef struct {
    size_t at, len;
    int seq; /* the order edits at one place are made in */
    char *text;
} gltf_edit;

typedef struct {
    gltf_edit *e;
    int n, cap;
} gltf_edits;

/* Adds an edit taking ownership of text (malloc'ed); 0 when memory ran out (text freed). */
int evr_gltf_edit(gltf_edits *E, size_t at, size_t len, char *text);
/* Appends elements (JSON text, comma-separated) to the root array `key`: before its ']', or as
 * a whole member after the root's '{' when the array is missing. 0: out of memory. */
int evr_gltf_append(gltf_edits *E, const evr_jdoc *d, int root, const char *key, const char *elems);
/* Base64 text of n bytes (free()), NULL when out of memory. */
char *evr_gltf_b64(const unsigned char *p, size_t n);
/* The file with the edits applied (sorted by place): *out (free()); a GLB keeps its BIN chunk
 * (read from the file when src holds only the JSON). */
evr_status evr_gltf_edits_apply(const gltf_source *src, gltf_edits *E, const char *json,
                                size_t jlen, unsigned char **out, size_t *nout, evr_error *err);
void evr_gltf_edits_free(gltf_edits *E);

/* ---- glTF geometry Assimp 5.2 misreads (import_gltf_geometry.c) ---- */

/* KHR_mesh_quantization: Assimp 5.2 copies an integer attribute's bytes into its floats
 * (positions collapse to a point, silently). Every non-float vertex attribute but JOINTS_n
 * (mesh and morph target) is read here, normalized integers scaled as glTF says, and given to
 * Assimp as a float accessor. EXT_mesh_gpu_instancing: Assimp ignores it (one instance shows);
 * each instance becomes a child node of the instancing node with the instance's translation,
 * rotation and scale, placing the node's mesh (and skin, weights), and the node itself places
 * none. *patched as in evr_gltf_deform_check (NULL: nothing to change). */
evr_status evr_gltf_geometry_patch(const gltf_source *src, unsigned char **patched,
                                   size_t *npatched, evr_error *err);

/* ---- serving Assimp a patched file (import_memfile.c) ---- */

struct aiFileIO;
/* An aiFileIO that gives Assimp `bytes` (which must outlive the import; NULL: the file on disk)
 * for the file `path` and opens every other file (the buffers and textures beside it) from disk
 * when evr_import_file_check(dir, ..., allow_external) allows it; NULL when out of memory. */
struct aiFileIO *evr_memfile_io_new(const char *path, const unsigned char *bytes, size_t n,
                                    const char *dir, int allow_external);
void evr_memfile_io_free(struct aiFileIO *io);

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
    gltf_source src; /* the glTF's bytes (bytes NULL: not glTF) */
    char **tex_keys; /* per scene texture: what it was loaded from (to share it) */
    int *tex_srgb;   /* per scene texture: 1 when sRGB-decoded (a colour slot) */
    int tex_cap;
    int *mat_uv; /* per material: the UV channel its textures use (the base colour's) */
    const struct aiNode **ai_nodes; /* per evr node */
    unsigned char *clip_played;     /* per aiAnimation: 1 when its curves are imported (NULL:
                                       every clip plays) */
    name_index *by_name;            /* nodes sorted by Assimp name */
    int strict;                     /* evr_load_options.strict: a warning is an error */
    int allow_external;             /* evr_load_options.allow_external */
    int in_memory;                  /* loaded from memory: no folder to read files from */
} importer;

/* ---- shared helpers (import.c) ---- */

/* Fills err with one line (newlines from library messages become spaces) and returns st. */
evr_status evr_import_fail(evr_error *err, evr_status st, const char *fmt, ...);
void evr_import_copy_name(char *dst, size_t cap, const char *src);
/* One warning line (what evray does not render of the file) added to the scene's list. */
void evr_import_warn(importer *im, const char *fmt, ...);
/* An Assimp matrix as evr_m34 (its last row dropped). */
struct aiMatrix4x4;
evr_m34 evr_import_m34(const struct aiMatrix4x4 *a);
/* Whether a scene in folder dir (with a trailing '/', "" the current one, NULL: a scene in
 * memory, which has none) may read the file at path (dir and the name joined): a regular file
 * inside the folder, or anywhere when allow_external (import_files.c). Else one line naming it
 * (`what`: "buffer 0", "texture", ...): EVR_ERR_IO when it cannot be read, EVR_ERR_FORMAT when
 * it is outside. */
evr_status evr_import_file_check(const char *dir, const char *path, int allow_external,
                                 const char *what, evr_error *err);
/* Reads at most max bytes of a file (the whole file when max is 0), 0-ended. */
evr_status evr_import_read_file(const char *path, size_t max, unsigned char **data, size_t *size,
                                evr_error *err);

/* ---- the steps, in the order import.c runs them ---- */

/* Materials (with their textures) and then meshes: a mesh's UVs are its material's channel. */
evr_status evr_import_materials(importer *im);
evr_status evr_import_meshes(importer *im, uint64_t *total_tris);
/* Loads (or shares) the texture Assimp names ai_path for material mat_name, sRGB-decoded when
 * srgb (a colour slot): *out its index. */
evr_status evr_import_texture(importer *im, const char *ai_path, const char *mat_name, int srgb,
                              int *out);
/* The same for an encoded image's bytes shared under key (data NULL: the file key), `what`
 * naming it in messages. */
evr_status evr_import_texture_image(importer *im, const char *key, const unsigned char *data,
                                    size_t n, const char *what, int srgb, int *out);
/* glTF: checks every material of the JSON (bad values, texture indices out of range) before
 * Assimp reads the file: one error naming the material. A document that is not glTF 2.0 JSON
 * passes unchecked. */
evr_status evr_gltf_material_check(const gltf_source *src, evr_error *err);
/* glTF: the materials of im->src's JSON (every property, textures loaded) into im->s->materials
 * [0 .. *count), warnings for what evray does not render; im->mat_uv set. *count 0 when the
 * document is not glTF 2.0 JSON. */
evr_status evr_gltf_materials_read(importer *im, int *count);
/* Tangents of mesh m (tangents.c): MikkTSpace's definition from its uvs (glTF's v, pointing down
 * the image) and normals; m->tangents allocated. 0 when out of memory. */
int evr_mesh_generate_tangents(evr_mesh *m);
/* The same on `threads` threads (1: on the caller alone), the vertices welded by a sort
 * (by_sort) or by a hash where that gives the same groups; the tangents are the same bits either
 * way (tests/test_tangents_par.c). evr_mesh_generate_tangents uses the processors for a big
 * mesh, and the hash. */
int evr_mesh_tangents_threads(evr_mesh *m, int threads, int by_sort);
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
/* How many nodes have Assimp name `name`. */
int evr_import_name_count(const importer *im, const char *name);
evr_status evr_import_animation(importer *im);
void evr_import_curve_free(evr_curve *c);
/* Sorts a curve's keys by time (stable; dim values per key). */
void evr_import_curve_sort(evr_curve *c, int dim);
/* Skins and morph targets of the meshes, the nodes' morph weights and their curves (after
 * evr_import_animation: it widens the animation's time range). */
evr_status evr_import_deform(importer *im);
/* The scene's world bounds at rest pose. */
void evr_import_bounds(evr_scene *s);
evr_status evr_import_cameras(importer *im);
evr_status evr_import_lights(importer *im);
/* Every number of the imported scene finite (vertices, transforms, keys, cameras, lights),
 * quaternions not zero, cameras with a field of view in (0, pi) and znear > 0, lights not
 * negative: one error line naming the element (import_check.c). */
evr_status evr_import_check_numbers(importer *im);
/* 1 when Assimp's JoinIdenticalVertices would change no mesh of ai (every vertex used, no two
 * it could merge), found without it (import_join.c); 0 when it may change one. */
int evr_import_join_is_noop(const struct aiScene *ai);

#endif
