/* Fuzz target: labels.h5 as evray plot and labels_compare read it (io/labels_read.c): its
 * times and sizes, then every frame (each read in a child process first: io/h5_read.h). */
#include <stdint.h>
#include <stdlib.h>

#include "evray_experimental.h"
#include "fuzz_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("h5", data, size);
    evr_labels_info info;
    evr_error err;
    float *depth, *flow;
    uint32_t *inst;
    size_t n, k;
    if (!path) return 0;
    if (evr_labels_read_info(path, &info, &err) != EVR_OK) return 0;
    n = (size_t)info.width * (size_t)info.height;
    if (n > ((size_t)1 << 22)) { /* a size a corrupt file claims: within libFuzzer's limit */
        evr_labels_info_free(&info);
        return 0;
    }
    depth = malloc(n * sizeof *depth);
    flow = malloc(2 * n * sizeof *flow);
    inst = malloc(n * sizeof *inst);
    /* a frame that fails does not stop the others: each is read on its own */
    for (k = 0; depth && flow && inst && k < info.frames && k < 8; k++)
        (void)evr_labels_read_frame(path, &info, k, depth, inst, flow, &err);
    free(depth);
    free(flow);
    free(inst);
    evr_labels_info_free(&info);
    return 0;
}
