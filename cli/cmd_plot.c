/* evray plot: the event rate over time (ON and OFF per bin), an events-per-pixel heat map, and a
 * run's labels.h5 at one label frame: the optical flow in the colour wheel and the depth. */
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
        "usage: evray plot EVENTS [-o rate.png] [--bin-ms MS] [--heatmap heat.png] [--size WxH]\n"
        "                  [--flow flow.png] [--depth depth.png] [--time S] [--labels FILE]\n"
        "                  [--flow-max PX_S]\n"
        "       evray plot --labels labels.h5 [--flow flow.png] [--depth depth.png] [--time S]\n\n"
        "Reads an event file evray writes (.h5, .txt, .npy, Prophesee .raw and .dat) and draws:\n"
        "  -o FILE         the number of ON and OFF events per time bin, two lines against time\n"
        "                  (default rate.png); an asynchronous simulator gives a continuous curve,\n"
        "                  a frame-based one spikes at every frame\n"
        "  --bin-ms MS     the bin width in milliseconds (default 1)\n"
        "  --heatmap FILE  also the events per pixel, log colour map with a colour bar\n"
        "  --size WxH      the rate plot's size in pixels (default 1000x420)\n"
        "and from a run's ground truth (labels.h5, --labels-fps) at the label frame nearest --time:\n"
        "  --flow FILE     the optical flow in the standard colour wheel (hue: direction, +x red;\n"
        "                  saturation: speed, white still; black: no surface), the wheel beside it\n"
        "  --depth FILE    the depth, near white, far black (heat map colours over the frame's\n"
        "                  range); teal: no surface\n"
        "  --time S        scene time in seconds (default: the middle frame)\n"
        "  --labels FILE   the labels file (default: labels.h5 beside EVENTS)\n"
        "  --flow-max PX_S the speed at the wheel's edge (default: the frame's 99th percentile)");
    return 0;
}

