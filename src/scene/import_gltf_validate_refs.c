/* The glTF elements that use the binary data, checked after it (import_gltf_validate.c):
 * meshes (attributes of one length, finite positions, indices below the vertex count), nodes (a
 * tree: one parent each, no loops; transforms of the right length and finite, rotations not
 * zero), scenes (roots only), skins, animations (channels naming nodes that exist, keys finite
 * and not negative, as many values as keys, quaternions not zero), cameras (0 < yfov < pi,
 * znear > 0), KHR_lights_punctual lights (intensity >= 0, cone angles in order), textures and
 * images. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/import_gltf_validate.h"

#define PI_D 3.14159265358979323846

/* "mesh 'name'" when the element has a name, else "mesh 3". */
static void label(gv *c, int obj, const char *kind, int i, char *out, size_t cap)
{
    char name[64];
    if (evr_jdoc_string(c->d, evr_jdoc_get(c->d, obj, "name"), name, sizeof name) && name[0])
        snprintf(out, cap, "%s '%s'", kind, name);
    else snprintf(out, cap, "%s %d", kind, i);
}

/* The accessor member key of obj (required or not): *a its index, checked to exist. */
static int accessor_of(gv *c, int obj, const char *key, int required, const char *what, int *a)
{
    return evr_gv_index(c, obj, key, c->n_acc, required, what, "accessor", a);
}

/* Components an attribute must have, by its name: 0 for any (an attribute glTF does not name). */
static int attr_comps(const char *name, int *alt)
{
    *alt = 0;
    if (!strcmp(name, "POSITION") || !strcmp(name, "NORMAL")) return 3;
    if (!strcmp(name, "TANGENT")) return 4;
    if (!strncmp(name, "TEXCOORD_", 9)) return 2;
    if (!strncmp(name, "COLOR_", 6)) return *alt = 3, 4;
    if (!strncmp(name, "JOINTS_", 7) || !strncmp(name, "WEIGHTS_", 8)) return 4;
    return 0;
}

/* Indices of primitive `what` below the vertex count nv, and as many as its mode needs. */
static int check_indices(gv *c, int a, int nv, int mode, const char *what)
{
    double *v = NULL;
    int n, nc, k;
    if (c->acc_comps[a] != 1 ||
        (c->acc_ctype[a] != 5121 && c->acc_ctype[a] != 5123 && c->acc_ctype[a] != 5125))
        return evr_gv_fail(c, "%s: indices (accessor %d) must be unsigned integer scalars", what,
                           a);
    if (evr_gv_read(c, a, &v, &n, &nc)) return -1;
    for (k = 0; k < n; k++)
        if (!(v[k] >= 0 && v[k] < nv)) {
            double bad = v[k];
            free(v);
            return evr_gv_fail(c, "%s: index %d is %.0f, past its %d vertices", what, k, bad, nv);
        }
    free(v);
    if ((mode == 4 && n % 3) || (mode == 1 && n % 2))
        return evr_gv_fail(c, "%s: %d indices do not make whole %s", what, n,
                           mode == 4 ? "triangles" : "lines");
    return 0;
}

