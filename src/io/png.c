#include "io/png.h"
#include "io/file_commit.h"

#include <errno.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    unsigned char *data;
    size_t size, cap;
    int failed;
} png_mem;

static void png_mem_write(png_structp png, png_bytep bytes, png_size_t n)
{
    png_mem *m = (png_mem *)png_get_io_ptr(png);
    if (m->failed) return;
    if (m->size + n > m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 65536;
        while (cap < m->size + n) cap *= 2;
        unsigned char *p = realloc(m->data, cap);
        if (!p) {
            m->failed = 1;
            return;
        }
        m->data = p;
        m->cap = cap;
    }
    memcpy(m->data + m->size, bytes, n);
    m->size += n;
}

static void png_mem_flush(png_structp png) { (void)png; }

evr_status evr_png_encode(const void *pixels, int width, int height, int channels, int bit_depth,
                          void **out, size_t *out_size, evr_error *err)
{
    static const int color_types[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                       PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGBA};
    png_mem mem = {NULL, 0, 0, 0};
    png_structp png = NULL;
    png_infop info = NULL;
    png_bytep *rows = NULL;
    volatile evr_status st = EVR_OK;
    int y;

    if (width <= 0 || height <= 0 || channels < 1 || channels > 4 ||
        (bit_depth != 8 && bit_depth != 16)) {
        snprintf(err->msg, sizeof err->msg, "png: bad image shape %dx%dx%d/%d", width, height,
                 channels, bit_depth);
        return EVR_ERR_ARG;
    }
    rows = malloc(sizeof(png_bytep) * (size_t)height);
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    if (png) info = png_create_info_struct(png);
    if (!rows || !png || !info) {
        snprintf(err->msg, sizeof err->msg, "png: out of memory");
        st = EVR_ERR_NOMEM;
        goto done;
    }
    if (setjmp(png_jmpbuf(png))) {
        snprintf(err->msg, sizeof err->msg, "png: encoding failed");
        st = EVR_ERR_IO;
        goto done;
    }
    png_set_write_fn(png, &mem, png_mem_write, png_mem_flush);
    png_set_compression_level(png, 3); /* previews are many: favour speed */
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bit_depth,
                 color_types[channels], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (bit_depth == 16) {
        const uint16_t probe = 1;
        if (*(const unsigned char *)&probe == 1) png_set_swap(png); /* PNG is big-endian */
    }
    for (y = 0; y < height; y++)
        rows[y] = (png_bytep)pixels +
                  (size_t)y * (size_t)width * (size_t)channels * (size_t)(bit_depth / 8);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    if (mem.failed) {
        snprintf(err->msg, sizeof err->msg, "png: out of memory");
        st = EVR_ERR_NOMEM;
    }
done:
    if (png) png_destroy_write_struct(&png, info ? &info : NULL);
    free(rows);
    if (st != EVR_OK) {
        free(mem.data);
        return st;
    }
    *out = mem.data;
    *out_size = mem.size;
    return EVR_OK;
}

evr_status evr_png_write(const char *path, const void *pixels, int width, int height, int channels,
                         int bit_depth, evr_error *err)
{
    void *buf = NULL;
    size_t n = 0;
    char tmp[4096];
    evr_status st = evr_png_encode(pixels, width, height, channels, bit_depth, &buf, &n, err);
    if (st != EVR_OK) return st;
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        snprintf(err->msg, sizeof err->msg, "cannot write %s", tmp);
        free(buf);
        return EVR_ERR_IO;
    }
    int ok = fwrite(buf, 1, n, f) == n;
    ok = (fclose(f) == 0) && ok;
    free(buf);
    if (!ok || evr_file_publish(tmp, path) != 0) {
        const int e = errno;
        remove(tmp);
        snprintf(err->msg, sizeof err->msg, "cannot write %s: %s", path, strerror(e));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}