/* Reads labels.h5's frame nearest t (NaN: the middle one) and draws its flow and depth. */
static int plot_labels(const char *labels, double t, double flow_max, const char *flow_png,
                       const char *depth_png)
{
    evr_labels_info info;
    evr_error err = {{0}};
    size_t k, n, i, none = 0;
    float *depth = NULL, *flow = NULL;
    uint32_t *inst = NULL;
    int rc = 1, scale = 0;
    char title[160], at[160];
    if (evr_labels_read_info(labels, &info, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 1;
    }
    if (isnan(t)) k = (info.frames - 1) / 2;
    else if (evr_labels_nearest_frame(&info, t, &k, &err) != EVR_OK) {
        cli_error("%s: %s", labels, err.msg);
        goto done;
    }
    n = (size_t)info.width * (size_t)info.height;
    depth = malloc(n * sizeof *depth);
    flow = malloc(2 * n * sizeof *flow);
    inst = malloc(n * sizeof *inst);
    if (!depth || !flow || !inst) {
        cli_error("out of memory for %dx%d label frames", info.width, info.height);
        goto done;
    }
    if (evr_labels_read_frame(labels, &info, k, depth, inst, flow, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        goto done;
    }
    if (!info.complete)
        fprintf(stderr, "evray: note: %s is not marked complete (an interrupted run?)\n", labels);
    /* instance 0 is the file's mark of a pixel without a surface, whatever the values there */
    for (i = 0; i < n; i++)
        if (inst[i] == 0) {
            depth[i] = flow[2 * i] = flow[2 * i + 1] = NAN;
            none++;
        }
    if (isnan(t)) snprintf(at, sizeof at, "t = %g s, the middle frame", info.t[k]);
    else snprintf(at, sizeof at, "t = %g s, the nearest to %g s", info.t[k], t);
    if (flow_png) {
        double max = flow_max;
        snprintf(title, sizeof title, "optical flow at t = %g s", info.t[k]);
        if (evr_plot_flow_png(flow_png, flow, info.width, info.height, title, &max, &scale, &err) !=
            EVR_OK) {
            cli_error("%s", err.msg);
            goto done;
        }
        printf("%s: label frame %zu of %zu (%s), %dx%d drawn at %dx; wheel edge %g px/s (%s); "
               "%zu pixels without a surface\n",
               flow_png, k, info.frames, at, info.width, info.height, scale, max,
               flow_max > 0.0 ? "--flow-max" : "99th percentile", none);
    }
    if (depth_png) {
        double lo, hi;
        snprintf(title, sizeof title, "depth at t = %g s", info.t[k]);
        if (evr_plot_depth_png(depth_png, depth, info.width, info.height, title, &lo, &hi, &scale,
                               &err) != EVR_OK) {
            cli_error("%s", err.msg);
            goto done;
        }
        printf("%s: label frame %zu of %zu (%s), %dx%d drawn at %dx; depth %g (near, white) to "
               "%g (far, black); %zu pixels without a surface\n",
               depth_png, k, info.frames, at, info.width, info.height, scale, lo, hi, none);
    }
    rc = 0;
done:
    free(depth);
    free(flow);
    free(inst);
    evr_labels_info_free(&info);
    return rc;
}

/* labels.h5 in the folder of the event file at path. NULL when out of memory. */
static char *labels_beside(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t dir = slash ? (size_t)(slash - path + 1) : 0;
    char *out = malloc(dir + sizeof "labels.h5");
    if (out) {
        memcpy(out, path, dir);
        memcpy(out + dir, "labels.h5", sizeof "labels.h5");
    }
    return out;
}

int cmd_plot(int argc, char **argv)
{
    const char *in = NULL, *out = "rate.png", *heat = NULL, *v, *labels = NULL, *flow_png = NULL,
               *depth_png = NULL, *event_opt = NULL;
    char *labels_alloc = NULL;
    double bin_ms = 1.0, t = NAN, flow_max = 0.0;
    int pw = 1000, ph = 420, i, width = -1, height = -1, rc = 1, timed = 0;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return plot_usage();
        if (!strcmp(a, "-o") || opt_is(a, "--out") || opt_is(a, "--heatmap") ||
            opt_is(a, "--bin-ms") || opt_is(a, "--size"))
            event_opt = a;
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
        } else if (opt_is(a, "--labels")) {
            if (!(labels = opt_value(argc, argv, &i, "--labels"))) return 2;
        } else if (opt_is(a, "--flow")) {
            if (!(flow_png = opt_value(argc, argv, &i, "--flow"))) return 2;
        } else if (opt_is(a, "--depth")) {
            if (!(depth_png = opt_value(argc, argv, &i, "--depth"))) return 2;
        } else if (opt_is(a, "--time")) {
            if (!(v = opt_value(argc, argv, &i, "--time")) || !opt_double("--time", v, &t))
                return 2;
            if (!isfinite(t)) {
                cli_error("--time must be a finite number of seconds (got %s)", v);
                return 2;
            }
            timed = 1;
        } else if (opt_is(a, "--flow-max")) {
            if (!(v = opt_value(argc, argv, &i, "--flow-max")) ||
                !opt_double("--flow-max", v, &flow_max))
                return 2;
            if (!(flow_max > 0.0 && flow_max < 1e30)) {
                cli_error("--flow-max must be a speed above 0 px/s (got %s)", v);
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
    if (!in && !labels) {
        cli_error("plot: no event file given (evray plot EVENTS [-o rate.png], or --labels "
                  "labels.h5 --flow flow.png)");
        return 2;
    }
    if (!in && event_opt) {
        cli_error("plot: %.*s draws events: give an event file", (int)strcspn(event_opt, "="),
                  event_opt);
        return 2;
    }
    if (labels && !flow_png && !depth_png) {
        cli_error("plot: --labels needs --flow FILE or --depth FILE (what to draw)");
        return 2;
    }
    if ((timed || flow_max > 0.0) && !flow_png && !depth_png) {
        cli_error("plot: %s applies to --flow and --depth", timed ? "--time" : "--flow-max");
        return 2;
    }
    if (flow_max > 0.0 && !flow_png) {
        cli_error("plot: --flow-max applies to --flow");
        return 2;
    }
    if (!in) return plot_labels(labels, timed ? t : NAN, flow_max, flow_png, depth_png);

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
    if ((flow_png || depth_png) && !labels && !(labels = labels_alloc = labels_beside(in)))
        cli_error("out of memory");
    else if (flow_png || depth_png)
        rc = plot_labels(labels, timed ? t : NAN, flow_max, flow_png, depth_png);
done:
    free(counts);
    free(x);
    free(on);
    free(off);
    free(ev);
    free(labels_alloc);
    return rc;
}
