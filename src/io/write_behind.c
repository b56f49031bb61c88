#include "io/write_behind.h"
#include "io/write_at.h"

#include <errno.h>

static void *behind_main(void *arg)
{
    evr_write_behind *wb = arg;
    pthread_mutex_lock(&wb->mu);
    for (;;) {
        while (!wb->busy && !wb->stop) pthread_cond_wait(&wb->cv, &wb->mu);
        if (!wb->busy) break; /* stopped with nothing in flight */
        pthread_mutex_unlock(&wb->mu);
        const int err = evr_write_at(wb->fd, wb->src, wb->len, wb->at) ? 0 : errno;
        pthread_mutex_lock(&wb->mu);
        if (err && !wb->err) wb->err = err;
        wb->busy = 0;
        pthread_cond_broadcast(&wb->cv);
    }
    pthread_mutex_unlock(&wb->mu);
    return NULL;
}

int evr_write_behind_start(evr_write_behind *wb, int fd, const void *src, size_t len, uint64_t at)
{
    if (!wb->started) {
        if (pthread_mutex_init(&wb->mu, NULL) != 0) return -1;
        if (pthread_cond_init(&wb->cv, NULL) != 0) {
            pthread_mutex_destroy(&wb->mu);
            return -1;
        }
        wb->busy = wb->stop = wb->err = 0;
        if (pthread_create(&wb->thread, NULL, behind_main, wb) != 0) {
            pthread_cond_destroy(&wb->cv);
            pthread_mutex_destroy(&wb->mu);
            return -1;
        }
        wb->started = 1;
    }
    pthread_mutex_lock(&wb->mu);
    wb->fd = fd;
    wb->src = src;
    wb->len = len;
    wb->at = at;
    wb->busy = 1;
    pthread_cond_broadcast(&wb->cv);
    pthread_mutex_unlock(&wb->mu);
    return 0;
}

int evr_write_behind_wait(evr_write_behind *wb)
{
    if (!wb->started) return 0;
    pthread_mutex_lock(&wb->mu);
    while (wb->busy) pthread_cond_wait(&wb->cv, &wb->mu);
    const int err = wb->err;
    wb->err = 0;
    pthread_mutex_unlock(&wb->mu);
    return err;
}

void evr_write_behind_stop(evr_write_behind *wb)
{
    if (!wb->started) return;
    pthread_mutex_lock(&wb->mu);
    wb->stop = 1;
    pthread_cond_broadcast(&wb->cv);
    pthread_mutex_unlock(&wb->mu);
    pthread_join(wb->thread, NULL);
    pthread_cond_destroy(&wb->cv);
    pthread_mutex_destroy(&wb->mu);
    wb->started = 0;
}
