/* Wall-clock seconds on the host (monotonic), for the run's time accounting. */
#ifndef EVR_HOST_CLOCK_H
#define EVR_HOST_CLOCK_H

#include <time.h>

static inline double evr_host_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
