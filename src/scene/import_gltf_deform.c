/* glTF skins and morph targets checked before Assimp 5.2 reads them (quirks (j) to (n) in
 * import.c). Assimp would crash on a skin without inverseBindMatrices, read past an accessor
 * with too few of them, drop a joint index out of range or a whole set of weights whose counts
 * differ, and replace a morph target of the wrong length by the base mesh: each is one error
 * here, naming the mesh, except the missing matrices, which glTF defines as identity: Assimp then
 * reads a copy of the file with an identity accessor added. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/byte_order.h"
#include "scene/import_internal.h"

typedef struct {
    const evr_jdoc *d;
    gltf_data data;
    int nodes, skins; /* the JSON arrays */
    int num_meshes, num_skins;
    int *mesh_v, *skin_v; /* the JSON value of each mesh and skin */
    evr_error *err;
} checker;

/* "mesh 'name'" or "mesh 3" when it has no name. */
static void label(const evr_jdoc *d, int obj, const char *what, int index, char *out, size_t cap)
{
    char name[96];
    if (evr_jdoc_string(d, evr_jdoc_get(d, obj, "name"), name, sizeof name) && name[0])
        snprintf(out, cap, "%s '%s'", what, name);
    else snprintf(out, cap, "%s %d", what, index);
}

static int index_of(const evr_jdoc *d, int obj, const char *key)
{
    return evr_gltf_index(d, evr_jdoc_get(d, obj, key));
}

/* Morph targets: every attribute as long as the primitive's POSITION, one count of targets
 * across primitives, and as many default weights (mesh.weights) as targets. Returns the number
 * of targets, or -1 after an error. */
static int check_mesh_targets(checker *c, int mesh, const char *ml)
{
    static const char *attrs[3] = {"POSITION", "NORMAL", "TANGENT"};
    int prims = evr_jdoc_get(c->d, mesh, "primitives"), p, pi = 0, ntargets = -1;
    int mw = evr_jdoc_get(c->d, mesh, "weights");
    for (p = evr_jdoc_first(c->d, prims); p >= 0; p = evr_jdoc_next(c->d, p), pi++) {
        int targets = evr_jdoc_get(c->d, p, "targets"), t, ti = 0;
        int nv = evr_gltf_accessor_count(
            &c->data, index_of(c->d, evr_jdoc_get(c->d, p, "attributes"), "POSITION"), NULL);
        if (nv < 0) continue; /* no positions: Assimp reports it */
        if (ntargets >= 0 && evr_jdoc_count(c->d, targets) != ntargets) {
            evr_import_fail(c->err, EVR_ERR_FORMAT,
                            "glTF %s: its primitives have different numbers of morph targets (%d "
                            "and %d)",
                            ml, ntargets, evr_jdoc_count(c->d, targets));
            return -1;
        }
        ntargets = evr_jdoc_count(c->d, targets);
        for (t = evr_jdoc_first(c->d, targets); t >= 0; t = evr_jdoc_next(c->d, t), ti++) {
            for (int k = 0; k < 3; k++) {
                int a = evr_jdoc_get(c->d, t, attrs[k]), n;
                if (a < 0) continue;
                n = evr_gltf_accessor_count(&c->data, index_of(c->d, t, attrs[k]), NULL);
                if (n != nv) {
                    evr_import_fail(c->err, EVR_ERR_FORMAT,
                                    "glTF %s: morph target %d's %s has %d elements for %d "
                                    "vertices (primitive %d)",
                                    ml, ti, attrs[k], n, nv, pi);
                    return -1;
                }
            }
        }
    }
    if (ntargets < 0) ntargets = 0;
    if (mw >= 0 && evr_jdoc_count(c->d, mw) != ntargets) {
        evr_import_fail(c->err, EVR_ERR_FORMAT, "glTF %s has %d weights for %d morph targets", ml,
                        evr_jdoc_count(c->d, mw), ntargets);
        return -1;
    }
    return ntargets;
}

/* A skinned primitive's JOINTS_n / WEIGHTS_n: in pairs, as long as POSITION, and every joint
 * index with a weight below the skin's joint count. */
