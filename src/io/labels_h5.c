/* labels.h5 (io/labels_h5.h): one chunk per frame and dataset, through HDF5's own filters (a
 * label frame is a few hundred kilobytes; unlike the event stream, H5Dwrite's serial deflate
 * keeps up). HDF5's error printing is off around every call (H5E_BEGIN_TRY). */
#include "io/labels_h5.h"
#include "io/file_commit.h"
#include "io/h5_file.h"
#include "io/h5_instances.h"

#include <hdf5.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LABELS_DEFLATE 4
#define LABELS_SETS 6 /* t, depth, instance, flow, displacement, normal */

struct evr_labels_h5 {
    char *path, *tmp;
    hid_t file;
    hid_t ds[LABELS_SETS];
    int width, height, normals;
    hsize_t frames;
};

static evr_status fail(evr_error *err, const char *what, const char *path)
{
    H5Eclear2(H5E_DEFAULT);
    snprintf(err->msg, sizeof err->msg, "hdf5: %s %s", what, path);
    return EVR_ERR_IO;
}

/* An extendible dataset of frames: [0, H, W(, c)] chunked one frame per chunk (c 0: none). */
static hid_t make_frames(hid_t file, const char *name, hid_t type, int h, int w, int c)
{
    hsize_t dims[4] = {0, (hsize_t)h, (hsize_t)w, (hsize_t)c},
            maxd[4] = {H5S_UNLIMITED, (hsize_t)h, (hsize_t)w, (hsize_t)c},
            ch[4] = {1, (hsize_t)h, (hsize_t)w, (hsize_t)c};
    const int rank = c ? 4 : 3;
    hid_t space = H5Screate_simple(rank, dims, maxd), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t ds = -1;
    if (space >= 0 && dcpl >= 0 && H5Pset_obj_track_times(dcpl, 0) >= 0 &&
        H5Pset_chunk(dcpl, rank, ch) >= 0 && H5Pset_shuffle(dcpl) >= 0 &&
        H5Pset_deflate(dcpl, LABELS_DEFLATE) >= 0)
        ds = H5Dcreate2(file, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (dcpl >= 0) H5Pclose(dcpl);
    if (space >= 0) H5Sclose(space);
    return ds;
}

static hid_t make_times(hid_t file)
{
    hsize_t dims[1] = {0}, maxd[1] = {H5S_UNLIMITED}, ch[1] = {1024};
    hid_t space = H5Screate_simple(1, dims, maxd), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t ds = -1;
    if (space >= 0 && dcpl >= 0 && H5Pset_obj_track_times(dcpl, 0) >= 0 &&
        H5Pset_chunk(dcpl, 1, ch) >= 0)
        ds = H5Dcreate2(file, "t", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (dcpl >= 0) H5Pclose(dcpl);
    if (space >= 0) H5Sclose(space);
    return ds;
}

static herr_t scalar_attr(hid_t loc, const char *name, hid_t file_type, hid_t mem_type,
                          const void *v)
{
    hid_t space = H5Screate(H5S_SCALAR), a = -1;
    herr_t r = -1;
    if (space >= 0) a = H5Acreate2(loc, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) r = H5Awrite(a, mem_type, v);
    if (a >= 0 && H5Aclose(a) < 0) r = -1;
    if (space >= 0) H5Sclose(space);
    return r;
}

static herr_t string_attr(hid_t loc, const char *name, const char *text)
{
    hid_t type = H5Tcopy(H5T_C_S1);
    herr_t r = -1;
    if (type >= 0 && H5Tset_size(type, strlen(text) + 1) >= 0)
        r = scalar_attr(loc, name, type, type, text);
    if (type >= 0) H5Tclose(type);
    return r;
}

static void close_all(evr_labels_h5 *w)
{
    int i;
    for (i = 0; i < LABELS_SETS; i++)
        if (w->ds[i] >= 0) H5Dclose(w->ds[i]);
    if (w->file >= 0) H5Fclose(w->file);
    for (i = 0; i < LABELS_SETS; i++) w->ds[i] = -1;
    w->file = -1;
}

static void free_writer(evr_labels_h5 *w)
{
    free(w->path);
    free(w->tmp);
    free(w);
}

evr_status evr_labels_h5_open(const char *path, const evr_labels_h5_meta *m, evr_labels_h5 **out,
                              evr_error *err)
{
    evr_labels_h5 *w = calloc(1, sizeof *w);
    int i, ok = 0;
    *out = NULL;
    if (w) {
        w->path = malloc(strlen(path) + 1);
        w->tmp = evr_file_tmp_name(path);
    }
    if (!w || !w->path || !w->tmp) {
        if (w) free_writer(w);
        snprintf(err->msg, sizeof err->msg, "out of memory opening %s", path);
        return EVR_ERR_NOMEM;
    }
    strcpy(w->path, path);
    w->width = m->width;
    w->height = m->height;
    w->normals = m->normals;
    w->file = -1;
    for (i = 0; i < LABELS_SETS; i++) w->ds[i] = -1;
    H5E_BEGIN_TRY
    {
        const int32_t width = m->width, height = m->height;
        const int8_t incomplete = 0;
        w->file = evr_h5_create_reproducible(w->tmp); /* the same bytes for the same labels */
        if (w->file >= 0 && (w->ds[0] = make_times(w->file)) >= 0 &&
            (w->ds[1] = make_frames(w->file, "depth", H5T_IEEE_F32LE, m->height, m->width, 0)) >=
                0 &&
            (w->ds[2] = make_frames(w->file, "instance", H5T_STD_U32LE, m->height, m->width, 0)) >=
                0 &&
            (w->ds[3] = make_frames(w->file, "flow", H5T_IEEE_F32LE, m->height, m->width, 2)) >=
                0 &&
            (w->ds[4] = make_frames(w->file, "displacement", H5T_IEEE_F32LE, m->height, m->width,
                                    2)) >= 0 &&
            (!m->normals || (w->ds[5] = make_frames(w->file, "normal", H5T_IEEE_F32LE, m->height,
                                                    m->width, 3)) >= 0) &&
            evr_h5_write_instances(w->file, m->inst_node, m->inst_mesh, m->num_instances) >= 0 &&
            scalar_attr(w->file, "width", H5T_STD_I32LE, H5T_NATIVE_INT32, &width) >= 0 &&
            scalar_attr(w->file, "height", H5T_STD_I32LE, H5T_NATIVE_INT32, &height) >= 0 &&
            scalar_attr(w->file, "fps", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &m->fps) >= 0 &&
            scalar_attr(w->file, "flow_dt", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &m->flow_dt) >= 0 &&
            scalar_attr(w->file, "complete", H5T_STD_I8LE, H5T_NATIVE_INT8, &incomplete) >= 0 &&
            string_attr(w->file, "config", m->config_json ? m->config_json : "{}") >= 0 &&
            H5Fflush(w->file, H5F_SCOPE_GLOBAL) >= 0)
            ok = 1;
    }
    H5E_END_TRY;
    if (!ok) {
        evr_status st = fail(err, "cannot create", w->tmp);
        H5E_BEGIN_TRY { close_all(w); }
        H5E_END_TRY;
        remove(w->tmp);
        free_writer(w);
        return st;
    }
    *out = w;
    return EVR_OK;
}

/* Appends one frame of values (c per pixel, 0: a scalar; for /t, h = w = 0 and one value). */
static herr_t append(hid_t ds, hsize_t frame, int h, int w, int c, hid_t mem, const void *data)
{
    const int rank = h == 0 ? 1 : c ? 4 : 3;
    hsize_t size[4] = {frame + 1, (hsize_t)h, (hsize_t)w, (hsize_t)c}, start[4] = {frame, 0, 0, 0},
            count[4] = {1, (hsize_t)h, (hsize_t)w, (hsize_t)c};
    hid_t fs = -1, ms = -1;
    herr_t r = -1;
    if (H5Dset_extent(ds, size) >= 0 && (fs = H5Dget_space(ds)) >= 0 &&
        H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
        (ms = H5Screate_simple(rank, count, NULL)) >= 0)
        r = H5Dwrite(ds, mem, ms, fs, H5P_DEFAULT, data);
    if (ms >= 0) H5Sclose(ms);
    if (fs >= 0) H5Sclose(fs);
    return r;
}

evr_status evr_labels_h5_append(evr_labels_h5 *w, double t, const float *depth,
                                const uint32_t *instance, const float *flow, const float *disp,
                                const float *normal, evr_error *err)
{
    int ok = 0;
    const int h = w->height, wd = w->width;
    H5E_BEGIN_TRY
    {
        ok = append(w->ds[0], w->frames, 0, 0, 0, H5T_NATIVE_DOUBLE, &t) >= 0 &&
             append(w->ds[1], w->frames, h, wd, 0, H5T_NATIVE_FLOAT, depth) >= 0 &&
             append(w->ds[2], w->frames, h, wd, 0, H5T_NATIVE_UINT32, instance) >= 0 &&
             append(w->ds[3], w->frames, h, wd, 2, H5T_NATIVE_FLOAT, flow) >= 0 &&
             append(w->ds[4], w->frames, h, wd, 2, H5T_NATIVE_FLOAT, disp) >= 0 &&
             (!w->normals || append(w->ds[5], w->frames, h, wd, 3, H5T_NATIVE_FLOAT, normal) >= 0);
    }
    H5E_END_TRY;
    if (!ok) return fail(err, "cannot append a label frame to", w->tmp);
    w->frames++;
    return EVR_OK;
}

evr_status evr_labels_h5_flush(evr_labels_h5 *w, evr_error *err)
{
    herr_t r;
    H5E_BEGIN_TRY { r = H5Fflush(w->file, H5F_SCOPE_GLOBAL); }
    H5E_END_TRY;
    return r < 0 ? fail(err, "cannot flush", w->tmp) : EVR_OK;
}

evr_status evr_labels_h5_finish(evr_labels_h5 *w, evr_error *err)
{
    evr_status st = EVR_OK;
    int ok = 0;
    const int8_t complete = 1;
    H5E_BEGIN_TRY
    {
        hid_t a = H5Aopen(w->file, "complete", H5P_DEFAULT);
        ok = a >= 0 && H5Awrite(a, H5T_NATIVE_INT8, &complete) >= 0;
        if (a >= 0 && H5Aclose(a) < 0) ok = 0;
        for (int i = 0; i < LABELS_SETS; i++) {
            if (w->ds[i] >= 0 && H5Dclose(w->ds[i]) < 0) ok = 0;
            w->ds[i] = -1;
        }
        if (H5Fclose(w->file) < 0) ok = 0;
        w->file = -1;
    }
    H5E_END_TRY;
    if (!ok) st = fail(err, "cannot complete", w->tmp);
    else if (rename(w->tmp, w->path) != 0) {
        snprintf(err->msg, sizeof err->msg, "cannot rename %s to %s", w->tmp, w->path);
        st = EVR_ERR_IO;
    }
    if (st != EVR_OK) remove(w->tmp);
    free_writer(w);
    return st;
}

void evr_labels_h5_abort(evr_labels_h5 *w)
{
    if (!w) return;
    H5E_BEGIN_TRY { close_all(w); }
    H5E_END_TRY;
    remove(w->tmp);
    free_writer(w);
}
