/* Scene import through Assimp's C API, into the flattened evr_scene model (scene.h).
 *
 * What we keep from Assimp: triangles (points and lines are dropped), the node hierarchy with
 * each node's rest transform, one instance per (node, mesh) pair, metallic-roughness materials
 * with their textures (decoded with stb_image; colour slots sRGB-decoded, data slots as they
 * are) and the mesh tangents normal maps need, punctual lights, perspective
 * cameras, and the node animation curves of the clips that play (import_clips.c says which)
 * converted to seconds.
 *
 * Assimp 5.2's glTF 2.0 importer has quirks that we correct here (the file counts as glTF 2.0
 * when Assimp's SourceAsset_Format metadata names the glTF2 importer, or failing that when the
 * extension or hint is gltf/glb or the bytes start with the GLB magic):
 *  (a) key times are in milliseconds with mTicksPerSecond = 1000: every key time is converted
 *      as mTime / (mTicksPerSecond > 0 ? mTicksPerSecond : 25), for every format;
 *  (b) aiCamera.mHorizontalFOV holds yfov * aspectRatio (yfov alone when the aspect is absent),
 *      so yfov = mHorizontalFOV / mAspect (mAspect > 0) or mHorizontalFOV;
 *  (c) aiCamera.mPosition holds a copy of the camera node's translation, which would apply it
 *      twice: for glTF the camera sits at its node's origin looking along -Z with +Y up;
 *  (d) CUBICSPLINE samplers: Assimp keeps each key's value and drops both tangents (one key
 *      per input time, tangents never appear as keys); we interpolate those values linearly,
 *      which is exact at the keys and an approximation between them;
 *  (e) nodes given by a `matrix` get no keys, and every aiNodeAnim gets keys for all three
 *      properties: those no glTF channel animates are one key synthesized from the node's
 *      decomposed rest transform (a matrix's skew lost). We drop the synthesized curves (the
 *      glTF JSON says which channels exist) and any curve that only repeats the rest value, so
 *      a node without curves keeps its rest matrix exactly, skew included, and a property
 *      without keys falls back to the node's rest value;
 *  STEP: Assimp 5.2 has no interpolation field (aiVectorKey/aiQuatKey carry a time and a value;
 *      the glTF2 importer ignores the sampler's mode except for CUBICSPLINE's stride), so STEP
 *      samplers arrive as plain keys. We read each channel's interpolation from the glTF JSON
 *      (the .gltf text or the GLB JSON chunk) and mark those curves STEP.
 *  (f) morph weight animation: one aiMeshMorphAnim per animated node, named exactly as the node
 *      (no suffix), its keys' mTime in milliseconds like (a), each key giving every target's
 *      index (mValues) and weight (mWeights); no interpolation field, so STEP comes from the JSON
 *      as above, and CUBICSPLINE keeps each key's value and drops both tangents: interpolated
 *      linearly, with a warning. Other importers name channels "node*N" or by mesh: a channel
 *      is matched to the node of its name, else of its name before '*', else to the nodes
 *      placing meshes of its name;
 *  (g) aiAnimMesh.mVertices / mNormals hold a target's ABSOLUTE positions and normals (base +
 *      delta; normals only when the target and the mesh have them), aiAnimMesh.mWeight the
 *      mesh's default weight: deltas are taken against the aiMesh;
 *  (h) node.weights (a node's own morph weights, which override mesh.weights) are dropped:
 *      read from the JSON;
 *  (i) aiProcess_JoinIdenticalVertices compares positions, normals and UVs only: two vertices
 *      that differ in their joint weights or morph targets are merged (the merged vertex gets
 *      both bones' weights and the first one's targets). It is applied (aiApplyPostProcessing)
 *      only to scenes without bones or anim meshes; their vertices stay as the file has them;
 *  (j) a skin without inverseBindMatrices (glTF: identity matrices) crashes Assimp (a null
 *      dereference): Assimp reads a copy of the file with an accessor of identity matrices
 *      added (import_gltf_deform.c), served under the file's name by import_memfile.c;
 *  (k) inverseBindMatrices with fewer matrices than joints: Assimp reads past the accessor;
 *  (l) a JOINTS_n index >= the number of joints: Assimp drops that influence silently; JOINTS_n
 *      and WEIGHTS_n of different lengths: it drops all weights of the primitive;
 *  (m) a morph target attribute with more or fewer elements than the mesh has vertices: Assimp
 *      logs a warning and keeps the base positions (a target that does nothing);
 *      (k), (l) and (m) are errors naming the mesh, checked in the JSON and the buffers before
 *      Assimp reads the file (import_gltf_deform.c);
 *  (n) a mesh placed by nodes with different skins (or with and without one) is one aiMesh with
 *      the bones of the last such node only (the earlier bones leak): the patched copy of (j)
 *      gives each further (mesh, skin) pair a copy of the mesh, referenced by its nodes.
 *  (o) KHR_mesh_quantization: an integer vertex attribute's bytes are copied into Assimp's
 *      floats as they are (a quantized mesh collapses to a point, without a message): Assimp
 *      reads a copy with every non-float attribute (JOINTS_n excepted) as a float accessor,
 *      normalized integers scaled as glTF says (import_gltf_geometry.c); node scales are
 *      applied as usual;
 *  (p) EXT_mesh_gpu_instancing is ignored (one copy of the mesh shows): the copy gives each
 *      instance a child node of its own (import_gltf_geometry.c).
 *  Assimp 5.2 does read JOINTS_1/WEIGHTS_1 (8 influences and more), sparse morph targets and
 *  unnamed joints (bones and nodes both named "nodes[i]"); it does not normalize the weights
 *  (we do, per vertex) and gives a bone without weights one of 0 on vertex 0 (ignored).
 *  Also from the JSON: every material property (import_gltf_material.c): Assimp 5.2 drops
 *      KHR_materials_emissive_strength and _specular, rewrites KHR_texture_transform for its
 *      flipped v and ignores its texCoord, and fails on a texture index out of range without
 *      naming the material (checked before Assimp reads the file, like (k) to (m)).
 *  Lights: for glTF, aiLight.mColorDiffuse already holds colour * intensity (candela for point
 *      and spot, lux for directional), and the spot cone angles are glTF's half angles.
 *
 * Skins of every format come through the same aiBone path: mOffsetMatrix maps the mesh's
 * space to the bone's at bind time (glTF: the inverse bind matrix; Collada: the joint's inverse
 * bind matrix times the bind shape matrix; FBX: the inverse of the cluster's TransformLink
 * times its Transform), so a vertex's world position is sum_k w_k world(bone node) *
 * mOffsetMatrix * p with the mesh node's own transform ignored, the glTF rule (tests/data/
 * import/skin.dae pins the Collada case: bind shape matrix included, ticks in milliseconds as
 * for glTF). Morph targets come through aiAnimMesh, absolute (deltas taken against the base
 * mesh) unless aiMesh.mMethod is aiMorphingMethod_MORPH_RELATIVE (Collada's RELATIVE morph:
 * the targets hold offsets; untested, Assimp 5.2 did not import our hand-written Collada morph
 * controller).
 *
 * For other formats: mHorizontalFOV is documented as the half angle, but Assimp's importers
 * (Collada's xfov, FBX's FieldOfView) store the full horizontal angle, so we read it as the full
 * angle and convert with the aspect; spot cone angles are read as full angles (Collada's falloff
 * angle, FBX's cone angles) and halved; the camera pose comes from mPosition/mLookAt/mUp.
 *
 * This unit loads the file and runs the steps; each step is a unit of its own (the list is in
 * import_internal.h): (a), (d), (e) and STEP in import_anim.c, (b) and (c) in import_camera.c,
 * (f) to (h) in import_deform.c, (j) to (n) in import_gltf_deform.c, (i) here, the glTF
 * JSON in import_gltf.c. What evray does not render of a file is a warning of the scene
 * (evr_scene_warnings), never a message printed here. */
