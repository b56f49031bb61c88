/* Minimal test support: CHECK records a failure and goes on; the program's exit code is the
 * number of failures, so ctest reports the test as failed when any check fails. */
#ifndef EVR_TESTS_CHECK_H
#define EVR_TESTS_CHECK_H

#include <math.h>
#include <stdio.h>

static int check_failures;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            check_failures++;                                                        \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                            \
    } while (0)
#define CHECK_NEAR(a, b, tol)                                                              \
    do {                                                                                   \
        double a_ = (double)(a), b_ = (double)(b);                                         \
        if (!(fabs(a_ - b_) <= (tol))) {                                                   \
            check_failures++;                                                              \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g vs %s = %.9g (tol %g)\n", \
                    __FILE__, __LINE__, #a, a_, #b, b_, (double)(tol));                    \
        }                                                                                  \
    } while (0)
#define CHECK_OK(call)                                                                      \
    do {                                                                                    \
        evr_error e_;                                                                       \
        e_.msg[0] = 0;                                                                      \
        evr_status s_ = (call);                                                             \
        (void)e_;                                                                           \
        if (s_ != EVR_OK) {                                                                 \
            check_failures++;                                                               \
            fprintf(stderr, "%s:%d: %s returned %d\n", __FILE__, __LINE__, #call, (int)s_); \
        }                                                                                   \
    } while (0)

static inline int check_report(const char *name)
{
    if (check_failures) fprintf(stderr, "%s: %d check(s) failed\n", name, check_failures);
    else printf("%s: all checks passed\n", name);
    return check_failures ? 1 : 0;
}

#endif
