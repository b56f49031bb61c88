#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t interrupted, signals;
static evr_sim *volatile running; /* the run the signals stop */

/* The first Ctrl-C stops the run after the segments being rendered; a second, or SIGTERM, stops
 * it at once (evr_sim_cancel); either way the files are completed. Should that hang, the third
 * signal ends the process as the signal does. */
static void on_signal(int sig)
{
    signals++;
    interrupted = 1;
    if (sig == SIGTERM || signals >= 2) evr_sim_cancel(running);
    if (signals >= 3) {
        signal(sig, SIG_DFL);
        raise(sig);
    }
}

typedef struct {
    int show;
    double duration;
    double started;
} progress_state;

static int on_progress(void *user, const evr_stats *st)
{
    progress_state *p = (progress_state *)user;
    if (p->duration <= 0 &&
        st->segments_done > 0) /* the animation's length: known from the first segment */
        p->duration = st->sim_time * st->segments_total / st->segments_done;
    if (p->show) {
        double frac = st->segments_total ? (double)st->segments_done / st->segments_total : 1.0;
        double el = evr_seconds() - p->started;
        double eta = frac > 0 ? el * (1.0 - frac) / frac : 0.0;
        char bar[31];
        int filled = (int)(frac * 30.0), i;
        for (i = 0; i < 30; i++) bar[i] = i < filled ? '#' : '-';
        bar[30] = 0;
        fprintf(stderr, "\r[%s] %6.3f/%.3f s  %llu events  %.1f Msamples/s  ETA %.0f s   ", bar,
                st->sim_time, p->duration, (unsigned long long)(st->events_on + st->events_off),
                st->samples_per_second / 1e6, eta);
        fflush(stderr);
    }
    return interrupted ? 1 : 0;
}

static void help(void)
{
    char *options = evr_config_options_help();
    fputs("usage: evray render SCENE [options]\n"
          "       evray [options]            (the built-in eye demo)\n"
          "\n"
          "Renders SCENE over time with every pixel sampling at its own times and writes the\n"
          "time-sorted DVS events, previews and run.json into the run folder.\n"
          "\n"
          "scene:\n" CLI_ANIMATION_HELP,
          stdout);
    if (options) fputs(options, stdout); /* made from the configuration table */
    free(options);
}

int cmd_render(int argc, char **argv, const char *default_demo, uint64_t demo_seed)
{
    evr_config cfg;
    render_options ro;
    const char *scene_path = NULL, *animation = NULL;
    int quiet, i, r;
    evr_config_defaults(&cfg);
    if (!render_options_init(&ro, &cfg, 0, argc)) return 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            render_options_free(&ro);
            return 0;
        } else if ((r = cli_is_animation_option(argc, argv, &i, &animation)) != 0) {
            if (r > 0) continue;
            render_options_free(&ro);
            return 2;
        } else if ((r = parse_render_option(argc, argv, &i, &ro)) < 0) {
            render_options_free(&ro);
            return 2;
        } else if (r > 0) continue;
        else if (a[0] == '-' && a[1]) {
            cli_error("unknown option '%s' (see evray render --help)", a);
            render_options_free(&ro);
            return 2;
        } else if (!scene_path && !default_demo) scene_path = a;
        else {
            cli_error("unexpected argument '%s'", a);
            render_options_free(&ro);
            return 2;
        }
    }
    r = render_options_finish(&ro, argc, argv);
    cfg = ro.cfg;
    quiet = ro.quiet;
    render_options_free(&ro);
    if (!r) return 2;
    if (!scene_path && !default_demo) {
        cli_error(
            "render needs a scene file (evray render SCENE [options]; evray demo for the built-in scene)");
        return 2;
    }

    evr_scene *scene = cli_load_scene(scene_path, default_demo, demo_seed, animation, cfg.strict,
                                      cfg.allow_external_files, quiet);
    if (!scene) return 1;
    evr_error err = {{0}};
    evr_status st;
    evr_sim *sim = NULL;
    if ((st = evr_sim_new(scene, &cfg, &sim, &err)) != EVR_OK) {
        cli_error("%s", err.msg);
        evr_scene_release(scene);
        return st == EVR_ERR_ARG ? 2 : 1;
    }
    const evr_stats *stats = evr_sim_stats(sim);
    if (stats->notice[0] && !quiet) fprintf(stderr, "evray: note: %s\n", stats->notice);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    running = sim;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    /* a file past the process's size limit is a write error (EFBIG), not the end of evray */
    signal(SIGXFSZ, SIG_IGN);

    progress_state ps;
    ps.show = !quiet && isatty(2);
    ps.started = evr_seconds();
    ps.duration = 0;
    ps.duration = cfg.duration;
    st = evr_sim_run(sim, on_progress, &ps, &err);
    if (ps.show) fputc('\n', stderr);
    int rc = 0;
    if (st != EVR_OK && st != EVR_ERR_INTERRUPTED) {
        cli_error("%s", err.msg);
        if (stats->outputs_kept)
            fprintf(stderr,
                    "evray: %s keeps every event before t = %.6f s (run.json: the run failed)\n",
                    cfg.out_dir, stats->complete_until);
        else fprintf(stderr, "evray: nothing kept in %s\n", cfg.out_dir);
        rc = 1;
    } else {
        cli_warn_photon_drops(stats);
        if (!quiet) {
            unsigned long long ev = (unsigned long long)(stats->events_on + stats->events_off);
            printf(
                "%s: %llu events (%llu ON, %llu OFF), %llu unique timestamps, %.3f s simulated\n",
                cfg.out_dir, ev, (unsigned long long)stats->events_on,
                (unsigned long long)stats->events_off, (unsigned long long)stats->unique_timestamps,
                stats->sim_time);
            printf("backend %s (%s)\n", stats->backend, stats->device);
            printf(
                "%llu samples, %llu rays in %.2f s: %.2f M samples/s, %.2f M rays/s, real-time factor %.4f\n",
                (unsigned long long)stats->samples, (unsigned long long)stats->rays,
                stats->wall_time, stats->samples_per_second / 1e6, stats->rays_per_second / 1e6,
                stats->realtime_factor);
            if (ev == 0)
                printf(
                    "no events: nothing in view changed brightness by a threshold over the simulated time "
                    "(a static scene gives none with the ideal sensor)\n");
        }
        if (st == EVR_ERR_INTERRUPTED) {
            fprintf(stderr, "evray: interrupted: %s holds every event before t = %.6f s\n",
                    cfg.out_dir, stats->complete_until);
            rc = 130;
        }
    }
    running = NULL;
    evr_sim_release(sim);
    evr_scene_release(scene);
    return rc;
}
