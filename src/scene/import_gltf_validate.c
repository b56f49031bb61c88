/* A glTF 2.0 file checked against its own structure before Assimp reads it (evr_gltf_validate,
 * first of the stages in import.c's gltf_before_assimp). Assimp 5.2 trusts what the file says:
 * a GLB's chunk lengths (a 2.6 KB file made it allocate 4.2 GB), accessor and index ranges (a
 * LINE_LOOP with indices past the vertices, an animation channel naming a node that does not
 * exist: both crashed it), and it accepts NaN vertices, keys and quaternions, a node translation
 * given as a string, cameras with a zero field of view. Here each of those is one line naming
 * the element, and "no suitable reader" is left for files that are not glTF at all.
 *
 * This unit checks the container and the binary data (buffers, views, accessors, and the
 * numbers in them); import_gltf_validate_refs.c the elements that use them (meshes, nodes,
 * scenes, skins, animations, cameras, lights, textures). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "io/byte_order.h"
#include "scene/import_gltf_validate.h"

int evr_gv_fail(gv *c, const char *fmt, ...)
{
    char line[sizeof c->err->msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    evr_import_fail(c->err, EVR_ERR_FORMAT, "glTF: %s", line);
    return -1;
}

int evr_gv_array(gv *c, int obj, const char *key, const char *what)
{
    int v = evr_jdoc_get(c->d, obj, key);
    if (v >= 0 && evr_jdoc_type(c->d, v) != EVR_JDOC_ARRAY)
        return evr_gv_fail(c, "%s: '%s' must be an array", what, key), -2;
    return v;
}

int evr_gv_index(gv *c, int obj, const char *key, int n, int required, const char *what,
                 const char *of, int *out)
{
    int v = evr_jdoc_get(c->d, obj, key);
    *out = -1;
    if (v < 0) return required ? evr_gv_fail(c, "%s has no '%s'", what, key) : 0;
    return evr_gv_index_value(c, v, n, what, of, out);
}

int evr_gv_index_value(gv *c, int v, int n, const char *what, const char *of, int *out)
{
    double x = evr_jdoc_number(c->d, v, -1);
    if (evr_jdoc_type(c->d, v) != EVR_JDOC_NUMBER || x != floor(x))
        return evr_gv_fail(c, "%s: a %s index must be a whole number", what, of);
    if (!(x >= 0 && x < n))
        return evr_gv_fail(c, "%s names %s %.0f, which the file does not have (it has %d)", what,
                           of, x, n);
    *out = (int)x;
    return 0;
}

int evr_gv_integer(gv *c, int obj, const char *key, double lo, double hi, double def,
                   const char *what, double *out)
{
    int v = evr_jdoc_get(c->d, obj, key);
    double x = evr_jdoc_number(c->d, v, NAN);
    if (v < 0) {
        if (isnan(def)) return evr_gv_fail(c, "%s has no '%s'", what, key);
        *out = def;
        return 0;
    }
    if (!(x >= lo && x <= hi) || x != floor(x))
        return evr_gv_fail(c, "%s: '%s' must be an integer from %.0f to %.0f", what, key, lo, hi);
    *out = x;
    return 0;
}

int evr_gv_numbers(gv *c, int obj, const char *key, int want, double *out, const char *what)
{
    int v = evr_jdoc_get(c->d, obj, key), e, k = 0;
    if (v < 0) return 1;
    if (evr_jdoc_type(c->d, v) != EVR_JDOC_ARRAY || (want > 0 && evr_jdoc_count(c->d, v) != want))
        return want > 0 ? evr_gv_fail(c, "%s: '%s' must be an array of %d numbers", what, key, want)
                        : evr_gv_fail(c, "%s: '%s' must be an array of numbers", what, key);
    for (e = evr_jdoc_first(c->d, v); e >= 0; e = evr_jdoc_next(c->d, e), k++) {
        double x = evr_jdoc_number(c->d, e, NAN);
        if (evr_jdoc_type(c->d, e) != EVR_JDOC_NUMBER || !isfinite(x))
            return evr_gv_fail(c, "%s: '%s' must hold finite numbers", what, key);
        if (out && k < want) out[k] = x;
    }
    return 0;
}

int evr_gv_number(gv *c, int obj, const char *key, double def, const char *what, double *out)
{
    int v = evr_jdoc_get(c->d, obj, key);
    double x = evr_jdoc_number(c->d, v, NAN);
    if (v < 0) {
        *out = def;
        return 0;
    }
    if (evr_jdoc_type(c->d, v) != EVR_JDOC_NUMBER || !isfinite(x))
        return evr_gv_fail(c, "%s: '%s' must be a finite number", what, key);
    *out = x;
    return 0;
}

/* ---- the GLB container ---- */

