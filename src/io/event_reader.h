/* Event files: evr_events_read (declared in evray_experimental.h) reads a whole file of any
 * format; this adds the HDF5 index. */
#ifndef EVR_IO_EVENT_READER_H
#define EVR_IO_EVENT_READER_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"
#include "evray_experimental.h" /* evr_events_read */

/* Reads the ms_to_idx index of an HDF5 event file: (*idx)[i] is the index of the first event with
 * t >= i ms. *idx is malloc'ed (free() it). EVR_ERR_FORMAT when the file has no such index. */
evr_status evr_h5_read_ms_to_idx(const char *path, uint64_t **idx, size_t *n, evr_error *err);

/* Reads a whole file into memory (*data is malloc'ed and 0-terminated; free() it). */
evr_status evr_file_slurp(const char *path, char **data, size_t *size, evr_error *err);

#endif
