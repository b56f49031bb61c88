/* Intensity frames for frame-based tools: planning, the folder, the PNGs and frames.csv. */
#include "run/frames_out.h"
#include "core/shading.h"
#include "io/png.h"
#include "io/file_commit.h"
#include "io/mkdir_p.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAX_FRAMES 1000000 /* six-digit file numbers */

void evr_frame_to_srgb8(const float *linear, size_t n, float exposure, uint8_t *out)
{
    size_t i;
    for (i = 0; i < n; i++) {
        float v = linear[i] * exposure;
        if (!(v > 0.0f)) v = 0.0f; /* also NaN */
        if (v > 1.0f) v = 1.0f;
        out[i] = (uint8_t)lrintf(evr_linear_to_srgb(v) * 255.0f);
    }
}

void evr_frame_to_linear16(const float *linear, size_t n, float max, uint16_t *out)
{
    size_t i;
    for (i = 0; i < n; i++) {
        double v = (double)linear[i] * 65535.0 / (double)max;
        if (!(v > 0.0)) v = 0.0;
        if (v > 65535.0) v = 65535.0;
        out[i] = (uint16_t)floor(v + 0.5);
    }
}

evr_status evr_frames_plan(evr_sim *sim, evr_error *err)
{
    int i, k;
    if (!sim->cfg.frames_out) return EVR_OK;
    if (snprintf(sim->frames_dir, sizeof sim->frames_dir, "%s", sim->cfg.frames_out) >=
        (int)sizeof sim->frames_dir) {
        snprintf(err->msg, sizeof err->msg, "frames folder path too long");
        return EVR_ERR_ARG;
    }
    sim->cfg.frames_out = sim->frames_dir; /* the caller's string is not ours to keep */
    sim->frames_fps = sim->cfg.frames_fps > 0.0 ? sim->cfg.frames_fps : sim->fps;
    double n = floor(sim->duration * sim->frames_fps + 1e-9) + 1.0; /* both ends included */
    if (n > MAX_FRAMES) {
        snprintf(err->msg, sizeof err->msg,
                 "%.0f intensity frames (%g s at %g frames/s) is more than %d", n, sim->duration,
                 sim->frames_fps, MAX_FRAMES);
        return EVR_ERR_ARG;
    }
    sim->num_frames = (int)n;
    sim->frame_times = malloc(sizeof(double) * (size_t)sim->num_frames);
    sim->seg_first_frame = malloc(sizeof(int) * ((size_t)sim->num_segments + 1));
    if (!sim->frame_times || !sim->seg_first_frame) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    for (k = 0; k < sim->num_frames; k++)
        sim->frame_times[k] = sim->cfg.start + (double)k / sim->frames_fps;
    /* segment i covers [start + i/fps, start + (i+1)/fps), the last one up to and including the end */
    for (i = 0, k = 0; i < sim->num_segments; i++) {
        int last = i + 1 == sim->num_segments;
        double t1 = sim->cfg.start + (double)(i + 1) / sim->fps;
        sim->seg_first_frame[i] = k;
        while (k < sim->num_frames && (last || sim->frame_times[k] < t1)) k++;
    }
    sim->seg_first_frame[sim->num_segments] = k;
    return EVR_OK;
}

void evr_frames_of_segment(const evr_sim *sim, int i, int *first, int *count)
{
    if (!sim->num_frames) {
        *first = *count = 0;
        return;
    }
    *first = sim->seg_first_frame[i];
    *count = sim->seg_first_frame[i + 1] - sim->seg_first_frame[i];
}

/* frames.csv, frame_*.png (and their temporary files) */
static int is_frame_file(const char *name)
{
    size_t n = strlen(name);
    if (!strcmp(name, "frames.csv") || !strcmp(name, "frames.csv.tmp")) return 1;
    if (strncmp(name, "frame_", 6)) return 0;
    return (n > 10 && !strcmp(name + n - 4, ".png")) ||
           (n > 14 && !strcmp(name + n - 8, ".png.tmp"));
}

/* Whether the folder holds frames; -1 when it cannot be read (errno set). */
static int holds_frames(const char *dir, int remove_them)
{
    DIR *d = opendir(dir);
    struct dirent *de;
    int found = 0;
    char p[4400];
    if (!d) return errno == ENOENT ? 0 : -1;
    while ((de = readdir(d)) != NULL) {
        if (!is_frame_file(de->d_name)) continue;
        found = 1;
        if (remove_them) {
            snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
            remove(p);
        }
    }
    closedir(d);
    return found;
}