static evr_status check_skin_weights(checker *c, int prim, int pi, int njoints, const char *ml,
                                     const char *sl)
{
    int attrs = evr_jdoc_get(c->d, prim, "attributes");
    int nv = evr_gltf_accessor_count(&c->data, index_of(c->d, attrs, "POSITION"), NULL);
    for (int set = 0;; set++) {
        char jn[16], wn[16];
        int ja, wa, jc, wc, jk, wk;
        double *j = NULL, *w = NULL;
        evr_status st;
        snprintf(jn, sizeof jn, "JOINTS_%d", set);
        snprintf(wn, sizeof wn, "WEIGHTS_%d", set);
        ja = evr_jdoc_get(c->d, attrs, jn);
        wa = evr_jdoc_get(c->d, attrs, wn);
        if (ja < 0 && wa < 0) return EVR_OK;
        if (ja < 0 || wa < 0)
            return evr_import_fail(c->err, EVR_ERR_FORMAT, "glTF %s: %s without %s (primitive %d)",
                                   ml, ja < 0 ? wn : jn, ja < 0 ? jn : wn, pi);
        if ((st = evr_gltf_accessor_read(&c->data, index_of(c->d, attrs, jn), &j, &jc, &jk,
                                         c->err)) != EVR_OK)
            return st;
        if ((st = evr_gltf_accessor_read(&c->data, index_of(c->d, attrs, wn), &w, &wc, &wk,
                                         c->err)) != EVR_OK) {
            free(j);
            return st;
        }
        if (jc != nv || wc != nv || jk != 4 || wk != 4) {
            free(j);
            free(w);
            return evr_import_fail(c->err, EVR_ERR_FORMAT,
                                   "glTF %s: %s and %s must be VEC4 with one element per vertex "
                                   "(%d and %d for %d vertices, primitive %d)",
                                   ml, jn, wn, jc, wc, nv, pi);
        }
        for (int v = 0; v < nv; v++)
            for (int k = 0; k < 4; k++) {
                double jv = j[4 * v + k], wv = w[4 * v + k];
                if (wv != 0.0 && !(jv < njoints)) {
                    free(j);
                    free(w);
                    return evr_import_fail(c->err, EVR_ERR_FORMAT,
                                           "glTF %s: vertex %d has joint index %.0f (weight %g), "
                                           "but %s has %d joints (primitive %d)",
                                           ml, v, jv, wv, sl, njoints, pi);
                }
            }
        free(j);
        free(w);
    }
}

/* A skin used by a node with a mesh: its joints are nodes, its inverse bind matrices are MAT4
 * floats, at least one per joint. *no_ibm: the skin has none (identity). Returns the number of
 * joints, or -1 after an error. */
static int check_skin(checker *c, int skin, const char *ml, const char *sl, int *no_ibm)
{
    int joints = evr_jdoc_get(c->d, skin, "joints"), nj = evr_jdoc_count(c->d, joints), j, ji = 0;
    int ibm = index_of(c->d, skin, "inverseBindMatrices"), acc, nmat, ncomp;
    *no_ibm = 0;
    if (nj <= 0) {
        evr_import_fail(c->err, EVR_ERR_FORMAT, "glTF %s: %s has no joints", ml, sl);
        return -1;
    }
    for (j = evr_jdoc_first(c->d, joints); j >= 0; j = evr_jdoc_next(c->d, j), ji++) {
        double n = evr_jdoc_number(c->d, j, -1);
        if (!(n >= 0 && n < evr_jdoc_count(c->d, c->nodes))) {
            evr_import_fail(c->err, EVR_ERR_FORMAT, "glTF %s: %s's joint %d is not a node", ml, sl,
                            ji);
            return -1;
        }
    }
    if (evr_jdoc_get(c->d, skin, "inverseBindMatrices") < 0) {
        *no_ibm = 1;
        return nj;
    }
    nmat = evr_gltf_accessor_count(&c->data, ibm, &ncomp);
    acc = evr_gltf_accessor(&c->data, ibm);
    if (nmat < 0 || ncomp != 16 ||
        evr_jdoc_number(c->d, evr_jdoc_get(c->d, acc, "componentType"), 0) != 5126) {
        evr_import_fail(c->err, EVR_ERR_FORMAT,
                        "glTF %s: %s's inverseBindMatrices is not an accessor of MAT4 floats", ml,
                        sl);
        return -1;
    }
    if (nmat < nj) {
        evr_import_fail(c->err, EVR_ERR_FORMAT,
                        "glTF %s: %s has %d inverse bind matri%s for %d joints", ml, sl, nmat,
                        nmat == 1 ? "x" : "ces", nj);
        return -1;
    }
    return nj;
}

