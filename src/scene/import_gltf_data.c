/* glTF binary data read directly: buffers (data: URIs, files beside the .gltf, a GLB's BIN
 * chunk, each loaded once when first needed) and accessors (strided, normalized, sparse), for
 * the checks Assimp 5.2 does not make (import_gltf_deform.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/byte_order.h"
#include "scene/import_internal.h"

evr_status evr_gltf_data_init(gltf_data *g, const evr_jdoc *d, int root, const gltf_source *src,
                              evr_error *err)
{
    memset(g, 0, sizeof *g);
    g->d = d;
    g->src = src;
    g->accessors = evr_jdoc_get(d, root, "accessors");
    g->num_accessors = evr_jdoc_count(d, g->accessors);
    g->num_views = evr_jdoc_count(d, evr_jdoc_get(d, root, "bufferViews"));
    g->num_buffers = evr_jdoc_count(d, evr_jdoc_get(d, root, "buffers"));
    g->acc_v = evr_jdoc_elements(d, g->accessors);
    g->view_v = evr_jdoc_elements(d, evr_jdoc_get(d, root, "bufferViews"));
    g->buf_v = evr_jdoc_elements(d, evr_jdoc_get(d, root, "buffers"));
    g->buf = calloc((size_t)g->num_buffers + 1, sizeof *g->buf);
    g->buf_len = calloc((size_t)g->num_buffers + 1, sizeof *g->buf_len);
    if (!g->acc_v || !g->view_v || !g->buf_v || !g->buf || !g->buf_len) {
        evr_gltf_data_free(g);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF buffers");
    }
    return EVR_OK;
}

void evr_gltf_data_free(gltf_data *g)
{
    int i;
    for (i = 0; i < g->num_buffers && g->buf; i++) free(g->buf[i]);
    free(g->buf);
    free(g->buf_len);
    free(g->acc_v);
    free(g->view_v);
    free(g->buf_v);
    memset(g, 0, sizeof *g);
}

int evr_gltf_accessor(const gltf_data *g, int a)
{
    return a >= 0 && a < g->num_accessors ? g->acc_v[a] : -1;
}

static int b64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+' || c == '-') return 62;
    if (c == '/' || c == '_') return 63;
    return -1;
}

/* Decodes base64 text (padding and whitespace skipped) into a new buffer. */
static unsigned char *b64_decode(const char *s, size_t n, size_t *out_len)
{
    unsigned char *out = malloc(n / 4 * 3 + 4);
    size_t i, o = 0;
    unsigned acc = 0;
    int bits = 0;
    if (!out) return NULL;
    for (i = 0; i < n; i++) {
        int v = b64_value((unsigned char)s[i]);
        if (v < 0) continue;
        acc = (acc << 6) | (unsigned)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[o++] = (unsigned char)(acc >> bits);
        }
    }
    *out_len = o;
    return out;
}

void evr_gltf_uri_decode(const char *in, char *out, size_t cap)
{
    size_t o = 0;
    while (*in && o + 1 < cap) {
        if (in[0] == '%' && in[1] && in[2]) {
            char hex[3] = {in[1], in[2], 0};
            char *end;
            long c = strtol(hex, &end, 16);
            if (*end == 0) {
                out[o++] = (char)c;
                in += 3;
                continue;
            }
        }
        out[o++] = *in++;
    }
    out[o] = 0;
}

/* The GLB's BIN chunk: from the bytes when they hold it, else read from the file. */
static evr_status glb_bin(const gltf_source *src, unsigned char **out, size_t *len, evr_error *err)
{
    const unsigned char *b = src->bytes;
    size_t at, clen;
    unsigned char head[8];
    FILE *f;
    if (src->nbytes < 20) return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: a short GLB header");
    at = 20 + (size_t)evr_get_le32(b + 12);
    at = (at + 3) & ~(size_t)3;
    if (src->nbytes >= at + 8) { /* the whole file is in memory */
        clen = evr_get_le32(b + at);
        if (memcmp(b + at + 4, "BIN", 4) || clen > src->nbytes - at - 8)
            return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB has no BIN chunk");
        *out = malloc(clen + 1);
        if (!*out) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the GLB");
        memcpy(*out, b + at + 8, clen);
        *len = clen;
        return EVR_OK;
    }
    if (!src->path) return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB has no BIN chunk");
    f = fopen(src->path, "rb");
    if (!f || fseek(f, (long)at, SEEK_SET) != 0 || fread(head, 1, 8, f) != 8 ||
        memcmp(head + 4, "BIN", 4)) {
        if (f) fclose(f);
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB '%s' has no BIN chunk",
                               src->path);
    }
    clen = evr_get_le32(head);
    *out = malloc(clen + 1);
    if (!*out) {
        fclose(f);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the GLB");
    }
    if (fread(*out, 1, clen, f) != clen) {
        fclose(f);
        free(*out);
        *out = NULL;
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB '%s' ends inside its BIN chunk",
                               src->path);
    }
    fclose(f);
    *len = clen;
    return EVR_OK;
}

