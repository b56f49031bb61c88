/* Reads a whole event file written by evray (or in the same layouts by other tools), picking the
 * format by the file name's extension:
 *   .h5 / .hdf5  events/x, events/y, events/t, events/p (any integer types); width and height
 *                from the file attributes when present. Timestamps are returned as stored (DSEC
 *                files keep an offset in t_offset; ours is 0).
 *   .txt         lines "t x y p", t in seconds (decimal); empty lines and lines starting with '#'
 *                are skipped.
 *   .npy         a 1-D structured array with integer fields t (us), x, y, p in any order and of
 *                any integer width, either byte order.
 * Polarity is returned as 1 (p > 0) or 0 (p <= 0, so -1/1 files read too). Events keep the file's
 * order. *ev is malloc'ed (free() it; NULL when *n is 0). width/height are set to -1 when the
 * format does not store them; either pointer may be NULL. */
#ifndef EVR_IO_EVENT_READER_H
#define EVR_IO_EVENT_READER_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"

evr_status evr_events_read(const char *path, evr_event **ev, size_t *n, int *width, int *height, evr_error *err);

/* Reads the ms_to_idx index of an HDF5 event file: (*idx)[i] is the index of the first event with
 * t >= i ms. *idx is malloc'ed (free() it). EVR_ERR_FORMAT when the file has no such index. */
evr_status evr_h5_read_ms_to_idx(const char *path, uint64_t **idx, size_t *n, evr_error *err);

#endif
