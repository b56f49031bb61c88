#include "compare.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Groups events by (pixel, polarity), keeping time order inside each group (counting sort). */
static int group(const evr_event *ev, size_t n, int width, size_t ngroups, size_t **start,
                 int64_t **times)
{
    size_t i;
    *start = calloc(ngroups + 1, sizeof **start);
    *times = malloc((n + 1) * sizeof **times);
    if (!*start || !*times) return 0;
    for (i = 0; i < n; i++)
        (*start)[((size_t)ev[i].y * (size_t)width + ev[i].x) * 2 + (ev[i].p ? 1 : 0) + 1]++;
    for (i = 1; i <= ngroups; i++) (*start)[i] += (*start)[i - 1];
    size_t *fill = malloc((ngroups + 1) * sizeof *fill);
    if (!fill) return 0;
    memcpy(fill, *start, (ngroups + 1) * sizeof *fill);
    for (i = 0; i < n; i++)
        (*times)[fill[((size_t)ev[i].y * (size_t)width + ev[i].x) * 2 + (ev[i].p ? 1 : 0)]++] =
            ev[i].t;
    free(fill);
    return 1;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Reference event a's tolerance in its group [a0, a1) of times t (evr_compare_events); tol_us
 * alone where tol_level is 0. */
static int64_t ref_tolerance(const int64_t *t, size_t a0, size_t a1, size_t a, int64_t tol_us,
                             double tol_level)
{
    int64_t gap = a > a0 ? t[a] - t[a - 1] : (a + 1 < a1 ? t[a + 1] - t[a] : 0);
    int64_t by_level = (int64_t)floor(tol_level * (double)gap);
    return by_level > tol_us ? by_level : tol_us;
}

evr_status evr_compare_events(const evr_event *ref, size_t nref, const evr_event *test,
                              size_t ntest, int64_t tol_us, double tol_level,
                              evr_compare_result *out, evr_error *err)
{
    size_t i, g;
    int width = 1, height = 1;
    memset(out, 0, sizeof *out);
    for (i = 0; i < nref; i++) {
        if (ref[i].x >= width) width = ref[i].x + 1;
        if (ref[i].y >= height) height = ref[i].y + 1;
        if (ref[i].p) out->ref_on++;
        else out->ref_off++;
    }
    for (i = 0; i < ntest; i++) {
        if (test[i].x >= width) width = test[i].x + 1;
        if (test[i].y >= height) height = test[i].y + 1;
        if (test[i].p) out->test_on++;
        else out->test_off++;
    }
    size_t npix = (size_t)width * (size_t)height, ngroups = npix * 2;
    size_t *sa = NULL, *sb = NULL;
    int64_t *ta = NULL, *tb = NULL,
            *dts = malloc((nref < ntest ? nref : ntest) * sizeof(int64_t) + 8);
    evr_status st = EVR_OK;
    if (!dts || !group(ref, nref, width, ngroups, &sa, &ta) ||
        !group(test, ntest, width, ngroups, &sb, &tb)) {
        snprintf(err->msg, sizeof err->msg, "out of memory comparing %zu and %zu events", nref,
                 ntest);
        st = EVR_ERR_NOMEM;
        goto done;
    }
    /* greedy matching in time order per group: optimal for equal tolerance windows */
    size_t matched = 0;
    for (g = 0; g < ngroups; g++) {
        size_t a = sa[g], ae = sa[g + 1], b = sb[g], be = sb[g + 1];
        while (a < ae && b < be) {
            int64_t d = tb[b] - ta[a];
            if (llabs(d) <= ref_tolerance(ta, sa[g], ae, a, tol_us, tol_level)) {
                dts[matched++] = llabs(d);
                a++;
                b++;
            } else if (d > 0) {
                a++;
            } else {
                b++;
            }
        }
    }
    out->matched = matched;
    out->precision = ntest ? (double)matched / (double)ntest : (nref ? 0.0 : 1.0);
    out->recall = nref ? (double)matched / (double)nref : (ntest ? 0.0 : 1.0);
    out->f1 = out->precision + out->recall > 0
                  ? 2 * out->precision * out->recall / (out->precision + out->recall)
                  : 0.0;
    out->count_ratio = nref ? (double)ntest / (double)nref : (ntest ? INFINITY : 1.0);
    if (matched) {
        qsort(dts, matched, sizeof *dts, cmp_i64);
        out->median_dt_us = (double)dts[matched / 2];
        out->p95_dt_us = (double)dts[(size_t)floor(0.95 * (double)(matched - 1))];
    }
    /* correlation of per-pixel counts (both polarities) */
    {
        double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
        for (i = 0; i < npix; i++) {
            double x = (double)(sa[2 * i + 2] - sa[2 * i]), y = (double)(sb[2 * i + 2] - sb[2 * i]);
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
        }
        double nn = (double)npix, vx = sxx - sx * sx / nn, vy = syy - sy * sy / nn;
        out->pixel_count_correlation =
            vx > 0 && vy > 0 ? (sxy - sx * sy / nn) / sqrt(vx * vy) : (vx == vy ? 1.0 : 0.0);
    }
done:
    free(sa);
    free(sb);
    free(ta);
    free(tb);
    free(dts);
    return st;
}