#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <assimp/cimport.h>
#include <assimp/scene.h>
#include <assimp/postprocess.h>
#include <assimp/config.h>

#include "host_clock.h"
#include "io/byte_order.h"
#include "io/child_job.h"
#include "io/file_read.h"
#include "scene/import_internal.h"

/* The first evr_load_options (size and animation): the smallest size a caller may pass. */
#define EVR_LOAD_OPTIONS_FIRST_SIZE (offsetof(evr_load_options, animation) + sizeof(const char *))

/* Fills err with one line (newlines from library messages become spaces) and returns st. */
evr_status evr_import_fail(evr_error *err, evr_status st, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        char *p;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        for (p = err->msg; *p; p++)
            if (*p == '\n' || *p == '\r' || *p == '\t') *p = ' ';
        /* trailing spaces left by a library message ending in a newline */
        while (p > err->msg && p[-1] == ' ') *--p = 0;
    }
    return st;
}

void evr_import_warn(importer *im, const char *fmt, ...)
{
    evr_scene *s = im->s;
    char line[512], *p;
    size_t have = s->warnings ? strlen(s->warnings) : 0, n;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line - 1, fmt, ap);
    va_end(ap);
    for (p = line; *p; p++)
        if (*p == '\n' || *p == '\r' || *p == '\t') *p = ' ';
    n = strlen(line);
    line[n++] = '\n';
    line[n] = 0;
    if (s->warnings && strstr(s->warnings, line)) return; /* said already */
    if (s->num_warnings++ >= EVR_MAX_WARNINGS) return;
    p = realloc(s->warnings, have + n + 1);
    if (!p) return; /* a warning lost to memory: the import itself goes on */
    memcpy(p + have, line, n + 1);
    s->warnings = p;
}

