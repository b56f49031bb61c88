/* Fuzz target: glTF 2.0 scenes (a GLB, or a .gltf whose buffers and images are data: URIs) given
 * to evr_scene_load_memory, then described as `evray info` does. Any input must end in a scene
 * or one error line: never a crash, a leak, a hang or an allocation out of proportion to it. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "evray.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    evr_scene *s = NULL;
    evr_error err;
    const char *hint = size >= 4 && !memcmp(data, "glTF", 4) ? "glb" : "gltf";
    if (evr_scene_load_memory(data, size, hint, &s, &err) == EVR_OK) {
        free(evr_scene_describe(s));
        evr_scene_release(s);
    }
    return 0;
}
