/* Which files a scene may make evray read. A scene file names other files (glTF buffers and
 * images, an OBJ's material library and textures, ...); scenes come from anywhere, so by default
 * only files inside the scene file's own folder are read: the name is resolved (symbolic links
 * and '..' included) and must stay under the folder. evr_load_options.allow_external lifts that.
 * Either way only regular files are read: a FIFO would block for ever and /dev/zero never ends. */
/* realpath */
#define _XOPEN_SOURCE 700
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/file_read.h"
#include "scene/import_internal.h"

/* 1 when the real path of `path` lies under the real path of folder `dir` ("" the current one). */
static int inside(const char *dir, const char *path)
{
    char *rd = realpath(dir[0] ? dir : ".", NULL), *rp = realpath(path, NULL);
    size_t n;
    int in = 0;
    if (rd && rp) {
        n = strlen(rd);
        /* "/" as the folder: everything is inside it */
        in = !strncmp(rd, rp, n) && (rp[n] == '/' || (n == 1 && rd[0] == '/'));
    }
    free(rd);
    free(rp);
    return in;
}

evr_status evr_import_file_check(const char *dir, const char *path, int allow_external,
                                 const char *what, evr_error *err)
{
    const char *why = NULL;
    if (!evr_is_regular_file(path, &why))
        return evr_import_fail(err, EVR_ERR_IO, "%s '%s': %s", what, path, why);
    if (allow_external) return EVR_OK;
    if (!dir)
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "%s '%s': a scene in memory reads no files (allow external files "
                               "to read it)",
                               what, path);
    if (!inside(dir, path))
        return evr_import_fail(err, EVR_ERR_FORMAT,
                               "%s '%s' is outside the scene's folder (--allow-external-files "
                               "reads it)",
                               what, path);
    return EVR_OK;
}
