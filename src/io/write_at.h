/* A whole range written at its place in a file: pwrite again after a short write or a signal. */
#ifndef EVR_IO_WRITE_AT_H
#define EVR_IO_WRITE_AT_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>
#include <unistd.h>

/* Writes src[0 .. len) at offset `at` of fd: 1, or 0 with errno set (EIO when nothing could be
 * written without an error). */
static inline int evr_write_at(int fd, const void *src, size_t len, uint64_t at)
{
    const unsigned char *p = src;
    while (len > 0) {
        const ssize_t wrote = pwrite(fd, p, len, (off_t)at);
        if (wrote <= 0) {
            if (wrote < 0 && errno == EINTR) continue;
            if (wrote == 0) errno = EIO;
            return 0;
        }
        p += wrote;
        len -= (size_t)wrote;
        at += (uint64_t)wrote;
    }
    return 1;
}

#endif
