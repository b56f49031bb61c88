/* HDF5 files whose bytes depend only on what is written to them (events.h5, labels.h5). */
#ifndef EVR_IO_H5_FILE_H
#define EVR_IO_H5_FILE_H

#include <hdf5.h>

/* Creates (truncates) the file so that the same calls give the same bytes: no modification times
 * on any object (the root group's come from the file creation list), and the file format pinned
 * to HDF5 1.8's (readable by 1.8 and later), whatever library version writes it. Negative on
 * failure. Datasets and groups made in it need H5Pset_obj_track_times(.., 0) too. */
hid_t evr_h5_create_reproducible(const char *path);

#endif
