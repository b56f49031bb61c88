/* PNG encoding through libpng: to memory (for textures embedded in generated glTF) or to a file. */
#ifndef EVR_IO_PNG_H
#define EVR_IO_PNG_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"
#include "evray_experimental.h"

/* channels: 1 (gray), 3 (RGB) or 4 (RGBA); bit_depth 8 or 16 (16-bit samples in native order).
 * Rows are top to bottom. *out is malloc'ed; free() it. */
evr_status evr_png_encode(const void *pixels, int width, int height, int channels, int bit_depth,
                          void **out, size_t *out_size, evr_error *err);
/* evr_png_write (to a file) is declared in evray_experimental.h. */

#endif
