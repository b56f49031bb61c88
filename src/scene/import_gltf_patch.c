/* A patched copy of a glTF for Assimp to read: edits of the JSON text (replacements and
 * insertions at byte offsets of the parsed document), applied in one pass; a GLB keeps its BIN
 * chunk. Each stage that patches (import_gltf_deform.c, import_gltf_geometry.c) parses the
 * output of the one before, so that no two stages' edits meet. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/byte_order.h"
#include "scene/import_internal.h"

/* By place; edits at one place in the order they were made. */
static int edit_cmp(const void *pa, const void *pb)
{
    const gltf_edit *a = pa, *b = pb;
    if (a->at != b->at) return (a->at > b->at) - (a->at < b->at);
    return (a->seq > b->seq) - (a->seq < b->seq);
}

int evr_gltf_edit(gltf_edits *E, size_t at, size_t len, char *text)
{
    if (!text) return 0;
    if (E->n == E->cap) {
        int ncap = E->cap ? 2 * E->cap : 16;
        gltf_edit *ne = realloc(E->e, (size_t)ncap * sizeof *ne);
        if (!ne) {
            free(text);
            return 0;
        }
        E->e = ne;
        E->cap = ncap;
    }
    E->e[E->n].at = at;
    E->e[E->n].len = len;
    E->e[E->n].seq = E->n;
    E->e[E->n++].text = text;
    return 1;
}

void evr_gltf_edits_free(gltf_edits *E)
{
    for (int i = 0; i < E->n; i++) free(E->e[i].text);
    free(E->e);
    memset(E, 0, sizeof *E);
}

char *evr_gltf_b64(const unsigned char *p, size_t n)
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

int evr_gltf_append(gltf_edits *E, const evr_jdoc *d, int root, const char *key, const char *elems)
{
    int arr = evr_jdoc_get(d, root, key);
    size_t n = strlen(key) + strlen(elems) + 16;
    char *t = malloc(n);
    if (!t) return 0;
    if (arr >= 0 && evr_jdoc_type(d, arr) == EVR_JDOC_ARRAY) {
        snprintf(t, n, "%s%s", evr_jdoc_count(d, arr) ? "," : "", elems);
        return evr_gltf_edit(E, d->v[arr].off + d->v[arr].len - 1, 0, t);
    }
    snprintf(t, n, "\"%s\":[%s],", key, elems);
    return evr_gltf_edit(E, d->v[root].off + 1, 0, t);
}

evr_status evr_gltf_edits_apply(const gltf_source *src, gltf_edits *E, const char *json,
                                size_t jlen, unsigned char **out, size_t *nout, evr_error *err)
{
    unsigned char *file = NULL, *res;
    const unsigned char *rest = NULL;
    size_t nrest = 0, nfile = 0, total = jlen + 24, o, prev = 0;
    int glb = src->nbytes >= 20 && !memcmp(src->bytes, "glTF", 4), i;
    evr_status st;

    qsort(E->e, (size_t)E->n, sizeof *E->e, edit_cmp);
    if (glb) { /* what follows the JSON chunk (the BIN chunk) */
        size_t end = 20 + (size_t)evr_get_le32(src->bytes + 12);
        size_t whole = evr_get_le32(src->bytes + 8); /* the GLB's length, from its header */
        if (src->nbytes < whole && src->path) {
            if ((st = evr_import_read_file(src->path, 0, &file, &nfile, err)) != EVR_OK) return st;
            if (nfile < end) {
                free(file);
                return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB '%s' is cut short",
                                       src->path);
            }
            rest = file + end;
            nrest = nfile - end;
        } else if (src->nbytes >= end) {
            rest = src->bytes + end;
            nrest = src->nbytes - end;
        }
    }
    total += nrest;
    for (i = 0; i < E->n; i++) total += strlen(E->e[i].text);
    if (!(res = malloc(total + 4))) {
        free(file);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory patching the glTF");
    }
    o = glb ? 20 : 0;
    for (i = 0; i < E->n; i++) {
        size_t n = strlen(E->e[i].text);
        memcpy(res + o, json + prev, E->e[i].at - prev);
        o += E->e[i].at - prev;
        memcpy(res + o, E->e[i].text, n);
        o += n;
        prev = E->e[i].at + E->e[i].len;
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
    free(file);
    *out = res;
    *nout = o;
    return EVR_OK;
}
