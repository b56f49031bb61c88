/* Animated PNG (APNG) writer: io/apng.h. The chunk layout (PNG's, with the APNG extension):
 *   signature, IHDR, acTL (frames, plays 0: loop), then per frame an fcTL (sequence number, size,
 *   offset 0 0, delay, dispose NONE, blend SOURCE) and its image data: IDAT chunks for frame 0,
 *   fdAT chunks (sequence number, then the same zlib data) after, then IEND.
 * Sequence numbers count the fcTL and fdAT chunks from 0. */
#include "io/apng.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "io/png.h"
#include "io/file_commit.h"

struct evr_apng {
    FILE *f;
    char *path, *tmp;
    int width, height, channels, frames;
    unsigned delay_num, delay_den;
    uint32_t seq;
    long actl_at; /* where the acTL chunk's data starts, to write the frame count at the end */
};

static void be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static uint32_t get_be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* One chunk: length, type, data (a prefix of 4 bytes, e.g. a sequence number, then data), CRC. */
static int put_chunk(FILE *f, const char *type, const unsigned char *prefix, const void *data,
                     size_t n)
{
    unsigned char head[8], crc[4];
    uLong c = crc32(0L, Z_NULL, 0);
    size_t total = n + (prefix ? 4 : 0);
    be32(head, (uint32_t)total);
    memcpy(head + 4, type, 4);
    c = crc32(c, head + 4, 4);
    if (prefix) c = crc32(c, prefix, 4);
    if (n) c = crc32(c, data, (uInt)n);
    be32(crc, (uint32_t)c);
    return fwrite(head, 1, 8, f) == 8 && (!prefix || fwrite(prefix, 1, 4, f) == 4) &&
           (!n || fwrite(data, 1, n, f) == n) && fwrite(crc, 1, 4, f) == 4;
}

static evr_status io_fail(evr_apng *a, evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "cannot write %s: %s", a->tmp, strerror(errno));
    return EVR_ERR_IO;
}

evr_status evr_apng_open(const char *path, int width, int height, int channels, unsigned delay_num,
                         unsigned delay_den, evr_apng **out, evr_error *err)
{
    evr_apng *a;
    *out = NULL;
    if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) || delay_num > 65535 ||
        delay_den == 0 || delay_den > 65535) {
        snprintf(err->msg, sizeof err->msg, "apng: bad shape %dx%dx%d or delay %u/%u", width,
                 height, channels, delay_num, delay_den);
        return EVR_ERR_ARG;
    }
    a = calloc(1, sizeof *a);
    if (a) a->path = malloc(strlen(path) + 1);
    if (a && a->path) a->tmp = malloc(strlen(path) + 5);
    if (!a || !a->path || !a->tmp) {
        evr_apng_abort(a);
        snprintf(err->msg, sizeof err->msg, "apng: out of memory");
        return EVR_ERR_NOMEM;
    }
    strcpy(a->path, path);
    sprintf(a->tmp, "%s.tmp", path);
    a->width = width;
    a->height = height;
    a->channels = channels;
    a->delay_num = delay_num;
    a->delay_den = delay_den;
    *out = a;
    return EVR_OK;
}

/* The file's start, from the first frame's PNG (its signature and IHDR) and an acTL. */
static int write_head(evr_apng *a, const unsigned char *png)
{
    unsigned char actl[8];
    if (fwrite(png, 1, 8 + 25, a->f) != 33) return 0; /* signature, IHDR (13 bytes of data) */
    a->actl_at = 33 + 8;
    be32(actl, 0); /* frames: written by evr_apng_finish */
    be32(actl + 4, 0);
    return put_chunk(a->f, "acTL", NULL, actl, 8);
}

evr_status evr_apng_add(evr_apng *a, const uint8_t *pixels, evr_error *err)
{
    void *buf = NULL;
    size_t n = 0, at = 8;
    unsigned char fctl[26], seq[4];
    const unsigned char *png;
    evr_status st;
    if ((st = evr_png_encode(pixels, a->width, a->height, a->channels, 8, &buf, &n, err)) != EVR_OK)
        return st;
    png = buf;
    if (!a->f) {
        if (!(a->f = fopen(a->tmp, "wb"))) {
            free(buf);
            return io_fail(a, err);
        }
        if (n < 33 || !write_head(a, png)) {
            free(buf);
            return io_fail(a, err);
        }
    }
    be32(fctl, a->seq++);
    be32(fctl + 4, (uint32_t)a->width);
    be32(fctl + 8, (uint32_t)a->height);
    be32(fctl + 12, 0);
    be32(fctl + 16, 0);
    fctl[20] = (unsigned char)(a->delay_num >> 8);
    fctl[21] = (unsigned char)a->delay_num;
    fctl[22] = (unsigned char)(a->delay_den >> 8);
    fctl[23] = (unsigned char)a->delay_den;
    fctl[24] = 0; /* dispose: none */
    fctl[25] = 0; /* blend: source (every frame is whole) */
    if (!put_chunk(a->f, "fcTL", NULL, fctl, sizeof fctl)) {
        free(buf);
        return io_fail(a, err);
    }
    /* the encoded PNG's IDAT chunks, as they are (frame 0) or as fdAT */
    while (at + 12 <= n) {
        uint32_t len = get_be32(png + at);
        const unsigned char *type = png + at + 4, *data = png + at + 8;
        if (len > n - at - 12) break;
        if (!memcmp(type, "IDAT", 4)) {
            int ok;
            if (a->frames == 0) ok = put_chunk(a->f, "IDAT", NULL, data, len);
            else {
                be32(seq, a->seq++);
                ok = put_chunk(a->f, "fdAT", seq, data, len);
            }
            if (!ok) {
                free(buf);
                return io_fail(a, err);
            }
        }
        at += 12 + len;
    }
    free(buf);
    a->frames++;
    return EVR_OK;
}

int evr_apng_frames(const evr_apng *a) { return a ? a->frames : 0; }

evr_status evr_apng_finish(evr_apng *a, evr_error *err)
{
    unsigned char actl[8], crc[4];
    uLong c;
    int ok;
    evr_status st = EVR_OK;
    if (!a->f) { /* no frame: no file */
        evr_apng_abort(a);
        return EVR_OK;
    }
    be32(actl, (uint32_t)a->frames);
    be32(actl + 4, 0);
    c = crc32(crc32(0L, Z_NULL, 0), (const Bytef *)"acTL", 4);
    be32(crc, (uint32_t)crc32(c, actl, 8));
    ok = put_chunk(a->f, "IEND", NULL, NULL, 0) && fseek(a->f, a->actl_at, SEEK_SET) == 0 &&
         fwrite(actl, 1, 8, a->f) == 8 && fwrite(crc, 1, 4, a->f) == 4;
    ok = fclose(a->f) == 0 && ok;
    a->f = NULL;
    if (!ok || evr_file_publish(a->tmp, a->path) != 0) st = io_fail(a, err);
    evr_apng_abort(a); /* the temporary file is gone once renamed */
    return st;
}

void evr_apng_abort(evr_apng *a)
{
    if (!a) return;
    if (a->f) fclose(a->f);
    if (a->tmp) remove(a->tmp);
    free(a->path);
    free(a->tmp);
    free(a);
}
