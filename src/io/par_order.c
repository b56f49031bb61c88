#include "io/par_order.h"

/* Pause instructions the caller spins for a part before it sleeps (about 0.1 ms on the GPU
 * machine's Xeon) */
#define ORDER_SPINS 2000

static inline void cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

int evr_par_order_init(evr_par_order *o)
{
    for (int k = 0; k < EVR_PAR_ORDER_MAX; k++) atomic_init(&o->done[k], 0);
    if (pthread_mutex_init(&o->mu, NULL) != 0) return -1;
    if (pthread_cond_init(&o->cv, NULL) != 0) {
        pthread_mutex_destroy(&o->mu);
        return -1;
    }
    return 0;
}

void evr_par_order_done(evr_par_order *o, int k)
{
    pthread_mutex_lock(&o->mu);
    atomic_store_explicit(&o->done[k], 1, memory_order_release); /* the spin reads it */
    pthread_cond_signal(&o->cv);
    pthread_mutex_unlock(&o->mu);
}

void evr_par_order_wait(evr_par_order *o, int k)
{
    for (int n = 0; n < ORDER_SPINS && !atomic_load_explicit(&o->done[k], memory_order_acquire);
         n++)
        cpu_relax();
    pthread_mutex_lock(&o->mu);
    while (!atomic_load_explicit(&o->done[k], memory_order_relaxed))
        pthread_cond_wait(&o->cv, &o->mu);
    pthread_mutex_unlock(&o->mu);
}

void evr_par_order_destroy(evr_par_order *o)
{
    pthread_cond_destroy(&o->cv);
    pthread_mutex_destroy(&o->mu);
}
