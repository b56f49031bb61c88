#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int sorted(const evr_event *e, size_t n)
{
    size_t i;
    for (i = 1; i < n; i++)
        if (e[i].t < e[i - 1].t) return 0;
    return 1;
}

int cmd_compare(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL}, *v;
    double tol = 100.0, tol_level = 0.0;
    int json = 0, np = 0, i;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            puts(
                "usage: evray compare REF TEST [--tol-us 100] [--tol-level F] [--json]\n\n"
                "Matches TEST's events one-to-one against REF's (same pixel, same polarity, |dt| <= tolerance,\n"
                "in time order) and prints event counts and their ratio, precision, recall, F1, the median\n"
                "and 95th percentile |dt| of matches and the correlation of per-pixel event counts.\n"
                "Reads any format evray writes (.h5, .txt, .npy, Prophesee .raw EVT 2.0/3.0 and .dat).\n\n"
                "  --tol-level F  (0 to 0.5) a REF event also matches within F times the time since the\n"
                "                 previous REF event of its pixel and polarity: the timing error that a\n"
                "                 log-intensity error of F thresholds makes where the pixel changes slowly");
            return 0;
        }
        if (!strcmp(a, "--json")) json = 1;
        else if (opt_is(a, "--tol-us")) {
            if (!(v = opt_value(argc, argv, &i, "--tol-us")) || !opt_double("--tol-us", v, &tol))
                return 2;
            if (tol < 0) {
                cli_error("--tol-us must be >= 0");
                return 2;
            }
        } else if (opt_is(a, "--tol-level")) {
            if (!(v = opt_value(argc, argv, &i, "--tol-level")) ||
                !opt_double("--tol-level", v, &tol_level))
                return 2;
            if (!(tol_level >= 0.0 && tol_level <= 0.5)) {
                cli_error("--tol-level must be between 0 and 0.5");
                return 2;
            }
        } else if (a[0] == '-' && a[1]) {
            cli_error("compare: unknown option '%s'", a);
            return 2;
        } else if (np < 2) paths[np++] = a;
        else {
            cli_error("compare takes two event files");
            return 2;
        }
    }
    if (np != 2) {
        cli_error("compare needs two event files (evray compare REF TEST)");
        return 2;
    }
    evr_event *ev[2] = {NULL, NULL};
    size_t n[2] = {0, 0};
    evr_error err = {{0}};
    for (i = 0; i < 2; i++) {
        if (evr_events_read(paths[i], &ev[i], &n[i], NULL, NULL, &err) != EVR_OK) {
            cli_error("%s", err.msg);
            free(ev[0]);
            return 1;
        }
        if (!sorted(ev[i], n[i])) {
            cli_error("%s: events are not in time order", paths[i]);
            free(ev[0]);
            free(ev[1]);
            return 1;
        }
    }
    evr_compare_result r;
    evr_status st = evr_compare_events(ev[0], n[0], ev[1], n[1], (int64_t)tol, tol_level, &r, &err);
    free(ev[0]);
    free(ev[1]);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        return 1;
    }
    if (json) {
        printf(
            "{\"tol_us\": %.17g, \"tol_level\": %.17g, \"ref_on\": %llu, \"ref_off\": %llu, \"test_on\": %llu, \"test_off\": %llu, "
            "\"count_ratio\": %.6f, \"matched\": %llu, \"precision\": %.6f, \"recall\": %.6f, \"f1\": %.6f, "
            "\"median_dt_us\": %.1f, \"p95_dt_us\": %.1f, \"pixel_count_correlation\": %.6f}\n",
            tol, tol_level, (unsigned long long)r.ref_on, (unsigned long long)r.ref_off,
            (unsigned long long)r.test_on, (unsigned long long)r.test_off, r.count_ratio,
            (unsigned long long)r.matched, r.precision, r.recall, r.f1, r.median_dt_us, r.p95_dt_us,
            r.pixel_count_correlation);
    } else {
        printf("reference: %llu events (%llu ON, %llu OFF)\n",
               (unsigned long long)(r.ref_on + r.ref_off), (unsigned long long)r.ref_on,
               (unsigned long long)r.ref_off);
        printf("test:      %llu events (%llu ON, %llu OFF), ratio %.4f\n",
               (unsigned long long)(r.test_on + r.test_off), (unsigned long long)r.test_on,
               (unsigned long long)r.test_off, r.count_ratio);
        printf("matched within %.0f us", tol);
        if (tol_level > 0.0) printf(" or %g of the reference's gap", tol_level);
        printf(": %llu; precision %.4f, recall %.4f, F1 %.4f\n", (unsigned long long)r.matched,
               r.precision, r.recall, r.f1);
        printf("|dt| of matches: median %.0f us, 95th percentile %.0f us\n", r.median_dt_us,
               r.p95_dt_us);
        printf("per-pixel event count correlation: %.4f\n", r.pixel_count_correlation);
    }
    return 0;
}
