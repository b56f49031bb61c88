/* Animated PNG (APNG) written frame by frame: each frame is encoded by evr_png_encode (libpng)
 * and its image data moved into the animation's chunks (IDAT for the first frame, fdAT for the
 * others, each after its fcTL), so the file is a plain PNG showing the first frame to a viewer
 * that knows no APNG, and the whole animation to a web browser. The frame count, unknown until
 * the end, is written into the acTL chunk by evr_apng_finish; until then the file has a
 * temporary name (".tmp" appended), so an APNG under the final name is always complete. */
#ifndef EVR_IO_APNG_H
#define EVR_IO_APNG_H

#include <stdint.h>
#include "evray.h"

typedef struct evr_apng evr_apng;

/* An APNG of width x height pixels of `channels` 8-bit samples (1 gray, 3 RGB), each frame
 * shown for delay_num / delay_den seconds (both at most 65535; delay_den > 0). Nothing is
 * written before the first frame. */
evr_status evr_apng_open(const char *path, int width, int height, int channels, unsigned delay_num,
                         unsigned delay_den, evr_apng **out, evr_error *err);
/* Appends a frame: width * height * channels bytes, rows top to bottom. */
evr_status evr_apng_add(evr_apng *a, const uint8_t *pixels, evr_error *err);
/* Frames added so far. */
int evr_apng_frames(const evr_apng *a);
/* Completes the file (frame count, IEND), renames it to its path, and releases a; a without a
 * frame writes no file. a is released whatever the result. */
evr_status evr_apng_finish(evr_apng *a, evr_error *err);
/* Removes the temporary file and releases a (NULL: nothing). */
void evr_apng_abort(evr_apng *a);

#endif