const char *evr_scene_warnings(const evr_scene *s) { return s && s->warnings ? s->warnings : ""; }

void evr_import_copy_name(char *dst, size_t cap, const char *src)
{
    size_t n = src ? strlen(src) : 0;
    if (n >= cap) n = cap - 1;
    if (n) memcpy(dst, src, n);
    dst[n] = 0;
}

/* Reads at most max bytes of a file (the whole file when max is 0). */
evr_status evr_import_read_file(const char *path, size_t max, unsigned char **data, size_t *size,
                                evr_error *err)
{
    const char *why = NULL;
    FILE *f = evr_fopen_regular(path, &why);
    unsigned char *buf = NULL;
    size_t len = 0, cap = 0;
    *data = NULL;
    *size = 0;
    if (!f) return evr_import_fail(err, EVR_ERR_IO, "cannot open '%s': %s", path, why);
    for (;;) {
        size_t want, got;
        if (len == cap) {
            size_t ncap = cap ? cap * 2 : 65536;
            unsigned char *nb;
            if (max && ncap > max) ncap = max;
            if (ncap == cap) break;
            nb = realloc(buf, ncap + 1);
            if (!nb) {
                free(buf);
                fclose(f);
                return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading '%s'", path);
            }
            buf = nb;
            cap = ncap;
        }
        want = cap - len;
        got = fread(buf + len, 1, want, f);
        len += got;
        if (got < want) {
            if (ferror(f)) {
                free(buf);
                fclose(f);
                return evr_import_fail(err, EVR_ERR_IO, "cannot read '%s': %s", path,
                                       strerror(errno));
            }
            break;
        }
    }
    fclose(f);
    if (!buf) {
        buf = malloc(1);
        if (!buf) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading '%s'", path);
    }
    buf[len] = 0;
    *data = buf;
    *size = len;
    return EVR_OK;
}

static const char *file_extension(const char *path)
{
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash)) return "";
    return dot + 1;
}

static int ext_is(const char *ext, const char *want)
{
    size_t i;
    for (i = 0; want[i]; i++) {
        char c = ext[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != want[i]) return 0;
    }
    return ext[i] == 0;
}

/* Format name from the importer's metadata (Assimp 5.2 writes SourceAsset_Format). */
static void read_format(const struct aiScene *ai, char *out, size_t cap)
{
    unsigned i;
    out[0] = 0;
    if (!ai->mMetaData) return;
    for (i = 0; i < ai->mMetaData->mNumProperties; i++) {
        const struct aiMetadataEntry *e = &ai->mMetaData->mValues[i];
        if (!strcmp(ai->mMetaData->mKeys[i].data, "SourceAsset_Format") &&
            e->mType == AI_AISTRING && e->mData) {
            evr_import_copy_name(out, cap, ((const struct aiString *)e->mData)->data);
            return;
        }
    }
}

static unsigned import_flags(void)
{
    /* FlipUVs: Assimp stores v upwards (it flips glTF's v); flipped back, v = 0 is the image's
     * first row, as stb_image returns it and as glTF defines it. SortByPType (which removes
     * points and lines) and JoinIdenticalVertices come after, in sort_and_join: what is removed
     * is counted first, and quirk (i). */
    return aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_ValidateDataStructure |
           aiProcess_FlipUVs;
}

/* The points and lines SortByPType is about to remove (AI_CONFIG_PP_SBP_REMOVE, make_props), as
 * one warning line into buf ("" when there are none); returns the number of other faces. */
