/* Scene import through Assimp's C API, into the flattened evr_scene model (scene.h).
 *
 * What we keep from Assimp: triangles (points and lines are dropped), the node hierarchy with
 * each node's rest transform, one instance per (node, mesh) pair, metallic-roughness materials,
 * base colour textures (decoded with stb_image and linearized), punctual lights, perspective
 * cameras, and node animation curves converted to seconds.
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
 *  Also from the JSON: KHR_materials_emissive_strength, which Assimp 5.2 does not import.
 *  Lights: for glTF, aiLight.mColorDiffuse already holds colour * intensity (candela for point
 *      and spot, lux for directional), and the spot cone angles are glTF's half angles.
 *
 * For other formats: mHorizontalFOV is documented as the half angle, but Assimp's importers
 * (Collada's xfov, FBX's FieldOfView) store the full horizontal angle, so we read it as the full
 * angle and convert with the aspect; spot cone angles are read as full angles (Collada's falloff
 * angle, FBX's cone angles) and halved; the camera pose comes from mPosition/mLookAt/mUp. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <assimp/cimport.h>
#include <assimp/scene.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/config.h>
#include <stb/stb_image.h>

#include "scene/scene.h"
#include "core/photon.h"

#define EVR_PI_D 3.14159265358979323846

/* ------------------------------------------------------------------------------------------ */
/* Errors                                                                                     */

/* Fills err with one line (newlines from library messages become spaces) and returns st. */
static evr_status fail(evr_error *err, evr_status st, const char *fmt, ...)
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

static void copy_name(char *dst, size_t cap, const char *src)
{
    size_t n = src ? strlen(src) : 0;
    if (n >= cap) n = cap - 1;
    if (n) memcpy(dst, src, n);
    dst[n] = 0;
}

/* ------------------------------------------------------------------------------------------ */
/* A growable text buffer (for evr_scene_describe)                                           */

typedef struct {
    char *buf;
    size_t len, cap;
    int failed;
} strbuf;

