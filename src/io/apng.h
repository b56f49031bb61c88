/* Animated PNG (APNG) written frame by frame: each frame is encoded by evr_png_encode (libpng)
 * and its image data moved into the animation's chunks (IDAT for the first frame, fdAT for the
 * others, each after its fcTL), so the file is a plain PNG showing the first frame to a viewer
 * that knows no APNG, and the whole animation to a web browser. The frame count, unknown until
 * the end, is written into the acTL chunk by evr_apng_finish; until then the file has a
 * temporary name (".tmp" appended), so an APNG under the final name is always complete.
 *
 * Why an animated PNG for the run's preview video rather than MP4 through libavcodec: no new
 * dependency (libpng and zlib are there already); lossless, which matters because an event is
 * one saturated pixel and H.264's 4:2:0 chroma and quantization would smear it into a pale
 * blob; deterministic bytes, so tests compare every frame exactly; and it plays in any web
 * browser. The cost is size: about 4 to 75 KB a frame at 346x260 (more for textured scenes). */
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