/* Buffer i's bytes, loaded on first use. */
static evr_status load_buffer(gltf_data *g, int i, evr_error *err)
{
    const evr_jdoc *d = g->d;
    int b = g->buf_v[i], uri;
    char *text = NULL;
    evr_status st;
    if (g->buf[i]) return EVR_OK;
    uri = evr_jdoc_get(d, b, "uri");
    if (uri < 0) { /* a GLB's own buffer */
        if (g->src->nbytes < 4 || memcmp(g->src->bytes, "glTF", 4))
            return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: buffer %d has no uri", i);
        st = glb_bin(g->src, &g->buf[i], &g->buf_len[i], err);
    } else {
        size_t n = d->v[uri].len + 1;
        text = malloc(n);
        if (!text) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF buffers");
        evr_jdoc_string(d, uri, text, n);
        if (!strncmp(text, "data:", 5)) {
            const char *comma = strchr(text, ',');
            if (!comma || !strstr(text, ";base64,")) {
                free(text);
                return evr_import_fail(err, EVR_ERR_FORMAT,
                                       "glTF: buffer %d's data: URI is not base64", i);
            }
            g->buf[i] = b64_decode(comma + 1, strlen(comma + 1), &g->buf_len[i]);
            st = g->buf[i]
                     ? EVR_OK
                     : evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF buffers");
        } else if (!g->src->dir && !g->src->allow_external) {
            st = evr_import_fail(
                err, EVR_ERR_FORMAT,
                "glTF: buffer %d is an external file, which a scene in memory cannot read", i);
        } else {
            char name[1024], path[1600], what[32];
            evr_gltf_uri_decode(text, name, sizeof name);
            snprintf(path, sizeof path, "%s%s", g->src->dir && name[0] != '/' ? g->src->dir : "",
                     name);
            snprintf(what, sizeof what, "glTF: buffer %d", i);
            st = evr_import_file_check(g->src->dir, path, g->src->allow_external, what, err);
            if (st == EVR_OK) st = evr_import_read_file(path, 0, &g->buf[i], &g->buf_len[i], err);
        }
        free(text);
    }
    if (st == EVR_OK && !g->buf[i]) st = evr_import_fail(err, EVR_ERR_NOMEM, "out of memory");
    return st;
}