static void sb_printf(strbuf *b, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (b->failed) return;
    for (;;) {
        size_t room = b->cap - b->len;
        va_start(ap, fmt);
        n = vsnprintf(b->buf ? b->buf + b->len : NULL, b->buf ? room : 0, fmt, ap);
        va_end(ap);
        if (n < 0) { b->failed = 1; return; }
        if (b->buf && (size_t)n < room) { b->len += (size_t)n; return; }
        {
            size_t ncap = b->cap ? b->cap * 2 : 1024;
            char *nb;
            while (ncap < b->len + (size_t)n + 1) ncap *= 2;
            nb = realloc(b->buf, ncap);
            if (!nb) { b->failed = 1; return; }
            b->buf = nb;
            b->cap = ncap;
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Files                                                                                      */

/* Reads at most max bytes of a file (the whole file when max is 0). */
static evr_status read_file(const char *path, size_t max, unsigned char **data, size_t *size, evr_error *err)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    size_t len = 0, cap = 0;
    *data = NULL;
    *size = 0;
    if (!f) return fail(err, EVR_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    for (;;) {
        size_t want, got;
        if (len == cap) {
            size_t ncap = cap ? cap * 2 : 65536;
            unsigned char *nb;
            if (max && ncap > max) ncap = max;
            if (ncap == cap) break;
            nb = realloc(buf, ncap + 1);
            if (!nb) { free(buf); fclose(f); return fail(err, EVR_ERR_NOMEM, "out of memory reading '%s'", path); }
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
                return fail(err, EVR_ERR_IO, "cannot read '%s': %s", path, strerror(errno));
            }
            break;
        }
    }
    fclose(f);
    if (!buf) {
        buf = malloc(1);
        if (!buf) return fail(err, EVR_ERR_NOMEM, "out of memory reading '%s'", path);
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

/* ------------------------------------------------------------------------------------------ */
/* A minimal JSON reader: enough of the glTF JSON for what Assimp 5.2 does not pass on        */

enum { J_NULL, J_BOOL, J_NUM, J_STR, J_ARR, J_OBJ };

typedef struct {
    unsigned char type;
    int first, next;          /* first child, next sibling; -1 for none */
    int count;                /* children */
    size_t off, len;          /* strings: the raw (escaped) text between the quotes */
    size_t key_off, key_len;  /* object members: the raw key */
    double num;
} jval;

typedef struct {
    const char *text;
    size_t len, pos;
    jval *v;
    int n, cap;
    int failed;
} jdoc;

#define J_MAX_DEPTH 128

static int j_new(jdoc *d, unsigned char type)
{
    if (d->n == d->cap) {
        int ncap = d->cap ? d->cap * 2 : 256;
        jval *nv = realloc(d->v, (size_t)ncap * sizeof *nv);
        if (!nv) { d->failed = 1; return -1; }
        d->v = nv;
        d->cap = ncap;
    }
    memset(&d->v[d->n], 0, sizeof d->v[d->n]);
    d->v[d->n].type = type;
    d->v[d->n].first = d->v[d->n].next = -1;
    return d->n++;
}

static void j_ws(jdoc *d)
{
    while (d->pos < d->len) {
        char c = d->text[d->pos];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r') break;
        d->pos++;
    }
}

/* Scans a string starting at the opening quote; sets the raw span. */
static int j_string_span(jdoc *d, size_t *off, size_t *len)
{
    size_t p = d->pos + 1;
    while (p < d->len && d->text[p] != '"') {
        if (d->text[p] == '\\') p++;
        p++;
    }
    if (p >= d->len) return 0;
    *off = d->pos + 1;
    *len = p - *off;
    d->pos = p + 1;
    return 1;
}

static int j_number(jdoc *d, double *out)
{
    size_t p = d->pos;
    double mant = 0.0, sign = 1.0;
    int exp10 = 0, esign = 1, e = 0, digits = 0;
    if (p < d->len && d->text[p] == '-') { sign = -1.0; p++; }
    while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') { mant = mant * 10.0 + (d->text[p] - '0'); p++; digits++; }
    if (p < d->len && d->text[p] == '.') {
        p++;
        while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') { mant = mant * 10.0 + (d->text[p] - '0'); exp10--; p++; digits++; }
    }
    if (!digits) return 0;
    if (p < d->len && (d->text[p] == 'e' || d->text[p] == 'E')) {
        p++;
        if (p < d->len && (d->text[p] == '+' || d->text[p] == '-')) { if (d->text[p] == '-') esign = -1; p++; }
        if (p >= d->len || d->text[p] < '0' || d->text[p] > '9') return 0;
        while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') { if (e < 10000) e = e * 10 + (d->text[p] - '0'); p++; }
    }
    *out = sign * mant * pow(10.0, (double)(exp10 + esign * e));
    d->pos = p;
    return 1;
}

static int j_value(jdoc *d, int depth);

static int j_container(jdoc *d, int depth, int is_obj)
{
    int self = j_new(d, is_obj ? J_OBJ : J_ARR), last = -1;
    if (self < 0) return -1;
    d->pos++;   /* '{' or '[' */
    j_ws(d);
    if (d->pos < d->len && d->text[d->pos] == (is_obj ? '}' : ']')) { d->pos++; return self; }
    for (;;) {
        size_t koff = 0, klen = 0;
        int child;
        j_ws(d);
        if (is_obj) {
            if (d->pos >= d->len || d->text[d->pos] != '"' || !j_string_span(d, &koff, &klen)) return -1;
            j_ws(d);
            if (d->pos >= d->len || d->text[d->pos] != ':') return -1;
            d->pos++;
        }
        child = j_value(d, depth + 1);
        if (child < 0) return -1;
        d->v[child].key_off = koff;
        d->v[child].key_len = klen;
        if (last < 0) d->v[self].first = child;
        else d->v[last].next = child;
        last = child;
        d->v[self].count++;
        j_ws(d);
        if (d->pos >= d->len) return -1;
        if (d->text[d->pos] == ',') { d->pos++; continue; }
        if (d->text[d->pos] == (is_obj ? '}' : ']')) { d->pos++; return self; }
        return -1;
    }
}

static int j_value(jdoc *d, int depth)
{
    int idx;
    char c;
    if (depth > J_MAX_DEPTH) return -1;
    j_ws(d);
    if (d->pos >= d->len) return -1;
    c = d->text[d->pos];
    if (c == '{' || c == '[') return j_container(d, depth, c == '{');
    if (c == '"') {
        size_t off, len;
        if (!j_string_span(d, &off, &len)) return -1;
        if ((idx = j_new(d, J_STR)) < 0) return -1;
        d->v[idx].off = off;
        d->v[idx].len = len;
        return idx;
    }
    if (c == 't' && d->len - d->pos >= 4 && !memcmp(d->text + d->pos, "true", 4)) {
        d->pos += 4;
        if ((idx = j_new(d, J_BOOL)) >= 0) d->v[idx].num = 1;
        return idx;
    }
    if (c == 'f' && d->len - d->pos >= 5 && !memcmp(d->text + d->pos, "false", 5)) {
        d->pos += 5;
        return j_new(d, J_BOOL);
    }
    if (c == 'n' && d->len - d->pos >= 4 && !memcmp(d->text + d->pos, "null", 4)) {
        d->pos += 4;
        return j_new(d, J_NULL);
    }
    {
        double num;
        if (!j_number(d, &num)) return -1;
        if ((idx = j_new(d, J_NUM)) >= 0) d->v[idx].num = num;
        return idx;
    }
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static size_t put_utf8(char *out, size_t o, size_t cap, unsigned cp)
{
    char tmp[4];
    size_t n, i;
    if (cp < 0x80) { tmp[0] = (char)cp; n = 1; }
    else if (cp < 0x800) { tmp[0] = (char)(0xC0 | (cp >> 6)); tmp[1] = (char)(0x80 | (cp & 0x3F)); n = 2; }
    else if (cp < 0x10000) {
        tmp[0] = (char)(0xE0 | (cp >> 12)); tmp[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        tmp[2] = (char)(0x80 | (cp & 0x3F)); n = 3;
    } else {
        tmp[0] = (char)(0xF0 | (cp >> 18)); tmp[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
        tmp[2] = (char)(0x80 | ((cp >> 6) & 0x3F)); tmp[3] = (char)(0x80 | (cp & 0x3F)); n = 4;
    }
    for (i = 0; i < n && o + 1 < cap; i++) out[o++] = tmp[i];
    return o;
}

static unsigned read_hex4(const char *s, size_t len, size_t i, int *ok)
{
    unsigned v = 0;
    int k;
    if (i + 4 > len) { *ok = 0; return 0; }
    for (k = 0; k < 4; k++) {
        int h = hexval(s[i + (size_t)k]);
        if (h < 0) { *ok = 0; return 0; }
        v = v * 16 + (unsigned)h;
    }
    return v;
}

/* Decodes a raw JSON string (escapes, \u with surrogate pairs) into out (truncated, 0-ended). */
static void j_decode(const char *s, size_t len, char *out, size_t cap)
{
    size_t i = 0, o = 0;
    while (i < len && o + 1 < cap) {
        char c = s[i++];
        if (c != '\\' || i >= len) { out[o++] = c; continue; }
        c = s[i++];
        switch (c) {
        case 'b': out[o++] = '\b'; break;
        case 'f': out[o++] = '\f'; break;
        case 'n': out[o++] = '\n'; break;
        case 'r': out[o++] = '\r'; break;
        case 't': out[o++] = '\t'; break;
        case 'u': {
            int ok = 1;
            unsigned cp = read_hex4(s, len, i, &ok);
            if (!ok) break;
            i += 4;
            if (cp >= 0xD800 && cp < 0xDC00 && i + 6 <= len && s[i] == '\\' && s[i + 1] == 'u') {
                unsigned lo = read_hex4(s, len, i + 2, &ok);
                if (ok && lo >= 0xDC00 && lo < 0xE000) {
                    cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                    i += 6;
                }
            }
            o = put_utf8(out, o, cap, cp);
            break;
        }
        default: out[o++] = c; break;   /* \" \\ \/ */
        }
    }
    out[o] = 0;
}

static int j_get(const jdoc *d, int obj, const char *key)
{
    int c;
    size_t klen = strlen(key);
    if (obj < 0 || d->v[obj].type != J_OBJ) return -1;
    for (c = d->v[obj].first; c >= 0; c = d->v[c].next) {
        const jval *v = &d->v[c];
        if (v->key_len == klen && !memcmp(d->text + v->key_off, key, klen)) return c;
        if (v->key_len > klen && memchr(d->text + v->key_off, '\\', v->key_len)) {
            char buf[128];
            j_decode(d->text + v->key_off, v->key_len, buf, sizeof buf);
            if (!strcmp(buf, key)) return c;
        }
    }
    return -1;
}

static double j_num(const jdoc *d, int v, double def)
{
    return (v >= 0 && d->v[v].type == J_NUM) ? d->v[v].num : def;
}

static int j_str(const jdoc *d, int v, char *out, size_t cap)
{
    if (v < 0 || d->v[v].type != J_STR) { out[0] = 0; return 0; }
    j_decode(d->text + d->v[v].off, d->v[v].len, out, cap);
    return 1;
}

/* ------------------------------------------------------------------------------------------ */
/* glTF side information: what Assimp 5.2 drops                                               */

enum { PATH_T = 0, PATH_R = 1, PATH_S = 2 };
enum { GL_LINEAR = 0, GL_STEP = 1, GL_CUBIC = 2 };

/* One glTF animation channel that targets a node's translation, rotation or scale. */
typedef struct {
    const char *node;   /* the node's name as Assimp gives it (points into node_names) */
    int anim, path, interp;
} side_channel;

typedef struct {
    int num_nodes;
    char **node_names;          /* as Assimp names them: the name, or "nodes[i]" when empty */
    int num_anims;
    side_channel *ch;           /* sorted by node name, animation, path */
    int num_ch;
    int num_materials;
    float *emissive_strength;   /* KHR_materials_emissive_strength, 1 when absent */
    float *t_extras;            /* per material: extras.t_diffuse, extras.t_specular (T_ABSENT when absent) */
} gltf_side;

static void side_free(gltf_side *g)
{
    int i;
    for (i = 0; i < g->num_nodes && g->node_names; i++) free(g->node_names[i]);
    free(g->node_names);
    free(g->ch);
    free(g->emissive_strength);
    free(g->t_extras);
    memset(g, 0, sizeof *g);
}

static int side_channel_cmp(const void *pa, const void *pb)
{
    const side_channel *a = pa, *b = pb;
    int c = strcmp(a->node, b->node);
    if (c) return c;
    if (a->anim != b->anim) return a->anim < b->anim ? -1 : 1;
    return a->path - b->path;
}

/* The JSON text of a .gltf or of a GLB's first chunk. */
static int gltf_json_span(const unsigned char *data, size_t size, const char **json, size_t *len)
{
    if (size >= 20 && !memcmp(data, "glTF", 4)) {
        uint32_t clen = (uint32_t)data[12] | (uint32_t)data[13] << 8 | (uint32_t)data[14] << 16 | (uint32_t)data[15] << 24;
        if (memcmp(data + 16, "JSON", 4) || (size_t)clen > size - 20) return 0;
        *json = (const char *)data + 20;
        *len = clen;
        return 1;
    }
    *json = (const char *)data;
    *len = size;
    return 1;
}

#define NAME_CAP 1024
#define T_ABSENT -1e30f

static int j_count(const jdoc *d, int arr)
{
    return (arr >= 0 && d->v[arr].type == J_ARR) ? d->v[arr].count : 0;
}

static evr_status side_parse(const unsigned char *data, size_t size, gltf_side *g, evr_error *err)
{
    jdoc d;
    int root, nodes, anims, mats, i, a, m, cap = 0;
    int *samplers = NULL;
    const char *json;
    size_t jlen;
    evr_status st = EVR_OK;
    memset(g, 0, sizeof *g);
    memset(&d, 0, sizeof d);
    if (!gltf_json_span(data, size, &json, &jlen))
        return fail(err, EVR_ERR_FORMAT, "glTF: the GLB has no JSON chunk");
    d.text = json;
    d.len = jlen;
    root = j_value(&d, 0);
    if (root < 0 || d.v[root].type != J_OBJ) {
        st = d.failed ? fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
                      : fail(err, EVR_ERR_FORMAT, "glTF: cannot parse the JSON near byte %zu", d.pos);
        free(d.v);
        return st;
    }

    nodes = j_get(&d, root, "nodes");
    anims = j_get(&d, root, "animations");
    mats = j_get(&d, root, "materials");
    g->num_nodes = j_count(&d, nodes);
    g->num_anims = j_count(&d, anims);
    g->num_materials = j_count(&d, mats);
    g->node_names = calloc((size_t)g->num_nodes + 1, sizeof *g->node_names);
    g->emissive_strength = calloc((size_t)g->num_materials + 1, sizeof *g->emissive_strength);
    g->t_extras = calloc(2 * (size_t)g->num_materials + 2, sizeof *g->t_extras);
    if (!g->node_names || !g->emissive_strength || !g->t_extras) goto nomem;

    for (i = 0, m = g->num_nodes ? d.v[nodes].first : -1; m >= 0; m = d.v[m].next, i++) {
        char buf[NAME_CAP];
        if (!j_str(&d, j_get(&d, m, "name"), buf, sizeof buf) || !buf[0])
            snprintf(buf, sizeof buf, "nodes[%d]", i);
        g->node_names[i] = malloc(strlen(buf) + 1);
        if (!g->node_names[i]) goto nomem;
        strcpy(g->node_names[i], buf);
    }
    for (a = 0, i = g->num_anims ? d.v[anims].first : -1; i >= 0; i = d.v[i].next, a++) {
        int samps = j_get(&d, i, "samplers"), nsamp = j_count(&d, samps), c, k;
        free(samplers);
        samplers = malloc(((size_t)nsamp + 1) * sizeof *samplers);
        if (!samplers) goto nomem;
        for (k = 0, c = nsamp ? d.v[samps].first : -1; c >= 0; c = d.v[c].next) samplers[k++] = c;
        for (c = j_count(&d, j_get(&d, i, "channels")) ? d.v[j_get(&d, i, "channels")].first : -1; c >= 0; c = d.v[c].next) {
            int tgt = j_get(&d, c, "target");
            double si = j_num(&d, j_get(&d, c, "sampler"), -1), ni = j_num(&d, j_get(&d, tgt, "node"), -1);
            char path[32], interp[32];
            side_channel sc;
            j_str(&d, j_get(&d, tgt, "path"), path, sizeof path);
            if (!strcmp(path, "translation")) sc.path = PATH_T;
            else if (!strcmp(path, "rotation")) sc.path = PATH_R;
            else if (!strcmp(path, "scale")) sc.path = PATH_S;
            else continue;   /* morph weights: not a transform */
            if (!(si >= 0 && si < nsamp) || !(ni >= 0 && ni < g->num_nodes)) continue;
            if (!j_str(&d, j_get(&d, samplers[(int)si], "interpolation"), interp, sizeof interp)) strcpy(interp, "LINEAR");
            sc.interp = !strcmp(interp, "STEP") ? GL_STEP : !strcmp(interp, "CUBICSPLINE") ? GL_CUBIC : GL_LINEAR;
            sc.node = g->node_names[(int)ni];
            sc.anim = a;
            if (g->num_ch == cap) {
                int ncap = cap ? cap * 2 : 64;
                side_channel *nc = realloc(g->ch, (size_t)ncap * sizeof *nc);
                if (!nc) goto nomem;
                g->ch = nc;
                cap = ncap;
            }
            g->ch[g->num_ch++] = sc;
        }
    }
    if (g->num_ch) qsort(g->ch, (size_t)g->num_ch, sizeof *g->ch, side_channel_cmp);
    for (i = 0, m = g->num_materials ? d.v[mats].first : -1; m >= 0; m = d.v[m].next, i++) {
        int es = j_get(&d, j_get(&d, j_get(&d, m, "extensions"), "KHR_materials_emissive_strength"), "emissiveStrength");
        g->emissive_strength[i] = (float)j_num(&d, es, 1.0);
        g->t_extras[2 * i] = (float)j_num(&d, j_get(&d, j_get(&d, m, "extras"), "t_diffuse"), T_ABSENT);
        g->t_extras[2 * i + 1] = (float)j_num(&d, j_get(&d, j_get(&d, m, "extras"), "t_specular"), T_ABSENT);
    }
    free(samplers);
    free(d.v);
    return EVR_OK;
nomem:
    free(samplers);
    free(d.v);
    side_free(g);
    return fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON");
}

/* The interpolation of the glTF channel (animation anim, node named `name`, path): GL_*, or -1
 * when the file has no such channel (Assimp synthesized the keys). anim < 0: any animation. */
static int side_interp(const gltf_side *g, int anim, const char *name, int path)
{
    int lo = 0, hi = g->num_ch, i;
    while (lo < hi) {   /* first channel whose node name is >= name */
        int mid = lo + (hi - lo) / 2;
        if (strcmp(g->ch[mid].node, name) < 0) lo = mid + 1;
        else hi = mid;
    }
    for (i = lo; i < g->num_ch && !strcmp(g->ch[i].node, name); i++)
        if ((anim < 0 || g->ch[i].anim == anim) && g->ch[i].path == path) return g->ch[i].interp;
    return -1;
}

/* ------------------------------------------------------------------------------------------ */
/* Textures                                                                                   */

/* The exact sRGB electro-optical transfer function. */
static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

/* Decodes an encoded image (PNG, JPEG, ...) into linear RGBA floats. */
static evr_status decode_image(const unsigned char *data, size_t size, const char *what, evr_texture *t, evr_error *err)
{
    int w = 0, h = 0, comp = 0;
    size_t i, n;
    if (size > INT_MAX) return fail(err, EVR_ERR_FORMAT, "texture %s: image too large", what);
    if (stbi_is_hdr_from_memory(data, (int)size)) {
        float *px = stbi_loadf_from_memory(data, (int)size, &w, &h, &comp, 4);
        if (!px) return fail(err, EVR_ERR_FORMAT, "texture %s: cannot decode the image (%s)", what, stbi_failure_reason());
        n = (size_t)w * (size_t)h;
        t->rgba = malloc(n * 4 * sizeof(float));
        if (!t->rgba) { stbi_image_free(px); return fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what); }
        memcpy(t->rgba, px, n * 4 * sizeof(float));   /* HDR images are linear already */
        stbi_image_free(px);
    } else if (stbi_is_16_bit_from_memory(data, (int)size)) {
        unsigned short *px = stbi_load_16_from_memory(data, (int)size, &w, &h, &comp, 4);
        if (!px) return fail(err, EVR_ERR_FORMAT, "texture %s: cannot decode the image (%s)", what, stbi_failure_reason());
        n = (size_t)w * (size_t)h;
        t->rgba = malloc(n * 4 * sizeof(float));
        if (!t->rgba) { stbi_image_free(px); return fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what); }
        for (i = 0; i < n * 4; i++) {
            float v = (float)px[i] / 65535.0f;
            t->rgba[i] = (i % 4 == 3) ? v : srgb_to_linear(v);
        }
        stbi_image_free(px);
    } else {
        float lut[256];
        unsigned char *px = stbi_load_from_memory(data, (int)size, &w, &h, &comp, 4);
        if (!px) return fail(err, EVR_ERR_FORMAT, "texture %s: cannot decode the image (%s)", what, stbi_failure_reason());
        for (i = 0; i < 256; i++) lut[i] = srgb_to_linear((float)i / 255.0f);
        n = (size_t)w * (size_t)h;
        t->rgba = malloc(n * 4 * sizeof(float));
        if (!t->rgba) { stbi_image_free(px); return fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what); }
        for (i = 0; i < n * 4; i++) t->rgba[i] = (i % 4 == 3) ? (float)px[i] / 255.0f : lut[px[i]];
        stbi_image_free(px);
    }
    t->width = w;
    t->height = h;
    return EVR_OK;
}

/* An uncompressed embedded texture: aiTexel (b, g, r, a bytes), row 0 first. */
static evr_status decode_texels(const struct aiTexture *tex, const char *what, evr_texture *t, evr_error *err)
{
    float lut[256];
    size_t i, n = (size_t)tex->mWidth * (size_t)tex->mHeight;
    if (!tex->pcData || tex->mWidth > INT_MAX || tex->mHeight > INT_MAX)
        return fail(err, EVR_ERR_FORMAT, "texture %s: invalid embedded image", what);
    for (i = 0; i < 256; i++) lut[i] = srgb_to_linear((float)i / 255.0f);
    t->rgba = malloc(n * 4 * sizeof(float) + 1);
    if (!t->rgba) return fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what);
    for (i = 0; i < n; i++) {
        const struct aiTexel *px = &tex->pcData[i];
        t->rgba[4 * i + 0] = lut[px->r];
        t->rgba[4 * i + 1] = lut[px->g];
        t->rgba[4 * i + 2] = lut[px->b];
        t->rgba[4 * i + 3] = (float)px->a / 255.0f;
    }
    t->width = (int)tex->mWidth;
    t->height = (int)tex->mHeight;
    return EVR_OK;
}

static const char *short_name(const char *p)
{
    const char *a = strrchr(p, '/'), *b = strrchr(p, '\\');
    if (b && (!a || b > a)) a = b;
    return a ? a + 1 : p;
}

/* Replaces %XX escapes (URIs in glTF) in place; returns 1 if anything changed. */
static int percent_decode(char *s)
{
    char *r = s, *w = s;
    int changed = 0;
    while (*r) {
        if (r[0] == '%' && hexval(r[1]) >= 0 && hexval(r[2]) >= 0) {
            *w++ = (char)(hexval(r[1]) * 16 + hexval(r[2]));
            r += 3;
            changed = 1;
        } else {
            *w++ = *r++;
        }
    }
    *w = 0;
    return changed;
}

/* ------------------------------------------------------------------------------------------ */
/* The importer                                                                               */

typedef struct {
    const char *name;   /* Assimp's full name (evr names are cut at 63 characters) */
    int index;
} name_index;

typedef struct {
    const struct aiScene *ai;
    evr_scene *s;
    evr_error *err;
    char dir[512];            /* folder of the scene file with a trailing '/', "" for memory */
    int gltf;                 /* Assimp's glTF 2.0 quirks apply */
    int have_side;
    gltf_side side;
    char **tex_keys;          /* per scene texture: what it was loaded from (to share it) */
    int tex_cap;
    int *mat_uv;              /* per material: UV channel of its base colour texture */
    const struct aiNode **ai_nodes;   /* per evr node */
    name_index *by_name;              /* nodes sorted by Assimp name */
} importer;

static int name_index_cmp(const void *pa, const void *pb)
{
    const name_index *a = pa, *b = pb;
    int c = strcmp(a->name, b->name);
    return c ? c : (a->index > b->index) - (a->index < b->index);
}

/* The first node (in depth-first order) with Assimp name `name`, or -1. Assimp attaches
 * animation channels, cameras and lights to nodes by name. */
static int find_ai_node(const importer *im, const char *name)
{
    int lo = 0, hi = im->s->num_nodes;
    if (!im->by_name) return -1;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (strcmp(im->by_name[mid].name, name) < 0) lo = mid + 1;
        else hi = mid;
    }
    return (lo < im->s->num_nodes && !strcmp(im->by_name[lo].name, name)) ? im->by_name[lo].index : -1;
}

static evr_status load_texture(importer *im, const char *ai_path, const char *mat_name, int *out)
{
    evr_scene *s = im->s;
    const struct aiScene *ai = im->ai;
    char key[1100], what[1200];
    int emb = -1, i;
    evr_status st;
    evr_texture t;

    memset(&t, 0, sizeof t);
    *out = -1;
    if (ai_path[0] == '*') {
        char *end;
        long k = strtol(ai_path + 1, &end, 10);
        if (*end || k < 0 || k >= (long)ai->mNumTextures)
            return fail(im->err, EVR_ERR_FORMAT, "material '%s': embedded texture '%s' does not exist", mat_name, ai_path);
        emb = (int)k;
    } else if (short_name(ai_path)[0]) {
        /* aiScene::GetEmbeddedTexture: match by file name without folders */
        for (i = 0; i < (int)ai->mNumTextures; i++) {
            const char *tn = short_name(ai->mTextures[i]->mFilename.data);
            if (tn[0] && !strcmp(tn, short_name(ai_path))) { emb = i; break; }
        }
    }
    if (emb >= 0) {
        snprintf(key, sizeof key, "*%d", emb);
    } else if (ai_path[0] == '/' || !im->dir[0]) {
        snprintf(key, sizeof key, "%s", ai_path);
    } else {
        snprintf(key, sizeof key, "%s%s", im->dir, ai_path);
    }
    if (emb < 0) {
        struct stat sb;
        if (stat(key, &sb) != 0) {
            /* URIs may be percent-encoded; Windows exporters may leave backslash folders */
            char alt[1100];
            snprintf(alt, sizeof alt, "%s", key);
            if (percent_decode(alt) && stat(alt, &sb) == 0) {
                snprintf(key, sizeof key, "%s", alt);
            } else if (short_name(ai_path) != ai_path) {
                snprintf(alt, sizeof alt, "%s%s", im->dir, short_name(ai_path));
                if (stat(alt, &sb) == 0) snprintf(key, sizeof key, "%s", alt);
            }
        }
    }
    for (i = 0; i < s->num_textures; i++) {
        if (!strcmp(im->tex_keys[i], key)) { *out = i; return EVR_OK; }
    }
    snprintf(what, sizeof what, "'%s' of material '%s'", ai_path, mat_name);

    if (emb >= 0) {
        const struct aiTexture *tex = ai->mTextures[emb];
        if (tex->mHeight == 0) {
            if (!tex->pcData) return fail(im->err, EVR_ERR_FORMAT, "texture %s: no image data", what);
            st = decode_image((const unsigned char *)tex->pcData, tex->mWidth, what, &t, im->err);
        } else {
            st = decode_texels(tex, what, &t, im->err);
        }
    } else {
        unsigned char *data = NULL;
        size_t size = 0;
        {
            evr_error e;
            st = read_file(key, 0, &data, &size, &e);
            if (st != EVR_OK) return fail(im->err, st, "texture %s: %s", what, e.msg);
        }
        st = decode_image(data, size, what, &t, im->err);
        free(data);
    }
    if (st != EVR_OK) return st;

    if (s->num_textures == im->tex_cap) {
        int ncap = im->tex_cap ? im->tex_cap * 2 : 8;
        evr_texture *nt = realloc(s->textures, (size_t)ncap * sizeof *nt);
        char **nk;
        if (nt) s->textures = nt;
        nk = nt ? realloc(im->tex_keys, (size_t)ncap * sizeof *nk) : NULL;
        if (nk) im->tex_keys = nk;
        if (!nt || !nk) { free(t.rgba); return fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures"); }
        im->tex_cap = ncap;
    }
    im->tex_keys[s->num_textures] = malloc(strlen(key) + 1);
    if (!im->tex_keys[s->num_textures]) { free(t.rgba); return fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures"); }
    strcpy(im->tex_keys[s->num_textures], key);
    s->textures[s->num_textures] = t;
    *out = s->num_textures++;
    return EVR_OK;
}

static evr_status build_materials(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    int n = ai->mNumMaterials ? (int)ai->mNumMaterials : 1;   /* at least a default one */

    s->materials = calloc((size_t)n, sizeof *s->materials);
    im->mat_uv = calloc((size_t)n, sizeof *im->mat_uv);
    if (!s->materials || !im->mat_uv) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading materials");
    s->num_materials = n;
    for (i = 0; i < (unsigned)n; i++) {
        evr_material *m = &s->materials[i];
        m->base_color[0] = m->base_color[1] = m->base_color[2] = m->base_color[3] = 1.0f;
        m->base_texture = -1;
        m->metallic = 0.0f;
        m->roughness = 1.0f;
        evr_photon_material_map(m->base_color, m->metallic, m->roughness, &m->t_diffuse, &m->t_specular);
    }
    for (i = 0; i < ai->mNumMaterials; i++) {
        const struct aiMaterial *am = ai->mMaterials[i];
        evr_material *m = &s->materials[i];
        struct aiString str;
        struct aiColor4D c;
        ai_real f;
        unsigned int one = 1, uv = 0;
        int tt;
        static const enum aiTextureType kinds[2] = {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE};

        if (aiGetMaterialString(am, AI_MATKEY_NAME, &str) == aiReturn_SUCCESS) copy_name(m->name, sizeof m->name, str.data);
        else snprintf(m->name, sizeof m->name, "material%u", i);
        if (aiGetMaterialColor(am, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS ||
            aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS) {
            m->base_color[0] = c.r; m->base_color[1] = c.g; m->base_color[2] = c.b; m->base_color[3] = c.a;
        }
        if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS) {
            float k = 1.0f;
            one = 1;
            if (aiGetMaterialFloatArray(am, AI_MATKEY_EMISSIVE_INTENSITY, &f, &one) == aiReturn_SUCCESS) k = (float)f;
            else if (im->have_side && (int)i < im->side.num_materials) k = im->side.emissive_strength[i];
            m->emissive[0] = c.r * k; m->emissive[1] = c.g * k; m->emissive[2] = c.b * k;
        }
        one = 1;
        if (aiGetMaterialFloatArray(am, AI_MATKEY_METALLIC_FACTOR, &f, &one) == aiReturn_SUCCESS) m->metallic = (float)f;
        one = 1;
        if (aiGetMaterialFloatArray(am, AI_MATKEY_ROUGHNESS_FACTOR, &f, &one) == aiReturn_SUCCESS) m->roughness = (float)f;
        evr_photon_material_map(m->base_color, m->metallic, m->roughness, &m->t_diffuse, &m->t_specular);
        if (im->have_side && (int)i < im->side.num_materials &&
            (im->side.t_extras[2 * i] != T_ABSENT || im->side.t_extras[2 * i + 1] != T_ABSENT)) {
            float td = im->side.t_extras[2 * i], ts = im->side.t_extras[2 * i + 1];
            if (td == T_ABSENT) td = m->t_diffuse;
            if (ts == T_ABSENT) ts = td > m->t_specular ? td : m->t_specular;
            if (!(td >= 0.0f && td <= ts && ts <= 1.0f))
                return fail(im->err, EVR_ERR_FORMAT,
                            "material '%s': extras need 0 <= t_diffuse <= t_specular <= 1 (got %g, %g)", m->name,
                            (double)td, (double)ts);
            m->t_diffuse = td;
            m->t_specular = ts;
        }

        for (tt = 0; tt < 2; tt++) {
            if (aiGetMaterialTextureCount(am, kinds[tt]) == 0) continue;
            uv = 0;
            if (aiGetMaterialTexture(am, kinds[tt], 0, &str, NULL, &uv, NULL, NULL, NULL, NULL) != aiReturn_SUCCESS || !str.data[0])
                continue;
            {
                evr_status st = load_texture(im, str.data, m->name, &m->base_texture);
                if (st != EVR_OK) return st;
            }
            im->mat_uv[i] = (int)uv;
            break;
        }
    }
    if (!ai->mNumMaterials) strcpy(s->materials[0].name, "default");
    return EVR_OK;
}

static evr_status build_meshes(importer *im, uint64_t *total_tris)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    *total_tris = 0;
    s->meshes = calloc((size_t)ai->mNumMeshes + 1, sizeof *s->meshes);
    if (!s->meshes) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
    s->num_meshes = (int)ai->mNumMeshes;
    for (i = 0; i < ai->mNumMeshes; i++) {
        const struct aiMesh *am = ai->mMeshes[i];
        evr_mesh *m = &s->meshes[i];
        unsigned f, v, ntri = 0;
        int uvch;
        if (am->mName.length) copy_name(m->name, sizeof m->name, am->mName.data);
        else snprintf(m->name, sizeof m->name, "mesh%u", i);
        m->material = (am->mMaterialIndex < (unsigned)s->num_materials) ? (int)am->mMaterialIndex : 0;
        for (f = 0; f < am->mNumFaces; f++)
            if (am->mFaces[f].mNumIndices == 3) ntri++;
        m->num_vertices = am->mNumVertices;
        m->num_triangles = ntri;
        m->positions = malloc((size_t)am->mNumVertices * 3 * sizeof(float) + 1);
        m->normals = malloc((size_t)am->mNumVertices * 3 * sizeof(float) + 1);
        m->indices = malloc((size_t)ntri * 3 * sizeof(uint32_t) + 1);
        if (!m->positions || !m->normals || !m->indices) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
        m->bounds_min = evr_v3_make(INFINITY, INFINITY, INFINITY);
        m->bounds_max = evr_v3_make(-INFINITY, -INFINITY, -INFINITY);
        for (v = 0; v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            m->positions[3 * v] = p->x; m->positions[3 * v + 1] = p->y; m->positions[3 * v + 2] = p->z;
            m->bounds_min = evr_v3_make(fminf(m->bounds_min.x, p->x), fminf(m->bounds_min.y, p->y), fminf(m->bounds_min.z, p->z));
            m->bounds_max = evr_v3_make(fmaxf(m->bounds_max.x, p->x), fmaxf(m->bounds_max.y, p->y), fmaxf(m->bounds_max.z, p->z));
        }
        if (!am->mNumVertices) m->bounds_min = m->bounds_max = evr_v3_make(0, 0, 0);
        ntri = 0;
        for (f = 0; f < am->mNumFaces; f++) {
            const struct aiFace *fc = &am->mFaces[f];
            if (fc->mNumIndices != 3) continue;
            if (fc->mIndices[0] >= am->mNumVertices || fc->mIndices[1] >= am->mNumVertices || fc->mIndices[2] >= am->mNumVertices)
                return fail(im->err, EVR_ERR_FORMAT, "mesh '%s': a triangle refers to a missing vertex", m->name);
            m->indices[3 * ntri] = fc->mIndices[0];
            m->indices[3 * ntri + 1] = fc->mIndices[1];
            m->indices[3 * ntri + 2] = fc->mIndices[2];
            ntri++;
        }
        /* Normals: Assimp's (GenSmoothNormals makes them where the file has none), made unit;
         * area-weighted face normals for any vertex still without a usable one. */
        {
            unsigned char *fix = calloc((size_t)am->mNumVertices + 1, 1);
            int any_fix = 0;
            if (!fix) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
            for (v = 0; v < am->mNumVertices; v++) {
                float *nv = &m->normals[3 * v];
                if (am->mNormals) { nv[0] = am->mNormals[v].x; nv[1] = am->mNormals[v].y; nv[2] = am->mNormals[v].z; }
                if (!am->mNormals || !isfinite(nv[0] + nv[1] + nv[2]) || (nv[0] == 0.0f && nv[1] == 0.0f && nv[2] == 0.0f)) {
                    nv[0] = nv[1] = nv[2] = 0.0f;
                    fix[v] = 1;
                    any_fix = 1;
                }
            }
            for (f = 0; f < ntri && any_fix; f++) {
                const uint32_t *t = &m->indices[3 * f];
                evr_v3 a = evr_v3_make(m->positions[3 * t[0]], m->positions[3 * t[0] + 1], m->positions[3 * t[0] + 2]);
                evr_v3 b = evr_v3_make(m->positions[3 * t[1]], m->positions[3 * t[1] + 1], m->positions[3 * t[1] + 2]);
                evr_v3 c = evr_v3_make(m->positions[3 * t[2]], m->positions[3 * t[2] + 1], m->positions[3 * t[2] + 2]);
                evr_v3 fn = evr_v3_cross(evr_v3_sub(b, a), evr_v3_sub(c, a));
                int k;
                for (k = 0; k < 3; k++) {
                    float *nv = &m->normals[3 * t[k]];
                    if (!fix[t[k]]) continue;
                    nv[0] += fn.x; nv[1] += fn.y; nv[2] += fn.z;
                }
            }
            free(fix);
        }
        for (v = 0; v < am->mNumVertices; v++) {
            float *nv = &m->normals[3 * v];
            float l = sqrtf(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
            if (l > 0.0f && isfinite(l)) { nv[0] /= l; nv[1] /= l; nv[2] /= l; }
            else { nv[0] = 0.0f; nv[1] = 0.0f; nv[2] = 1.0f; }
        }
        uvch = im->mat_uv[m->material];
        if (uvch < 0 || uvch >= AI_MAX_NUMBER_OF_TEXTURECOORDS || !am->mTextureCoords[uvch]) uvch = 0;
        if (am->mTextureCoords[uvch]) {
            m->uvs = malloc((size_t)am->mNumVertices * 2 * sizeof(float) + 1);
            if (!m->uvs) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading meshes");
            for (v = 0; v < am->mNumVertices; v++) {
                m->uvs[2 * v] = am->mTextureCoords[uvch][v].x;
                m->uvs[2 * v + 1] = am->mTextureCoords[uvch][v].y;
            }
        }
        *total_tris += ntri;
    }
    return EVR_OK;
}

static evr_m34 m34_from_ai(const struct aiMatrix4x4 *a)
{
    evr_m34 m;
    m.m[0][0] = a->a1; m.m[0][1] = a->a2; m.m[0][2] = a->a3; m.m[0][3] = a->a4;
    m.m[1][0] = a->b1; m.m[1][1] = a->b2; m.m[1][2] = a->b3; m.m[1][3] = a->b4;
    m.m[2][0] = a->c1; m.m[2][1] = a->c2; m.m[2][2] = a->c3; m.m[2][3] = a->c4;
    return m;
}

/* Flattens the node tree depth-first (parents before children) and makes the instances. */
static evr_status build_nodes(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    const struct aiNode **stack = NULL;
    int *stack_parent = NULL;
    int sp = 0, cap = 0, count = 0, ninst = 0, i;
    unsigned c;

    if (!ai->mRootNode) return fail(im->err, EVR_ERR_FORMAT, "the scene has no node hierarchy");
    /* Count the nodes (iteratively: hierarchies can be deep). */
    cap = 64;
    stack = malloc((size_t)cap * sizeof *stack);
    stack_parent = malloc((size_t)cap * sizeof *stack_parent);
    if (!stack || !stack_parent) goto nomem;
    stack[sp++] = ai->mRootNode;
    while (sp) {
        const struct aiNode *n = stack[--sp];
        count++;
        ninst += (int)n->mNumMeshes;
        for (c = 0; c < n->mNumChildren; c++) {
            if (sp == cap) {
                const struct aiNode **ns;
                int *np;
                cap *= 2;
                ns = realloc(stack, (size_t)cap * sizeof *stack);
                if (ns) stack = ns;
                np = ns ? realloc(stack_parent, (size_t)cap * sizeof *stack_parent) : NULL;
                if (np) stack_parent = np;
                if (!ns || !np) goto nomem;
            }
            stack[sp++] = n->mChildren[c];
        }
        if (count > (1 << 26)) { free(stack); free(stack_parent); return fail(im->err, EVR_ERR_FORMAT, "the node hierarchy is too large or cyclic"); }
    }

    s->nodes = calloc((size_t)count, sizeof *s->nodes);
    im->ai_nodes = calloc((size_t)count, sizeof *im->ai_nodes);
    s->instances = calloc((size_t)ninst + 1, sizeof *s->instances);
    if (!s->nodes || !im->ai_nodes || !s->instances) goto nomem;
    s->num_nodes = count;

    sp = 0;
    stack[sp] = ai->mRootNode;
    stack_parent[sp++] = -1;
    count = 0;
    while (sp) {
        const struct aiNode *an = stack[--sp];
        int parent = stack_parent[sp], self = count++;
        evr_node *n = &s->nodes[self];
        struct aiVector3D sc, pos;
        struct aiQuaternion q;
        im->ai_nodes[self] = an;
        copy_name(n->name, sizeof n->name, an->mName.data);
        n->parent = parent;
        n->rest_matrix = m34_from_ai(&an->mTransformation);
        aiDecomposeMatrix(&an->mTransformation, &sc, &q, &pos);
        n->translation = evr_v3_make(pos.x, pos.y, pos.z);
        n->scale = evr_v3_make(sc.x, sc.y, sc.z);
        n->rotation = evr_quat_normalize(evr_quat_make(q.w, q.x, q.y, q.z));
        for (c = 0; c < an->mNumMeshes; c++) {
            if (an->mMeshes[c] >= (unsigned)s->num_meshes) continue;
            s->instances[s->num_instances].mesh = (int)an->mMeshes[c];
            s->instances[s->num_instances].node = self;
            s->num_instances++;
        }
        /* children in reverse so that they come out in file order */
        for (c = an->mNumChildren; c-- > 0;) {
            stack[sp] = an->mChildren[c];
            stack_parent[sp++] = self;
        }
    }
    free(stack);
    free(stack_parent);

    im->by_name = malloc((size_t)s->num_nodes * sizeof *im->by_name);
    if (!im->by_name) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading the node hierarchy");
    for (i = 0; i < s->num_nodes; i++) {
        im->by_name[i].name = im->ai_nodes[i]->mName.data;
        im->by_name[i].index = i;
    }
    qsort(im->by_name, (size_t)s->num_nodes, sizeof *im->by_name, name_index_cmp);

    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        evr_node *n = &s->nodes[s->instances[i].node];
        if (!n->has_bounds) {
            n->bounds_min = m->bounds_min;
            n->bounds_max = m->bounds_max;
            n->has_bounds = 1;
        } else {
            n->bounds_min = evr_v3_make(fminf(n->bounds_min.x, m->bounds_min.x), fminf(n->bounds_min.y, m->bounds_min.y), fminf(n->bounds_min.z, m->bounds_min.z));
            n->bounds_max = evr_v3_make(fmaxf(n->bounds_max.x, m->bounds_max.x), fmaxf(n->bounds_max.y, m->bounds_max.y), fmaxf(n->bounds_max.z, m->bounds_max.z));
        }
    }
    return EVR_OK;
nomem:
    free(stack);
    free(stack_parent);
    return fail(im->err, EVR_ERR_NOMEM, "out of memory reading the node hierarchy");
}

/* 1 when every key of the curve holds the node's rest value (such a curve changes nothing). */
static int curve_is_rest(const evr_curve *c, const float *rest, int dim)
{
    int k, j;
    for (k = 0; k < c->num_keys; k++) {
        const float *v = c->values + (size_t)k * (size_t)dim;
        if (dim == 4) {
            float d = v[0] * rest[0] + v[1] * rest[1] + v[2] * rest[2] + v[3] * rest[3];
            if (fabsf(d) < 1.0f - 1e-7f) return 0;
        } else {
            for (j = 0; j < dim; j++)
                if (fabsf(v[j] - rest[j]) > 1e-6f * fmaxf(1.0f, fabsf(rest[j]))) return 0;
        }
    }
    return 1;
}

static void curve_free(evr_curve *c)
{
    free(c->times);
    free(c->values);
    memset(c, 0, sizeof *c);
}

/* Copies one kind of keys (dim 3: aiVectorKey, 4: aiQuatKey) into a curve in seconds. */
static int make_curve(evr_curve *c, const void *keys, unsigned nkeys, int dim, double tps)
{
    unsigned k;
    int sorted = 1;
    c->times = malloc((size_t)nkeys * sizeof(double));
    c->values = malloc((size_t)nkeys * (size_t)dim * sizeof(float));
    if (!c->times || !c->values) { curve_free(c); return 0; }
    c->num_keys = (int)nkeys;
    for (k = 0; k < nkeys; k++) {
        float *v = c->values + (size_t)k * (size_t)dim;
        if (dim == 3) {
            const struct aiVectorKey *key = (const struct aiVectorKey *)keys + k;
            c->times[k] = key->mTime / tps;
            v[0] = key->mValue.x; v[1] = key->mValue.y; v[2] = key->mValue.z;
        } else {
            const struct aiQuatKey *key = (const struct aiQuatKey *)keys + k;
            evr_quat q = evr_quat_normalize(evr_quat_make(key->mValue.w, key->mValue.x, key->mValue.y, key->mValue.z));
            c->times[k] = key->mTime / tps;
            v[0] = q.w; v[1] = q.x; v[2] = q.y; v[3] = q.z;
        }
        if (k && c->times[k] < c->times[k - 1]) sorted = 0;
    }
    if (!sorted) {
        /* insertion sort by time (keys are nearly always sorted already) */
        int i, j, d;
        for (i = 1; i < c->num_keys; i++) {
            double t = c->times[i];
            float tmp[4];
            for (d = 0; d < dim; d++) tmp[d] = c->values[(size_t)i * (size_t)dim + (size_t)d];
            for (j = i; j > 0 && c->times[j - 1] > t; j--) {
                c->times[j] = c->times[j - 1];
                for (d = 0; d < dim; d++) c->values[(size_t)j * (size_t)dim + (size_t)d] = c->values[(size_t)(j - 1) * (size_t)dim + (size_t)d];
            }
            c->times[j] = t;
            for (d = 0; d < dim; d++) c->values[(size_t)j * (size_t)dim + (size_t)d] = tmp[d];
        }
    }
    return 1;
}

static evr_status build_animation(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned a, ch;
    int i, any = 0;
    double t_min = INFINITY, t_max = -INFINITY;
    int side_ok = im->have_side && im->side.num_anims == (int)ai->mNumAnimations;

    s->num_animations = (int)ai->mNumAnimations;
    for (a = 0; a < ai->mNumAnimations; a++) {
        const struct aiAnimation *an = ai->mAnimations[a];
        /* quirk (a): glTF keys are in milliseconds, mTicksPerSecond = 1000 */
        double tps = an->mTicksPerSecond > 0.0 ? an->mTicksPerSecond : 25.0;
        for (ch = 0; ch < an->mNumChannels; ch++) {
            const struct aiNodeAnim *na = an->mChannels[ch];
            int ni = find_ai_node(im, na->mNodeName.data), kind;
            evr_node *n;
            if (ni < 0) continue;   /* targets no node of the scene */
            n = &s->nodes[ni];
            for (kind = 0; kind < 3; kind++) {
                evr_curve *c = kind == PATH_T ? &n->t_curve : kind == PATH_R ? &n->r_curve : &n->s_curve;
                unsigned nk = kind == PATH_T ? na->mNumPositionKeys : kind == PATH_R ? na->mNumRotationKeys : na->mNumScalingKeys;
                const void *keys = kind == PATH_T ? (const void *)na->mPositionKeys
                                 : kind == PATH_R ? (const void *)na->mRotationKeys : (const void *)na->mScalingKeys;
                int interp = GL_LINEAR;
                float rest[4];
                if (nk == 0 || !keys || c->num_keys > 0) continue;   /* first animation wins */
                if (im->have_side) {
                    /* quirk (e): keys of properties no glTF channel animates are synthesized */
                    interp = side_interp(&im->side, side_ok ? (int)a : -1, na->mNodeName.data, kind);
                    if (interp < 0) continue;
                }
                if (!make_curve(c, keys, nk, kind == PATH_R ? 4 : 3, tps))
                    return fail(im->err, EVR_ERR_NOMEM, "out of memory reading animations");
                /* STEP from the JSON; CUBICSPLINE values (quirk (d)) are interpolated linearly */
                c->interp = interp == GL_STEP ? EVR_INTERP_STEP : EVR_INTERP_LINEAR;
                if (kind == PATH_T) { rest[0] = n->translation.x; rest[1] = n->translation.y; rest[2] = n->translation.z; }
                else if (kind == PATH_S) { rest[0] = n->scale.x; rest[1] = n->scale.y; rest[2] = n->scale.z; }
                else { rest[0] = n->rotation.w; rest[1] = n->rotation.x; rest[2] = n->rotation.y; rest[3] = n->rotation.z; }
                if (curve_is_rest(c, rest, kind == PATH_R ? 4 : 3)) curve_free(c);
            }
        }
    }
    for (i = 0; i < s->num_nodes; i++) {
        evr_node *n = &s->nodes[i];
        const evr_curve *cv[3];
        int k;
        cv[0] = &n->t_curve; cv[1] = &n->r_curve; cv[2] = &n->s_curve;
        for (k = 0; k < 3; k++) {
            if (cv[k]->num_keys <= 0) continue;
            n->animated = 1;
            any = 1;
            if (cv[k]->times[0] < t_min) t_min = cv[k]->times[0];
            if (cv[k]->times[cv[k]->num_keys - 1] > t_max) t_max = cv[k]->times[cv[k]->num_keys - 1];
        }
    }
    if (any) { s->anim_start = t_min; s->anim_end = t_max; }
    /* glTF has no frame rate. FBX and BVH store keys in frames (ticks per second = frames per
     * second); Collada uses 1 tick per second, which says nothing. */
    if (!im->gltf && ai->mNumAnimations && ai->mAnimations[0]->mTicksPerSecond >= 10.0 &&
        ai->mAnimations[0]->mTicksPerSecond <= 240.0)
        s->frame_rate = ai->mAnimations[0]->mTicksPerSecond;
    return EVR_OK;
}

/* World transform of a node at its rest pose. */
static evr_m34 rest_world(const evr_scene *s, int node)
{
    evr_m34 m = evr_m34_identity();
    while (node >= 0) {
        m = evr_m34_mul(s->nodes[node].rest_matrix, m);
        node = s->nodes[node].parent;
    }
    return m;
}

static void build_bounds(evr_scene *s)
{
    int i, c, any = 0;
    evr_v3 lo = evr_v3_make(INFINITY, INFINITY, INFINITY), hi = evr_v3_make(-INFINITY, -INFINITY, -INFINITY);
    for (i = 0; i < s->num_instances; i++) {
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        evr_m34 w;
        if (!m->num_triangles) continue;
        w = rest_world(s, s->instances[i].node);
        for (c = 0; c < 8; c++) {
            evr_v3 p = evr_v3_make((c & 1) ? m->bounds_max.x : m->bounds_min.x,
                                   (c & 2) ? m->bounds_max.y : m->bounds_min.y,
                                   (c & 4) ? m->bounds_max.z : m->bounds_min.z);
            p = evr_m34_point(&w, p);
            lo = evr_v3_make(fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z));
            hi = evr_v3_make(fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z));
            any = 1;
        }
    }
    if (!any) lo = hi = evr_v3_make(0, 0, 0);
    s->bounds_min = lo;
    s->bounds_max = hi;
}

/* Camera pose from a position, a viewing direction and an up vector: -Z along look, +Y up. */
static evr_m34 look_matrix(evr_v3 pos, evr_v3 look, evr_v3 up)
{
    evr_m34 m;
    evr_v3 z = evr_v3_norm(evr_v3_scale(look, -1.0f)), x, y;
    if (evr_v3_len(z) == 0.0f) z = evr_v3_make(0, 0, 1);
    x = evr_v3_cross(up, z);
    if (evr_v3_len(x) < 1e-6f) x = evr_v3_cross(fabsf(z.y) < 0.9f ? evr_v3_make(0, 1, 0) : evr_v3_make(1, 0, 0), z);
    x = evr_v3_norm(x);
    y = evr_v3_cross(z, x);
    m.m[0][0] = x.x; m.m[0][1] = y.x; m.m[0][2] = z.x; m.m[0][3] = pos.x;
    m.m[1][0] = x.y; m.m[1][1] = y.y; m.m[1][2] = z.y; m.m[1][3] = pos.y;
    m.m[2][0] = x.z; m.m[2][1] = y.z; m.m[2][2] = z.z; m.m[2][3] = pos.z;
    return m;
}

static evr_status build_cameras(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    s->cameras = calloc((size_t)ai->mNumCameras + 1, sizeof *s->cameras);
    if (!s->cameras) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading cameras");
    for (i = 0; i < ai->mNumCameras; i++) {
        const struct aiCamera *ac = ai->mCameras[i];
        evr_camera_desc *c = &s->cameras[s->num_cameras++];
        float h = ac->mHorizontalFOV;
        copy_name(c->name, sizeof c->name, ac->mName.data);
        if (!c->name[0]) snprintf(c->name, sizeof c->name, "camera%u", i);
        c->node = find_ai_node(im, ac->mName.data);
        c->aspect = ac->mAspect > 0.0f ? ac->mAspect : 0.0f;
        c->znear = ac->mClipPlaneNear > 0.0f ? ac->mClipPlaneNear : 0.01f;
        if (!(h > 0.0f)) {
            c->yfov = (float)(EVR_PI_D / 4.0);   /* orthographic: not supported, 45 degrees */
        } else if (im->gltf) {
            /* quirk (b): Assimp stored yfov * aspect */
            c->yfov = ac->mAspect > 0.0f ? h / ac->mAspect : h;
        } else {
            /* the full horizontal angle, as Assimp's importers store it */
            c->yfov = ac->mAspect > 0.0f ? 2.0f * atanf(tanf(0.5f * h) / ac->mAspect) : h;
        }
        if (im->gltf) {
            /* quirk (c): mPosition repeats the node's translation; glTF cameras sit at their
             * node's origin looking along -Z with +Y up */
            c->local = evr_m34_identity();
        } else {
            c->local = look_matrix(evr_v3_make(ac->mPosition.x, ac->mPosition.y, ac->mPosition.z),
                                   evr_v3_make(ac->mLookAt.x, ac->mLookAt.y, ac->mLookAt.z),
                                   evr_v3_make(ac->mUp.x, ac->mUp.y, ac->mUp.z));
        }
    }
    if (s->num_cameras == 0) {
        /* Frame the rest-pose bounds: look along -Z at the centre from where the bounding
         * sphere fills a 45-degree vertical field of view. */
        evr_camera_desc *c = &s->cameras[s->num_cameras++];
        evr_v3 centre = evr_v3_scale(evr_v3_add(s->bounds_min, s->bounds_max), 0.5f);
        float r = 0.5f * evr_v3_len(evr_v3_sub(s->bounds_max, s->bounds_min));
        float fov = (float)(EVR_PI_D / 4.0), dist;
        if (!(r > 0.0f)) r = 1.0f;
        dist = r / sinf(0.5f * fov);
        strcpy(c->name, "automatic");
        c->node = -1;
        c->yfov = fov;
        c->aspect = 0.0f;
        c->znear = fmaxf(1e-4f * dist, 0.01f * (dist - r));
        c->local = look_matrix(evr_v3_add(centre, evr_v3_make(0, 0, dist)), evr_v3_make(0, 0, -1), evr_v3_make(0, 1, 0));
        c->automatic = 1;
    }
    return EVR_OK;
}

static evr_status build_lights(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    s->lights = calloc((size_t)ai->mNumLights + 1, sizeof *s->lights);
    if (!s->lights) return fail(im->err, EVR_ERR_NOMEM, "out of memory reading lights");
    for (i = 0; i < ai->mNumLights; i++) {
        const struct aiLight *al = ai->mLights[i];
        evr_light *l = &s->lights[s->num_lights];
        evr_v3 dir = evr_v3_make(al->mDirection.x, al->mDirection.y, al->mDirection.z);
        if (al->mType == aiLightSource_POINT) l->type = EVR_LIGHT_POINT;
        else if (al->mType == aiLightSource_SPOT) l->type = EVR_LIGHT_SPOT;
        else if (al->mType == aiLightSource_DIRECTIONAL) l->type = EVR_LIGHT_DIRECTIONAL;
        else continue;   /* ambient and area lights: not punctual (the config has an ambient term) */
        s->num_lights++;
        copy_name(l->name, sizeof l->name, al->mName.data);
        if (!l->name[0]) snprintf(l->name, sizeof l->name, "light%u", i);
        l->node = find_ai_node(im, al->mName.data);
        /* glTF: colour * intensity already */
        l->color[0] = al->mColorDiffuse.r; l->color[1] = al->mColorDiffuse.g; l->color[2] = al->mColorDiffuse.b;
        l->position = evr_v3_make(al->mPosition.x, al->mPosition.y, al->mPosition.z);
        l->direction = evr_v3_len(dir) > 0.0f ? evr_v3_norm(dir) : evr_v3_make(0, 0, -1);
        if (l->type == EVR_LIGHT_SPOT) {
            float k = im->gltf ? 1.0f : 0.5f;   /* glTF gives half angles, the others full ones */
            l->inner_cone = al->mAngleInnerCone * k;
            l->outer_cone = al->mAngleOuterCone * k;
            if (!(l->outer_cone > 0.0f) || l->outer_cone > (float)(EVR_PI_D / 2.0)) l->outer_cone = (float)(EVR_PI_D / 4.0);
            if (!(l->inner_cone >= 0.0f) || l->inner_cone > l->outer_cone) l->inner_cone = l->outer_cone;
        } else {
            l->inner_cone = l->outer_cone = (float)EVR_PI_D;
        }
    }
    if (s->num_lights == 0) {
        /* A headlight: directional, riding with the first camera, shining along its view
         * direction tilted to come from above-left; illuminance pi makes a white Lambertian
         * surface facing it radiance 1. */
        const evr_camera_desc *c = &s->cameras[0];
        evr_light *l = &s->lights[s->num_lights++];
        evr_v3 d = evr_v3_norm(evr_v3_make(0.25f, -0.25f, -1.0f));   /* camera space */
        strcpy(l->name, "headlight");
        l->type = EVR_LIGHT_DIRECTIONAL;
        l->node = c->node;
        l->color[0] = l->color[1] = l->color[2] = (float)EVR_PI_D;
        l->position = evr_m34_point(&c->local, evr_v3_make(0, 0, 0));
        l->direction = evr_v3_norm(evr_m34_vector(&c->local, d));
        l->inner_cone = l->outer_cone = (float)EVR_PI_D;
        s->default_light = 1;
    }
    return EVR_OK;
}

/* Format name from the importer's metadata (Assimp 5.2 writes SourceAsset_Format). */
static void read_format(const struct aiScene *ai, char *out, size_t cap)
{
    unsigned i;
    out[0] = 0;
    if (!ai->mMetaData) return;
    for (i = 0; i < ai->mMetaData->mNumProperties; i++) {
        const struct aiMetadataEntry *e = &ai->mMetaData->mValues[i];
        if (!strcmp(ai->mMetaData->mKeys[i].data, "SourceAsset_Format") && e->mType == AI_AISTRING && e->mData) {
            copy_name(out, cap, ((const struct aiString *)e->mData)->data);
            return;
        }
    }
}

static unsigned import_flags(void)
{
    /* FlipUVs: Assimp stores v upwards (it flips glTF's v); flipped back, v = 0 is the image's
     * first row, as stb_image returns it and as glTF defines it. */
    return aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices |
           aiProcess_SortByPType | aiProcess_ValidateDataStructure | aiProcess_FlipUVs;
}

static void importer_free(importer *im)
{
    int i;
    if (im->tex_keys)
        for (i = 0; i < im->s->num_textures; i++) free(im->tex_keys[i]);
    free(im->tex_keys);
    free(im->mat_uv);
    free((void *)im->ai_nodes);
    free(im->by_name);
    side_free(&im->side);
}

/* Everything after Assimp: ai -> *out. `bytes` is the file or memory content (for the glTF
 * JSON), `dir` the folder for external textures. */
static evr_status convert(const struct aiScene *ai, const char *source, const char *dir, const char *ext,
                          const unsigned char *bytes, size_t nbytes, evr_scene **out, evr_error *err)
{
    importer im;
    evr_scene *s;
    evr_status st;
    uint64_t tris = 0;
    int i;

    memset(&im, 0, sizeof im);
    s = calloc(1, sizeof *s);
    if (!s) return fail(err, EVR_ERR_NOMEM, "out of memory");
    im.ai = ai;
    im.s = s;
    im.err = err;
    copy_name(im.dir, sizeof im.dir, dir);
    copy_name(s->source, sizeof s->source, source);
    read_format(ai, s->format, sizeof s->format);
    if (s->format[0]) im.gltf = strstr(s->format, "glTF2") != NULL;
    else im.gltf = ext_is(ext, "gltf") || ext_is(ext, "glb") || (nbytes >= 8 && !memcmp(bytes, "glTF", 4) && bytes[4] == 2);
    if (im.gltf && bytes) {
        if ((st = side_parse(bytes, nbytes, &im.side, err)) != EVR_OK) goto fail;
        im.have_side = 1;
    }

    if ((st = build_materials(&im)) != EVR_OK) goto fail;
    if ((st = build_meshes(&im, &tris)) != EVR_OK) goto fail;
    if (tris == 0) {
        st = fail(err, EVR_ERR_FORMAT, "'%s' has no triangles (points and lines are not rendered)", source);
        goto fail;
    }
    if ((st = build_nodes(&im)) != EVR_OK) goto fail;
    tris = 0;
    for (i = 0; i < s->num_instances; i++) tris += s->meshes[s->instances[i].mesh].num_triangles;
    if (tris == 0) {
        st = fail(err, EVR_ERR_FORMAT, "'%s' has meshes but no node places them", source);
        goto fail;
    }
    if ((st = build_animation(&im)) != EVR_OK) goto fail;
    build_bounds(s);
    if ((st = build_cameras(&im)) != EVR_OK) goto fail;
    if ((st = build_lights(&im)) != EVR_OK) goto fail;
    importer_free(&im);
    *out = s;
    return EVR_OK;
fail:
    importer_free(&im);
    evr_scene_release(s);
    return st;
}

/* Assimp failed: its reason, or ours when SortByPType removed every mesh. */
static evr_status import_error(evr_error *err, const char *source)
{
    const char *why = aiGetErrorString();
    if (why && strstr(why, "No meshes remaining"))
        return fail(err, EVR_ERR_FORMAT, "'%s' has no triangles (points and lines are not rendered)", source);
    return fail(err, EVR_ERR_FORMAT, "cannot import '%s': %s", source, why && why[0] ? why : "unknown Assimp error");
}

static struct aiPropertyStore *make_props(void)
{
    struct aiPropertyStore *p = aiCreatePropertyStore();
    if (p) aiSetImportPropertyInteger(p, AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    return p;
}

evr_status evr_scene_load(const char *path, evr_scene **out, evr_error *err)
{
    struct stat sb;
    const struct aiScene *ai;
    struct aiPropertyStore *props;
    unsigned char *bytes = NULL;
    size_t nbytes = 0;
    char dir[512];
    const char *ext, *slash;
    evr_status st;

    if (err) err->msg[0] = 0;
    if (!out) return fail(err, EVR_ERR_ARG, "evr_scene_load: no output pointer");
    *out = NULL;
    if (!path || !path[0]) return fail(err, EVR_ERR_ARG, "no scene file given");
    if (stat(path, &sb) != 0) return fail(err, EVR_ERR_IO, "cannot open scene file '%s': %s", path, strerror(errno));
    if (S_ISDIR(sb.st_mode)) return fail(err, EVR_ERR_IO, "cannot open scene file '%s': it is a folder", path);
    {
        FILE *f = fopen(path, "rb");
        if (!f) return fail(err, EVR_ERR_IO, "cannot open scene file '%s': %s", path, strerror(errno));
        fclose(f);
    }
    if (sb.st_size == 0) return fail(err, EVR_ERR_FORMAT, "scene file '%s' is empty", path);

    props = make_props();
    if (!props) return fail(err, EVR_ERR_NOMEM, "out of memory");
    ai = aiImportFileExWithProperties(path, import_flags(), NULL, props);
    aiReleasePropertyStore(props);
    if (!ai) return import_error(err, path);

    ext = file_extension(path);
    slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path) + 1;
        if (n >= sizeof dir) n = sizeof dir - 1;
        memcpy(dir, path, n);
        dir[n] = 0;
    } else {
        dir[0] = 0;   /* the current folder */
    }
    {
        /* The glTF JSON for what Assimp drops (GLB: header and JSON chunk only). */
        char fmt[32];
        read_format(ai, fmt, sizeof fmt);
        if (fmt[0] ? strstr(fmt, "glTF2") != NULL : (ext_is(ext, "gltf") || ext_is(ext, "glb"))) {
            unsigned char head[20];
            size_t want = 0;
            FILE *f = fopen(path, "rb");
            if (f) {
                if (fread(head, 1, 20, f) == 20 && !memcmp(head, "glTF", 4))
                    want = 20 + ((size_t)head[12] | (size_t)head[13] << 8 | (size_t)head[14] << 16 | (size_t)head[15] << 24);
                fclose(f);
            }
            if ((st = read_file(path, want, &bytes, &nbytes, err)) != EVR_OK) { aiReleaseImport(ai); return st; }
        }
    }
    st = convert(ai, path, dir, ext, bytes, nbytes, out, err);
    free(bytes);
    aiReleaseImport(ai);
    return st;
}

