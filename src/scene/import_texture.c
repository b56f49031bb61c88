/* Textures: found beside the scene file or embedded in it (Assimp's names), or given as bytes (a
 * glTF image read from the JSON, import_gltf_material.c), decoded with stb_image to RGBA floats, their mip levels appended
 * (texture_mips.c). A texture that cannot be read or decoded (a path from another machine, a
 * broken file, a format stb_image does not read such as KTX2) is a warning naming it: its slot
 * stays empty and the material keeps its factors (evr_load_options.strict makes every warning an
 * error). Only running out of memory stops the import here.
 * Colour textures (base colour, emissive) are sRGB-decoded; data textures (metallic-roughness,
 * normal, occlusion, transmission) keep their values (v / 255). Each image is loaded once per
 * colour space however many materials use it: one image used both ways is decoded twice. */
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

/* The values of the 256 8-bit levels: sRGB-decoded, or i / 255 for data. */
static void level8_table(float lut[256], int srgb)
{
    for (int i = 0; i < 256; i++)
        lut[i] = srgb ? evr_srgb_to_linear((float)i / 255.0f) : (float)i / 255.0f;
}

/* The name of an image format stb_image does not decode, from its first bytes, or NULL. KTX2
 * (Basis Universal) has no decoder in Debian 12 (no libktx), so such textures are named in the
 * warning rather than decoded. */
static const char *undecodable_format(const unsigned char *p, size_t n)
{
    static const unsigned char ktx2[12] = {0xAB, 'K',  'T',  'X',  ' ',  '2',
                                           '0',  0xBB, '\r', '\n', 0x1A, '\n'};
    static const unsigned char ktx1[12] = {0xAB, 'K',  'T',  'X',  ' ',  '1',
                                           '1',  0xBB, '\r', '\n', 0x1A, '\n'};
    if (n >= 12 && !memcmp(p, ktx2, 12)) return "KTX2 (Basis Universal)";
    if (n >= 12 && !memcmp(p, ktx1, 12)) return "KTX";
    if (n >= 4 && !memcmp(p, "DDS ", 4)) return "DDS";
    if (n >= 12 && !memcmp(p, "RIFF", 4) && !memcmp(p + 8, "WEBP", 4)) return "WebP";
    return NULL;
}

/* Decodes an encoded image (PNG, JPEG, ...) into RGBA floats: HDR images are linear already;
 * 16- and 8-bit colour channels are sRGB-decoded when srgb, else scaled to [0, 1]; alpha is
 * linear. */
static evr_status decode_image(const unsigned char *data, size_t size, const char *what, int srgb,
                               evr_texture *t, evr_error *err)
{
    enum { HDR, BITS16, BITS8 } kind;
    int w = 0, h = 0, comp = 0;
    size_t i, n;
    void *px;
    const char *fmt = undecodable_format(data, size);
    if (fmt)
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "texture %s is a %s image, which evray cannot decode", what, fmt);
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
            t->rgba[i] = (i % 4 == 3 || !srgb) ? v : evr_srgb_to_linear(v);
        }
    } else {
        const unsigned char *p8 = px;
        float lut[256];
        level8_table(lut, srgb);
        for (i = 0; i < n * 4; i++) t->rgba[i] = (i % 4 == 3) ? (float)p8[i] / 255.0f : lut[p8[i]];
    }
    stbi_image_free(px);
    t->width = w;
    t->height = h;
    return EVR_OK;
}

