/* Preview exposure (io/preview.h), the animated PNG writer (io/apng.h) and the run's previews
 * (run/preview_out.h): one exposure from the visible pixels, fixed from the first frames that
 * show anything; a valid APNG whose frames are what was added. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <stb/stb_image.h>
#include <zlib.h>

#include "check.h"
#include "evray.h"
#include "io/apng.h"
#include "io/preview.h"
#include "run/preview_out.h"

static uint64_t rng_next(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 33;
}

/* The 8-bit sRGB level of linear value v. */
static int srgb8(double v)
{
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (int)lround(v * 255.0);
}

static void test_exposure(void)
{
    enum { N = 4096 };
    float *v = malloc(N * sizeof *v);
    uint8_t *o = malloc(N), *o2 = malloc(N);
    evr_exposure e;
    uint64_t s = 99;
    int mono = 1, same = 1, i, k;

    /* random values: the map is monotonic */
    for (i = 0; i < N; i++)
        v[i] = (float)(rng_next(&s) % 100000) * 1e-3f * (i % 7 == 0 ? 50.0f : 1.0f);
    CHECK_OK(evr_tonemap_frame(v, N, o, &e_));
    for (i = 0; i < N; i++)
        for (k = i + 1; k < N; k += 97)
            if ((v[i] < v[k] && o[i] > o[k]) || (v[i] > v[k] && o[i] < o[k])) mono = 0;
    CHECK(mono);

    /* a ramp: black stays black, the median shows at the key, nothing clips (its 99th
     * percentile at the key's scale is 0.6) */
    for (i = 0; i < N; i++) v[i] = (float)i / (N - 1) * 10.0f;
    CHECK_OK(evr_exposure_of(v, N, &e, &e_));
    CHECK_NEAR(e.scale, EVR_EXPOSURE_KEY / v[(N - 1) / 2 + 1], 1e-4); /* median of the visible */
    CHECK(e.white == 1.0);
    evr_tonemap_exposed(v, N, &e, o);
    CHECK(o[0] == 0);
    CHECK(abs((int)o[N / 2] - srgb8(EVR_EXPOSURE_KEY)) <= 1);
    CHECK(o[N - 1] < 255);
    mono = 1;
    for (i = 1; i < N; i++)
        if (o[i] < o[i - 1]) mono = 0;
    CHECK(mono);

    /* scale invariance */
    for (i = 0; i < N; i++) v[i] *= 1000.0f;
    CHECK_OK(evr_tonemap_frame(v, N, o2, &e_));
    for (i = 0; i < N; i++)
        if (abs((int)o[i] - (int)o2[i]) > 1) same = 0;
    CHECK(same);

    /* a bright spread: the median at the key would clip more than 1%, so the 99th percentile is
     * white (values 1 .. 100, log-uniform) */
    for (i = 0; i < N; i++) v[i] = (float)pow(100.0, (double)i / (N - 1));
    CHECK_OK(evr_exposure_of(v, N, &e, &e_));
    CHECK_NEAR(e.scale * v[(size_t)floor(0.99 * (N - 1) + 0.5)], 1.0, 1e-6);
    evr_tonemap_exposed(v, N, &e, o);
    k = 0;
    for (i = 0; i < N; i++) k += o[i] == 255;
    CHECK(k <= N / 100 + 2);

    /* a few hot pixels do not darken the rest; NaN, negative and infinite values are handled */
    for (i = 0; i < N; i++) v[i] = 0.5f + 0.5f * (float)(i % 64) / 63.0f;
    v[10] = 1e9f;
    v[11] = 1e9f;
    v[12] = 0.0f / 0.0f;
    v[13] = -3.0f;
    v[14] = 1.0f / 0.0f;
    CHECK_OK(evr_tonemap_frame(v, N, o, &e_));
    CHECK(o[10] == 255 && o[14] == 255);
    CHECK(o[12] == 0 && o[13] == 0);
    CHECK(o[64] > 100 && o[63] > o[64] && o[63] < 255); /* 0.5 and 1.0: neither black nor white */

    /* a dark background: 90% black (rays that met nothing), an object of 0.2 .. 0.4; the object
     * is exposed by itself, not blown out by the black around it */
    for (i = 0; i < N; i++) v[i] = i % 10 ? 0.0f : 0.2f + 0.2f * (float)(i % 7) / 6.0f;
    CHECK_OK(evr_tonemap_frame(v, N, o, &e_));
    k = 0;
    for (i = 0; i < N; i += 10) k += o[i] == 255;
    CHECK(k == 0);
    CHECK(abs((int)o[10] - srgb8(EVR_EXPOSURE_KEY)) <= 2); /* 0.3: the object's median */
    CHECK(o[1] == 0);

    /* nothing visible: no exposure, every pixel black */
    memset(v, 0, N * sizeof *v);
    CHECK_OK(evr_exposure_of(v, N, &e, &e_));
    CHECK(e.scale == 0.0);
    evr_tonemap_exposed(v, N, &e, o);
    k = 1;
    for (i = 0; i < N; i++)
        if (o[i]) k = 0;
    CHECK(k);
    free(v);
    free(o);
    free(o2);
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static unsigned char *read_all(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b;
    long len;
    *n = 0;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    fseek(f, 0, SEEK_SET);
    b = malloc((size_t)len + 1);
    if (b && fread(b, 1, (size_t)len, f) != (size_t)len) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *n = b ? (size_t)len : 0;
    return b;
}

/* Checks an APNG's chunks: CRCs, order, sequence numbers; returns the frame count of acTL (-1
 * when the structure is wrong) and the delay of the first fcTL. */
static int apng_structure(const unsigned char *b, size_t n, int *fctl_count, unsigned *num,
                          unsigned *den)
{
    static const unsigned char sig[8] = {137, 'P', 'N', 'G', 13, 10, 26, 10};
    size_t at = 8;
    int frames = -1, seq = 0, idat_seen = 0, ended = 0;
    *fctl_count = 0;
    if (n < 8 || memcmp(b, sig, 8)) return -1;
    while (at + 12 <= n) {
        uint32_t len = be32(b + at);
        const unsigned char *type = b + at + 4, *data = b + at + 8;
        if (len > n - at - 12) return -1;
        if ((uint32_t)crc32(crc32(0L, Z_NULL, 0), type, len + 4) != be32(data + len)) return -1;
        if (at == 8 && memcmp(type, "IHDR", 4)) return -1;
        if (!memcmp(type, "acTL", 4)) {
            if (idat_seen) return -1; /* acTL comes before the image data */
            frames = (int)be32(data);
        } else if (!memcmp(type, "fcTL", 4)) {
            if ((int)be32(data) != seq++) return -1;
            if (!*fctl_count) {
                *num = (unsigned)(data[20] << 8 | data[21]);
                *den = (unsigned)(data[22] << 8 | data[23]);
            }
            ++*fctl_count;
        } else if (!memcmp(type, "fdAT", 4)) {
            if ((int)be32(data) != seq++ || !idat_seen) return -1;
        } else if (!memcmp(type, "IDAT", 4)) {
            if (*fctl_count != 1) return -1; /* frame 0's data, after its fcTL */
            idat_seen = 1;
        } else if (!memcmp(type, "IEND", 4)) {
            ended = 1;
        }
        at += 12 + len;
    }
    return ended && at == n ? frames : -1;
}

static void test_apng(const char *root)
{
    char path[600], tmp[620];
    uint8_t px[4 * 3 * 3];
    evr_apng *a = NULL;
    evr_error err;
    int k, fctl = 0, w = 0, h = 0, c = 0;
    unsigned num = 0, den = 0;
    size_t n;
    unsigned char *b, *img;
    snprintf(path, sizeof path, "%s/anim.apng", root);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    CHECK(evr_apng_open(path, 4, 3, 2, 1, 20, &a, &err) == EVR_ERR_ARG);
    CHECK(evr_apng_open(path, 4, 3, 3, 1, 0, &a, &err) == EVR_ERR_ARG);
    CHECK_OK(evr_apng_open(path, 4, 3, 3, 1, 20, &a, &e_));
    if (!a) return;
    for (k = 0; k < 3; k++) { /* frame k: every pixel (40 k, 7, 255 - k) */
        for (int i = 0; i < 12; i++) {
            px[3 * i] = (uint8_t)(40 * k);
            px[3 * i + 1] = 7;
            px[3 * i + 2] = (uint8_t)(255 - k);
        }
        CHECK_OK(evr_apng_add(a, px, &e_));
        CHECK(access(path, F_OK) != 0 && access(tmp, F_OK) == 0); /* temporary until finished */
    }
    CHECK(evr_apng_frames(a) == 3);
    CHECK_OK(evr_apng_finish(a, &e_));
    CHECK(access(tmp, F_OK) != 0);
    b = read_all(path, &n);
    CHECK(b != NULL);
    if (b) {
        CHECK(apng_structure(b, n, &fctl, &num, &den) == 3);
        CHECK(fctl == 3 && num == 1 && den == 20);
        /* a viewer without APNG sees frame 0 */
        img = stbi_load_from_memory(b, (int)n, &w, &h, &c, 3);
        CHECK(img && w == 4 && h == 3);
        if (img) CHECK(img[0] == 0 && img[1] == 7 && img[2] == 255 && img[33] == 0);
        stbi_image_free(img);
        free(b);
    }
    /* no frame: no file; an aborted one leaves nothing */
    snprintf(path, sizeof path, "%s/empty.apng", root);
    CHECK_OK(evr_apng_open(path, 4, 3, 3, 1, 20, &a, &e_));
    CHECK_OK(evr_apng_finish(a, &e_));
    CHECK(access(path, F_OK) != 0);
    CHECK_OK(evr_apng_open(path, 4, 3, 3, 1, 20, &a, &e_));
    CHECK_OK(evr_apng_add(a, px, &e_));
    evr_apng_abort(a);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    CHECK(access(path, F_OK) != 0 && access(tmp, F_OK) != 0);
}

/* The run's previews as PNGs: the exposure is fixed from the first frames that show anything,
 * so a pixel that keeps its intensity keeps its level when something brighter comes in. */
static void test_preview_out(const char *root)
{
    enum { W = 8, H = 4, NPIX = W * H };
    float f[NPIX];
    evr_preview_out *p = NULL;
    evr_event ev[2];
    char dir[600], path[700];
    int i, k, lv[6], w = 0, h = 0, c = 0;
    snprintf(dir, sizeof dir, "%s/run", root);
    CHECK_OK(evr_preview_out_new(EVR_PREVIEW_PNG, dir, W, H, 0, 1000, &p, &e_));
    if (!p) return;
    /* frame 0: black; frames 1-3: pixel 0 at 0.5 (the rest black); frames 4-5: pixel 1 at 50 */
    for (k = 0; k < 6; k++) {
        for (i = 0; i < NPIX; i++) f[i] = 0.0f;
        if (k >= 1) f[0] = 0.5f;
        if (k >= 4) f[1] = 50.0f;
        CHECK_OK(evr_preview_out_intensity(p, f, &e_));
        if (k == 0 || k == 2) { /* black at once; frames 1 and 2 held for the exposure */
            snprintf(path, sizeof path, "%s/preview/intensity_%06d.png", dir, k == 0 ? 0 : 1);
            CHECK((access(path, F_OK) == 0) == (k == 0));
        }
    }
    CHECK_NEAR(evr_preview_out_exposure(p).scale, EVR_EXPOSURE_KEY / 0.5, 1e-9);
    memset(ev, 0, sizeof ev);
    ev[0].t = 500;
    ev[0].p = 1;
    ev[1].t = 2500;
    CHECK_OK(evr_preview_out_events(p, ev, 2, &e_));
    CHECK(evr_preview_out_windows(p) == 2);
    CHECK_OK(evr_preview_out_advance(p, 4000, &e_));
    CHECK(evr_preview_out_windows(p) == 4);
    CHECK_OK(evr_preview_out_finish(p, 5500, &e_));
    CHECK(evr_preview_out_windows(p) == 6);
    for (k = 0; k < 6; k++) {
        unsigned char *img;
        snprintf(path, sizeof path, "%s/preview/intensity_%06d.png", dir, k);
        img = stbi_load(path, &w, &h, &c, 1);
        CHECK(img && w == W && h == H);
        lv[k] = img ? img[0] : -1;
        if (img && k >= 4) CHECK(img[1] == 255);
        stbi_image_free(img);
        snprintf(path, sizeof path, "%s/preview/events_%06d.png", dir, k);
        CHECK(access(path, F_OK) == 0);
    }
    CHECK(lv[0] == 0);
    CHECK(lv[1] == srgb8(EVR_EXPOSURE_KEY));
    CHECK(lv[1] == lv[2] && lv[2] == lv[3] && lv[3] == lv[4] && lv[4] == lv[5]);
    evr_preview_out_release(p);

    /* as a video: one APNG of 2W x H with a frame per window */
    snprintf(dir, sizeof dir, "%s/video", root);
    CHECK(mkdir(dir, 0700) == 0);
    CHECK_OK(evr_preview_out_new(EVR_PREVIEW_VIDEO, dir, W, H, 1000000, 50000, &p, &e_));
    if (!p) return;
    for (k = 0; k < 4; k++) {
        for (i = 0; i < NPIX; i++) f[i] = 0.1f * (float)(i + 1);
        CHECK_OK(evr_preview_out_intensity(p, f, &e_));
    }
    ev[0].t = 1000000 + 60000; /* window 1 */
    ev[0].x = 2;
    ev[0].y = 1;
    ev[0].p = 0;
    CHECK_OK(evr_preview_out_events(p, ev, 1, &e_));
    CHECK_OK(evr_preview_out_finish(p, 200000, &e_));
    evr_preview_out_release(p);
    snprintf(path, sizeof path, "%s/preview.apng", dir);
    {
        size_t n;
        int fctl = 0;
        unsigned num = 0, den = 0;
        unsigned char *b = read_all(path, &n), *img;
        CHECK(b != NULL);
        if (b) {
            CHECK(apng_structure(b, n, &fctl, &num, &den) == 4);
            CHECK(num * 20 == den); /* 50 ms */
            img = stbi_load_from_memory(b, (int)n, &w, &h, &c, 3);
            CHECK(img && w == 2 * W && h == H);
            if (img) { /* frame 0: no event (white) on the left, the intensity on the right */
                CHECK(img[0] == 255 && img[1] == 255 && img[2] == 255);
                CHECK(img[3 * W] > 0 && img[3 * W] == img[3 * W + 1]);
            }
            stbi_image_free(img);
            free(b);
        }
    }
}

int main(void)
{
    char root[] = "/tmp/evray-test-preview-XXXXXX";
    if (!mkdtemp(root)) return 1;
    test_exposure();
    test_apng(root);
    test_preview_out(root);
    {
        char cmd[600];
        if (!check_failures) {
            snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
            if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", root);
        } else fprintf(stderr, "files kept in %s\n", root);
    }
    return check_report("test_preview");
}
