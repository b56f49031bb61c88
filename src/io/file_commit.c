#include "io/file_commit.h"
#include "io/file_room.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
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

/* fsync of a file (opened for writing: room claimed past its end is freed first, io/file_room.h)
 * or folder by path; 0, or -1 with errno. */
static int sync_path(const char *path, int flags)
{
    int fd = open(path, flags | O_CLOEXEC), r, e;
    if (fd < 0) return -1;
    if ((flags & O_ACCMODE) == O_WRONLY) evr_file_unclaim_tail(fd);
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
    if (sync_path(tmp, O_WRONLY) != 0 || evr_folder_sync(tmp) != 0 || rename(tmp, path) != 0)
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

evr_status evr_file_salvage(FILE *f, const char *tmp, const char *path, uint64_t keep,
                            uint64_t stream_end, const unsigned char *tail, size_t tail_len,
                            const void *head, size_t head_len, const char *who, evr_error *err)
{
    struct stat sb;
    int fd;
    const char *what = "cannot reopen";
    /* closing writes out what stdio still holds; if that fails, the file is a shorter prefix */
    fclose(f);
    errno = 0;
    fd = open(tmp, O_WRONLY | O_CLOEXEC);
    if (fd >= 0) {
        what = "cannot read the size of";
        if (fstat(fd, &sb) == 0) {
            /* the file holds the stream's first size bytes (appends in order: a failed write
             * leaves a shorter prefix); the bytes it lacks must come from the tail in memory */
            uint64_t size = (uint64_t)sb.st_size, tail_at = stream_end - tail_len;
            what = "lost written events in";
            if (keep > stream_end || (size < keep && size < tail_at)) {
                errno = 0;
                goto fail;
            }
            what = "cannot complete";
            if (size < keep && pwrite(fd, tail + (size - tail_at), (size_t)(keep - size),
                                      (off_t)size) != (ssize_t)(keep - size))
                goto fail;
            if (ftruncate(fd, (off_t)keep) != 0) goto fail;
            if (head_len && pwrite(fd, head, head_len, 0) != (ssize_t)head_len) goto fail;
            if (fsync(fd) != 0) goto fail;
            if (close(fd) != 0) {
                fd = -1;
                goto fail;
            }
            fd = -1;
            if (evr_file_publish(tmp, path) == 0) return EVR_OK;
        }
    }
fail:
    snprintf(err->msg, sizeof err->msg, "%s: %s %s%s%s", who, what, tmp, errno ? ": " : "",
             errno ? strerror(errno) : "");
    if (fd >= 0) close(fd);
    remove(tmp);
    return EVR_ERR_IO;
}
