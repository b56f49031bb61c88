/* Reading labels.h5 (the layout: io/labels_h5.h) for evray plot and the labels comparison
 * program: its frame times, and one frame's depth, instance ids and flow at a time. Every read
 * is made in a child process first (io/h5_read.h says why). */
#include "evray_experimental.h"
#include "io/h5_read.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SIDE 65536 /* larger than any image evray renders: a corrupt size is refused */

/* The frame datasets: name, rank, channels per pixel (0: a scalar). */
static const struct {
    const char *name;
    int rank, channels;
} FRAME_SETS[3] = {{"depth", 3, 0}, {"instance", 3, 0}, {"flow", 4, 2}};

/* Opens dataset name of file and checks its shape: rank 1 ([N]) for t, else [N, H, W(, c)] with
 * N frames, H and W as in *info (0: not known yet, then taken from it). NULL what: it fits. */
static const char *check_set(hid_t file, const char *name, int rank, int channels,
                             evr_labels_info *info, hid_t *ds)
{
    hsize_t dims[4] = {0, 0, 0, 0};
    hid_t space;
    int ok;
    if (H5Lexists(file, name, H5P_DEFAULT) <= 0)
        return "no t, depth, instance and flow datasets: not a labels.h5 file";
    if ((*ds = H5Dopen2(file, name, H5P_DEFAULT)) < 0) return "cannot open a label dataset";
    space = H5Dget_space(*ds);
    ok = space >= 0 && H5Sget_simple_extent_ndims(space) == rank &&
         H5Sget_simple_extent_dims(space, dims, NULL) == rank;
    if (space >= 0) H5Sclose(space);
    if (!ok) return "a label dataset has the wrong number of dimensions";
    if (rank == 1) {
        info->frames = (size_t)dims[0];
        return NULL;
    }
    if (dims[0] != (hsize_t)info->frames) return "the label datasets differ in frames";
    if (rank == 4 && dims[3] != (hsize_t)channels) return "flow is not 2 values per pixel";
    if (dims[1] < 1 || dims[2] < 1 || dims[1] > MAX_SIDE || dims[2] > MAX_SIDE)
        return "the label frames' size is out of range";
    if (info->height == 0) {
        info->height = (int)dims[1];
        info->width = (int)dims[2];
    } else if (dims[1] != (hsize_t)info->height || dims[2] != (hsize_t)info->width)
        return "the label datasets differ in size";
    return NULL;
}

static double double_attr(hid_t file, const char *name)
{
    double v = NAN;
    if (H5Aexists(file, name) > 0) {
        hid_t a = H5Aopen(file, name, H5P_DEFAULT);
        if (a >= 0) {
            hid_t space = H5Aget_space(a);
            if (space < 0 || H5Sget_simple_extent_npoints(space) != 1 ||
                H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0)
                v = NAN;
            if (space >= 0) H5Sclose(space);
            H5Aclose(a);
        }
    }
    return v;
}

/* Opens path and its four frame datasets with their shapes checked (*info's sizes filled);
 * ds[0] is t, ds[1..3] FRAME_SETS. NULL what: done; else what is wrong (everything closed). */
static const char *open_sets(const char *path, hid_t *file, hid_t ds[4], evr_labels_info *info,
                             evr_status *st)
{
    const char *what = NULL;
    int k;
    *file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    *st = EVR_ERR_FORMAT;
    if (*file < 0) {
        *st = EVR_ERR_IO;
        return "cannot open as HDF5";
    }
    what = check_set(*file, "t", 1, 0, info, &ds[0]);
    for (k = 0; k < 3 && !what; k++)
        what = check_set(*file, FRAME_SETS[k].name, FRAME_SETS[k].rank, FRAME_SETS[k].channels,
                         info, &ds[k + 1]);
    if (!what && info->frames == 0) what = "no label frames";
    return what;
}

static void close_sets(hid_t file, hid_t ds[4])
{
    for (int k = 0; k < 4; k++)
        if (ds[k] >= 0) H5Dclose(ds[k]);
    if (file >= 0) H5Fclose(file);
    H5Eclear2(H5E_DEFAULT);
}

static evr_status read_info_here(const char *path, evr_labels_info *info, evr_error *err)
{
    hid_t file = -1, ds[4] = {-1, -1, -1, -1};
    evr_status st = EVR_OK;
    const char *what;
    memset(info, 0, sizeof *info);
    H5E_BEGIN_TRY
    {
        what = open_sets(path, &file, ds, info, &st);
        if (!what) {
            int w = evr_h5_int_attr(file, "width"), h = evr_h5_int_attr(file, "height");
            if ((w >= 0 && w != info->width) || (h >= 0 && h != info->height))
                what = "the width and height attributes differ from the frames' size";
        }
        if (!what && !(info->t = malloc(info->frames * sizeof *info->t))) {
            what = "out of memory";
            st = EVR_ERR_NOMEM;
        } else if (!what &&
                   H5Dread(ds[0], H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, info->t) < 0)
            what = "cannot read t";
        for (size_t i = 0; !what && i < info->frames; i++)
            if (!isfinite(info->t[i]) || (i > 0 && info->t[i] < info->t[i - 1]))
                what = "the frame times are not finite and increasing";
        if (!what) {
            info->fps = double_attr(file, "fps");
            info->flow_dt = double_attr(file, "flow_dt");
            info->complete = evr_h5_int_attr(file, "complete") == 1;
        }
        if (what) evr_h5_fail(err, what, path, st);
        close_sets(file, ds);
    }
    H5E_END_TRY;
    if (what) {
        evr_labels_info_free(info);
        return st;
    }
    return EVR_OK;
}