static unsigned note_points_lines(const struct aiScene *ai, char *buf, size_t cap)
{
    unsigned i, f, meshes = 0, points = 0, lines = 0, others = 0;
    const char *first = NULL;
    buf[0] = 0;
    for (i = 0; i < ai->mNumMeshes; i++) {
        const struct aiMesh *m = ai->mMeshes[i];
        unsigned p0 = points, l0 = lines;
        for (f = 0; f < m->mNumFaces; f++) {
            points += m->mFaces[f].mNumIndices == 1;
            lines += m->mFaces[f].mNumIndices == 2;
            others += m->mFaces[f].mNumIndices > 2;
        }
        if (points == p0 && lines == l0) continue;
        if (!meshes++) first = m->mName.data;
    }
    if (meshes) {
        char p[32] = "", l[32] = "";
        if (points) snprintf(p, sizeof p, "%u point%s", points, points == 1 ? "" : "s");
        if (lines) snprintf(l, sizeof l, "%u line%s", lines, lines == 1 ? "" : "s");
        snprintf(buf, cap,
                 "%s%s%s in %u mesh%s (the first '%.64s') %s not rendered: evray renders triangles",
                 p, points && lines ? " and " : "", l, meshes, meshes == 1 ? "" : "es",
                 first && first[0] ? first : "(unnamed)", points + lines == 1 ? "is" : "are");
    }
    return others;
}

/* Points and lines noted (into dropped) and removed, then quirk (i): identical vertices
 * joined, unless a mesh has bones or morph targets (which the join ignores). Assimp runs
 * SortByPType and JoinIdenticalVertices after the import's other steps either way (with the
 * import's properties), so a scene comes out as from one pass with every flag. NULL: Assimp
 * failed (and released the scene), or the scene has no triangles (*none set, the scene
 * released: Assimp 5.2 crashes releasing it after SortByPType removed every mesh). */
static const struct aiScene *sort_and_join(const struct aiScene *ai, char *dropped, size_t cap,
                                           int *none)
{
    unsigned i;
    *none = 0;
    if (!note_points_lines(ai, dropped, cap)) {
        *none = 1;
        aiReleaseImport(ai);
        return NULL;
    }
    if (!(ai = aiApplyPostProcessing(ai, aiProcess_SortByPType))) return NULL;
    for (i = 0; i < ai->mNumMeshes; i++)
        if (ai->mMeshes[i]->mNumBones || ai->mMeshes[i]->mNumAnimMeshes) return ai;
    if (evr_import_join_is_noop(ai)) return ai; /* the same scene, without the step's time */
    return aiApplyPostProcessing(ai, aiProcess_JoinIdenticalVertices);
}

static void importer_free(importer *im)
{
    int i;
    if (im->tex_keys)
        for (i = 0; i < im->s->num_textures; i++) free(im->tex_keys[i]);
    free(im->tex_keys);
    free(im->tex_srgb);
    free(im->mat_uv);
    free((void *)im->ai_nodes);
    free(im->by_name);
    free(im->clip_played);
    evr_gltf_side_free(&im->side);
}

/* Everything after Assimp: ai -> *out. `bytes` is the file or memory content (for the glTF
 * JSON), `path` the file (NULL: memory), `dir` the folder for external textures, `opts` the
 * caller's (current) options. */
