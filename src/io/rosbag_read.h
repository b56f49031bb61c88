/* Reader of ROS1 bag files (format 2.0): the dvs_msgs/EventArray messages of the first connection
 * of that type (one topic, so a stereo recording gives its first camera), in file order. */
#ifndef EVR_IO_ROSBAG_READ_H
#define EVR_IO_ROSBAG_READ_H

#include <stddef.h>
#include "evray.h"

/* data[0 .. size) is the whole file named path (for messages). Width and height from the first
 * message (-1 when none). Chunks may be compressed (none, bz2, lz4: each uncompressed on its
 * own, at most 1 GB). Wrong magic, a truncated record, a corrupt or unknown chunk compression or
 * no EventArray connection: EVR_ERR_FORMAT with one line naming the file. Timestamps are rounded
 * down to whole microseconds. */
evr_status evr_rosbag_parse(const char *path, const unsigned char *data, size_t size,
                            evr_event **ev, size_t *n, int *width, int *height, evr_error *err);

#endif
