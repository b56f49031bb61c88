/* glTF skins and morph targets checked before Assimp 5.2 reads them (quirks (j) to (n) in
 * import.c). Assimp would read past an accessor with too few inverse bind matrices, drop a joint
 * index out of range or a whole set of weights whose counts differ, and replace a morph target
 * of the wrong length by the base mesh: each is one error here, naming the mesh. Two more are
 * valid glTF that Assimp mishandles, so it reads a patched copy of the file instead: a skin
 * without inverseBindMatrices (identity, by glTF's rule) crashes it, and a mesh placed by nodes
 * with different skins would get the last node's bones only (the others leaked); the copy has
 * an identity accessor added, and a copy of the mesh for each further skin. */
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

/* ---- the patched copy (import_gltf_patch.c) ---- */

/* Gives the skins marked in need[] an accessor of `count` identity matrices as their
 * inverseBindMatrices (quirk (j)). */
static int add_identity(gltf_edits *E, const evr_jdoc *d, int root, const checker *c,
                        const unsigned char *need, int count)
{
    int acc_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "accessors"));
    int view_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "bufferViews"));
    int buf_index = evr_jdoc_count(d, evr_jdoc_get(d, root, "buffers"));
    unsigned char *mats = malloc((size_t)count * 64);
    char *b64 = NULL, *elem = NULL;
    int ok = 0;
    if (!mats) return 0;
    for (int i = 0; i < count; i++)
        for (int k = 0; k < 16; k++) {
            float f = (k % 5 == 0) ? 1.0f : 0.0f; /* column-major identity */
            uint32_t u;
            memcpy(&u, &f, sizeof u);
            evr_put_le32(mats + (size_t)i * 64 + (size_t)k * 4, u);
        }
    if (!(b64 = evr_gltf_b64(mats, (size_t)count * 64)) || !(elem = malloc(strlen(b64) + 128)))
        goto done;
    for (int s = 0; s < c->num_skins; s++) {
        char *t;
        if (!need[s]) continue;
        if (!(t = malloc(48))) goto done;
        snprintf(t, 48, "\"inverseBindMatrices\":%d,", acc_index);
        if (!evr_gltf_edit(E, d->v[c->skin_v[s]].off + 1, 0, t)) goto done;
    }
    sprintf(elem, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"MAT4\"}",
            view_index, count);
    if (!evr_gltf_append(E, d, root, "accessors", elem)) goto done;
    sprintf(elem, "{\"buffer\":%d,\"byteLength\":%d}", buf_index, count * 64);
    if (!evr_gltf_append(E, d, root, "bufferViews", elem)) goto done;
    sprintf(elem, "{\"byteLength\":%d,\"uri\":\"data:application/octet-stream;base64,%s\"}",
            count * 64, b64);
    ok = evr_gltf_append(E, d, root, "buffers", elem);
done:
    free(mats);
    free(b64);
    free(elem);
    return ok;
}

/* A mesh placed with another skin than its first node's (or with and without one) gets a copy
 * of its own, per (mesh, skin) pair (quirk (n)): *index its index in the patched file. */
typedef struct {
    int mesh, skin, index;
} mesh_copy;

evr_status evr_gltf_deform_check(const gltf_source *src, unsigned char **patched, size_t *npatched,
                                 evr_error *err)
{
    checker c;
    evr_jdoc d;
    const char *json;
    size_t jlen;
    char version[16];
    int root, n, ni = 0, m, max_patch = 0, ncopies = 0;
    int *mesh_targets = NULL, *mesh_skin_checked = NULL, *mesh_first_skin = NULL;
    unsigned char *need = NULL;
    mesh_copy *copies = NULL;
    gltf_edits E;
    evr_status st = EVR_OK;

    *patched = NULL;
    *npatched = 0;
    memset(&E, 0, sizeof E);
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
    mesh_first_skin = malloc(((size_t)c.num_meshes + 1) * sizeof *mesh_first_skin);
    copies = malloc(((size_t)evr_jdoc_count(&d, c.nodes) + 1) * sizeof *copies);
    need = calloc((size_t)c.num_skins + 1, 1);
    if (!c.mesh_v || !c.skin_v || !mesh_targets || !mesh_skin_checked || !mesh_first_skin ||
        !copies || !need)
        goto nomem;
    for (m = 0; m < c.num_meshes; m++) {
        char ml[128];
        label(&d, c.mesh_v[m], "mesh", m, ml, sizeof ml);
        mesh_skin_checked[m] = mesh_first_skin[m] = -2; /* -2: no node yet; -1: no skin */
        if ((mesh_targets[m] = check_mesh_targets(&c, c.mesh_v[m], ml)) < 0) {
            st = EVR_ERR_FORMAT;
            goto done;
        }
    }
    for (n = evr_jdoc_first(&d, c.nodes); n >= 0; n = evr_jdoc_next(&d, n), ni++) {
        int s = index_of(&d, n, "skin"), nw, mv, sv, nj, no_ibm, p, pi = 0, k;
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
        if (evr_jdoc_get(&d, n, "skin") >= 0 && (s < 0 || s >= c.num_skins)) {
            st = evr_import_fail(err, EVR_ERR_FORMAT,
                                 "glTF %s: its skin is not in the file's skins", nl);
            goto done;
        }
        if (mesh_first_skin[m] == -2) mesh_first_skin[m] = s;
        else if (mesh_first_skin[m] != s) { /* quirk (n): this node gets a copy of the mesh */
            int mn = evr_jdoc_get(&d, n, "mesh");
            for (k = 0; k < ncopies && (copies[k].mesh != m || copies[k].skin != s); k++) continue;
            if (k == ncopies) {
                copies[k].mesh = m;
                copies[k].skin = s;
                copies[k].index = c.num_meshes + ncopies++;
            }
            if (!evr_gltf_edit(&E, d.v[mn].off, d.v[mn].len, malloc(16))) goto nomem;
            snprintf(E.e[E.n - 1].text, 16, "%d", copies[k].index);
        }
        if (s < 0 || mesh_skin_checked[m] == s) continue; /* unskinned, or checked */
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
    if (max_patch > 0 && !add_identity(&E, &d, root, &c, need, max_patch)) goto nomem;
    if (ncopies) { /* the copies, in their order, after the file's meshes */
        size_t len = 0, o = 0;
        char *all;
        int k;
        for (k = 0; k < ncopies; k++) len += d.v[c.mesh_v[copies[k].mesh]].len + 1;
        if (!(all = malloc(len + 1))) goto nomem;
        for (k = 0; k < ncopies; k++) {
            const evr_jdoc_value *v = &d.v[c.mesh_v[copies[k].mesh]];
            if (k) all[o++] = ',';
            memcpy(all + o, json + v->off, v->len);
            o += v->len;
        }
        all[o] = 0;
        if (!evr_gltf_append(&E, &d, root, "meshes", all)) {
            free(all);
            goto nomem;
        }
        free(all);
    }
    if (E.n) st = evr_gltf_edits_apply(src, &E, json, jlen, patched, npatched, err);
    goto done;
nomem:
    st = evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON");
done:
    evr_gltf_edits_free(&E);
    free(mesh_targets);
    free(mesh_skin_checked);
    free(mesh_first_skin);
    free(copies);
    free(need);
    free(c.mesh_v);
    free(c.skin_v);
    evr_gltf_data_free(&c.data);
    evr_jdoc_free(&d);
    return st;
}
