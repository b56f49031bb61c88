/* One range of a file's bytes at a time written by a thread of its own while the caller prepares
 * the next (checks, lays out and packs the next events): writes to one file go one at a time in
 * the kernel, so the caller's own work then stays off the file's critical path. The bytes must
 * stay in place, unchanged, until evr_write_behind_wait returns. */
#ifndef EVR_IO_WRITE_BEHIND_H
#define EVR_IO_WRITE_BEHIND_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

typedef struct {
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int started, stop, busy;
    int fd;
    const unsigned char *src;
    size_t len;
    uint64_t at;
    int err; /* the errno of a failed write, until a wait returns it */
} evr_write_behind;

/* Starts writing src[0 .. len) at offset `at` of fd (the thread starts at the first range; a
 * zeroed evr_write_behind is ready). The previous range must have been waited for. 0, or -1 when
 * no thread can run: the caller then writes the bytes itself. */
int evr_write_behind_start(evr_write_behind *wb, int fd, const void *src, size_t len, uint64_t at);

/* Returns once the range started last is written (at once when none is): 0, or the errno of a
 * failed write. */
int evr_write_behind_wait(evr_write_behind *wb);

/* Waits for the range in flight and ends the thread (a zeroed one is fine). */
void evr_write_behind_stop(evr_write_behind *wb);

#endif