/* ---- the identity patch ---- */

typedef struct {
    size_t at;
    char *text;
} insertion;

static int insertion_cmp(const void *pa, const void *pb)
{
    const insertion *a = pa, *b = pb;
    return (a->at > b->at) - (a->at < b->at);
}

static char *b64_encode(const unsigned char *p, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc((n + 2) / 3 * 4 + 1), *o = out;
    size_t i;
    if (!out) return NULL;
    for (i = 0; i + 2 < n; i += 3) {
        unsigned v = (unsigned)p[i] << 16 | (unsigned)p[i + 1] << 8 | p[i + 2];
        *o++ = tab[v >> 18];
        *o++ = tab[(v >> 12) & 63];
        *o++ = tab[(v >> 6) & 63];
        *o++ = tab[v & 63];
    }
    if (i < n) {
        unsigned v = (unsigned)p[i] << 16 | (i + 1 < n ? (unsigned)p[i + 1] << 8 : 0);
        *o++ = tab[v >> 18];
        *o++ = tab[(v >> 12) & 63];
        *o++ = i + 1 < n ? tab[(v >> 6) & 63] : '=';
        *o++ = '=';
    }
    *o = 0;
    return out;
}

/* Text to add one element to the root array `key`: before its ']', or the whole member after
 * the root's '{' when the array is missing. */
static int add_to_array(const evr_jdoc *d, int root, const char *key, const char *elem,
                        insertion *ins)
{
    int arr = evr_jdoc_get(d, root, key);
    size_t n = strlen(key) + strlen(elem) + 16;
    ins->text = malloc(n);
    if (!ins->text) return 0;
    if (arr >= 0 && evr_jdoc_type(d, arr) == EVR_JDOC_ARRAY) {
        ins->at = d->v[arr].off + d->v[arr].len - 1;
        snprintf(ins->text, n, "%s%s", evr_jdoc_count(d, arr) ? "," : "", elem);
    } else {
        ins->at = d->v[root].off + 1;
        snprintf(ins->text, n, "\"%s\":[%s],", key, elem);
    }
    return 1;
}

/* The file with an accessor of `count` identity matrices added and given to the skins marked in
 * need[] as their inverseBindMatrices; a GLB keeps its BIN chunk (read from the file when the
 * bytes hold only the JSON). */
