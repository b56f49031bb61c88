/* glTF geometry that Assimp 5.2 misreads, patched before it reads the file (the patched copy:
 * import_gltf_patch.c).
 *
 * KHR_mesh_quantization: Assimp 5.2 copies an accessor's bytes into its float vectors whatever
 * the component type, so a quantized mesh (positions as SHORT or BYTE, normalized or not, the
 * node's scale undoing the quantization) collapses to a point without a message. Every
 * non-float vertex attribute of a mesh or morph target (JOINTS_n excepted: they are indices) is
 * read here (import_gltf_data.c scales normalized integers as glTF says: c / 127, c / 32767,
 * c / 255, c / 65535) and replaced by a float accessor in a new buffer; the nodes' scales stay
 * as they are, Assimp applies those.
 *
 * EXT_mesh_gpu_instancing: Assimp 5.2 ignores it, so one copy of the mesh shows at the node. Each
 * instance becomes a child node of the instancing node with the instance's translation,
 * rotation and scale (the extension's rule: the instance transform first, then the node's),
 * placing the node's mesh (with its skin and morph weights); the node keeps its children,
 * camera, light and animation but places no mesh itself. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/byte_order.h"
#include "scene/import_internal.h"

/* A growable text (JSON fragments) or byte buffer; failed once memory ran out. */
typedef struct {
    char *p;
    size_t len, cap;
    int failed;
} grow;

static int grow_room(grow *g, size_t n)
{
    if (g->failed) return 0;
    if (g->len + n + 1 > g->cap) {
        size_t cap = g->cap ? g->cap : 4096;
        char *np;
        while (cap < g->len + n + 1) cap *= 2;
        if (!(np = realloc(g->p, cap))) {
            g->failed = 1;
            return 0;
        }
        g->p = np;
        g->cap = cap;
    }
    return 1;
}

static void grow_printf(grow *g, const char *fmt, ...)
{
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || !grow_room(g, (size_t)n)) {
        g->failed = 1;
        return;
    }
    va_start(ap, fmt);
    vsnprintf(g->p + g->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    g->len += (size_t)n;
}

static void grow_bytes(grow *g, const void *p, size_t n)
{
    if (!grow_room(g, n)) return;
    memcpy(g->p + g->len, p, n);
    g->len += n;
}

/* Takes the text (0-ended) for an edit: the caller's copy, NULL when memory ran out. */
static char *grow_take(grow *g)
{
    char *t;
    if (g->failed || !grow_room(g, 0)) return NULL;
    g->p[g->len] = 0;
    t = g->p;
    memset(g, 0, sizeof *g);
    return t;
}

typedef struct {
    const evr_jdoc *d;
    int root;
    gltf_data data;
    gltf_edits E;
    evr_error *err;
    /* the float copies of quantized accessors, in one new buffer */
    int num_accessors, num_views, num_buffers;
    int *float_of; /* per accessor of the file: its float copy's index, -1 none yet */
    grow blob, views, accessors;
    int new_views;
} patcher;

static evr_status nomem(patcher *P)
{
    return evr_import_fail(P->err, EVR_ERR_NOMEM, "out of memory patching the glTF");
}

static void key_of(const evr_jdoc *d, int m, char *out, size_t cap)
{
    size_t n = d->v[m].key_len < cap - 1 ? d->v[m].key_len : cap - 1;
    memcpy(out, d->text + d->v[m].key_off, n);
    out[n] = 0;
}

