/* Reading HDF5 files safely: what every HDF5 reader here (event files, labels.h5) shares. HDF5
 * 1.10 crashes on some corrupt files (a division by zero, reads past its buffers: found by
 * tests/fuzz/fuzz_events_h5.c), so a file is read once in a child process first
 * (io/child_job.c) and only a file the child read completely is read again in the caller's. */
#ifndef EVR_IO_H5_READ_H
#define EVR_IO_H5_READ_H

#include <hdf5.h>
#include <stddef.h>
#include "evray.h"
#include "io/child_job.h"

/* HDF5 would open a FIFO and block, or read a device: EVR_OK for a regular file only, else
 * EVR_ERR_IO and "cannot open PATH: why". */
evr_status evr_h5_regular(const char *path, evr_error *err);

/* "PATH: what (HDF5's most specific description of the error on its stack)"; clears the stack
 * and returns st. */
evr_status evr_h5_fail(evr_error *err, const char *what, const char *path, evr_status st);

/* An integer attribute of obj, or -1 when it is missing or not one number. */
int evr_h5_int_attr(hid_t obj, const char *name);

/* Runs fn(ctx) (a read of path that the caller then repeats) in a child process, at most 600 s
 * (EVR_IMPORT_SECONDS: a test's switch). EVR_OK when it read the file there; otherwise
 * EVR_ERR_FORMAT with its line, or "PATH: HDF5 crashed reading it ...", in err. */
evr_status evr_h5_isolated(evr_child_job fn, void *ctx, const char *path, evr_error *err);

#endif