evr_status evr_scene_load_memory(const void *data, size_t size, const char *hint, evr_scene **out, evr_error *err)
{
    const struct aiScene *ai;
    struct aiPropertyStore *props;
    char source[64];
    evr_status st;

    if (err) err->msg[0] = 0;
    if (!out) return fail(err, EVR_ERR_ARG, "evr_scene_load_memory: no output pointer");
    *out = NULL;
    if (!data || size == 0) return fail(err, EVR_ERR_ARG, "no scene data given");
    if (size > UINT_MAX) return fail(err, EVR_ERR_ARG, "scene data too large (%zu bytes)", size);
    if (!hint) hint = "";
    props = make_props();
    if (!props) return fail(err, EVR_ERR_NOMEM, "out of memory");
    ai = aiImportFileFromMemoryWithProperties((const char *)data, (unsigned)size, import_flags(), hint, props);
    aiReleasePropertyStore(props);
    snprintf(source, sizeof source, "<memory>.%s", hint);
    if (!ai) return import_error(err, source);
    st = convert(ai, source, "", hint, (const unsigned char *)data, size, out, err);
    aiReleaseImport(ai);
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
        free(s->meshes[i].indices);
    }
    free(s->meshes);
    for (i = 0; i < s->num_textures && s->textures; i++) free(s->textures[i].rgba);
    free(s->textures);
    for (i = 0; i < s->num_nodes && s->nodes; i++) {
        curve_free(&s->nodes[i].t_curve);
        curve_free(&s->nodes[i].r_curve);
        curve_free(&s->nodes[i].s_curve);
    }
    free(s->nodes);
    free(s->materials);
    free(s->instances);
    free(s->lights);
    free(s->cameras);
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
            !strncmp(s->cameras[i].name, name, sizeof s->cameras[i].name - 1)) return i;
    return -1;
}

