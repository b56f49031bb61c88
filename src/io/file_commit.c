#include "io/file_commit.h"

evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st, const char *who, evr_error *err)
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
