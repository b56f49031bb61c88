/* For fuzz targets whose reader takes a path: the input written to a temporary file of this
 * process (one per extension, rewritten for every input) whose extension tells the reader the
 * format. */
#ifndef EVR_FUZZ_FILE_H
#define EVR_FUZZ_FILE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The path of a file holding data[0 .. size), or NULL when it cannot be written. */
static const char *fuzz_file(const char *ext, const uint8_t *data, size_t size)
{
    static char path[256];
    const char *dir = getenv("TMPDIR");
    FILE *f;
    snprintf(path, sizeof path, "%s/evray-fuzz-%ld.%s", dir && dir[0] ? dir : "/tmp",
             (long)getpid(), ext);
    f = fopen(path, "wb");
    if (!f) return NULL;
    if (size && fwrite(data, 1, size, f) != size) {
        fclose(f);
        return NULL;
    }
    return fclose(f) == 0 ? path : NULL;
}

#endif
