/* The CPU's worker threads: see workers.h. */
#include "cpu/workers.h"

#include <pthread.h>
#include <stdlib.h>
#include <unistd.h>

int evr_cpu_threads(int threads)
{
    if (threads > 0) return threads;
    long nc = sysconf(_SC_NPROCESSORS_ONLN);
    return nc > 0 ? (int)nc : 1;
}

int evr_run_workers(void *(*fn)(void *), void *arg, int threads)
{
    pthread_t *th = malloc(sizeof *th * (size_t)(threads > 1 ? threads : 1));
    int i, started = 0;
    if (!th) return 0;
    for (i = 1; i < threads; i++) {
        if (pthread_create(&th[i], NULL, fn, arg) != 0) break;
        started++;
    }
    fn(arg); /* the calling thread works too */
    for (i = 1; i <= started; i++) pthread_join(th[i], NULL);
    free(th);
    return 1;
}
