#include "io/file_commit.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

char *evr_file_tmp_name(const char *path)
{
    size_t len = strlen(path);
    char *tmp = malloc(len + 5);
    if (tmp) {
        memcpy(tmp, path, len);
        memcpy(tmp + len, ".tmp", 5);
    }
    return tmp;
}

FILE *evr_file_create(const char *tmp, const char *who, evr_error *err)
{
    FILE *f = fopen(tmp, "wb");
    if (!f)
        snprintf(err->msg, sizeof err->msg, "%s: cannot create %s: %s", who, tmp, strerror(errno));
    return f;
}

void evr_file_discard(FILE *f, const char *tmp)
{
    fclose(f);
    remove(tmp);
}

evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st,
                           const char *who, evr_error *err)
{
    int closed = fclose(f) == 0;
    if (st == EVR_OK && !closed) {
        snprintf(err->msg, sizeof err->msg, "%s: cannot write %s", who, tmp);
        st = EVR_ERR_IO;
    }
    if (st == EVR_OK && rename(tmp, path) != 0) {
        snprintf(err->msg, sizeof err->msg, "%s: cannot rename %s to %s", who, tmp, path);
        st = EVR_ERR_IO;
    }
    if (st != EVR_OK) remove(tmp);
    return st;
}