static int type_components(const evr_jdoc *d, int acc)
{
    char t[16];
    static const char *names[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
    static const int comps[] = {1, 2, 3, 4, 4, 9, 16};
    int i;
    if (!evr_jdoc_string(d, evr_jdoc_get(d, acc, "type"), t, sizeof t)) return 0;
    for (i = 0; i < 7; i++)
        if (!strcmp(t, names[i])) return comps[i];
    return 0;
}

static int component_size(int ctype)
{
    switch (ctype) {
    case 5120:
    case 5121: return 1;
    case 5122:
    case 5123: return 2;
    case 5125:
    case 5126: return 4;
    default: return 0;
    }
}

/* One component at p as a double (normalized integers to [0, 1] or [-1, 1]). */
static double component(const unsigned char *p, int ctype, int normalized)
{
    double v;
    switch (ctype) {
    case 5120: v = (signed char)p[0]; return normalized ? (v / 127.0 < -1.0 ? -1.0 : v / 127.0) : v;
    case 5121: v = p[0]; return normalized ? v / 255.0 : v;
    case 5122:
        v = (int16_t)evr_get_le16(p);
        return normalized ? (v / 32767.0 < -1.0 ? -1.0 : v / 32767.0) : v;
    case 5123: v = evr_get_le16(p); return normalized ? v / 65535.0 : v;
    case 5125: return (double)evr_get_le32(p);
    default: {
        uint32_t u = evr_get_le32(p);
        float f;
        memcpy(&f, &u, sizeof f);
        return f;
    }
    }
}

int evr_gltf_accessor_count(const gltf_data *g, int a, int *ncomp)
{
    int acc = evr_gltf_accessor(g, a);
    if (ncomp) *ncomp = acc < 0 ? 0 : type_components(g->d, acc);
    if (acc < 0) return -1;
    return evr_gltf_index(g->d, evr_jdoc_get(g->d, acc, "count"));
}

/* The bytes of bufferView `view` from byte `offset` on: *p and how many remain (*room); *stride
 * the view's byteStride (0 when absent). */
static evr_status view_bytes(gltf_data *g, int view, double offset, const unsigned char **p,
                             size_t *room, size_t *stride, int a, evr_error *err)
{
    const evr_jdoc *d = g->d;
    int v = view >= 0 && view < g->num_views ? g->view_v[view] : -1, b;
    double boff, blen, bi;
    evr_status st;
    if (v < 0)
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: accessor %d has no buffer view", a);
    bi = evr_jdoc_number(d, evr_jdoc_get(d, v, "buffer"), -1);
    boff = evr_jdoc_number(d, evr_jdoc_get(d, v, "byteOffset"), 0);
    blen = evr_jdoc_number(d, evr_jdoc_get(d, v, "byteLength"), -1);
    if (stride) { /* absent: 0 (tightly packed) */
        int bs = evr_gltf_index(d, evr_jdoc_get(d, v, "byteStride"));
        *stride = bs > 0 ? (size_t)bs : 0;
    }
    if (!(bi >= 0 && bi < g->num_buffers) || !(boff >= 0) || !(blen >= 0) || !(offset >= 0) ||
        offset > blen)
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: accessor %d's buffer view is invalid",
                               a);
    b = (int)bi;
    if ((st = load_buffer(g, b, err)) != EVR_OK) return st;
    if (boff + blen > (double)g->buf_len[b])
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "glTF: buffer view %d reaches past the end of buffer %d", view, b);
    *p = g->buf[b] + (size_t)boff + (size_t)offset;
    *room = (size_t)(blen - offset);
    return EVR_OK;
}