static int check_primitive(gv *c, int prim, const char *what, int *ntargets)
{
    const evr_jdoc *d = c->d;
    int attrs = evr_jdoc_get(d, prim, "attributes"), m, pos = -1, nv, ind, mat, targets, t;
    double mode = 4;
    if (evr_jdoc_type(d, prim) != EVR_JDOC_OBJECT || evr_jdoc_type(d, attrs) != EVR_JDOC_OBJECT)
        return evr_gv_fail(c, "%s has no attributes", what);
    if (accessor_of(c, attrs, "POSITION", 1, what, &pos)) return -1;
    nv = c->acc_count[pos];
    for (m = evr_jdoc_first(d, attrs); m >= 0; m = evr_jdoc_next(d, m)) {
        char name[64];
        int a, want, alt;
        size_t kl = d->v[m].key_len < sizeof name - 1 ? d->v[m].key_len : sizeof name - 1;
        memcpy(name, d->text + d->v[m].key_off, kl);
        name[kl] = 0;
        if (evr_gv_index_value(c, m, c->n_acc, what, "accessor", &a)) return -1;
        want = attr_comps(name, &alt);
        if (want && c->acc_comps[a] != want && c->acc_comps[a] != alt)
            return evr_gv_fail(c, "%s: attribute %s (accessor %d) has %d components, not %d", what,
                               name, a, c->acc_comps[a], want);
        if (c->acc_count[a] != nv)
            return evr_gv_fail(c, "%s: attribute %s has %d elements, POSITION %d", what, name,
                               c->acc_count[a], nv);
        /* normals and tangents that are not finite are replaced at import (face normals,
         * generated tangents), as for a degenerate face: only the others must be finite */
        if (c->acc_ctype[a] == 5126 && strcmp(name, "NORMAL") && strcmp(name, "TANGENT") &&
            evr_gv_finite(c, a, what))
            return -1;
    }
    if (c->acc_ctype[pos] != 5126 && evr_gv_finite(c, pos, what)) return -1;
    if (evr_gv_integer(c, prim, "mode", 0, 6, 4, what, &mode) ||
        accessor_of(c, prim, "indices", 0, what, &ind) ||
        evr_gv_index(c, prim, "material", c->n_materials, 0, what, "material", &mat))
        return -1;
    if (ind >= 0) {
        if (check_indices(c, ind, nv, (int)mode, what)) return -1;
    } else if (((int)mode == 4 && nv % 3) || ((int)mode == 1 && nv % 2)) {
        return evr_gv_fail(c, "%s: %d vertices do not make whole %s", what, nv,
                           mode == 4 ? "triangles" : "lines");
    }
    if ((targets = evr_gv_array(c, prim, "targets", what)) == -2) return -1;
    *ntargets = evr_jdoc_count(d, targets);
    for (t = evr_jdoc_first(d, targets); t >= 0; t = evr_jdoc_next(d, t)) {
        if (evr_jdoc_type(d, t) != EVR_JDOC_OBJECT)
            return evr_gv_fail(c, "%s: a morph target is not an object", what);
        for (m = evr_jdoc_first(d, t); m >= 0; m = evr_jdoc_next(d, m)) {
            int a;
            if (evr_gv_index_value(c, m, c->n_acc, what, "accessor", &a)) return -1;
            /* its length: import_gltf_deform.c says it, naming the mesh */
            if (c->acc_ctype[a] == 5126 && evr_gv_finite(c, a, what)) return -1;
        }
    }
    return 0;
}

/* Meshes; mesh_targets[m] the morph targets of mesh m (its first primitive's). */
static int check_meshes(gv *c, int *mesh_targets)
{
    const evr_jdoc *d = c->d;
    int i = 0, m;
    for (m = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "meshes")); m >= 0;
         m = evr_jdoc_next(d, m), i++) {
        char what[96];
        int prims, p, k = 0;
        label(c, m, "mesh", i, what, sizeof what);
        if (evr_jdoc_type(d, m) != EVR_JDOC_OBJECT ||
            (prims = evr_gv_array(c, m, "primitives", what)) == -2)
            return evr_gv_fail(c, "%s is not an object with primitives", what);
        if (evr_jdoc_count(d, prims) < 1) return evr_gv_fail(c, "%s has no primitives", what);
        if (evr_gv_numbers(c, m, "weights", 0, NULL, what) < 0) return -1;
        mesh_targets[i] = 0;
        for (p = evr_jdoc_first(d, prims); p >= 0; p = evr_jdoc_next(d, p), k++) {
            char pw[128];
            int nt = 0;
            snprintf(pw, sizeof pw, "%s primitive %d", what, k);
            if (check_primitive(c, p, pw, &nt)) return -1;
            if (k == 0) mesh_targets[i] = nt;
        }
    }
    return 0;
}