static evr_status convert(const struct aiScene *ai, const char *source, const char *path,
                          const char *dir, const char *ext, const unsigned char *bytes,
                          size_t nbytes, const evr_load_options *opts, const char *dropped,
                          const evr_load_times *before, evr_scene **out, evr_error *err)
{
    importer im;
    evr_scene *s;
    evr_status st;
    uint64_t tris = 0;
    int i;
    double t = evr_host_seconds(), t1;

    evr_error local;
    memset(&im, 0, sizeof im);
    if (!err) err = &local; /* the steps read messages back (a texture's, for its warning) */
    s = calloc(1, sizeof *s);
    if (!s) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory");
    im.ai = ai;
    im.s = s;
    s->times = *before;
    im.strict = opts->strict;
    im.allow_external = opts->allow_external;
    im.in_memory = path == NULL;
    im.err = err;
    evr_import_copy_name(im.dir, sizeof im.dir, dir);
    evr_import_copy_name(s->source, sizeof s->source, source);
    read_format(ai, s->format, sizeof s->format);
    if (s->format[0]) im.gltf = strstr(s->format, "glTF2") != NULL;
    else
        im.gltf = ext_is(ext, "gltf") || ext_is(ext, "glb") ||
                  (nbytes >= 8 && !memcmp(bytes, "glTF", 4) && bytes[4] == 2);
    if (im.gltf && bytes) {
        if ((st = evr_gltf_side_parse(bytes, nbytes, &im.side, err)) != EVR_OK) goto fail;
        im.have_side = 1;
        im.src.bytes = bytes;
        im.src.nbytes = nbytes;
        im.src.path = path;
        im.src.dir = path ? dir : NULL;
        im.src.allow_external = opts->allow_external;
    }

    if (dropped[0]) evr_import_warn(&im, "%s", dropped);
    if ((st = evr_import_materials(&im)) != EVR_OK) goto fail;
    t1 = evr_host_seconds();
    s->times.materials = t1 - t;
    if ((st = evr_import_meshes(&im, &tris)) != EVR_OK) goto fail;
    t = evr_host_seconds();
    s->times.meshes = t - t1;
    if (tris == 0) {
        st = evr_import_fail(err, EVR_ERR_FORMAT,
                             "'%s' has no triangles (points and lines are not rendered)", source);
        goto fail;
    }
    if ((st = evr_import_nodes(&im)) != EVR_OK) goto fail;
    tris = 0;
    for (i = 0; i < s->num_instances; i++) tris += s->meshes[s->instances[i].mesh].num_triangles;
    if (tris == 0) {
        st =
            evr_import_fail(err, EVR_ERR_FORMAT, "'%s' has meshes but no node places them", source);
        goto fail;
    }
    if ((st = evr_import_clips(&im, opts->animation)) != EVR_OK) goto fail;
    if ((st = evr_import_animation(&im)) != EVR_OK) goto fail;
    if ((st = evr_import_deform(&im)) != EVR_OK) goto fail;
    evr_import_bounds(s);
    if ((st = evr_import_cameras(&im)) != EVR_OK) goto fail;
    if ((st = evr_import_lights(&im)) != EVR_OK) goto fail;
    if ((st = evr_import_check_numbers(&im)) != EVR_OK) goto fail;
    if (opts->strict && s->num_warnings) {
        const char *w = evr_scene_warnings(s);
        int first = (int)strcspn(w, "\n");
        st = evr_import_fail(err, EVR_ERR_FORMAT, "'%s' (strict): %.*s%s", source, first, w,
                             s->num_warnings > 1 ? " (and more: evray info lists them)" : "");
        goto fail;
    }
    importer_free(&im);
    s->times.rest = evr_host_seconds() - t;
    *out = s;
    return EVR_OK;
fail:
    importer_free(&im);
    evr_scene_release(s);
    return st;
}

/* Assimp failed: its reason, or ours when there are no triangles (none, or SortByPType removed
 * every mesh). */
/* One read of a file by Assimp, post-processing included (sort_and_join), as a job that
 * io/child_job.c can run in a child process. */
typedef struct {
    const char *path;
    struct aiFileIO *io;
    struct aiPropertyStore *props;
    char *dropped;
    size_t ndropped;
} assimp_read;

/* Failure lines: "\001" for a file without triangles, else Assimp's reason. */
static const void *assimp_read_run(void *ctx, char *msg, size_t cap)
{
    assimp_read *r = ctx;
    int none = 0;
    const struct aiScene *ai =
        aiImportFileExWithProperties(r->path, import_flags(), r->io, r->props);
    if (ai) ai = sort_and_join(ai, r->dropped, r->ndropped, &none);
    if (!ai) {
        const char *why = aiGetErrorString();
        if (none || (why && strstr(why, "No meshes remaining"))) snprintf(msg, cap, "\001");
        else snprintf(msg, cap, "%s", why && why[0] ? why : "unknown Assimp error");
    }
    return ai;
}

/* The longest a child process may read a file of another format than glTF: 60 s, or
 * EVR_IMPORT_SECONDS (a test's switch, to see a hang refused in seconds). */
static int isolated_read_seconds(void)
{
    const char *e = getenv("EVR_IMPORT_SECONDS");
    int v = e ? atoi(e) : 0;
    return v > 0 ? v : 60;
}

/* Assimp reads the file: a glTF (checked before) in this process, any other format first in a
 * child process (io/child_job.c), where a crash or a hang becomes an error line. */
static evr_status assimp_load(assimp_read *r, int gltf, const char *source,
                              const struct aiScene **out, evr_error *err)
{
    char msg[512];
    int child = gltf ? -2
                     : evr_child_job_run(assimp_read_run, r, "Assimp", isolated_read_seconds(), msg,
                                         sizeof msg);
    *out = NULL;
    if (child == -1)
        return evr_import_fail(err, EVR_ERR_FORMAT, "cannot import '%s': %s", source, msg);
    if (child != 0) *out = assimp_read_run(r, msg, sizeof msg);
    if (*out) return EVR_OK;
    if (!strcmp(msg, "\001"))
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "'%s' has no triangles (points and lines are not rendered)", source);
    return evr_import_fail(err, EVR_ERR_FORMAT, "cannot import '%s': %s", source, msg);
}

