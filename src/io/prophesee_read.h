/* Readers of Prophesee's files: EVT 2.0 and EVT 3.0 RAW (the encoding named by the "% evt" or
 * "% format" header line) and DAT files of CD events. */
#ifndef EVR_IO_PROPHESEE_READ_H
#define EVR_IO_PROPHESEE_READ_H

#include <stddef.h>
#include "evray.h"

/* data[0 .. size) is the whole file named path (for messages). Width and height from the header
 * (-1 when absent). Corrupt words, a truncated stream or an unknown encoding: EVR_ERR_FORMAT with
 * one line naming the file. */
evr_status evr_raw_parse(const char *path, const unsigned char *data, size_t size, evr_event **ev,
                         size_t *n, int *width, int *height, evr_error *err);
evr_status evr_dat_parse(const char *path, const unsigned char *data, size_t size, evr_event **ev,
                         size_t *n, int *width, int *height, evr_error *err);

#endif