/* Reads frame k of one dataset (buf: H * W * max(c, 1) values of mem type). */
static herr_t read_one(hid_t ds, int rank, size_t k, const evr_labels_info *info, int c, hid_t mem,
                       void *buf)
{
    hsize_t start[4] = {(hsize_t)k, 0, 0, 0},
            count[4] = {1, (hsize_t)info->height, (hsize_t)info->width, (hsize_t)c};
    hid_t fs = H5Dget_space(ds), ms = -1;
    herr_t r = -1;
    if (fs >= 0 && H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
        (ms = H5Screate_simple(rank, count, NULL)) >= 0)
        r = H5Dread(ds, mem, ms, fs, H5P_DEFAULT, buf);
    if (ms >= 0) H5Sclose(ms);
    if (fs >= 0) H5Sclose(fs);
    return r;
}

typedef struct {
    const char *path;
    const evr_labels_info *want; /* the shape read before */
    size_t k;
    float *depth, *flow;
    uint32_t *instance;
    evr_labels_info *info; /* read_info's output */
    evr_error err;
} job;

static evr_status read_frame_here(const job *j, evr_error *err)
{
    hid_t file = -1, ds[4] = {-1, -1, -1, -1};
    evr_status st = EVR_OK;
    evr_labels_info got;
    const char *what;
    void *bufs[3] = {j->depth, j->instance, j->flow};
    const hid_t mem[3] = {H5T_NATIVE_FLOAT, H5T_NATIVE_UINT32, H5T_NATIVE_FLOAT};
    memset(&got, 0, sizeof got);
    H5E_BEGIN_TRY
    {
        what = open_sets(j->path, &file, ds, &got, &st);
        if (!what && (got.frames != j->want->frames || got.width != j->want->width ||
                      got.height != j->want->height))
            what = "the file changed while it was read";
        if (!what && j->k >= got.frames) what = "no such label frame";
        for (int s = 0; s < 3 && !what; s++)
            if (bufs[s] && read_one(ds[s + 1], FRAME_SETS[s].rank, j->k, &got,
                                    FRAME_SETS[s].channels, mem[s], bufs[s]) < 0) {
                snprintf(err->msg, sizeof err->msg, "cannot read frame %zu of %s (corrupt data?)",
                         j->k, FRAME_SETS[s].name);
                what = err->msg;
            }
        if (what) {
            char w[160];
            snprintf(w, sizeof w, "%s", what);
            evr_h5_fail(err, w, j->path, st);
        }
        close_sets(file, ds);
    }
    H5E_END_TRY;
    return what ? st : EVR_OK;
}

static const void *info_job(void *ctx, char *msg, size_t cap)
{
    job *j = ctx;
    if (read_info_here(j->path, j->info, &j->err) != EVR_OK) {
        snprintf(msg, cap, "%s", j->err.msg);
        return NULL;
    }
    evr_labels_info_free(j->info);
    return j;
}

static const void *frame_job(void *ctx, char *msg, size_t cap)
{
    job *j = ctx;
    if (read_frame_here(j, &j->err) != EVR_OK) {
        snprintf(msg, cap, "%s", j->err.msg);
        return NULL;
    }
    return j;
}

evr_status evr_labels_read_info(const char *path, evr_labels_info *info, evr_error *err)
{
    job j;
    evr_status st;
    memset(info, 0, sizeof *info);
    memset(&j, 0, sizeof j);
    j.path = path;
    j.info = info;
    if ((st = evr_h5_regular(path, err)) != EVR_OK ||
        (st = evr_h5_isolated(info_job, &j, path, err)) != EVR_OK)
        return st;
    return read_info_here(path, info, err);
}

void evr_labels_info_free(evr_labels_info *info)
{
    free(info->t);
    info->t = NULL;
}

evr_status evr_labels_read_frame(const char *path, const evr_labels_info *info, size_t k,
                                 float *depth, uint32_t *instance, float *flow, evr_error *err)
{
    job j;
    evr_status st;
    memset(&j, 0, sizeof j);
    j.path = path;
    j.want = info;
    j.k = k;
    j.depth = depth;
    j.instance = instance;
    j.flow = flow;
    if ((st = evr_h5_regular(path, err)) != EVR_OK ||
        (st = evr_h5_isolated(frame_job, &j, path, err)) != EVR_OK)
        return st;
    return read_frame_here(&j, err);
}

evr_status evr_labels_nearest_frame(const evr_labels_info *info, double t, size_t *k,
                                    evr_error *err)
{
    /* half a frame interval beyond either end still has a nearest frame */
    double half = info->fps > 0.0 && isfinite(info->fps) ? 0.5 / info->fps : 0.0;
    size_t i, best = 0;
    if (!(t >= info->t[0] - half && t <= info->t[info->frames - 1] + half)) {
        snprintf(err->msg, sizeof err->msg,
                 "time %g s is outside the label frames (%zu from %g to %g s)", t, info->frames,
                 info->t[0], info->t[info->frames - 1]);
        return EVR_ERR_ARG;
    }
    for (i = 1; i < info->frames; i++)
        if (fabs(info->t[i] - t) < fabs(info->t[best] - t)) best = i;
    *k = best;
    return EVR_OK;
}