/* 8 bytes of the file at `at`: from memory when the bytes hold them, else read from the file. */
static int read_at(const gv *c, size_t at, unsigned char out[8])
{
    FILE *f;
    int ok;
    if (c->src->nbytes >= at + 8) {
        memcpy(out, c->src->bytes + at, 8);
        return 1;
    }
    if (!c->src->path || !(f = fopen(c->src->path, "rb"))) return 0;
    ok = fseek(f, (long)at, SEEK_SET) == 0 && fread(out, 1, 8, f) == 8;
    fclose(f);
    return ok;
}

/* The header's length against the file's, each chunk inside the file: nothing is allocated from
 * a length the file cannot back. */
static int check_glb(gv *c)
{
    const unsigned char *b = c->src->bytes;
    size_t fsize = c->src->nbytes, at;
    uint32_t version, total, jlen;
    struct stat sb;
    if (c->src->path && stat(c->src->path, &sb) == 0) fsize = (size_t)sb.st_size;
    if (c->src->nbytes < 12)
        return evr_gv_fail(c, "the GLB is %zu bytes, shorter than its 12-byte header",
                           c->src->nbytes);
    version = evr_get_le32(b + 4);
    total = evr_get_le32(b + 8);
    if (version != 2) return evr_gv_fail(c, "GLB version %u: evray reads glTF 2.0", version);
    if (total != fsize)
        return evr_gv_fail(c, "the GLB header gives a length of %u bytes, the file has %zu", total,
                           fsize);
    if (c->src->nbytes < 20 || memcmp(b + 16, "JSON", 4))
        return evr_gv_fail(c, "the GLB has no JSON chunk");
    jlen = evr_get_le32(b + 12);
    if (jlen > total - 20)
        return evr_gv_fail(c, "the GLB's JSON chunk of %u bytes reaches past the end of the file",
                           jlen);
    at = 20 + (size_t)jlen;
    at = (at + 3) & ~(size_t)3; /* chunks start 4-byte aligned */
    while (at < total) {
        unsigned char head[8];
        uint32_t clen;
        if (total - at < 8 || !read_at(c, at, head))
            return evr_gv_fail(c, "the GLB ends inside a chunk header at byte %zu", at);
        clen = evr_get_le32(head);
        if (clen > total - at - 8)
            return evr_gv_fail(c,
                               "the GLB's chunk at byte %zu (%u bytes) reaches past the end "
                               "of the file",
                               at, clen);
        if (!memcmp(head + 4, "BIN", 4) && !c->has_bin &&
            at == ((20 + (size_t)jlen + 3) & ~(size_t)3)) {
            c->has_bin = 1;
            c->bin_len = clen;
        }
        at += 8 + (size_t)clen;
        at = (at + 3) & ~(size_t)3;
    }
    return 0;
}

/* ---- buffers, views, accessors ---- */

static int mime_char(char ch)
{
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           (ch && strchr("!#$&^_.+-", ch));
}

int evr_gv_data_uri(const char *uri)
{
    const char *p = uri + 5; /* after "data:" */
    int n = 0;
    /* Assimp 5.2 dereferences the media type it fails to parse: type/subtype;base64, only, */
    while (mime_char(*p)) p++, n++;
    if (!n || *p++ != '/') return 0;
    for (n = 0; mime_char(*p); p++) n++;
    /* and keeps the offsets of its parts in a char: past 127 bytes they wrap */
    return n && !strncmp(p, ";base64,", 8) && p + 8 - uri < 128;
}