static evr_status make_patch(const gltf_source *src, const evr_jdoc *d, int root, int skins,
                             const unsigned char *need, int count, const char *json, size_t jlen,
                             unsigned char **out, size_t *nout, evr_error *err)
{
    int nskins = evr_jdoc_count(d, skins), i, s, nins = 0;
    int acc_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "accessors"));
    int view_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "bufferViews"));
    int buf_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "buffers"));
    insertion *ins = calloc((size_t)nskins + 4, sizeof *ins);
    unsigned char *mats = malloc((size_t)count * 64), *file = NULL, *res = NULL;
    char *b64 = NULL, *elem = NULL;
    const unsigned char *rest = NULL;
    size_t nrest = 0, nfile = 0, total, o, prev;
    evr_status st = EVR_ERR_NOMEM;
    int glb = src->nbytes >= 20 && !memcmp(src->bytes, "glTF", 4);

    if (!ins || !mats) goto nomem;
    for (i = 0; i < count; i++)
        for (int k = 0; k < 16; k++) {
            float f = (k % 5 == 0) ? 1.0f : 0.0f; /* column-major identity */
            uint32_t u;
            memcpy(&u, &f, sizeof u);
            evr_put_le32(mats + (size_t)i * 64 + (size_t)k * 4, u);
        }
    if (!(b64 = b64_encode(mats, (size_t)count * 64))) goto nomem;
    if (!(elem = malloc(strlen(b64) + 128))) goto nomem;
    for (i = 0, s = evr_jdoc_first(d, skins); s >= 0; s = evr_jdoc_next(d, s), i++) {
        if (!need[i]) continue;
        ins[nins].at = d->v[s].off + 1;
        if (!(ins[nins].text = malloc(48))) goto nomem;
        snprintf(ins[nins++].text, 48, "\"inverseBindMatrices\":%d,", acc_index);
    }
    sprintf(elem, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"MAT4\"}",
            view_index, count);
    if (!add_to_array(d, root, "accessors", elem, &ins[nins++])) goto nomem;
    sprintf(elem, "{\"buffer\":%d,\"byteLength\":%d}", buf_index, count * 64);
    if (!add_to_array(d, root, "bufferViews", elem, &ins[nins++])) goto nomem;
    sprintf(elem, "{\"byteLength\":%d,\"uri\":\"data:application/octet-stream;base64,%s\"}",
            count * 64, b64);
    if (!add_to_array(d, root, "buffers", elem, &ins[nins++])) goto nomem;
    qsort(ins, (size_t)nins, sizeof *ins, insertion_cmp);

    if (glb) { /* what follows the JSON chunk (the BIN chunk) */
        size_t end = 20 + (size_t)evr_get_le32(src->bytes + 12);
        size_t whole = evr_get_le32(src->bytes + 8); /* the GLB's length, from its header */
        if (src->nbytes < whole && src->path) {
            if ((st = evr_import_read_file(src->path, 0, &file, &nfile, err)) != EVR_OK) goto done;
            if (nfile < end) {
                st = evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB '%s' is cut short",
                                     src->path);
                goto done;
            }
            rest = file + end;
            nrest = nfile - end;
        } else if (src->nbytes >= end) {
            rest = src->bytes + end;
            nrest = src->nbytes - end;
        }
    }
    total = jlen + nrest + 24;
    for (i = 0; i < nins; i++) total += strlen(ins[i].text);
    if (!(res = malloc(total + 4))) goto nomem;
    o = glb ? 20 : 0;
    prev = 0;
    for (i = 0; i < nins; i++) {
        size_t n = strlen(ins[i].text);
        memcpy(res + o, json + prev, ins[i].at - prev);
        o += ins[i].at - prev;
        memcpy(res + o, ins[i].text, n);
        o += n;
        prev = ins[i].at;
    }
    memcpy(res + o, json + prev, jlen - prev);
    o += jlen - prev;
    if (glb) {
        while ((o - 20) % 4) res[o++] = ' '; /* chunks are 4-byte aligned, JSON padded by spaces */
        memcpy(res, src->bytes, 12);
        evr_put_le32(res + 12, (uint32_t)(o - 20));
        memcpy(res + 16, "JSON", 4);
        if (nrest) memcpy(res + o, rest, nrest);
        o += nrest;
        evr_put_le32(res + 8, (uint32_t)o);
    }
    *out = res;
    *nout = o;
    res = NULL;
    st = EVR_OK;
    goto done;
nomem:
    st = evr_import_fail(err, EVR_ERR_NOMEM, "out of memory patching the glTF");
done:
    for (i = 0; ins && i < nins; i++) free(ins[i].text);
    free(ins);
    free(mats);
    free(b64);
    free(elem);
    free(file);
    free(res);
    return st;
}

