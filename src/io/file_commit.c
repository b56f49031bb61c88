#include "io/file_commit.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* fsync of an open file or folder by path; 0, or -1 with errno. */
static int sync_path(const char *path, int flags)
{
    int fd = open(path, flags | O_CLOEXEC), r, e;
    if (fd < 0) return -1;
    r = fsync(fd);
    e = errno;
    close(fd);
    errno = e;
    return r;
}

/* The folder holding path ("." when it names none), into dir. */
static void folder_of(const char *path, char *dir, size_t n)
{
    const char *slash = strrchr(path, '/');
    if (!slash) snprintf(dir, n, ".");
    else if (slash == path) snprintf(dir, n, "/");
    else snprintf(dir, n, "%.*s", (int)(slash - path), path);
}

int evr_folder_sync(const char *path)
{
    char dir[4200];
    folder_of(path, dir, sizeof dir);
    /* a folder that refuses fsync (some file systems do) is as durable as it gets */
    if (sync_path(dir, O_RDONLY | O_DIRECTORY) != 0 && errno != EINVAL && errno != EROFS) return -1;
    return 0;
}

int evr_file_publish(const char *tmp, const char *path)
{
    if (sync_path(tmp, O_RDONLY) != 0 || evr_folder_sync(tmp) != 0 || rename(tmp, path) != 0)
        return -1;
    return evr_folder_sync(path);
}

evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st,
                           const char *who, evr_error *err)
{
    int closed = fclose(f) == 0;
    if (st == EVR_OK && !closed) {
        snprintf(err->msg, sizeof err->msg, "%s: cannot write %s: %s", who, tmp, strerror(errno));
        st = EVR_ERR_IO;
    }
    if (st == EVR_OK && evr_file_publish(tmp, path) != 0) {
        snprintf(err->msg, sizeof err->msg, "%s: cannot complete %s: %s", who, path,
                 strerror(errno));
        st = EVR_ERR_IO;
    }
    if (st != EVR_OK) remove(tmp);
    return st;
}