size_t evr_gv_base64(const char *s, size_t n, int json)
{
    size_t i, k = 0, pad = 0;
    for (i = 0; i < n; i++) {
        char ch = s[i];
        if (json && ch == '\\' && i + 1 < n && s[i + 1] == '/') ch = s[++i]; /* JSON's "\/" */
        if (ch == '=') {
            pad++;
        } else if (pad || !((ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') ||
                            (ch >= '0' && ch <= '9') || ch == '+' || ch == '/')) {
            return (size_t)-1; /* Assimp fails on it, and leaks */
        }
        k++;
    }
    if (k % 4 || pad > 2) return (size_t)-1;
    return k / 4 * 3 - pad;
}

static int check_buffer(gv *c, int i, int b)
{
    char what[32], *text;
    const evr_jdoc *d = c->d;
    int uri = evr_jdoc_get(d, b, "uri");
    double len = 0;
    snprintf(what, sizeof what, "buffer %d", i);
    if (evr_jdoc_type(d, b) != EVR_JDOC_OBJECT) return evr_gv_fail(c, "%s is not an object", what);
    if (evr_gv_integer(c, b, "byteLength", 1, 9007199254740992.0, NAN, what, &len)) return -1;
    c->buf_len[i] = len;
    if (uri < 0) {
        if (!c->glb || i != 0)
            return evr_gv_fail(c, "%s has no uri (only a GLB's first buffer may be its BIN chunk)",
                               what);
        if (!c->has_bin) return evr_gv_fail(c, "%s is the GLB's BIN chunk, which it lacks", what);
        if ((double)c->bin_len < len)
            return evr_gv_fail(c, "%s needs %.0f bytes, the GLB's BIN chunk has %zu", what, len,
                               c->bin_len);
        return 0;
    }
    if (evr_jdoc_type(d, uri) != EVR_JDOC_STRING)
        return evr_gv_fail(c, "%s: 'uri' must be a string", what);
    if (!(text = malloc(d->v[uri].len + 1))) {
        c->err_status = evr_import_fail(c->err, EVR_ERR_NOMEM, "out of memory checking the glTF");
        return -1;
    }
    evr_jdoc_string(d, uri, text, d->v[uri].len + 1);
    if (!strncmp(text, "data:", 5)) {
        const char *comma = strstr(text, ";base64,");
        size_t have = comma ? evr_gv_base64(comma + 8, strlen(comma + 8), 0) : 0;
        int ok = evr_gv_data_uri(text);
        free(text);
        if (!ok)
            return evr_gv_fail(
                c, "%s's data: URI does not start data:TYPE/SUBTYPE;base64, (in under 128 bytes)",
                what);
        if (have == (size_t)-1) return evr_gv_fail(c, "%s's data: URI is not valid base64", what);
        if ((double)have < len)
            return evr_gv_fail(c, "%s's data: URI holds %zu bytes, its byteLength says %.0f", what,
                               have, len);
        return 0;
    }
    {
        char name[1024], path[1600];
        struct stat sb;
        evr_gltf_uri_decode(text, name, sizeof name);
        free(text);
        if (!c->src->dir && !c->src->allow_external)
            return evr_gv_fail(c,
                               "%s is an external file ('%s'), which a scene in memory cannot "
                               "read",
                               what, name);
        snprintf(path, sizeof path, "%s%s", c->src->dir && name[0] != '/' ? c->src->dir : "", name);
        snprintf(what, sizeof what, "glTF: buffer %d", i);
        if ((c->err_status = evr_import_file_check(c->src->dir, path, c->src->allow_external, what,
                                                   c->err)) != EVR_OK)
            return -1;
        if (stat(path, &sb) != 0 || (double)sb.st_size < len)
            return evr_gv_fail(c, "buffer %d ('%s') has %lld bytes, its byteLength says %.0f", i,
                               name, (long long)sb.st_size, len);
    }
    return 0;
}

static int check_view(gv *c, int i, int v)
{
    char what[32];
    int b;
    double off = 0, len = 0, stride = 0;
    snprintf(what, sizeof what, "buffer view %d", i);
    if (evr_jdoc_type(c->d, v) != EVR_JDOC_OBJECT)
        return evr_gv_fail(c, "%s is not an object", what);
    if (evr_gv_index(c, v, "buffer", c->n_buffers, 1, what, "buffer", &b) ||
        evr_gv_integer(c, v, "byteOffset", 0, 9007199254740992.0, 0, what, &off) ||
        evr_gv_integer(c, v, "byteLength", 1, 9007199254740992.0, NAN, what, &len) ||
        evr_gv_integer(c, v, "byteStride", 4, 252, 0, what, &stride))
        return -1;
    if (off + len > c->buf_len[b])
        return evr_gv_fail(c,
                           "%s (bytes %.0f to %.0f) reaches past the end of buffer %d (%.0f "
                           "bytes)",
                           what, off, off + len, b, c->buf_len[b]);
    if (fmod(stride, 4.0) != 0.0)
        return evr_gv_fail(c, "%s: byteStride %.0f is not a multiple of 4", what, stride);
    c->view_len[i] = len;
    c->view_stride[i] = stride;
    return 0;
}

static int type_comps(const char *t)
{
    static const char *names[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
    static const int comps[] = {1, 2, 3, 4, 4, 9, 16};
    int i;
    for (i = 0; i < 7; i++)
        if (!strcmp(t, names[i])) return comps[i];
    return 0;
}

static int ctype_size(int ct)
{
    return ct == 5120 || ct == 5121   ? 1
           : ct == 5122 || ct == 5123 ? 2
           : ct == 5125 || ct == 5126 ? 4
                                      : 0;
}

/* Bytes of one element (glTF pads each matrix column of 1- and 2-byte components to 4). */
static double elem_size(int nc, int cs)
{
    if (nc == 4 && cs == 1) return 4; /* VEC4 or MAT2 of bytes: the same 4 bytes */
    if (nc == 9 && cs < 4) return 3 * 4 * (cs == 1 ? 1 : 2);
    if (nc == 16) return 16.0 * cs;
    return (double)nc * cs;
}

/* `count` elements of elem bytes from `off` in view `view`, at its stride or packed. */
static int fits_view(gv *c, int view, double off, double count, double elem, const char *what)
{
    double stride = c->view_stride[view] > 0 ? c->view_stride[view] : elem;
    if (stride < elem)
        return evr_gv_fail(c, "%s: elements of %.0f bytes in buffer view %d of stride %.0f", what,
                           elem, view, stride);
    if (off + stride * (count - 1) + elem > c->view_len[view])
        return evr_gv_fail(c,
                           "%s (%.0f elements of %.0f bytes from byte %.0f) reaches past the "
                           "end of buffer view %d (%.0f bytes)",
                           what, count, elem, off, view, c->view_len[view]);
    return 0;
}

/* An accessor with no buffer view is zeros (and sparse values): its size comes from its count
 * alone, so it is bounded here rather than by the file. */
#define MAX_VIEWLESS_COUNT (1 << 24)

static int check_accessor(gv *c, int i, int a)
{
    const evr_jdoc *d = c->d;
    char what[32], type[16];
    double ct = 0, count = 0, off = 0;
    int view, nc, cs, sparse, nv;
    snprintf(what, sizeof what, "accessor %d", i);
    if (evr_jdoc_type(d, a) != EVR_JDOC_OBJECT) return evr_gv_fail(c, "%s is not an object", what);
    if (evr_gv_integer(c, a, "componentType", 5120, 5126, NAN, what, &ct) ||
        evr_gv_integer(c, a, "count", 1, 2147483647.0, NAN, what, &count) ||
        evr_gv_index(c, a, "bufferView", c->n_views, 0, what, "buffer view", &view) ||
        evr_gv_integer(c, a, "byteOffset", 0, 9007199254740992.0, 0, what, &off))
        return -1;
    cs = ctype_size((int)ct);
    if (!cs || ct == 5124)
        return evr_gv_fail(c, "%s: componentType %.0f is not one of glTF's", what, ct);
    if (!evr_jdoc_string(d, evr_jdoc_get(d, a, "type"), type, sizeof type) ||
        !(nc = type_comps(type)))
        return evr_gv_fail(c, "%s: 'type' must be SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4",
                           what);
    nv = evr_jdoc_get(d, a, "normalized");
    if (nv >= 0 && evr_jdoc_type(d, nv) != EVR_JDOC_BOOL)
        return evr_gv_fail(c, "%s: 'normalized' must be true or false", what);
    if (evr_gv_numbers(c, a, "min", nc, NULL, what) < 0 ||
        evr_gv_numbers(c, a, "max", nc, NULL, what) < 0)
        return -1;
    if (view >= 0) {
        if (fits_view(c, view, off, count, elem_size(nc, cs), what)) return -1;
    } else if (evr_jdoc_get(d, a, "sparse") < 0) {
        /* zeros by glTF's rule, but Assimp 5.2 fails on it ("data is null") and leaks */
        return evr_gv_fail(c, "%s has no buffer view (evray reads no accessor of zeros)", what);
    } else if (count > MAX_VIEWLESS_COUNT) {
        return evr_gv_fail(c, "%s has %.0f elements but no buffer view (at most %d)", what, count,
                           MAX_VIEWLESS_COUNT);
    }
    sparse = evr_jdoc_get(d, a, "sparse");
    if (sparse >= 0) {
        int ind = evr_jdoc_get(d, sparse, "indices"), val = evr_jdoc_get(d, sparse, "values");
        int iv, vv;
        double sc = 0, ict = 0, ioff = 0, voff = 0;
        if (evr_gv_integer(c, sparse, "count", 1, count, NAN, what, &sc) ||
            evr_gv_index(c, ind, "bufferView", c->n_views, 1, what, "buffer view", &iv) ||
            evr_gv_integer(c, ind, "componentType", 5121, 5125, NAN, what, &ict) ||
            evr_gv_integer(c, ind, "byteOffset", 0, 9007199254740992.0, 0, what, &ioff) ||
            evr_gv_index(c, val, "bufferView", c->n_views, 1, what, "buffer view", &vv) ||
            evr_gv_integer(c, val, "byteOffset", 0, 9007199254740992.0, 0, what, &voff))
            return -1;
        if (ict != 5121 && ict != 5123 && ict != 5125)
            return evr_gv_fail(c, "%s: sparse indices must be unsigned integers", what);
        /* sparse parts are tightly packed, whatever the view's stride */
        if (ioff + sc * ctype_size((int)ict) > c->view_len[iv] ||
            voff + sc * elem_size(nc, cs) > c->view_len[vv])
            return evr_gv_fail(c, "%s's sparse part reaches past its buffer view", what);
    }
    c->acc_count[i] = (int)count;
    c->acc_comps[i] = nc;
    c->acc_ctype[i] = (int)ct;
    return 0;
}

int evr_gv_read(gv *c, int a, double **vals, int *count, int *nc)
{
    evr_status st = evr_gltf_accessor_read(&c->data, a, vals, count, nc, c->err);
    if (st == EVR_OK) return 0;
    c->err_status = st;
    return -1;
}

int evr_gv_finite(gv *c, int a, const char *what)
{
    double *v = NULL;
    int n, nc;
    size_t k;
    if (c->acc_checked[a]) return 0;
    c->acc_checked[a] = 1;
    if (evr_gv_read(c, a, &v, &n, &nc)) return -1;
    for (k = 0; k < (size_t)n * (size_t)nc; k++)
        if (!isfinite(v[k])) {
            free(v);
            return evr_gv_fail(c, "%s: accessor %d holds a value that is not finite (element %zu)",
                               what, a, k / (size_t)nc);
        }
    free(v);
    return 0;
}

static void gv_free(gv *c)
{
    free(c->buf_len);
    free(c->view_len);
    free(c->view_stride);
    free(c->acc_count);
    free(c->acc_comps);
    free(c->acc_ctype);
    free(c->acc_checked);
    free(c->parent);
    evr_gltf_data_free(&c->data);
}

static int count_of(gv *c, const char *key, int *n)
{
    int v = evr_gv_array(c, c->root, key, "the document");
    if (v == -2) return -1;
    *n = evr_jdoc_count(c->d, v);
    return 0;
}

evr_status evr_gltf_validate(const gltf_source *src, evr_error *err)
{
    evr_jdoc d;
    gv c;
    const char *json;
    size_t jlen;
    char version[16];
    int i, v, bad = 0;
    evr_status st = EVR_OK;
    memset(&c, 0, sizeof c);
    c.src = src;
    c.err = err;
    c.d = &d;
    c.glb = src->nbytes >= 4 && !memcmp(src->bytes, "glTF", 4);
    if (c.glb && check_glb(&c)) return EVR_ERR_FORMAT;
    if (!evr_gltf_json_span(src->bytes, src->nbytes, &json, &jlen))
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB has no JSON chunk");
    c.root = evr_jdoc_parse(&d, json, jlen);
    if (c.root < 0 || evr_jdoc_type(&d, c.root) != EVR_JDOC_OBJECT) {
        st = d.failed ? evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
             : c.root < 0 ? evr_import_fail(err, EVR_ERR_FORMAT,
                                            "glTF: cannot parse the JSON near byte %zu", d.pos)
                          : evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the JSON is not an object");
        evr_jdoc_free(&d);
        return st;
    }
    if (!evr_jdoc_string(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, c.root, "asset"), "version"),
                         version, sizeof version)) {
        evr_jdoc_free(&d);
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: no asset.version: not a glTF 2.0 file");
    }
    if (strncmp(version, "2.", 2)) {
        evr_jdoc_free(&d);
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "glTF: version '%s': evray reads glTF 2.0 (convert the file)",
                               version);
    }
    if (count_of(&c, "buffers", &c.n_buffers) || count_of(&c, "bufferViews", &c.n_views) ||
        count_of(&c, "accessors", &c.n_acc) || count_of(&c, "meshes", &c.n_meshes) ||
        count_of(&c, "nodes", &c.n_nodes) || count_of(&c, "scenes", &c.n_scenes) ||
        count_of(&c, "skins", &c.n_skins) || count_of(&c, "cameras", &c.n_cameras) ||
        count_of(&c, "materials", &c.n_materials) || count_of(&c, "textures", &c.n_textures) ||
        count_of(&c, "images", &c.n_images) || count_of(&c, "samplers", &c.n_samplers) ||
        count_of(&c, "animations", &c.n_anims)) {
        evr_jdoc_free(&d);
        return EVR_ERR_FORMAT;
    }
    c.buf_len = calloc((size_t)c.n_buffers + 1, sizeof *c.buf_len);
    c.view_len = calloc((size_t)c.n_views + 1, sizeof *c.view_len);
    c.view_stride = calloc((size_t)c.n_views + 1, sizeof *c.view_stride);
    c.acc_count = calloc((size_t)c.n_acc + 1, sizeof *c.acc_count);
    c.acc_comps = calloc((size_t)c.n_acc + 1, sizeof *c.acc_comps);
    c.acc_ctype = calloc((size_t)c.n_acc + 1, sizeof *c.acc_ctype);
    c.acc_checked = calloc((size_t)c.n_acc + 1, 1);
    c.parent = malloc(((size_t)c.n_nodes + 1) * sizeof *c.parent);
    if (!c.buf_len || !c.view_len || !c.view_stride || !c.acc_count || !c.acc_comps ||
        !c.acc_ctype || !c.acc_checked || !c.parent ||
        evr_gltf_data_init(&c.data, &d, c.root, src, err) != EVR_OK) {
        gv_free(&c);
        evr_jdoc_free(&d);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory checking the glTF");
    }
    for (i = 0, v = evr_jdoc_first(&d, evr_jdoc_get(&d, c.root, "buffers")); v >= 0 && !bad;
         v = evr_jdoc_next(&d, v), i++)
        bad = check_buffer(&c, i, v);
    for (i = 0, v = evr_jdoc_first(&d, evr_jdoc_get(&d, c.root, "bufferViews")); v >= 0 && !bad;
         v = evr_jdoc_next(&d, v), i++)
        bad = check_view(&c, i, v);
    for (i = 0, v = evr_jdoc_first(&d, evr_jdoc_get(&d, c.root, "accessors")); v >= 0 && !bad;
         v = evr_jdoc_next(&d, v), i++)
        bad = check_accessor(&c, i, v);
    if (!bad) bad = evr_gv_refs(&c);
    st = !bad ? EVR_OK : c.err_status != EVR_OK ? c.err_status : EVR_ERR_FORMAT;
    gv_free(&c);
    evr_jdoc_free(&d);
    return st;
}
