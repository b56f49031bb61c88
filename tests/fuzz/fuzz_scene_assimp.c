/* Fuzz target: the scene formats other than glTF that evray reads through Assimp. The first byte
 * picks the file name extension Assimp is given as a hint (so each importer is reached whether
 * or not its format has a signature); the rest is the file. */
#include <stdint.h>
#include <stdlib.h>

#include "evray.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char *const hints[] = {"obj", "dae", "ply", "stl", "off", "fbx", "3ds", "x"};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    evr_scene *s = NULL;
    evr_error err;
    if (size < 2) return 0;
    if (evr_scene_load_memory(data + 1, size - 1, hints[data[0] % (sizeof hints / sizeof *hints)],
                              &s, &err) == EVR_OK) {
        free(evr_scene_describe(s));
        evr_scene_release(s);
    }
    return 0;
}