static int check_node(gv *c, int i, int n, int n_lights)
{
    const evr_jdoc *d = c->d;
    char what[96];
    int children, ch, k, mesh, skin, cam, light;
    double q[4];
    label(c, n, "node", i, what, sizeof what);
    if (evr_jdoc_type(d, n) != EVR_JDOC_OBJECT) return evr_gv_fail(c, "%s is not an object", what);
    if (evr_gv_index(c, n, "mesh", c->n_meshes, 0, what, "mesh", &mesh) ||
        evr_gv_index(c, n, "skin", c->n_skins, 0, what, "skin", &skin) ||
        evr_gv_index(c, n, "camera", c->n_cameras, 0, what, "camera", &cam) ||
        evr_gv_numbers(c, n, "translation", 3, NULL, what) < 0 ||
        evr_gv_numbers(c, n, "scale", 3, NULL, what) < 0 ||
        evr_gv_numbers(c, n, "matrix", 16, NULL, what) < 0 ||
        evr_gv_numbers(c, n, "weights", 0, NULL, what) < 0)
        return -1;
    switch (evr_gv_numbers(c, n, "rotation", 4, q, what)) {
    case -1: return -1;
    case 0:
        if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 1e-12))
            return evr_gv_fail(c, "%s: its rotation is the zero quaternion", what);
    }
    light = evr_jdoc_get(
        d, evr_jdoc_get(d, evr_jdoc_get(d, n, "extensions"), "KHR_lights_punctual"), "light");
    if (light >= 0 && evr_gv_index_value(c, light, n_lights, what, "light", &k)) return -1;
    if ((children = evr_gv_array(c, n, "children", what)) == -2) return -1;
    for (ch = evr_jdoc_first(d, children); ch >= 0; ch = evr_jdoc_next(d, ch)) {
        if (evr_gv_index_value(c, ch, c->n_nodes, what, "child node", &k)) return -1;
        if (k == i) return evr_gv_fail(c, "%s is its own child", what);
        if (c->parent[k] >= 0)
            return evr_gv_fail(c, "node %d is a child of both node %d and node %d", k, c->parent[k],
                               i);
        c->parent[k] = i;
    }
    return 0;
}

/* The nodes: a forest (one parent each, checked while reading the children, and no loop). */
static int check_nodes(gv *c, int n_lights)
{
    const evr_jdoc *d = c->d;
    int i, n, steps;
    for (i = 0; i < c->n_nodes; i++) c->parent[i] = -1;
    for (i = 0, n = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "nodes")); n >= 0;
         n = evr_jdoc_next(d, n), i++)
        if (check_node(c, i, n, n_lights)) return -1;
    for (i = 0; i < c->n_nodes; i++) {
        int up = c->parent[i];
        for (steps = 0; up >= 0 && steps <= c->n_nodes; steps++) up = c->parent[up];
        if (up >= 0) return evr_gv_fail(c, "node %d is its own ancestor (the nodes loop)", i);
    }
    return 0;
}

static int check_scenes(gv *c)
{
    const evr_jdoc *d = c->d;
    int i = 0, s, k, n, scene;
    for (s = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "scenes")); s >= 0;
         s = evr_jdoc_next(d, s), i++) {
        char what[32];
        int nodes;
        snprintf(what, sizeof what, "scene %d", i);
        if (evr_jdoc_type(d, s) != EVR_JDOC_OBJECT)
            return evr_gv_fail(c, "%s is not an object", what);
        if ((nodes = evr_gv_array(c, s, "nodes", what)) == -2) return -1;
        for (n = evr_jdoc_first(d, nodes); n >= 0; n = evr_jdoc_next(d, n)) {
            if (evr_gv_index_value(c, n, c->n_nodes, what, "node", &k)) return -1;
            if (c->parent[k] >= 0)
                return evr_gv_fail(c, "%s lists node %d, which is a child of node %d", what, k,
                                   c->parent[k]);
            if (c->parent[k] == -2 - i) /* Assimp attaches it twice and leaks it */
                return evr_gv_fail(c, "%s lists node %d twice", what, k);
            c->parent[k] = -2 - i; /* a root of scene i (reset below) */
        }
    }
    for (k = 0; k < c->n_nodes; k++)
        if (c->parent[k] < -1) c->parent[k] = -1;
    return evr_gv_index(c, c->root, "scene", c->n_scenes, 0, "the document", "scene", &scene);
}