static struct aiPropertyStore *make_props(void)
{
    struct aiPropertyStore *p = aiCreatePropertyStore();
    if (p)
        aiSetImportPropertyInteger(p, AI_CONFIG_PP_SBP_REMOVE,
                                   aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    return p;
}

/* The options as this library's evr_load_options, whatever the caller's size (NULL: defaults). */
static evr_status current_options(const evr_load_options *o, evr_load_options *cur, evr_error *err)
{
    evr_load_options_defaults(cur);
    if (!o) return EVR_OK;
    if (o->size < EVR_LOAD_OPTIONS_FIRST_SIZE || o->size > sizeof *cur)
        return evr_import_fail(
            err, EVR_ERR_ARG,
            "evr_load_options of %zu bytes is not one this evray (%zu bytes) knows: make it with evr_load_options_defaults",
            o->size, sizeof *cur);
    memcpy(cur, o, o->size);
    cur->size = sizeof *cur;
    return EVR_OK;
}

void evr_load_options_init(evr_load_options *o, size_t size)
{
    evr_load_options d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.animation = NULL; /* the default rule */
    if (!o || size < sizeof(size_t)) return;
    if (size <= sizeof d) { /* an older caller: its own fields only */
        memcpy(o, &d, size);
    } else { /* a newer caller: ours, and a size it will be refused with */
        memcpy(o, &d, sizeof d);
    }
    o->size = size;
}

const evr_load_times *evr_scene_load_times(const evr_scene *s)
{
    static const evr_load_times none;
    return s ? &s->times : &none;
}

const char *evr_scene_notice(const evr_scene *s) { return s && s->notice[0] ? s->notice : NULL; }

/* 1 when the bytes may be glTF 2.0: a GLB, or JSON text (after any byte order mark). */
static int may_be_gltf(const unsigned char *b, size_t n, const char *ext)
{
    size_t i = (n >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF) ? 3 : 0;
    if (n >= 8 && !memcmp(b, "glTF", 4)) return 1;
    if (ext_is(ext, "gltf") || ext_is(ext, "glb")) return 1;
    while (i < n && (b[i] == ' ' || b[i] == '\t' || b[i] == '\n' || b[i] == '\r')) i++;
    return i < n && b[i] == '{';
}

/* The bytes of a file that may be glTF (a GLB's header and JSON chunk only, a .gltf whole):
 * *bytes stays NULL for any other file. */
static evr_status read_gltf_json(const char *path, const char *ext, unsigned char **bytes,
                                 size_t *nbytes, evr_error *err)
{
    unsigned char head[64];
    size_t got, want = 0;
    FILE *f = fopen(path, "rb");
    *bytes = NULL;
    *nbytes = 0;
    if (!f) return evr_import_fail(err, EVR_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    got = fread(head, 1, sizeof head, f);
    fclose(f);
    if (!may_be_gltf(head, got, ext)) return EVR_OK;
    if (got >= 20 && !memcmp(head, "glTF", 4)) want = 20 + (size_t)evr_get_le32(head + 12);
    return evr_import_read_file(path, want, bytes, nbytes, err);
}

/* What runs on a glTF before Assimp reads it, in order: the materials checked, then each stage
 * that checks and patches (skins and morph targets, quantized attributes and GPU instancing) on
 * the output of the one before. *patched: the copy Assimp is to read, NULL for the file as it
 * is. */
static evr_status gltf_before_assimp(const gltf_source *src, unsigned char **patched,
                                     size_t *npatched, evr_error *err)
{
    typedef evr_status (*stage)(const gltf_source *, unsigned char **, size_t *, evr_error *);
    static const stage stages[] = {evr_gltf_deform_check, evr_gltf_geometry_patch};
    gltf_source cur = *src;
    evr_status st;
    size_t k;
    *patched = NULL;
    *npatched = 0;
    if ((st = evr_gltf_validate(src, err)) != EVR_OK) return st;
    if ((st = evr_gltf_material_check(src, err)) != EVR_OK) return st;
    for (k = 0; k < sizeof stages / sizeof *stages; k++) {
        unsigned char *out = NULL;
        size_t n = 0;
        if ((st = stages[k](&cur, &out, &n, err)) != EVR_OK) {
            free(*patched);
            *patched = NULL;
            return st;
        }
        if (!out) continue;
        free(*patched);
        *patched = out;
        *npatched = n;
        cur.bytes = out;
        cur.nbytes = n;
    }
    return EVR_OK;
}

evr_status evr_scene_load(const char *path, evr_scene **out, evr_error *err)
{
    return evr_scene_load_with(path, NULL, out, err);
}

evr_status evr_scene_load_with(const char *path, const evr_load_options *opts, evr_scene **out,
                               evr_error *err)
{
    struct stat sb;
    evr_load_options o;
    const struct aiScene *ai;
    struct aiPropertyStore *props;
    struct aiFileIO *io = NULL;
    unsigned char *bytes = NULL, *patched = NULL;
    size_t nbytes = 0, npatched = 0;
    char dir[512], dropped[256];
    const char *ext, *slash;
    evr_status st;
    evr_load_times times = {0};
    double t0 = evr_host_seconds(), t;

    if (err) err->msg[0] = 0;
    if (!out) return evr_import_fail(err, EVR_ERR_ARG, "evr_scene_load: no output pointer");
    *out = NULL;
    if ((st = current_options(opts, &o, err)) != EVR_OK) return st;
    if (!path || !path[0]) return evr_import_fail(err, EVR_ERR_ARG, "no scene file given");
    {
        const char *why = NULL;
        FILE *f = evr_fopen_regular(path, &why); /* a FIFO or a device is refused */
        if (!f || fstat(fileno(f), &sb) != 0) {
            if (f) fclose(f);
            return evr_import_fail(err, EVR_ERR_IO, "cannot open scene file '%s': %s", path,
                                   why ? why : strerror(errno));
        }
        fclose(f);
    }
    if (sb.st_size == 0)
        return evr_import_fail(err, EVR_ERR_FORMAT, "scene file '%s' is empty", path);

    ext = file_extension(path);
    slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path) + 1;
        if (n >= sizeof dir) n = sizeof dir - 1;
        memcpy(dir, path, n);
        dir[n] = 0;
    } else {
        dir[0] = 0; /* the current folder */
    }
    /* The glTF JSON before Assimp reads the file: materials, skins and morph targets are
     * checked first (quirks (j) to (m)), quantized attributes and GPU instancing patched (quirks
     * (o), (p)), and what Assimp drops is read from it after. */
    if ((st = read_gltf_json(path, ext, &bytes, &nbytes, err)) != EVR_OK) return st;
    if (bytes) {
        gltf_source src;
        src.bytes = bytes;
        src.nbytes = nbytes;
        src.path = path;
        src.dir = dir;
        src.allow_external = o.allow_external;
        if ((st = gltf_before_assimp(&src, &patched, &npatched, err)) != EVR_OK) {
            free(bytes);
            return st;
        }
    }
    times.gltf_checks = evr_host_seconds() - t0; /* with the file's first read */
    /* every file Assimp opens goes through this (import_memfile.c) */
    if (!(io = evr_memfile_io_new(path, patched, npatched, dir, o.allow_external))) {
        free(bytes);
        free(patched);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory");
    }