/* The float copy of accessor a (made once): its index in the patched file. */
static evr_status float_copy(patcher *P, int a, int is_position, int *out)
{
    static const char *types[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    double *v = NULL, lo[4], hi[4];
    int count = 0, nc = 0, i, c;
    size_t at;
    evr_status st;
    if (P->float_of[a] >= 0) {
        *out = P->float_of[a];
        return EVR_OK;
    }
    if ((st = evr_gltf_accessor_read(&P->data, a, &v, &count, &nc, P->err)) != EVR_OK) return st;
    while (P->blob.len % 4) grow_bytes(&P->blob, "", 1);
    at = P->blob.len;
    for (c = 0; c < nc; c++) lo[c] = HUGE_VAL, hi[c] = -HUGE_VAL;
    for (i = 0; i < count * nc; i++) {
        float f = (float)v[i];
        uint32_t u;
        unsigned char b[4];
        memcpy(&u, &f, sizeof u);
        evr_put_le32(b, u);
        grow_bytes(&P->blob, b, 4);
        if (f < lo[i % nc]) lo[i % nc] = f;
        if (f > hi[i % nc]) hi[i % nc] = f;
    }
    free(v);
    grow_printf(&P->views, "%s{\"buffer\":%d,\"byteOffset\":%zu,\"byteLength\":%zu}",
                P->new_views ? "," : "", P->num_buffers, at, P->blob.len - at);
    grow_printf(&P->accessors,
                "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"%s\"",
                P->new_views ? "," : "", P->num_views + P->new_views, count, types[nc]);
    if (is_position && count > 0) /* glTF requires POSITION's bounds */
        grow_printf(&P->accessors, ",\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]", lo[0],
                    lo[1], lo[2], hi[0], hi[1], hi[2]);
    grow_printf(&P->accessors, "}");
    if (P->blob.failed || P->views.failed || P->accessors.failed) return nomem(P);
    P->new_views++;
    *out = P->float_of[a] = P->num_accessors + P->new_views - 1;
    return EVR_OK;
}

/* The attributes of one primitive or morph target (an object of accessor indices). */
static evr_status dequantize_attributes(patcher *P, int attrs)
{
    const evr_jdoc *d = P->d;
    int m;
    for (m = evr_jdoc_first(d, attrs); m >= 0; m = evr_jdoc_next(d, m)) {
        char key[64], *t;
        int a = evr_gltf_index(d, m), acc = evr_gltf_accessor(&P->data, a), ct, copy = -1;
        evr_status st;
        key_of(d, m, key, sizeof key);
        if (acc < 0 || !strncmp(key, "JOINTS_", 7)) continue; /* Assimp reports a bad index */
        ct = evr_gltf_index(d, evr_jdoc_get(d, acc, "componentType"));
        if (ct == 5126 || ct < 0) continue;
        if ((st = float_copy(P, a, !strcmp(key, "POSITION"), &copy)) != EVR_OK) return st;
        if (!(t = malloc(16))) return nomem(P);
        snprintf(t, 16, "%d", copy);
        if (!evr_gltf_edit(&P->E, d->v[m].off, d->v[m].len, t)) return nomem(P);
    }
    return EVR_OK;
}

static evr_status dequantize(patcher *P)
{
    const evr_jdoc *d = P->d;
    int mesh, prim, tg;
    evr_status st;
    for (mesh = evr_jdoc_first(d, evr_jdoc_get(d, P->root, "meshes")); mesh >= 0;
         mesh = evr_jdoc_next(d, mesh))
        for (prim = evr_jdoc_first(d, evr_jdoc_get(d, mesh, "primitives")); prim >= 0;
             prim = evr_jdoc_next(d, prim)) {
            if ((st = dequantize_attributes(P, evr_jdoc_get(d, prim, "attributes"))) != EVR_OK)
                return st;
            for (tg = evr_jdoc_first(d, evr_jdoc_get(d, prim, "targets")); tg >= 0;
                 tg = evr_jdoc_next(d, tg))
                if ((st = dequantize_attributes(P, tg)) != EVR_OK) return st;
        }
    if (!P->new_views) return EVR_OK;
    {
        char *b64 = evr_gltf_b64((const unsigned char *)P->blob.p, P->blob.len), *t;
        grow buf;
        memset(&buf, 0, sizeof buf);
        if (!b64) return nomem(P);
        grow_printf(&buf,
                    "{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,%s\"}",
                    P->blob.len, b64);
        free(b64);
        if (!(t = grow_take(&buf)) || !evr_gltf_append(&P->E, d, P->root, "buffers", t)) {
            free(t);
            return nomem(P);
        }
        free(t);
        if (!(t = grow_take(&P->views)) || !evr_gltf_append(&P->E, d, P->root, "bufferViews", t)) {
            free(t);
            return nomem(P);
        }
        free(t);
        if (!(t = grow_take(&P->accessors)) ||
            !evr_gltf_append(&P->E, d, P->root, "accessors", t)) {
            free(t);
            return nomem(P);
        }
        free(t);
    }
    return EVR_OK;
}

/* The raw JSON text of value v (a string's without its quotes). */
static void raw_text(grow *g, const evr_jdoc *d, int v)
{
    grow_bytes(g, d->text + d->v[v].off, d->v[v].len);
}

/* One instancing node (n: its JSON value, ni its index): its instances as child nodes from
 * *next_node on. */
static evr_status instance_node(patcher *P, int n, int ni, int ext, int *next_node)
{
    static const char *names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
    static const int comps[3] = {3, 4, 3};
    const evr_jdoc *d = P->d;
    int attrs = evr_jdoc_get(d, ext, "attributes"), mesh = evr_jdoc_get(d, n, "mesh");
    int name = evr_jdoc_get(d, n, "name"), skin = evr_jdoc_get(d, n, "skin");
    int weights = evr_jdoc_get(d, n, "weights"), children = evr_jdoc_get(d, n, "children");
    int count = -1, k, i, first = *next_node;
    double *val[3] = {NULL, NULL, NULL};
    char label[160];
    grow nodes, kids;
    evr_status st = EVR_OK;
    memset(&nodes, 0, sizeof nodes);
    memset(&kids, 0, sizeof kids);
    if (name >= 0 && d->v[name].len) {
        char nm[128];
        evr_jdoc_string(d, name, nm, sizeof nm);
        snprintf(label, sizeof label, "glTF node '%s'", nm);
    } else snprintf(label, sizeof label, "glTF node %d", ni);
    if (mesh < 0) return EVR_OK; /* nothing to place: no instance shows */
    for (k = 0; k < 3; k++) {
        int a = evr_gltf_index(d, evr_jdoc_get(d, attrs, names[k])), c = 0, nc = 0;
        if (evr_jdoc_get(d, attrs, names[k]) < 0) continue;
        if ((st = evr_gltf_accessor_read(&P->data, a, &val[k], &c, &nc, P->err)) != EVR_OK)
            goto done;
        if (nc != comps[k]) {
            st = evr_import_fail(P->err, EVR_ERR_FORMAT,
                                 "%s: EXT_mesh_gpu_instancing %s must be VEC%d", label, names[k],
                                 comps[k]);
            goto done;
        }
        if (count >= 0 && c != count) {
            st = evr_import_fail(P->err, EVR_ERR_FORMAT,
                                 "%s: EXT_mesh_gpu_instancing attributes of %d and %d instances",
                                 label, count, c);
            goto done;
        }
        count = c;
    }
    if (count < 0) {
        st = evr_import_fail(P->err, EVR_ERR_FORMAT,
                             "%s: EXT_mesh_gpu_instancing has no TRANSLATION, ROTATION or SCALE",
                             label);
        goto done;
    }
    for (i = 0; i < count; i++) {
        const double *t = val[0] ? val[0] + 3 * i : NULL, *s = val[2] ? val[2] + 3 * i : NULL;
        double q[4] = {0, 0, 0, 1}, len;
        if (val[1]) memcpy(q, val[1] + 4 * i, sizeof q);
        len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(len > 0.0) || !isfinite(len)) {
            st = evr_import_fail(P->err, EVR_ERR_FORMAT,
                                 "%s: EXT_mesh_gpu_instancing rotation %d is not a quaternion",
                                 label, i);
            goto done;
        }
        grow_printf(&nodes, "%s{\"name\":\"", i ? "," : "");
        if (name >= 0 && d->v[name].len) raw_text(&nodes, d, name);
        else grow_printf(&nodes, "nodes[%d]", ni);
        grow_printf(&nodes, "#%d\",\"mesh\":", i);
        raw_text(&nodes, d, mesh);
        if (skin >= 0) grow_printf(&nodes, ",\"skin\":"), raw_text(&nodes, d, skin);
        if (weights >= 0) grow_printf(&nodes, ",\"weights\":"), raw_text(&nodes, d, weights);
        if (t) grow_printf(&nodes, ",\"translation\":[%.9g,%.9g,%.9g]", t[0], t[1], t[2]);
        grow_printf(&nodes, ",\"rotation\":[%.9g,%.9g,%.9g,%.9g]", q[0] / len, q[1] / len,
                    q[2] / len, q[3] / len);
        if (s) grow_printf(&nodes, ",\"scale\":[%.9g,%.9g,%.9g]", s[0], s[1], s[2]);
        grow_printf(&nodes, "}");
        grow_printf(&kids, "%s%d", i ? "," : "", first + i);
    }
    *next_node = first + count;
    if (count == 0) goto done;
    {
        /* the node places no mesh itself: its keys renamed, which Assimp ignores */
        static const char *const keys[2] = {"mesh", "skin"};
        const int members[2] = {mesh, skin};
        char *t;
        for (k = 0; k < 2; k++) {
            size_t n2 = strlen(keys[k]) + 16;
            if (members[k] < 0) continue;
            if (!(t = malloc(n2))) goto oom;
            snprintf(t, n2, "evray_instanced_%s", keys[k]);
            if (!evr_gltf_edit(&P->E, d->v[members[k]].key_off, d->v[members[k]].key_len, t))
                goto oom;
        }
        if (children >= 0 && evr_jdoc_type(d, children) == EVR_JDOC_ARRAY) {
            grow c;
            memset(&c, 0, sizeof c);
            grow_printf(&c, "%s%s", evr_jdoc_count(d, children) ? "," : "", kids.p);
            if (!(t = grow_take(&c)) ||
                !evr_gltf_edit(&P->E, d->v[children].off + d->v[children].len - 1, 0, t))
                goto oom;
        } else {
            grow c;
            memset(&c, 0, sizeof c);
            grow_printf(&c, "\"children\":[%s],", kids.p);
            if (!(t = grow_take(&c)) || !evr_gltf_edit(&P->E, d->v[n].off + 1, 0, t)) goto oom;
        }
        if (!(t = grow_take(&nodes)) || !evr_gltf_append(&P->E, d, P->root, "nodes", t)) {
            free(t);
            goto oom;
        }
        free(t);
    }
    goto done;
oom:
    st = nomem(P);
done:
    for (k = 0; k < 3; k++) free(val[k]);
    free(nodes.p);
    free(kids.p);
    if (st == EVR_OK && (nodes.failed || kids.failed)) st = nomem(P);
    return st;
}

