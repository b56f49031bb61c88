/* Fuzz target: HDF5 event files (evray compare, plot and convert read them with
 * evr_events_read, which reads the file in a child process first: io/child_job.c; then the
 * ms_to_idx index with evr_h5_read_ms_to_idx). */
#include <stdint.h>
#include <stdlib.h>

#include "io/event_reader.h"
#include "fuzz_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("h5", data, size);
    evr_event *ev = NULL;
    uint64_t *idx = NULL;
    size_t n = 0;
    int w, h;
    evr_error err;
    if (!path) return 0;
    if (evr_events_read(path, &ev, &n, &w, &h, &err) != EVR_OK) return 0;
    free(ev);
    /* as the program reads it: of a file whose events were read (the read, in a child process
     * first, has vetted it for HDF5's crashes) */
    if (evr_h5_read_ms_to_idx(path, &idx, &n, &err) == EVR_OK) free(idx);
    return 0;
}