evr_status evr_gltf_accessor_read(gltf_data *g, int a, double **out, int *count, int *ncomp,
                                  evr_error *err)
{
    const evr_jdoc *d = g->d;
    int acc = evr_gltf_accessor(g, a), ctype, csize, nc, norm, view, sparse;
    double cnt;
    size_t n, i, elem;
    double *vals;
    evr_status st;
    *out = NULL;
    if (acc < 0) return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: accessor %d is missing", a);
    ctype = evr_gltf_index(d, evr_jdoc_get(d, acc, "componentType"));
    csize = component_size(ctype);
    nc = type_components(d, acc);
    { /* a JSON boolean (evr_jdoc_number reads numbers only) */
        int nv = evr_jdoc_get(d, acc, "normalized");
        norm = evr_jdoc_type(d, nv) == EVR_JDOC_BOOL && d->v[nv].num != 0;
    }
    cnt = evr_jdoc_number(d, evr_jdoc_get(d, acc, "count"), -1);
    /* matrices of 1- and 2-byte components pad their columns: never needed here (float
     * matrices have no padding) */
    if (!csize || !nc || (nc > 4 && csize < 4) || !(cnt >= 0 && cnt <= (double)(1 << 30)))
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "glTF: accessor %d has an unsupported type or count", a);
    n = (size_t)cnt;
    elem = (size_t)nc * (size_t)csize;
    vals = calloc(n * (size_t)nc + 1, sizeof *vals);
    if (!vals) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading a glTF accessor");
    view = evr_gltf_index(d, evr_jdoc_get(d, acc, "bufferView"));
    if (view >= 0 && n > 0) { /* no view: zeros, then the sparse values */
        const unsigned char *p;
        size_t room, stride;
        st = view_bytes(g, view, evr_jdoc_number(d, evr_jdoc_get(d, acc, "byteOffset"), 0), &p,
                        &room, &stride, a, err);
        if (st != EVR_OK) goto fail;
        if (stride == 0) stride = elem;
        if (stride < elem || (n - 1) * stride + elem > room) {
            st = evr_import_fail(err, EVR_ERR_FORMAT,
                                 "glTF: accessor %d reaches past the end of its buffer view", a);
            goto fail;
        }
        for (i = 0; i < n; i++)
            for (int c = 0; c < nc; c++)
                vals[i * (size_t)nc + (size_t)c] =
                    component(p + i * stride + (size_t)c * (size_t)csize, ctype, norm);
    }
    sparse = evr_jdoc_get(d, acc, "sparse");
    if (sparse >= 0) {
        int ind = evr_jdoc_get(d, sparse, "indices"), val = evr_jdoc_get(d, sparse, "values");
        double sc = evr_jdoc_number(d, evr_jdoc_get(d, sparse, "count"), -1);
        int itype = evr_gltf_index(d, evr_jdoc_get(d, ind, "componentType"));
        int isize = component_size(itype);
        const unsigned char *pi, *pv;
        size_t ri, rv, k, m;
        if (!(sc >= 1 && sc <= cnt) || (itype != 5121 && itype != 5123 && itype != 5125)) {
            st = evr_import_fail(err, EVR_ERR_FORMAT, "glTF: accessor %d's sparse part is invalid",
                                 a);
            goto fail;
        }
        m = (size_t)sc;
        if ((st = view_bytes(g, evr_gltf_index(d, evr_jdoc_get(d, ind, "bufferView")),
                             evr_jdoc_number(d, evr_jdoc_get(d, ind, "byteOffset"), 0), &pi, &ri,
                             NULL, a, err)) != EVR_OK ||
            (st = view_bytes(g, evr_gltf_index(d, evr_jdoc_get(d, val, "bufferView")),
                             evr_jdoc_number(d, evr_jdoc_get(d, val, "byteOffset"), 0), &pv, &rv,
                             NULL, a, err)) != EVR_OK)
            goto fail;
        if (m * (size_t)isize > ri || m * elem > rv) {
            st = evr_import_fail(err, EVR_ERR_FORMAT,
                                 "glTF: accessor %d's sparse part reaches past its buffer view", a);
            goto fail;
        }
        for (k = 0; k < m; k++) {
            size_t at = (size_t)component(pi + k * (size_t)isize, itype, 0);
            if (at >= n) {
                st = evr_import_fail(err, EVR_ERR_FORMAT,
                                     "glTF: accessor %d's sparse index %zu is out of range", a, at);
                goto fail;
            }
            for (int c = 0; c < nc; c++)
                vals[at * (size_t)nc + (size_t)c] =
                    component(pv + k * elem + (size_t)c * (size_t)csize, ctype, norm);
        }
    }
    *out = vals;
    *count = (int)n;
    *ncomp = nc;
    return EVR_OK;
fail:
    free(vals);
    return st;
}

evr_status evr_gltf_image_source(gltf_data *g, int img, unsigned char **data, size_t *n, char *path,
                                 size_t cap, evr_error *err)
{
    const evr_jdoc *d = g->d;
    int uri = evr_jdoc_get(d, img, "uri"),
        view = evr_gltf_index(d, evr_jdoc_get(d, img, "bufferView"));
    evr_status st = EVR_OK;
    *data = NULL;
    *n = 0;
    path[0] = 0;
    if (uri >= 0) {
        size_t len = d->v[uri].len + 1;
        char *text = malloc(len);
        if (!text) return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF images");
        evr_jdoc_string(d, uri, text, len);
        if (!strncmp(text, "data:", 5)) {
            const char *comma = strchr(text, ',');
            if (!comma || !strstr(text, ";base64,"))
                st = evr_import_fail(err, EVR_ERR_FORMAT,
                                     "glTF: an image's data: URI is not base64");
            else if (!(*data = b64_decode(comma + 1, strlen(comma + 1), n)))
                st = evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF images");
        } else {
            char name[1024];
            evr_gltf_uri_decode(text, name, sizeof name);
            /* a scene in memory: relative to the current folder, as Assimp would look */
            snprintf(path, cap, "%s%s", g->src->dir && name[0] != '/' ? g->src->dir : "", name);
        }
        free(text);
        return st;
    }
    if (view >= 0) {
        const unsigned char *p;
        size_t room;
        int v = view < g->num_views ? g->view_v[view] : -1;
        if (v < 0)
            return evr_import_fail(err, EVR_ERR_FORMAT,
                                   "glTF: an image's buffer view %d is missing", view);
        if ((st = view_bytes(g, view, 0, &p, &room, NULL, -1, err)) != EVR_OK) return st;
        if (!(*data = malloc(room + 1)))
            return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading glTF images");
        memcpy(*data, p, room);
        *n = room;
        return EVR_OK;
    }
    return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: an image has neither uri nor bufferView");
}
