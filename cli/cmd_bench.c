/* evray bench: one simulation, one row of figures. */
#include "commands.h"
#include "evray.h"
#include "options.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

static void remove_run(const char *dir)
{
    static const char *files[] = {"events.h5", "events.txt", "events.npy", "run.json", NULL};
    char p[4200];
    int i;
    for (i = 0; files[i]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, files[i]);
        remove(p);
    }
    rmdir(dir);
}

int cmd_bench(int argc, char **argv)
{
    evr_config cfg;
    render_options ro;
    const char *scene_path = NULL, *demo = "eye";
    int json = 0, keep = 0, i, r;
    evr_config_defaults(&cfg);
    cfg.preview_window = 0.0;
    if (!render_options_init(&ro, &cfg, 1, argc)) return 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            puts("usage: evray bench [--scene NAME | SCENE] [render options] [--json]\n\n"
                 "Runs one simulation (no previews; into a temporary folder unless -o is given) and prints\n"
                 "one row: events, processing time, real-time factor, samples/s, rays/s, the mean time\n"
                 "between a pixel's samples (temporal resolution), unique timestamps, peak host and GPU\n"
                 "memory, and the share of the wall time spent rendering, sorting, copying and writing\n"
                 "(writing runs on its own thread, overlapping rendering).\n"
                 "Render options are those of evray render (--res, --samples-per-frame, --duration,\n"
                 "--backend, --format, ...).");
            render_options_free(&ro);
            return 0;
        }
        if (!strcmp(a, "--json")) json = 1;
        else if (opt_is(a, "--scene")) { if (!(demo = opt_value(argc, argv, &i, "--scene"))) { render_options_free(&ro); return 2; } }
        else if ((r = parse_render_option(argc, argv, &i, &ro)) < 0) { render_options_free(&ro); return 2; }
        else if (r > 0) { if (!strcmp(a, "-o") || opt_is(a, "--out")) keep = 1; }
        else if (a[0] == '-' && a[1]) { cli_error("bench: unknown option '%s'", a); render_options_free(&ro); return 2; }
        else if (!scene_path) scene_path = a;
        else { cli_error("bench: unexpected argument '%s'", a); render_options_free(&ro); return 2; }
    }
    r = render_options_finish(&ro, argc, argv);
    cfg = ro.cfg;
    render_options_free(&ro);
    if (!r) return 2;
    char tmpdir[] = "/tmp/evray-bench-XXXXXX";
    if (!keep) {
        if (!mkdtemp(tmpdir)) { cli_error("cannot create a temporary folder"); return 1; }
        cfg.out_dir = tmpdir;
        cfg.force = 1;
    }
    evr_error err = {{0}};
    evr_scene *scene = NULL;
    evr_status st = scene_path ? evr_scene_load(scene_path, &scene, &err) : evr_demo_load(demo, &scene, &err);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        if (!keep) rmdir(tmpdir);
        return 1;
    }
    evr_sim *sim = NULL;
    if ((st = evr_sim_new(scene, &cfg, &sim, &err)) != EVR_OK) {
        cli_error("%s", err.msg);
        evr_scene_release(scene);
        if (!keep) rmdir(tmpdir);
        return st == EVR_ERR_ARG ? 2 : 1;
    }
    st = evr_sim_run(sim, NULL, NULL, &err);
    const evr_stats *s = evr_sim_stats(sim);
    int rc = 0;
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        rc = 1;
    } else {
        struct rusage ru;
        getrusage(RUSAGE_SELF, &ru);
        double peak_mb = (double)ru.ru_maxrss / 1024.0, w = s->wall_time > 0 ? s->wall_time : 1.0;
        double fps = s->segments_total > 0 && s->sim_time > 0 ? s->segments_total / s->sim_time : 0.0;
        double temporal_us = fps > 0 ? 1e6 / (fps * cfg.samples_per_frame) : 0.0;
        double render = s->time_device > 0 ? s->time_device : s->time_render;
        const char *name = scene_path ? scene_path : demo;
        if (json) {
            printf("{\"scene\": \"%s\", \"backend\": \"%s\", \"device\": \"%s\", \"width\": %d, \"height\": %d, "
                   "\"samples_per_frame\": %d, \"simulated_seconds\": %.6f, \"events\": %llu, \"wall_seconds\": %.4f, "
                   "\"realtime_factor\": %.5f, \"samples_per_second\": %.6g, \"rays_per_second\": %.6g, "
                   "\"temporal_resolution_us\": %.2f, \"unique_timestamps\": %llu, \"peak_host_mb\": %.1f, "
                   "\"device_memory_mb\": %.1f, \"setup_seconds\": %.4f, \"render_seconds\": %.4f, "
                   "\"sort_seconds\": %.4f, \"copy_seconds\": %.4f, \"write_seconds\": %.4f}\n",
                   name, s->backend, s->device, cfg.width, cfg.height, cfg.samples_per_frame, s->sim_time,
                   (unsigned long long)(s->events_on + s->events_off), s->wall_time, s->realtime_factor,
                   s->samples_per_second, s->rays_per_second, temporal_us, (unsigned long long)s->unique_timestamps,
                   peak_mb, (double)s->device_memory / 1048576.0, s->time_setup, render, s->time_sort, s->time_copy,
                   s->time_write);
        } else {
            printf("%-8s %-5s %9s %4s %12s %9s %9s %12s %12s %9s %12s %9s %8s  %s\n", "scene", "bknd", "res", "spf",
                   "events", "wall_s", "rt_factor", "samples/s", "rays/s", "dt_us", "unique_ts", "host_MB", "gpu_MB",
                   "share render/sort/copy/write");
            char res[32];
            snprintf(res, sizeof res, "%dx%d", cfg.width, cfg.height);
            printf("%-8.8s %-5s %9s %4d %12llu %9.3f %9.4f %12.4g %12.4g %9.1f %12llu %9.1f %8.1f  %.2f/%.2f/%.2f/%.2f\n",
                   name, s->backend, res, cfg.samples_per_frame, (unsigned long long)(s->events_on + s->events_off),
                   s->wall_time, s->realtime_factor, s->samples_per_second, s->rays_per_second, temporal_us,
                   (unsigned long long)s->unique_timestamps, peak_mb, (double)s->device_memory / 1048576.0,
                   render / w, s->time_sort / w, s->time_copy / w, s->time_write / w);
            printf("(%s; %.3f s simulated; setup %.2f s not in wall_s)\n", s->device, s->sim_time, s->time_setup);
        }
    }
    evr_sim_release(sim);
    evr_scene_release(scene);
    if (!keep) remove_run(tmpdir);
    return rc;
}
