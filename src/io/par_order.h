/* Parts of a job done on a pool's threads (par_pool.h) and taken in order by the calling thread,
 * which writes each to a file as soon as it is ready (writes to one file go one at a time in the
 * kernel, so the caller writes while the pool packs). A part's thread marks it done; the caller
 * waits for part k, spinning briefly before it sleeps: where packing is the bottleneck, a sleep and
 * a wake-up per part cost the AEDAT 4.0 writer a tenth of its busy time (docs/benchmarks.md). */
#ifndef EVR_IO_PAR_ORDER_H
#define EVR_IO_PAR_ORDER_H

#include <pthread.h>
#include <stdatomic.h>

#define EVR_PAR_ORDER_MAX 64 /* parts of one job at most */

typedef struct {
    atomic_int done[EVR_PAR_ORDER_MAX];
    pthread_mutex_t mu;
    pthread_cond_t cv;
} evr_par_order;

/* No part done yet; 0, or -1 when the mutex or condition cannot be made. */
int evr_par_order_init(evr_par_order *o);
/* Part k is done (from the thread that did it). */
void evr_par_order_done(evr_par_order *o, int k);
/* Returns once part k is done. */
void evr_par_order_wait(evr_par_order *o, int k);
void evr_par_order_destroy(evr_par_order *o);

#endif