/* ------------------------------------------------------------------------------------------ */
/* Description                                                                                */

static const char *node_label(const evr_scene *s, int node)
{
    return (node >= 0 && node < s->num_nodes) ? s->nodes[node].name : "(world)";
}

static void describe_curve(strbuf *b, const char *what, const evr_curve *c)
{
    if (c->num_keys <= 0) return;
    sb_printf(b, " %s %d key%s %s", what, c->num_keys, c->num_keys == 1 ? "" : "s",
              c->interp == EVR_INTERP_STEP ? "step" : "linear");
}

char *evr_scene_describe(const evr_scene *s)
{
    strbuf b;
    int i, animated = 0;
    uint64_t tris = 0, verts = 0, inst_tris = 0;
    static const char *light_types[3] = {"point", "spot", "directional"};
    const int max_list = 50;

    memset(&b, 0, sizeof b);
    if (!s) return NULL;
    sb_printf(&b, "scene: %s\n", s->source);
    if (s->format[0]) sb_printf(&b, "format: %s\n", s->format);

    sb_printf(&b, "cameras: %d\n", s->num_cameras);
    for (i = 0; i < s->num_cameras; i++) {
        const evr_camera_desc *c = &s->cameras[i];
        sb_printf(&b, "  [%d] \"%s\" node \"%s\", yfov %.2f deg", i, c->name, node_label(s, c->node),
                  c->yfov * 180.0 / EVR_PI_D);
        if (c->aspect > 0.0f) sb_printf(&b, ", aspect %.4g", c->aspect);
        sb_printf(&b, ", znear %.4g%s\n", c->znear, c->automatic ? ", automatic (the file has no camera)" : "");
    }

    sb_printf(&b, "lights: %d%s\n", s->num_lights, s->default_light ? " (the file has none: default headlight added)" : "");
    for (i = 0; i < s->num_lights; i++) {
        const evr_light *l = &s->lights[i];
        float k = fmaxf(l->color[0], fmaxf(l->color[1], l->color[2]));
        sb_printf(&b, "  [%d] \"%s\" %s, node \"%s\", colour (%.3g %.3g %.3g), intensity %.4g %s",
                  i, l->name, light_types[l->type <= 2 ? l->type : 0], node_label(s, l->node),
                  k > 0 ? l->color[0] / k : 0.0, k > 0 ? l->color[1] / k : 0.0, k > 0 ? l->color[2] / k : 0.0,
                  k, l->type == EVR_LIGHT_DIRECTIONAL ? "lx" : "cd");
        if (l->type == EVR_LIGHT_SPOT)
            sb_printf(&b, ", cone %.1f-%.1f deg (half angles)", l->inner_cone * 180.0 / EVR_PI_D, l->outer_cone * 180.0 / EVR_PI_D);
        sb_printf(&b, "\n");
    }

    for (i = 0; i < s->num_nodes; i++) animated += s->nodes[i].animated;
    if (animated) {
        int listed = 0;
        sb_printf(&b, "animation: %.4g s to %.4g s, %d clip%s played together, %d animated node%s",
                  s->anim_start, s->anim_end, s->num_animations, s->num_animations == 1 ? "" : "s",
                  animated, animated == 1 ? "" : "s");
        if (s->frame_rate > 0) sb_printf(&b, ", %.4g frames/s", s->frame_rate);
        sb_printf(&b, "\n");
        for (i = 0; i < s->num_nodes && listed < max_list; i++) {
            const evr_node *n = &s->nodes[i];
            if (!n->animated) continue;
            listed++;
            sb_printf(&b, "  \"%s\":", n->name);
            describe_curve(&b, "translation", &n->t_curve);
            describe_curve(&b, "rotation", &n->r_curve);
            describe_curve(&b, "scale", &n->s_curve);
            sb_printf(&b, "\n");
        }
        if (animated > listed) sb_printf(&b, "  ... and %d more\n", animated - listed);
    } else {
        sb_printf(&b, "animation: none (static scene)\n");
    }

    for (i = 0; i < s->num_meshes; i++) {
        tris += s->meshes[i].num_triangles;
        verts += s->meshes[i].num_vertices;
    }
    for (i = 0; i < s->num_instances; i++) inst_tris += s->meshes[s->instances[i].mesh].num_triangles;
    sb_printf(&b, "meshes: %d, %llu vertices, %llu triangles\n", s->num_meshes, (unsigned long long)verts, (unsigned long long)tris);
    for (i = 0; i < s->num_meshes && i < max_list; i++) {
        const evr_mesh *m = &s->meshes[i];
        sb_printf(&b, "  [%d] \"%s\": %u vertices, %u triangles, material \"%s\"\n", i, m->name, m->num_vertices,
                  m->num_triangles, (m->material >= 0 && m->material < s->num_materials) ? s->materials[m->material].name : "?");
    }
    if (s->num_meshes > max_list) sb_printf(&b, "  ... and %d more\n", s->num_meshes - max_list);
    sb_printf(&b, "instances: %d (%llu triangles in the scene), nodes: %d\n", s->num_instances,
              (unsigned long long)inst_tris, s->num_nodes);
    sb_printf(&b, "materials: %d, textures: %d\n", s->num_materials, s->num_textures);
    sb_printf(&b, "bounds (rest pose): (%.4g %.4g %.4g) to (%.4g %.4g %.4g), size %.4g\n",
              s->bounds_min.x, s->bounds_min.y, s->bounds_min.z, s->bounds_max.x, s->bounds_max.y, s->bounds_max.z,
              evr_v3_len(evr_v3_sub(s->bounds_max, s->bounds_min)));
    if (b.failed) {
        free(b.buf);
        return NULL;
    }
    return b.buf;
}