evr_status evr_frames_check(const evr_sim *sim, evr_error *err)
{
    struct stat sb;
    if (!sim->num_frames) return EVR_OK;
    if (stat(sim->frames_dir, &sb) != 0) return EVR_OK;
    if (!S_ISDIR(sb.st_mode)) {
        snprintf(err->msg, sizeof err->msg, "frames path %s exists and is not a folder",
                 sim->frames_dir);
        return EVR_ERR_ARG;
    }
    int h = holds_frames(sim->frames_dir, 0);
    if (h < 0) {
        snprintf(err->msg, sizeof err->msg, "cannot open frames folder %s: %s", sim->frames_dir,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    if (h && !sim->cfg.force) {
        snprintf(err->msg, sizeof err->msg,
                 "frames folder %s already holds frames (use --force to overwrite)",
                 sim->frames_dir);
        return EVR_ERR_ARG;
    }
    return EVR_OK;
}

evr_status evr_frames_prepare(evr_sim *sim, evr_error *err)
{
    struct stat sb;
    size_t npix = (size_t)sim->cfg.width * (size_t)sim->cfg.height;
    if (!sim->num_frames) return EVR_OK;
    if (stat(sim->frames_dir, &sb) == 0) {
        if (sim->cfg.force) holds_frames(sim->frames_dir, 1); /* stale frames of an earlier run */
    } else {
        if (evr_mkdir_p(sim->frames_dir) != 0) {
            snprintf(err->msg, sizeof err->msg, "cannot create frames folder %s: %s",
                     sim->frames_dir, strerror(errno));
            return EVR_ERR_IO;
        }
        sim->created_frames_dir = 1;
    }
    sim->frame8 = malloc(npix);
    sim->frame16 = malloc(npix * sizeof *sim->frame16);
    if (!sim->frame8 || !sim->frame16) {
        snprintf(err->msg, sizeof err->msg, "out of memory for intensity frames");
        return EVR_ERR_NOMEM;
    }
    return EVR_OK;
}

static void frame_names(int k, char *name8, char *name16, size_t n)
{
    snprintf(name8, n, "frame_%06d.png", k);
    snprintf(name16, n, "frame_%06d_linear16.png", k);
}

evr_status evr_frames_write(evr_sim *sim, int k, const float *linear, evr_error *err)
{
    char n8[64], n16[64], p[4200];
    evr_status st;
    int w = sim->cfg.width, h = sim->cfg.height;
    size_t npix = (size_t)w * (size_t)h;
    frame_names(k, n8, n16, sizeof n8);
    evr_frame_to_srgb8(linear, npix, sim->cfg.frames_exposure, sim->frame8);
    evr_frame_to_linear16(linear, npix, sim->cfg.frames_max, sim->frame16);
    sim->frames_written = k + 1; /* for discard: either file may be on disk from here on */
    if ((size_t)snprintf(p, sizeof p, "%s/%s", sim->frames_dir, n8) >= sizeof p) {
        snprintf(err->msg, sizeof err->msg, "frames folder path too long");
        return EVR_ERR_ARG;
    }
    if ((st = evr_png_write(p, sim->frame8, w, h, 1, 8, err)) != EVR_OK) return st;
    snprintf(p, sizeof p, "%s/%s", sim->frames_dir, n16);
    return evr_png_write(p, sim->frame16, w, h, 1, 16, err);
}

evr_status evr_frames_finish(evr_sim *sim, evr_error *err)
{
    char p[4200], tmp[4300], n8[64], n16[64];
    int k, ok;
    if (!sim->num_frames) return EVR_OK;
    snprintf(p, sizeof p, "%s/frames.csv", sim->frames_dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", p);
    FILE *f = fopen(tmp, "w");
    ok = f && fprintf(f, "index,time_s,srgb8_png,linear16_png\n") > 0;
    for (k = 0; ok && k < sim->frames_written; k++) {
        frame_names(k, n8, n16, sizeof n8);
        ok = fprintf(f, "%d,%.9f,%s,%s\n", k, sim->frame_times[k], n8, n16) > 0;
    }
    if (f) ok = (fclose(f) == 0) && ok;
    if (!ok || evr_file_publish(tmp, p) != 0) {
        const int e = errno;
        remove(tmp);
        snprintf(err->msg, sizeof err->msg, "cannot write %s: %s", p, strerror(e));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

void evr_frames_discard(evr_sim *sim)
{
    char p[4200], n8[64], n16[64];
    int k;
    if (!sim->num_frames) return;
    for (k = 0; k < sim->frames_written; k++) {
        frame_names(k, n8, n16, sizeof n8);
        snprintf(p, sizeof p, "%s/%s", sim->frames_dir, n8);
        remove(p);
        snprintf(p, sizeof p, "%s/%s", sim->frames_dir, n16);
        remove(p);
    }
    sim->frames_written = 0;
    if (sim->created_frames_dir) rmdir(sim->frames_dir);
    sim->created_frames_dir = 0;
}

void evr_frames_free(evr_sim *sim)
{
    free(sim->frame_times);
    free(sim->seg_first_frame);
    free(sim->frame8);
    free(sim->frame16);
    sim->frame_times = NULL;
    sim->seg_first_frame = NULL;
    sim->frame8 = NULL;
    sim->frame16 = NULL;
}