static int check_skins(gv *c)
{
    const evr_jdoc *d = c->d;
    int i = 0, s, j, k, a;
    for (s = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "skins")); s >= 0;
         s = evr_jdoc_next(d, s), i++) {
        char what[96];
        int joints;
        label(c, s, "skin", i, what, sizeof what);
        if (evr_jdoc_type(d, s) != EVR_JDOC_OBJECT)
            return evr_gv_fail(c, "%s is not an object", what);
        if ((joints = evr_gv_array(c, s, "joints", what)) == -2) return -1;
        if (evr_jdoc_count(d, joints) < 1) return evr_gv_fail(c, "%s has no joints", what);
        for (j = evr_jdoc_first(d, joints); j >= 0; j = evr_jdoc_next(d, j))
            if (evr_gv_index_value(c, j, c->n_nodes, what, "joint node", &k)) return -1;
        if (evr_gv_index(c, s, "skeleton", c->n_nodes, 0, what, "node", &k) ||
            accessor_of(c, s, "inverseBindMatrices", 0, what, &a))
            return -1;
        if (a >= 0) {
            if (c->acc_comps[a] != 16 || c->acc_ctype[a] != 5126)
                return evr_gv_fail(c, "%s: inverseBindMatrices must be float MAT4", what);
            if (evr_gv_finite(c, a, what)) return -1;
        }
    }
    return 0;
}

/* One sampler's keys: times finite and not negative; values finite, quaternions not zero (for
 * CUBICSPLINE, only each key's value: its tangents may be zero). */
static int check_keys(gv *c, int in, int out, int rotation, int cubic, const char *what)
{
    double *t = NULL, *v = NULL;
    int n, nc, k, bad = 0;
    if (evr_gv_read(c, in, &t, &n, &nc)) return -1;
    for (k = 0; k < n && !bad; k++)
        if (!(isfinite(t[k]) && t[k] >= 0))
            bad = evr_gv_fail(c, "%s: key time %d is %g (times must be finite and >= 0)", what, k,
                              t[k]);
    free(t);
    if (bad || evr_gv_finite(c, out, what)) return -1;
    if (!rotation) return 0;
    if (evr_gv_read(c, out, &v, &n, &nc)) return -1;
    for (k = cubic ? 1 : 0; k < n && !bad; k += cubic ? 3 : 1) {
        const double *q = v + (size_t)k * (size_t)nc;
        if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 1e-12))
            bad = evr_gv_fail(c, "%s: rotation key %d is the zero quaternion", what,
                              cubic ? k / 3 : k);
    }
    free(v);
    return bad;
}

