/* Base colour textures: found beside the scene file or embedded in it, decoded with stb_image
 * and linearized to RGBA floats, their mip levels appended (texture_mips.c), each file loaded
 * once however many materials use it. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <assimp/scene.h>
#include <stb/stb_image.h>

#include "core/shading.h"
#include "scene/import_internal.h"
#include "scene/texture_mips.h"

/* The linear values of the 256 sRGB-encoded 8-bit levels. */
static void srgb8_table(float lut[256])
{
    for (int i = 0; i < 256; i++) lut[i] = evr_srgb_to_linear((float)i / 255.0f);
}

/* Decodes an encoded image (PNG, JPEG, ...) into linear RGBA floats: HDR images are linear
 * already; 16- and 8-bit colour channels are sRGB-encoded, alpha is linear. */
static evr_status decode_image(const unsigned char *data, size_t size, const char *what,
                               evr_texture *t, evr_error *err)
{
    enum { HDR, BITS16, BITS8 } kind;
    int w = 0, h = 0, comp = 0;
    size_t i, n;
    void *px;
    if (size > INT_MAX)
        return evr_import_fail(err, EVR_ERR_FORMAT, "texture %s: image too large", what);
    if (stbi_is_hdr_from_memory(data, (int)size)) {
        kind = HDR;
        px = stbi_loadf_from_memory(data, (int)size, &w, &h, &comp, 4);
    } else if (stbi_is_16_bit_from_memory(data, (int)size)) {
        kind = BITS16;
        px = stbi_load_16_from_memory(data, (int)size, &w, &h, &comp, 4);
    } else {
        kind = BITS8;
        px = stbi_load_from_memory(data, (int)size, &w, &h, &comp, 4);
    }
    if (!px)
        return evr_import_fail(err, EVR_ERR_FORMAT, "texture %s: cannot decode the image (%s)",
                               what, stbi_failure_reason());
    n = (size_t)w * (size_t)h;
    t->rgba = malloc(n * 4 * sizeof(float));
    if (!t->rgba) {
        stbi_image_free(px);
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what);
    }
    if (kind == HDR) {
        memcpy(t->rgba, px, n * 4 * sizeof(float));
    } else if (kind == BITS16) {
        const unsigned short *p16 = px;
        for (i = 0; i < n * 4; i++) {
            float v = (float)p16[i] / 65535.0f;
            t->rgba[i] = (i % 4 == 3) ? v : evr_srgb_to_linear(v);
        }
    } else {
        const unsigned char *p8 = px;
        float lut[256];
        srgb8_table(lut);
        for (i = 0; i < n * 4; i++) t->rgba[i] = (i % 4 == 3) ? (float)p8[i] / 255.0f : lut[p8[i]];
    }
    stbi_image_free(px);
    t->width = w;
    t->height = h;
    return EVR_OK;
}

/* An uncompressed embedded texture: aiTexel (b, g, r, a bytes), row 0 first. */
static evr_status decode_texels(const struct aiTexture *tex, const char *what, evr_texture *t,
                                evr_error *err)
{
    float lut[256];
    size_t i, n = (size_t)tex->mWidth * (size_t)tex->mHeight;
    if (!tex->pcData || tex->mWidth > INT_MAX || tex->mHeight > INT_MAX)
        return evr_import_fail(err, EVR_ERR_FORMAT, "texture %s: invalid embedded image", what);
    srgb8_table(lut);
    t->rgba = malloc(n * 4 * sizeof(float) + 1);
    if (!t->rgba)
        return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory decoding texture %s", what);
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

static int hex_digit(char c)
{
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : -1;
}

/* Replaces %XX escapes (URIs in glTF) in place; returns 1 if anything changed. */
static int percent_decode(char *s)
{
    char *r = s, *w = s;
    int changed = 0;
    while (*r) {
        if (r[0] == '%' && hex_digit(r[1]) >= 0 && hex_digit(r[2]) >= 0) {
            *w++ = (char)(hex_digit(r[1]) * 16 + hex_digit(r[2]));
            r += 3;
            changed = 1;
        } else {
            *w++ = *r++;
        }
    }
    *w = 0;
    return changed;
}

evr_status evr_import_texture(importer *im, const char *ai_path, const char *mat_name, int *out)
{
    evr_scene *s = im->s;
    const struct aiScene *ai = im->ai;
    char key[1100], what[1200];
    int emb = -1, i;
    evr_status st;
    evr_texture t = {0};

    memset(&t, 0, sizeof t);
    *out = -1;
    if (ai_path[0] == '*') {
        char *end;
        long k = strtol(ai_path + 1, &end, 10);
        if (*end || k < 0 || k >= (long)ai->mNumTextures)
            return evr_import_fail(im->err, EVR_ERR_FORMAT,
                                   "material '%s': embedded texture '%s' does not exist", mat_name,
                                   ai_path);
        emb = (int)k;
    } else if (short_name(ai_path)[0]) {
        /* aiScene::GetEmbeddedTexture: match by file name without folders */
        for (i = 0; i < (int)ai->mNumTextures; i++) {
            const char *tn = short_name(ai->mTextures[i]->mFilename.data);
            if (tn[0] && !strcmp(tn, short_name(ai_path))) {
                emb = i;
                break;
            }
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
        if (!strcmp(im->tex_keys[i], key)) {
            *out = i;
            return EVR_OK;
        }
    }
    snprintf(what, sizeof what, "'%s' of material '%s'", ai_path, mat_name);

    if (emb >= 0) {
        const struct aiTexture *tex = ai->mTextures[emb];
        if (tex->mHeight == 0) {
            if (!tex->pcData)
                return evr_import_fail(im->err, EVR_ERR_FORMAT, "texture %s: no image data", what);
            st = decode_image((const unsigned char *)tex->pcData, tex->mWidth, what, &t, im->err);
        } else {
            st = decode_texels(tex, what, &t, im->err);
        }
    } else {
        unsigned char *data = NULL;
        size_t size = 0;
        {
            evr_error e;
            st = evr_import_read_file(key, 0, &data, &size, &e);
            if (st != EVR_OK) return evr_import_fail(im->err, st, "texture %s: %s", what, e.msg);
        }
        st = decode_image(data, size, what, &t, im->err);
        free(data);
    }
    if (st != EVR_OK) return st;
    st = evr_texture_build_mips(&t, im->err);
    if (st != EVR_OK) {
        free(t.rgba);
        return st;
    }

    if (s->num_textures == im->tex_cap) {
        int ncap = im->tex_cap ? im->tex_cap * 2 : 8;
        evr_texture *nt = realloc(s->textures, (size_t)ncap * sizeof *nt);
        char **nk;
        if (nt) s->textures = nt;
        nk = nt ? realloc(im->tex_keys, (size_t)ncap * sizeof *nk) : NULL;
        if (nk) im->tex_keys = nk;
        if (!nt || !nk) {
            free(t.rgba);
            return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures");
        }
        im->tex_cap = ncap;
    }
    im->tex_keys[s->num_textures] = malloc(strlen(key) + 1);
    if (!im->tex_keys[s->num_textures]) {
        free(t.rgba);
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures");
    }
    strcpy(im->tex_keys[s->num_textures], key);
    s->textures[s->num_textures] = t;
    *out = s->num_textures++;
    return EVR_OK;
}