evr_status evr_gltf_deform_check(const gltf_source *src, unsigned char **patched, size_t *npatched,
                                 evr_error *err)
{
    checker c;
    evr_jdoc d;
    const char *json;
    size_t jlen;
    char version[16];
    int root, n, ni = 0, m, max_patch = 0;
    int *mesh_targets = NULL, *mesh_skin_checked = NULL;
    unsigned char *need = NULL;
    evr_status st = EVR_OK;

    *patched = NULL;
    *npatched = 0;
    if (!evr_gltf_json_span(src->bytes, src->nbytes, &json, &jlen)) return EVR_OK;
    root = evr_jdoc_parse(&d, json, jlen);
    if (root < 0 || evr_jdoc_type(&d, root) != EVR_JDOC_OBJECT ||
        !evr_jdoc_string(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, root, "asset"), "version"), version,
                         sizeof version) ||
        version[0] != '2') {
        st = d.failed ? evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
                      : EVR_OK;
        evr_jdoc_free(&d);
        return st;
    }
    memset(&c, 0, sizeof c);
    c.d = &d;
    c.err = err;
    c.nodes = evr_jdoc_get(&d, root, "nodes");
    c.skins = evr_jdoc_get(&d, root, "skins");
    c.num_meshes = evr_jdoc_count(&d, evr_jdoc_get(&d, root, "meshes"));
    c.num_skins = evr_jdoc_count(&d, c.skins);
    if ((st = evr_gltf_data_init(&c.data, &d, root, src, err)) != EVR_OK) {
        evr_jdoc_free(&d);
        return st;
    }
    c.mesh_v = evr_jdoc_elements(&d, evr_jdoc_get(&d, root, "meshes"));
    c.skin_v = evr_jdoc_elements(&d, c.skins);
    mesh_targets = malloc(((size_t)c.num_meshes + 1) * sizeof *mesh_targets);
    mesh_skin_checked = malloc(((size_t)c.num_meshes + 1) * sizeof *mesh_skin_checked);
    need = calloc((size_t)c.num_skins + 1, 1);
    if (!c.mesh_v || !c.skin_v || !mesh_targets || !mesh_skin_checked || !need) {
        st = evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON");
        goto done;
    }
    for (m = 0; m < c.num_meshes; m++) {
        char ml[128];
        label(&d, c.mesh_v[m], "mesh", m, ml, sizeof ml);
        mesh_skin_checked[m] = -1;
        if ((mesh_targets[m] = check_mesh_targets(&c, c.mesh_v[m], ml)) < 0) {
            st = EVR_ERR_FORMAT;
            goto done;
        }
    }
    for (n = evr_jdoc_first(&d, c.nodes); n >= 0; n = evr_jdoc_next(&d, n), ni++) {
        int s = index_of(&d, n, "skin"), nw, mv, sv, nj, no_ibm, p, pi = 0;
        char ml[128], nl[128], sl[128];
        m = index_of(&d, n, "mesh");
        if (m < 0 || m >= c.num_meshes) continue; /* Assimp reports a mesh that is not there */
        mv = c.mesh_v[m];
        label(&d, mv, "mesh", m, ml, sizeof ml);
        label(&d, n, "node", ni, nl, sizeof nl);
        nw = evr_jdoc_get(&d, n, "weights");
        if (nw >= 0 && evr_jdoc_count(&d, nw) != mesh_targets[m]) {
            st = evr_import_fail(err, EVR_ERR_FORMAT,
                                 "glTF %s has %d morph weights, but its %s has %d morph targets",
                                 nl, evr_jdoc_count(&d, nw), ml, mesh_targets[m]);
            goto done;
        }
        if (evr_jdoc_get(&d, n, "skin") < 0) continue;
        if (s < 0 || s >= c.num_skins) {
            st = evr_import_fail(err, EVR_ERR_FORMAT,
                                 "glTF %s: its skin is not in the file's skins", nl);
            goto done;
        }
        if (mesh_skin_checked[m] == s) continue; /* this mesh with this skin: checked */
        mesh_skin_checked[m] = s;
        sv = c.skin_v[s];
        label(&d, sv, "skin", s, sl, sizeof sl);
        if ((nj = check_skin(&c, sv, ml, sl, &no_ibm)) < 0) {
            st = EVR_ERR_FORMAT;
            goto done;
        }
        if (no_ibm) {
            need[s] = 1;
            if (nj > max_patch) max_patch = nj;
        }
        for (p = evr_jdoc_first(&d, evr_jdoc_get(&d, mv, "primitives")); p >= 0;
             p = evr_jdoc_next(&d, p), pi++)
            if ((st = check_skin_weights(&c, p, pi, nj, ml, sl)) != EVR_OK) goto done;
    }
    if (max_patch > 0)
        st =
            make_patch(src, &d, root, c.skins, need, max_patch, json, jlen, patched, npatched, err);
done:
    free(mesh_targets);
    free(mesh_skin_checked);
    free(need);
    free(c.mesh_v);
    free(c.skin_v);
    evr_gltf_data_free(&c.data);
    evr_jdoc_free(&d);
    return st;
}
