/* Shared pieces of the HDF5 readers; see h5_read.h. */
#include "io/h5_read.h"
#include "io/file_read.h"

#include <stdio.h>
#include <stdlib.h>

evr_status evr_h5_regular(const char *path, evr_error *err)
{
    const char *why = NULL;
    if (evr_is_regular_file(path, &why)) return EVR_OK;
    snprintf(err->msg, sizeof err->msg, "cannot open %s: %s", path, why);
    return EVR_ERR_IO;
}

typedef struct {
    char desc[200];
    int got;
} walk_data;

static herr_t walk(unsigned i, const H5E_error2_t *e, void *data)
{
    walk_data *d = (walk_data *)data;
    (void)i;
    if (!d->got && e->desc && e->desc[0]) { /* keep the most specific one */
        snprintf(d->desc, sizeof d->desc, "%s", e->desc);
        d->got = 1;
    }
    return 0;
}

evr_status evr_h5_fail(evr_error *err, const char *what, const char *path, evr_status st)
{
    walk_data d;
    d.desc[0] = 0;
    d.got = 0;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk, &d);
    H5Eclear2(H5E_DEFAULT);
    if (d.got) snprintf(err->msg, sizeof err->msg, "%s: %s (%s)", path, what, d.desc);
    else snprintf(err->msg, sizeof err->msg, "%s: %s", path, what);
    return st;
}

int evr_h5_int_attr(hid_t obj, const char *name)
{
    int v = -1;
    if (H5Aexists(obj, name) > 0) {
        hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
        if (a >= 0) {
            hid_t space = H5Aget_space(a);
            if (space >= 0 && H5Sget_simple_extent_npoints(space) == 1 &&
                H5Aread(a, H5T_NATIVE_INT, &v) < 0)
                v = -1;
            if (space >= 0) H5Sclose(space);
            H5Aclose(a);
        }
    }
    return v;
}

/* The longest the child may read: 600 s, or EVR_IMPORT_SECONDS (a test's switch). */
static int child_seconds(void)
{
    const char *e = getenv("EVR_IMPORT_SECONDS");
    int v = e ? atoi(e) : 0;
    return v > 0 ? v : 600;
}

evr_status evr_h5_isolated(evr_child_job fn, void *ctx, const char *path, evr_error *err)
{
    char msg[sizeof err->msg];
    int r = evr_child_job_run(fn, ctx, "HDF5", child_seconds(), msg, sizeof msg);
    if (r == -1) snprintf(err->msg, sizeof err->msg, "%s: %s", path, msg);
    else if (r == 0) snprintf(err->msg, sizeof err->msg, "%s", msg);
    return r == -1 || r == 0 ? EVR_ERR_FORMAT : EVR_OK;
}
