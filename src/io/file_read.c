#include "io/file_read.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t m)
{
    if (S_ISDIR(m)) return "it is a folder, not a file";
    if (S_ISFIFO(m)) return "it is a FIFO, not a regular file";
    if (S_ISCHR(m)) return "it is a character device, not a regular file";
    if (S_ISBLK(m)) return "it is a block device, not a regular file";
    if (S_ISSOCK(m)) return "it is a socket, not a regular file";
    return "it is not a regular file";
}

int evr_is_regular_file(const char *path, const char **why)
{
    struct stat sb;
    if (stat(path, &sb) != 0) {
        *why = strerror(errno);
        return 0;
    }
    if (!S_ISREG(sb.st_mode)) {
        *why = kind_of(sb.st_mode);
        return 0;
    }
    return 1;
}

FILE *evr_fopen_regular(const char *path, const char **why)
{
    struct stat sb;
    FILE *f;
    /* O_NONBLOCK: opening a FIFO with no writer returns at once instead of waiting for one */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC), flags;
    if (fd < 0) {
        *why = strerror(errno);
        return NULL;
    }
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        *why = fstat(fd, &sb) != 0 ? strerror(errno) : kind_of(sb.st_mode);
        close(fd);
        return NULL;
    }
    flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0 || !(f = fdopen(fd, "rb"))) {
        *why = strerror(errno);
        close(fd);
        return NULL;
    }
    return f;
}