static int check_channel(gv *c, int ch, int samps, int nsamp, const int *node_mesh,
                         const int *mesh_targets, const char *what)
{
    const evr_jdoc *d = c->d;
    int si, node, s, in, out, path_k, per_key, cubic;
    int tgt = evr_jdoc_get(d, ch, "target");
    char path[16] = "", interp[16] = "LINEAR";
    static const char *paths[] = {"translation", "rotation", "scale", "weights"};
    if (evr_gv_index(c, ch, "sampler", nsamp, 1, what, "sampler", &si)) return -1;
    if (evr_jdoc_type(d, tgt) != EVR_JDOC_OBJECT) return evr_gv_fail(c, "%s has no target", what);
    if (evr_gv_index(c, tgt, "node", c->n_nodes, 1, what, "node", &node)) return -1;
    evr_jdoc_string(d, evr_jdoc_get(d, tgt, "path"), path, sizeof path);
    for (path_k = 0; path_k < 4 && strcmp(path, paths[path_k]); path_k++) continue;
    if (path_k == 4)
        return evr_gv_fail(c, "%s: target path '%s' is not translation, rotation, scale or weights",
                           what, path);
    for (s = evr_jdoc_first(d, samps); si > 0; si--) s = evr_jdoc_next(d, s);
    if (evr_jdoc_type(d, s) != EVR_JDOC_OBJECT || accessor_of(c, s, "input", 1, what, &in) ||
        accessor_of(c, s, "output", 1, what, &out))
        return -1;
    if (evr_jdoc_get(d, s, "interpolation") >= 0 &&
        !evr_jdoc_string(d, evr_jdoc_get(d, s, "interpolation"), interp, sizeof interp))
        return evr_gv_fail(c, "%s: the sampler's interpolation is not a string", what);
    if (strcmp(interp, "LINEAR") && strcmp(interp, "STEP") && strcmp(interp, "CUBICSPLINE"))
        return evr_gv_fail(c, "%s: interpolation '%s' is not LINEAR, STEP or CUBICSPLINE", what,
                           interp);
    cubic = !strcmp(interp, "CUBICSPLINE");
    if (c->acc_comps[in] != 1 || c->acc_ctype[in] != 5126)
        return evr_gv_fail(c, "%s: key times (accessor %d) must be float scalars", what, in);
    if (path_k == 3) {
        int mesh = node_mesh[node];
        per_key = mesh >= 0 ? mesh_targets[mesh] : 0;
        if (per_key < 1)
            return evr_gv_fail(c,
                               "%s animates the morph weights of node %d, which has no morph "
                               "targets",
                               what, node);
        if (c->acc_comps[out] != 1)
            return evr_gv_fail(c, "%s: morph weights must be scalars", what);
    } else {
        per_key = 1;
        if (c->acc_comps[out] != (path_k == 1 ? 4 : 3))
            return evr_gv_fail(c, "%s: %s values must be VEC%d", what, path, path_k == 1 ? 4 : 3);
    }
    if ((double)c->acc_count[out] != (double)c->acc_count[in] * per_key * (cubic ? 3 : 1))
        return evr_gv_fail(c, "%s: %d keys but %d values (%d expected)", what, c->acc_count[in],
                           c->acc_count[out], c->acc_count[in] * per_key * (cubic ? 3 : 1));
    return check_keys(c, in, out, path_k == 1, cubic, what);
}

static int check_animations(gv *c, const int *node_mesh, const int *mesh_targets)
{
    const evr_jdoc *d = c->d;
    int i = 0, a;
    for (a = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "animations")); a >= 0;
         a = evr_jdoc_next(d, a), i++) {
        char what[160], an[96];
        int samps, chans, ch, k = 0;
        label(c, a, "animation", i, an, sizeof an);
        snprintf(what, sizeof what, "%s", an);
        if (evr_jdoc_type(d, a) != EVR_JDOC_OBJECT)
            return evr_gv_fail(c, "%s is not an object", what);
        if ((samps = evr_gv_array(c, a, "samplers", what)) == -2 ||
            (chans = evr_gv_array(c, a, "channels", what)) == -2)
            return -1;
        for (ch = evr_jdoc_first(d, chans); ch >= 0; ch = evr_jdoc_next(d, ch), k++) {
            snprintf(what, sizeof what, "%s channel %d", an, k);
            if (evr_jdoc_type(d, ch) != EVR_JDOC_OBJECT)
                return evr_gv_fail(c, "%s is not an object", what);
            if (check_channel(c, ch, samps, evr_jdoc_count(d, samps), node_mesh, mesh_targets,
                              what))
                return -1;
        }
    }
    return 0;
}