/* An uncompressed embedded texture: aiTexel (b, g, r, a bytes), row 0 first. */
static evr_status decode_texels(const struct aiTexture *tex, const char *what, int srgb,
                                evr_texture *t, evr_error *err)
{
    float lut[256];
    size_t i, n = (size_t)tex->mWidth * (size_t)tex->mHeight;
    if (!tex->pcData || tex->mWidth > INT_MAX || tex->mHeight > INT_MAX)
        return evr_import_fail(err, EVR_ERR_FORMAT, "texture %s: invalid embedded image", what);
    level8_table(lut, srgb);
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

/* The texture already loaded from key in this colour space, or -1. */
static int find_texture(const importer *im, const char *key, int srgb)
{
    for (int i = 0; i < im->s->num_textures; i++)
        if (im->tex_srgb[i] == srgb && !strcmp(im->tex_keys[i], key)) return i;
    return -1;
}

/* Appends t (owned from here on) as the scene's next texture, loaded from key. */
static evr_status add_texture(importer *im, const char *key, int srgb, evr_texture *t, int *out)
{
    evr_scene *s = im->s;
    evr_status st = evr_texture_build_mips(t, im->err);
    if (st != EVR_OK) {
        free(t->rgba);
        return st;
    }
    if (s->num_textures == im->tex_cap) {
        int ncap = im->tex_cap ? im->tex_cap * 2 : 8;
        evr_texture *nt = realloc(s->textures, (size_t)ncap * sizeof *nt);
        char **nk = NULL;
        int *ns = NULL;
        if (nt) s->textures = nt;
        if (nt && (nk = realloc(im->tex_keys, (size_t)ncap * sizeof *nk))) im->tex_keys = nk;
        if (nk && (ns = realloc(im->tex_srgb, (size_t)ncap * sizeof *ns))) im->tex_srgb = ns;
        if (!ns) {
            free(t->rgba);
            return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures");
        }
        im->tex_cap = ncap;
    }
    im->tex_keys[s->num_textures] = malloc(strlen(key) + 1);
    if (!im->tex_keys[s->num_textures]) {
        free(t->rgba);
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory loading textures");
    }
    strcpy(im->tex_keys[s->num_textures], key);
    im->tex_srgb[s->num_textures] = srgb;
    s->textures[s->num_textures] = *t; /* levels: evr_texture_build_mips's */
    *out = s->num_textures++;
    return EVR_OK;
}

/* A texture that failed with st (not EVR_OK): out of memory stops the import, and so does
 * anything else when loading strictly; otherwise (the file missing or unreadable, the image
 * undecodable) it is a warning, the slot left empty. */
static evr_status texture_failed(importer *im, evr_status st, int *out)
{
    *out = -1;
    if (st == EVR_ERR_NOMEM || im->strict) return st;
    evr_import_warn(im, "%s: the material keeps its factors", im->err->msg);
    im->err->msg[0] = 0;
    return EVR_OK;
}

/* A file's texture: decoded once per colour space. */
static evr_status load_file(importer *im, const char *key, const char *what, int srgb, int *out)
{
    unsigned char *data = NULL;
    size_t size = 0;
    evr_texture t;
    evr_status st;
    evr_error e;
    memset(&t, 0, sizeof t);
    if ((*out = find_texture(im, key, srgb)) >= 0) return EVR_OK;
    st = evr_import_file_check(im->in_memory ? NULL : im->dir, key, im->allow_external, "file", &e);
    if (st == EVR_OK) st = evr_import_read_file(key, 0, &data, &size, &e);
    if (st != EVR_OK)
        return texture_failed(im, evr_import_fail(im->err, st, "texture %s: %s", what, e.msg), out);
    st = decode_image(data, size, what, srgb, &t, im->err);
    free(data);
    if (st != EVR_OK) return texture_failed(im, st, out);
    return add_texture(im, key, srgb, &t, out);
}

evr_status evr_import_texture_image(importer *im, const char *key, const unsigned char *data,
                                    size_t n, const char *what, int srgb, int *out)
{
    evr_texture t;
    evr_status st;
    memset(&t, 0, sizeof t);
    if (!data) return load_file(im, key, what, srgb, out);
    if ((*out = find_texture(im, key, srgb)) >= 0) return EVR_OK;
    if ((st = decode_image(data, n, what, srgb, &t, im->err)) != EVR_OK)
        return texture_failed(im, st, out);
    return add_texture(im, key, srgb, &t, out);
}

evr_status evr_import_texture(importer *im, const char *ai_path, const char *mat_name, int srgb,
                              int *out)
{
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
            return texture_failed(im,
                                  evr_import_fail(im->err, EVR_ERR_FORMAT,
                                                  "material '%s': embedded texture '%s' does not "
                                                  "exist",
                                                  mat_name, ai_path),
                                  out);
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
    snprintf(what, sizeof what, "'%s' of material '%s'", ai_path, mat_name);
    if (emb < 0) return load_file(im, key, what, srgb, out);
    if ((*out = find_texture(im, key, srgb)) >= 0) return EVR_OK;
    {
        const struct aiTexture *tex = ai->mTextures[emb];
        if (tex->mHeight == 0) {
            if (!tex->pcData)
                return texture_failed(
                    im, evr_import_fail(im->err, EVR_ERR_FORMAT, "texture %s: no image data", what),
                    out);
            st = decode_image((const unsigned char *)tex->pcData, tex->mWidth, what, srgb, &t,
                              im->err);
        } else {
            st = decode_texels(tex, what, srgb, &t, im->err);
        }
    }
    if (st != EVR_OK) return texture_failed(im, st, out);
    return add_texture(im, key, srgb, &t, out);
}