    props = make_props();
    if (!props) {
        free(bytes);
        free(patched);
        evr_memfile_io_free(io);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory");
    }
    t = evr_host_seconds();
    {
        assimp_read r = {path, io, props, dropped, sizeof dropped};
        st = assimp_load(&r, bytes != NULL, path, &ai, err);
    }
    times.assimp = evr_host_seconds() - t;
    aiReleasePropertyStore(props);
    evr_memfile_io_free(io);
    free(patched);
    if (st != EVR_OK) {
        free(bytes);
        return st;
    }
    st = convert(ai, path, path, dir, ext, bytes, nbytes, &o, dropped, &times, out, err);
    free(bytes);
    aiReleaseImport(ai);
    if (st == EVR_OK) (*out)->times.total = evr_host_seconds() - t0;
    return st;
}

evr_status evr_scene_load_memory(const void *data, size_t size, const char *hint, evr_scene **out,
                                 evr_error *err)
{
    return evr_scene_load_memory_with(data, size, hint, NULL, out, err);
}

evr_status evr_scene_load_memory_with(const void *data, size_t size, const char *hint,
                                      const evr_load_options *opts, evr_scene **out, evr_error *err)
{
    evr_load_options o;
    const struct aiScene *ai;
    struct aiPropertyStore *props;
    struct aiFileIO *io;
    unsigned char *patched = NULL;
    size_t npatched = 0;
    char source[64], dropped[256], name[64];
    evr_status st;
    int gltf;
    evr_load_times times = {0};
    double t0 = evr_host_seconds(), t;

    if (err) err->msg[0] = 0;
    if (!out) return evr_import_fail(err, EVR_ERR_ARG, "evr_scene_load_memory: no output pointer");
    *out = NULL;
    if ((st = current_options(opts, &o, err)) != EVR_OK) return st;
    if (!data || size == 0) return evr_import_fail(err, EVR_ERR_ARG, "no scene data given");
    if (size > UINT_MAX)
        return evr_import_fail(err, EVR_ERR_ARG, "scene data too large (%zu bytes)", size);
    if (!hint) hint = "";
    gltf = may_be_gltf(data, size, hint);
    if (gltf) { /* as for a file (quirks (j) to (p)) */
        gltf_source src;
        src.bytes = data;
        src.nbytes = size;
        src.path = NULL;
        src.dir = NULL;
        src.allow_external = o.allow_external;
        if ((st = gltf_before_assimp(&src, &patched, &npatched, err)) != EVR_OK) return st;
    }
    t = evr_host_seconds();
    times.gltf_checks = t - t0;
    /* Assimp reads the bytes as a file of this name through import_memfile.c, which opens no
     * other file unless external files are allowed (then relative to the current folder) */
    snprintf(name, sizeof name, "evray-memory.%.32s", hint);
    props = make_props();
    io = evr_memfile_io_new(name, patched ? patched : (const unsigned char *)data,
                            patched ? npatched : size, NULL, o.allow_external);
    if (!props || !io) {
        if (props) aiReleasePropertyStore(props);
        evr_memfile_io_free(io);
        free(patched);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory");
    }
    snprintf(source, sizeof source, "<memory>.%s", hint);
    {
        assimp_read r = {name, io, props, dropped, sizeof dropped};
        st = assimp_load(&r, gltf, source, &ai, err);
    }
    times.assimp = evr_host_seconds() - t;
    aiReleasePropertyStore(props);
    evr_memfile_io_free(io);
    free(patched);
    if (st != EVR_OK) return st;
    st = convert(ai, source, NULL, "", hint, (const unsigned char *)data, size, &o, dropped, &times,
                 out, err);
    aiReleaseImport(ai);
    if (st == EVR_OK) (*out)->times.total = evr_host_seconds() - t0;
    return st;
}