static int check_cameras(gv *c)
{
    const evr_jdoc *d = c->d;
    int i = 0, cam;
    for (cam = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "cameras")); cam >= 0;
         cam = evr_jdoc_next(d, cam), i++) {
        char what[96], type[16] = "";
        double yfov = 0, znear = 0, zfar = 0, aspect = 0, xmag = 0, ymag = 0;
        int p;
        label(c, cam, "camera", i, what, sizeof what);
        evr_jdoc_string(d, evr_jdoc_get(d, cam, "type"), type, sizeof type);
        if (!strcmp(type, "perspective")) {
            p = evr_jdoc_get(d, cam, "perspective");
            if (evr_jdoc_type(d, p) != EVR_JDOC_OBJECT)
                return evr_gv_fail(c, "%s has no 'perspective' object", what);
            if (evr_gv_number(c, p, "yfov", NAN, what, &yfov) ||
                evr_gv_number(c, p, "znear", NAN, what, &znear) ||
                evr_gv_number(c, p, "zfar", INFINITY, what, &zfar) ||
                evr_gv_number(c, p, "aspectRatio", 1.0, what, &aspect))
                return -1;
            if (!(yfov > 0 && yfov < PI_D))
                return evr_gv_fail(c, "%s: yfov %g must be between 0 and pi radians", what, yfov);
            if (!(znear > 0)) return evr_gv_fail(c, "%s: znear %g must be > 0", what, znear);
            if (!(zfar > znear))
                return evr_gv_fail(c, "%s: zfar %g must be greater than znear %g", what, zfar,
                                   znear);
            if (!(aspect > 0))
                return evr_gv_fail(c, "%s: aspectRatio %g must be > 0", what, aspect);
        } else if (!strcmp(type, "orthographic")) {
            p = evr_jdoc_get(d, cam, "orthographic");
            if (evr_jdoc_type(d, p) != EVR_JDOC_OBJECT)
                return evr_gv_fail(c, "%s has no 'orthographic' object", what);
            if (evr_gv_number(c, p, "xmag", NAN, what, &xmag) ||
                evr_gv_number(c, p, "ymag", NAN, what, &ymag) ||
                evr_gv_number(c, p, "znear", NAN, what, &znear) ||
                evr_gv_number(c, p, "zfar", NAN, what, &zfar))
                return -1;
            if (xmag == 0 || ymag == 0 || !(znear >= 0) || !(zfar > znear))
                return evr_gv_fail(c, "%s: xmag and ymag must not be 0, 0 <= znear < zfar", what);
        } else {
            return evr_gv_fail(c, "%s: type '%s' is not perspective or orthographic", what, type);
        }
    }
    return 0;
}

/* KHR_lights_punctual's lights; *count their number. */
static int check_lights(gv *c, int *count)
{
    const evr_jdoc *d = c->d;
    int lights = evr_jdoc_get(
        d, evr_jdoc_get(d, evr_jdoc_get(d, c->root, "extensions"), "KHR_lights_punctual"),
        "lights");
    int i = 0, l;
    *count = evr_jdoc_count(d, lights);
    for (l = evr_jdoc_first(d, lights); l >= 0; l = evr_jdoc_next(d, l), i++) {
        char what[96], type[16] = "";
        double col[3] = {1, 1, 1}, intensity = 0, range = 0, inner = 0, outer = 0;
        int spot = evr_jdoc_get(d, l, "spot");
        label(c, l, "light", i, what, sizeof what);
        evr_jdoc_string(d, evr_jdoc_get(d, l, "type"), type, sizeof type);
        if (strcmp(type, "point") && strcmp(type, "spot") && strcmp(type, "directional"))
            return evr_gv_fail(c, "%s: type '%s' is not point, spot or directional", what, type);
        if (evr_gv_numbers(c, l, "color", 3, col, what) < 0 ||
            evr_gv_number(c, l, "intensity", 1.0, what, &intensity) ||
            evr_gv_number(c, l, "range", 1.0, what, &range) ||
            evr_gv_number(c, spot, "innerConeAngle", 0.0, what, &inner) ||
            evr_gv_number(c, spot, "outerConeAngle", PI_D / 4, what, &outer))
            return -1;
        if (col[0] < 0 || col[1] < 0 || col[2] < 0)
            return evr_gv_fail(c, "%s: a colour component is negative", what);
        if (intensity < 0) return evr_gv_fail(c, "%s: intensity %g is negative", what, intensity);
        if (!(range > 0)) return evr_gv_fail(c, "%s: range %g must be > 0", what, range);
        if (!strcmp(type, "spot") && !(inner >= 0 && inner < outer && outer <= PI_D / 2))
            return evr_gv_fail(c, "%s: cone angles must be 0 <= inner (%g) < outer (%g) <= pi/2",
                               what, inner, outer);
    }
    return 0;
}

