/* Accuracy of one event stream against a reference: one-to-one matching of events at the same
 * pixel with the same polarity within a time tolerance, in time order. */
#ifndef EVR_COMPARE_H
#define EVR_COMPARE_H

#include <stddef.h>
#include "evray.h"

typedef struct {
    uint64_t ref_on, ref_off, test_on, test_off;
    uint64_t matched;
    double precision, recall, f1;        /* matched / test, matched / ref, harmonic mean */
    double count_ratio;                  /* test events / reference events */
    double median_dt_us, p95_dt_us;      /* |t_test - t_ref| of matched pairs */
    double pixel_count_correlation;      /* Pearson correlation of per-pixel event counts */
} evr_compare_result;

/* Both streams sorted by time. tol_us >= 0. */
evr_status evr_compare_events(const evr_event *ref, size_t nref, const evr_event *test, size_t ntest, int64_t tol_us,
                              evr_compare_result *out, evr_error *err);

#endif
