/* Fuzz target: the text (t x y p per line) and NumPy (.npy, structured or 2-D) event files. The
 * first byte picks the format; the rest is the file. */
#include <stdint.h>
#include <stdlib.h>

#include "io/event_reader.h"
#include "fuzz_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path;
    evr_event *ev = NULL;
    size_t n = 0;
    int w, h;
    evr_error err;
    if (size < 1) return 0;
    if (!(path = fuzz_file(data[0] & 1 ? "npy" : "txt", data + 1, size - 1))) return 0;
    if (evr_events_read(path, &ev, &n, &w, &h, &err) == EVR_OK) free(ev);
    return 0;
}
