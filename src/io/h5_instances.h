/* The /instances table of labels.h5 and events.h5: compound [M] of id (uint32, 1 + the
 * instance), node (its node's path, '/' between names) and mesh (its mesh's name), so that the
 * ids of /instance and events/id can be named. */
#ifndef EVR_IO_H5_INSTANCES_H
#define EVR_IO_H5_INSTANCES_H

#include <hdf5.h>

/* Writes /instances under loc (node[i], mesh[i] for id i + 1); negative on failure (HDF5's
 * error stack says why). */
herr_t evr_h5_write_instances(hid_t loc, const char *const *node, const char *const *mesh, int n);

#endif