static evr_status instance(patcher *P)
{
    const evr_jdoc *d = P->d;
    int nodes = evr_jdoc_get(d, P->root, "nodes"), n, ni = 0, next = evr_jdoc_count(d, nodes);
    evr_status st;
    /* each node's instances are appended to the nodes in turn (edits at one place keep their
     * order), numbered from the file's node count on */
    for (n = evr_jdoc_first(d, nodes); n >= 0; n = evr_jdoc_next(d, n), ni++) {
        int ext = evr_jdoc_get(d, evr_jdoc_get(d, n, "extensions"), "EXT_mesh_gpu_instancing");
        if (ext >= 0 && (st = instance_node(P, n, ni, ext, &next)) != EVR_OK) return st;
    }
    return EVR_OK;
}

evr_status evr_gltf_geometry_patch(const gltf_source *src, unsigned char **patched,
                                   size_t *npatched, evr_error *err)
{
    patcher P;
    evr_jdoc d;
    const char *json;
    size_t jlen;
    char version[16];
    evr_status st;
    *patched = NULL;
    *npatched = 0;
    if (!evr_gltf_json_span(src->bytes, src->nbytes, &json, &jlen)) return EVR_OK;
    memset(&P, 0, sizeof P);
    P.root = evr_jdoc_parse(&d, json, jlen);
    if (P.root < 0 || evr_jdoc_type(&d, P.root) != EVR_JDOC_OBJECT ||
        !evr_jdoc_string(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, P.root, "asset"), "version"),
                         version, sizeof version) ||
        version[0] != '2') {
        st = d.failed ? evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
                      : EVR_OK;
        evr_jdoc_free(&d);
        return st;
    }
    P.d = &d;
    P.err = err;
    P.num_accessors = evr_jdoc_count(&d, evr_jdoc_get(&d, P.root, "accessors"));
    P.num_views = evr_jdoc_count(&d, evr_jdoc_get(&d, P.root, "bufferViews"));
    P.num_buffers = evr_jdoc_count(&d, evr_jdoc_get(&d, P.root, "buffers"));
    P.float_of = malloc(((size_t)P.num_accessors + 1) * sizeof *P.float_of);
    if ((st = evr_gltf_data_init(&P.data, &d, P.root, src, err)) != EVR_OK) {
        free(P.float_of);
        evr_jdoc_free(&d);
        return st;
    }
    if (!P.float_of) st = nomem(&P);
    else {
        for (int a = 0; a < P.num_accessors; a++) P.float_of[a] = -1;
        if ((st = dequantize(&P)) == EVR_OK) st = instance(&P);
    }
    if (st == EVR_OK && P.E.n)
        st = evr_gltf_edits_apply(src, &P.E, json, jlen, patched, npatched, err);
    evr_gltf_edits_free(&P.E);
    free(P.float_of);
    free(P.blob.p);
    free(P.views.p);
    free(P.accessors.p);
    evr_gltf_data_free(&P.data);
    evr_jdoc_free(&d);
    return st;
}
