/* The pool of src/par_pool.h: every part of every job runs exactly once, on a thread numbered
 * below the pool's count, jobs follow each other without mixing (thousands of them, as the
 * segments' passes do), in one call or started and waited for, and a pool of one thread or none
 * runs the parts on the caller. */
#include "check.h"
#include "par_pool.h"

#include <string.h>

typedef struct {
    int runs[64];
    int job;
    int wrong_job;
    int threads, wrong_thread;
} job_state;

static int current_job;

static void part(void *ctx, int k, int thread)
{
    job_state *s = ctx;
    if (thread < 0 || thread >= s->threads) __atomic_store_n(&s->wrong_thread, 1, __ATOMIC_RELAXED);
    __atomic_add_fetch(&s->runs[k], 1, __ATOMIC_RELAXED);
    if (__atomic_load_n(&current_job, __ATOMIC_RELAXED) != s->job)
        __atomic_store_n(&s->wrong_job, 1, __ATOMIC_RELAXED);
}

/* split: every other job started, then waited for, instead of run in one call */
static void run_jobs(evr_par_pool *p, int jobs, int split)
{
    int bad = 0;
    for (int j = 0; j < jobs; j++) {
        job_state s;
        memset(&s, 0, sizeof s);
        s.job = j;
        s.threads = evr_par_pool_threads(p);
        __atomic_store_n(&current_job, j, __ATOMIC_RELAXED);
        const int parts = 1 + j % 64;
        if (split && j % 2 && p) {
            evr_par_pool_start(p, parts, part, &s);
            evr_par_pool_wait(p);
        } else {
            evr_par_pool_run(p, parts, part, &s);
        }
        for (int k = 0; k < 64; k++)
            if (s.runs[k] != (k < parts ? 1 : 0)) bad++;
        if (s.wrong_job || s.wrong_thread) bad++;
    }
    CHECK(bad == 0);
}

int main(void)
{
    evr_par_pool *p = evr_par_pool_new(8);
    CHECK(p != NULL && evr_par_pool_threads(p) >= 1 && evr_par_pool_threads(p) <= 8);
    run_jobs(p, 5000, 0);
    run_jobs(p, 5000, 1);
    evr_par_pool_run(p, 0, part, NULL); /* nothing to do */
    evr_par_pool_free(p);
    evr_par_pool *one = evr_par_pool_new(1);
    CHECK(one != NULL && evr_par_pool_threads(one) == 1);
    run_jobs(one, 100, 1);
    evr_par_pool_free(one);
    run_jobs(NULL, 100, 0); /* no pool: the caller runs them */
    evr_par_pool_free(NULL);
    CHECK(evr_par_threads(16) >= 1 && evr_par_threads(16) <= 16 && evr_par_threads(1) == 1);
    return check_report("test_par_pool");
}
