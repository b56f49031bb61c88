/* The pool of src/par_pool.h: every part of every job runs exactly once, jobs follow each other
 * without mixing (thousands of them, as the segments' passes do), and a pool of one thread or
 * none runs the parts on the caller. */
#include "check.h"
#include "par_pool.h"

#include <string.h>

typedef struct {
    int runs[64];
    int job;
    int wrong_job;
} job_state;

static int current_job;

static void part(void *ctx, int k)
{
    job_state *s = ctx;
    __atomic_add_fetch(&s->runs[k], 1, __ATOMIC_RELAXED);
    if (__atomic_load_n(&current_job, __ATOMIC_RELAXED) != s->job) __atomic_store_n(&s->wrong_job, 1, __ATOMIC_RELAXED);
}

static void run_jobs(evr_par_pool *p, int jobs)
{
    int bad = 0;
    for (int j = 0; j < jobs; j++) {
        job_state s;
        memset(&s, 0, sizeof s);
        s.job = j;
        __atomic_store_n(&current_job, j, __ATOMIC_RELAXED);
        const int parts = 1 + j % 64;
        evr_par_pool_run(p, parts, part, &s);
        for (int k = 0; k < 64; k++)
            if (s.runs[k] != (k < parts ? 1 : 0)) bad++;
        if (s.wrong_job) bad++;
    }
    CHECK(bad == 0);
}

int main(void)
{
    evr_par_pool *p = evr_par_pool_new(8);
    CHECK(p != NULL && evr_par_pool_threads(p) >= 1 && evr_par_pool_threads(p) <= 8);
    run_jobs(p, 5000);
    evr_par_pool_run(p, 0, part, NULL);   /* nothing to do */
    evr_par_pool_free(p);
    evr_par_pool *one = evr_par_pool_new(1);
    CHECK(one != NULL && evr_par_pool_threads(one) == 1);
    run_jobs(one, 100);
    evr_par_pool_free(one);
    run_jobs(NULL, 100);   /* no pool: the caller runs them */
    evr_par_pool_free(NULL);
    return check_report("test_par_pool");
}
