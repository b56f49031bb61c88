/* Fuzz target: the camera makers' formats read from memory: Prophesee EVT 2.0 / EVT 3.0 RAW and
 * DAT (prophesee_read.c), ROS1 bags of dvs_msgs/EventArray (rosbag_read.c). The first byte picks
 * the reader; the rest is the file. */
#include <stdint.h>
#include <stdlib.h>

#include "io/prophesee_read.h"
#include "io/rosbag_read.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    evr_event *ev = NULL;
    size_t n = 0;
    int w, h;
    evr_error err;
    evr_status st;
    if (size < 1) return 0;
    switch (data[0] % 3) {
    case 0: st = evr_raw_parse("in.raw", data + 1, size - 1, &ev, &n, &w, &h, &err); break;
    case 1: st = evr_dat_parse("in.dat", data + 1, size - 1, &ev, &n, &w, &h, &err); break;
    default: st = evr_rosbag_parse("in.bag", data + 1, size - 1, &ev, &n, &w, &h, &err); break;
    }
    if (st == EVR_OK) free(ev);
    return 0;
}
