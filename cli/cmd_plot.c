/* evray plot: the event rate over time (ON and OFF per bin) and an events-per-pixel heat map. */
#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int plot_usage(void)
{
    puts(
        "usage: evray plot EVENTS [-o rate.png] [--bin-ms MS] [--heatmap heat.png] [--size WxH]\n\n"
        "Reads an event file evray writes (.h5, .txt, .npy, Prophesee .raw and .dat) and draws:\n"
        "  -o FILE         the number of ON and OFF events per time bin, two lines against time\n"
        "                  (default rate.png); an asynchronous simulator gives a continuous curve,\n"
        "                  a frame-based one spikes at every frame\n"
        "  --bin-ms MS     the bin width in milliseconds (default 1)\n"
        "  --heatmap FILE  also the events per pixel, log colour map with a colour bar\n"
        "  --size WxH      the rate plot's size in pixels (default 1000x420)");
    return 0;
}

int cmd_plot(int argc, char **argv)
{
    const char *in = NULL, *out = "rate.png", *heat = NULL, *v;
    double bin_ms = 1.0;
    int pw = 1000, ph = 420, i, width = -1, height = -1, rc = 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return plot_usage();
        if (!strcmp(a, "-o")) {
            if (!(out = opt_value(argc, argv, &i, "-o"))) return 2;
        } else if (opt_is(a, "--out")) {
            if (!(out = opt_value(argc, argv, &i, "--out"))) return 2;
        } else if (opt_is(a, "--heatmap")) {
            if (!(heat = opt_value(argc, argv, &i, "--heatmap"))) return 2;
        } else if (opt_is(a, "--bin-ms")) {
            if (!(v = opt_value(argc, argv, &i, "--bin-ms")) || !opt_double("--bin-ms", v, &bin_ms))
                return 2;
            if (!(bin_ms >= 0.001 && bin_ms <= 1e7)) {
                cli_error("--bin-ms must be between 0.001 and 1e7 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--size")) {
            if (!(v = opt_value(argc, argv, &i, "--size")) || !opt_size("--size", v, &pw, &ph))
                return 2;
            if (pw < 200 || ph < 150 || pw > 8000 || ph > 8000) {
                cli_error("--size must be between 200x150 and 8000x8000 (got %s)", v);
                return 2;
            }
        } else if (a[0] == '-' && a[1]) {
            cli_error("plot: unknown option '%s'", a);
            return 2;
        } else if (!in) in = a;
        else {
            cli_error("plot: unexpected argument '%s'", a);
            return 2;
        }
    }
    if (!in) {
        cli_error("plot: no event file given (evray plot EVENTS [-o rate.png])");
        return 2;
    }

    evr_error err = {{0}};
    evr_event *ev = NULL;
    size_t n = 0, k;
    double *x = NULL, *on = NULL, *off = NULL;
    uint32_t *counts = NULL;
    if (evr_events_read(in, &ev, &n, &width, &height, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 1;
    }
    if (n == 0) {
        cli_error("%s: no events to plot", in);
        free(ev);
        return 1;
    }
    int64_t t0 = ev[0].t, t1 = ev[0].t;
    for (k = 1; k < n; k++) {
        if (ev[k].t < t0) t0 = ev[k].t;
        if (ev[k].t > t1) t1 = ev[k].t;
    }
    double bin_us = bin_ms * 1000.0, span = (double)(t1 - t0);
    if (span / bin_us > 5e6) {
        cli_error("plot: %.0f bins of %g ms; choose a larger --bin-ms", span / bin_us, bin_ms);
        free(ev);
        return 2;
    }
    /* bins aligned to multiples of the bin width from t = 0 so that runs plot on one grid */
    int64_t first = (int64_t)floor((double)t0 / bin_us);
    size_t nb = (size_t)((int64_t)floor((double)t1 / bin_us) - first + 1);
    x = malloc(nb * sizeof *x);
    on = calloc(nb, sizeof *on);
    off = calloc(nb, sizeof *off);
    if (!x || !on || !off) {
        cli_error("out of memory");
        goto done;
    }
    for (k = 0; k < n; k++) {
        size_t b = (size_t)((int64_t)floor((double)ev[k].t / bin_us) - first);
        if (b >= nb) b = nb - 1;
        if (ev[k].p) on[b] += 1.0;
        else off[b] += 1.0;
    }
    for (k = 0; k < nb; k++) x[k] = ((double)(first + (int64_t)k) + 0.5) * bin_us * 1e-6;
    {
        char title[160], ylabel[64];
        evr_plot_series s[2];
        evr_plot_spec spec;
        memset(s, 0, sizeof s);
        memset(&spec, 0, sizeof spec);
        s[0].x = x;
        s[0].y = on;
        s[0].n = nb;
        s[0].color[2] = 255;
        s[0].label = "ON";
        s[1].x = x;
        s[1].y = off;
        s[1].n = nb;
        s[1].color[0] = 220;
        s[1].label = "OFF";
        snprintf(title, sizeof title, "events per %g ms bin (%zu events)", bin_ms, n);
        snprintf(ylabel, sizeof ylabel, "events per %g ms", bin_ms);
        spec.width = pw;
        spec.height = ph;
        spec.title = title;
        spec.xlabel = "time (s)";
        spec.ylabel = ylabel;
        spec.y_from_zero = 1;
        if (evr_plot_lines_png(out, &spec, s, 2, &err) != EVR_OK) {
            cli_error("%s", err.msg);
            goto done;
        }
        printf("%s: %zu events, %zu bins of %g ms\n", out, n, nb, bin_ms);
    }
    if (heat) {
        int mx = 0, my = 0, hw, hh;
        char title[160];
        for (k = 0; k < n; k++) {
            if (ev[k].x > mx) mx = ev[k].x;
            if (ev[k].y > my) my = ev[k].y;
        }
        if (width < 1 || width <= mx) width = mx + 1;
        if (height < 1 || height <= my) height = my + 1;
        counts = calloc((size_t)width * (size_t)height, sizeof *counts);
        if (!counts) {
            cli_error("out of memory");
            goto done;
        }
        for (k = 0; k < n; k++) counts[(size_t)ev[k].y * (size_t)width + ev[k].x]++;
        snprintf(title, sizeof title, "events per pixel (%dx%d, log scale)", width, height);
        if (evr_plot_heatmap_png(heat, counts, width, height, title, &hw, &hh, &err) != EVR_OK) {
            cli_error("%s", err.msg);
            goto done;
        }
        printf("%s: %dx%d pixels, heat map %dx%d\n", heat, width, height, hw, hh);
    }
    rc = 0;
done:
    free(counts);
    free(x);
    free(on);
    free(off);
    free(ev);
    return rc;
}
