/* Reader of iniVation AEDAT 4.0 files (io/aedat4.h; DV and dv-processing recordings, evray's
 * events.aedat4): the events of the first event stream the header names (typeIdentifier EVTS),
 * in file order; other streams (frames, IMU, triggers) are skipped. */
#ifndef EVR_IO_AEDAT4_READ_H
#define EVR_IO_AEDAT4_READ_H

#include <stddef.h>
#include "evray.h"

/* data[0 .. size) is the whole file named path (for messages). Width and height from the event
 * stream's sizeX and sizeY (-1 when absent). Packets compressed by LZ4, ZSTD or not at all are
 * read up to the data table (or the end of the file when there is none). Another AEDAT version,
 * a corrupt header, FlatBuffer or frame, a truncated packet, no event stream: EVR_ERR_FORMAT with
 * one line naming the file. */
evr_status evr_aedat4_parse(const char *path, const unsigned char *data, size_t size,
                            evr_event **ev, size_t *n, int *width, int *height, evr_error *err);

#endif