static int check_textures(gv *c)
{
    const evr_jdoc *d = c->d;
    int i = 0, t, k;
    for (t = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "textures")); t >= 0;
         t = evr_jdoc_next(d, t), i++) {
        char what[32];
        snprintf(what, sizeof what, "texture %d", i);
        if (evr_gv_index(c, t, "source", c->n_images, 0, what, "image", &k) ||
            evr_gv_index(c, t, "sampler", c->n_samplers, 0, what, "sampler", &k))
            return -1;
    }
    for (i = 0, t = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "images")); t >= 0;
         t = evr_jdoc_next(d, t), i++) {
        char what[32];
        int uri = evr_jdoc_get(d, t, "uri");
        snprintf(what, sizeof what, "image %d", i);
        if (uri >= 0 && evr_jdoc_type(d, uri) != EVR_JDOC_STRING)
            return evr_gv_fail(c, "%s: 'uri' must be a string", what);
        if (uri >= 0) {
            char head[160];
            /* the media type is all that is parsed here (the string cut to head's size) */
            evr_jdoc_string(d, uri, head, sizeof head);
            if (!strncmp(head, "data:", 5)) {
                const char *raw = d->text + d->v[uri].off, *comma;
                size_t len = d->v[uri].len;
                if (!evr_gv_data_uri(head))
                    return evr_gv_fail(
                        c,
                        "%s's data: URI does not start data:TYPE/SUBTYPE;base64, (in under 128 bytes)",
                        what);
                comma = memchr(raw, ',', len);
                if (!comma ||
                    evr_gv_base64(comma + 1, len - (size_t)(comma + 1 - raw), 1) == (size_t)-1)
                    return evr_gv_fail(c, "%s's data: URI is not valid base64", what);
            }
        }
        if (evr_gv_index(c, t, "bufferView", c->n_views, 0, what, "buffer view", &k)) return -1;
        if (uri < 0 && k < 0) return evr_gv_fail(c, "%s has neither uri nor bufferView", what);
    }
    return 0;
}

int evr_gv_refs(gv *c)
{
    const evr_jdoc *d = c->d;
    int *mesh_targets = calloc((size_t)c->n_meshes + 1, sizeof(int));
    int *node_mesh = calloc((size_t)c->n_nodes + 1, sizeof(int));
    int n_lights = 0, bad, i, n;
    if (!mesh_targets || !node_mesh) {
        free(mesh_targets);
        free(node_mesh);
        c->err_status = evr_import_fail(c->err, EVR_ERR_NOMEM, "out of memory checking the glTF");
        return -1;
    }
    for (i = 0, n = evr_jdoc_first(d, evr_jdoc_get(d, c->root, "nodes")); n >= 0;
         n = evr_jdoc_next(d, n), i++)
        node_mesh[i] = evr_gltf_index(d, evr_jdoc_get(d, n, "mesh"));
    bad = check_lights(c, &n_lights) || check_meshes(c, mesh_targets) || check_nodes(c, n_lights) ||
          check_scenes(c) || check_skins(c) || check_animations(c, node_mesh, mesh_targets) ||
          check_cameras(c) || check_textures(c);
    free(mesh_targets);
    free(node_mesh);
    return bad ? -1 : 0;
}
