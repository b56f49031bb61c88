/* Room on the file system claimed ahead of a library's writes: see file_room.h. */
#define _GNU_SOURCE /* fallocate */
#include "io/file_room.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

int evr_file_claim(int fd, uint64_t from, uint64_t len)
{
#ifdef FALLOC_FL_KEEP_SIZE
    if (len == 0) return 0;
    while (fallocate(fd, FALLOC_FL_KEEP_SIZE, (off_t)from, (off_t)len) != 0) {
        if (errno == EINTR) continue;
        if (errno == ENOSPC || errno == EFBIG || errno == EIO || errno == EDQUOT) return -1;
        return 0; /* EOPNOTSUPP, ENOSYS, ...: this file system claims no room ahead */
    }
    return 0;
#else
    (void)fd, (void)from, (void)len;
    return 0;
#endif
}

void evr_file_unclaim_tail(int fd)
{
    struct stat sb;
    const int r = fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) ? ftruncate(fd, sb.st_size) : 0;
    (void)r;
}