void evr_scene_free_contents(evr_scene *s)
{
    int i;
    if (!s) return;
    for (i = 0; i < s->num_meshes && s->meshes; i++) {
        free(s->meshes[i].positions);
        free(s->meshes[i].normals);
        free(s->meshes[i].uvs);
        free(s->meshes[i].tangents);
        free(s->meshes[i].indices);
        if (s->meshes[i].skin) {
            free(s->meshes[i].skin->joint_nodes);
            free(s->meshes[i].skin->inverse_bind);
            free(s->meshes[i].skin->joints);
            free(s->meshes[i].skin->weights);
            free(s->meshes[i].skin);
        }
        if (s->meshes[i].morph) {
            free(s->meshes[i].morph->d_positions);
            free(s->meshes[i].morph->d_normals);
            free(s->meshes[i].morph->default_weights);
            free(s->meshes[i].morph);
        }
    }
    free(s->meshes);
    for (i = 0; i < s->num_textures && s->textures; i++) free(s->textures[i].rgba);
    free(s->textures);
    for (i = 0; i < s->num_nodes && s->nodes; i++) {
        evr_import_curve_free(&s->nodes[i].t_curve);
        evr_import_curve_free(&s->nodes[i].r_curve);
        evr_import_curve_free(&s->nodes[i].s_curve);
        evr_import_curve_free(&s->nodes[i].w_curve);
        free(s->nodes[i].weights);
    }
    free(s->nodes);
    free(s->materials);
    free(s->instances);
    free(s->lights);
    free(s->cameras);
    free(s->clips);
    free(s->warnings);
    memset(s, 0, sizeof *s);
}

void evr_scene_release(evr_scene *s)
{
    if (!s) return;
    evr_scene_free_contents(s);
    free(s);
}

int evr_scene_find_camera(const evr_scene *s, const char *name)
{
    int i;
    if (!s || s->num_cameras <= 0) return -1;
    if (!name || !name[0]) return 0;
    for (i = 0; i < s->num_cameras; i++)
        if (!strcmp(s->cameras[i].name, name)) return i;
    /* names longer than the stored 63 characters */
    for (i = 0; i < s->num_cameras; i++)
        if (strlen(name) >= sizeof s->cameras[i].name - 1 &&
            !strncmp(s->cameras[i].name, name, sizeof s->cameras[i].name - 1))
            return i;
    return -1;
}
