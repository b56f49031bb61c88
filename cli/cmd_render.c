#include "commands.h"
#include "host_clock.h"
#include "evray.h"
#include "options.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t interrupted;

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
}

typedef struct {
    int show;
    double duration;
    double started;
} progress_state;

static int on_progress(void *user, const evr_stats *st)
{
    progress_state *p = (progress_state *)user;
    if (p->duration <= 0 && st->segments_done > 0)   /* the animation's length: known from the first segment */
        p->duration = st->sim_time * st->segments_total / st->segments_done;
    if (p->show) {
        double frac = st->segments_total ? (double)st->segments_done / st->segments_total : 1.0;
        double el = evr_host_seconds() - p->started;
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

void render_options_help(void);
static void help(void)
{
    puts("usage: evray render SCENE [options]\n"
         "       evray [options]            (the built-in eye demo)\n"
         "\n"
         "Renders SCENE over time with every pixel sampling at its own times and writes the\n"
         "time-sorted DVS events, previews and run.json into the run folder.\n"
         "\n"
         "output:\n"
         "  -o, --out DIR              run folder (default ./evray-out)\n"
         "  --force                    overwrite a non-empty run folder\n"
         "  --format LIST              h5, txt, npy or all, comma-separated (default h5)\n"
         "  --preview-window S         seconds per preview frame (default 0.05)\n"
         "  --no-preview               no preview images\n"
         "  -q, --quiet                no progress bar or summary\n"
         "intensity frames for frame-based tools (v2e and the like):\n"
         "  --frames-out DIR           also write frame k = every pixel's intensity at exactly\n"
         "                             start + k/F (one sample at the pixel centre, unseen by the\n"
         "                             pixel model), for every such time up to and including the end\n"
         "                             (floor(duration*F) + 1 frames): DIR/frame_NNNNNN.png (8-bit\n"
         "                             sRGB), DIR/frame_NNNNNN_linear16.png (16-bit linear) and\n"
         "                             DIR/frames.csv (index,time_s,srgb8_png,linear16_png); DIR may\n"
         "                             be inside the run folder or not, and must hold no frames\n"
         "                             unless --force\n"
         "  --frames-fps F             frames per second (default: the segment rate, --fps)\n"
         "  --frames-exposure E        8-bit frames: intensity * E clamped to [0, 1], sRGB-encoded\n"
         "                             (default 1: intensity 1 is white)\n"
         "  --frames-max M             16-bit frames: value = round(intensity * 65535 / M), clamped\n"
         "                             (default 4)\n"
         "image and time:\n"
         "  --res WxH                  resolution (default 346x260)\n"
         "  --camera NAME              camera of the scene (default: the first)\n"
         "  --duration S               seconds to simulate (default: the animation's length)\n"
         "  --start S                  start time in the animation (default 0)\n"
         "  --fps F                    segments per second (default: the scene's frame rate, else 30)\n"
         "  --samples-per-frame N      samples per pixel per segment (default 10)\n"
         "  --threads N                worker threads (default: all cores)\n"
         "  --backend B                auto (default: CUDA when a GPU is usable, else CPU), cpu or cuda\n"
         "  --gpu-bvh L                GPU BVH node layout: cw8 (default, compressed 8-wide) or bvh4\n"
         "  --gpu-event-capacity N     events a GPU segment buffer holds at first (default: automatic; it\n"
         "                             grows and the segment is rendered again whenever it overflows)\n"
         "  --no-skip                  trace every sample (brute force); by default a pixel that nothing\n"
         "                             moving can reach keeps its last intensity (identical events)\n"
         "  --sampling S               uniform (default: --samples-per-frame samples per pixel per\n"
         "                             segment) or adaptive: each pixel picks its next sample time so\n"
         "                             that its log intensity moves by at most --adapt-frac of a\n"
         "                             threshold and anything its rays meet moves by at most\n"
         "                             2 * --adapt-frac pixels; a pixel nothing moving reaches samples\n"
         "                             every --max-dt; a sample that changed by more than that is\n"
         "                             held back while the interval before it is bisected down to\n"
         "                             --min-dt (ignores --samples-per-frame and --no-skip)\n"
         "  --adapt-frac F             adaptive: in (0, 1] (default 0.25)\n"
         "  --min-dt S, --max-dt S     adaptive: bounds on the time between a pixel's samples, seconds\n"
         "                             (default 20e-6; one segment); a moving camera or light samples\n"
         "                             every pixel every --min-dt\n"
         "global illumination (CPU and CUDA backends):\n"
         "  --gi MODE                  none (default) or photon: image-space photon mapping, a photon\n"
         "                             pass at every segment boundary and the indirect light linear in\n"
         "                             time between them (the same photons every pass: a still scene\n"
         "                             gets the same indirect light, so GI makes no events by itself)\n"
         "  --photons N                photons per pass (default: one per pixel)\n"
         "  --gather-radius R          distance filter, world units (default 2% of the scene's diagonal)\n"
         "  --gather-max N             photons per estimate at most (default 0: no limit, every photon of the disk)\n"
         "  --gather-window N          gather window half size at most, pixels (default 8)\n"
         "  --photon-layers N          photons each pixel of the buffer holds (default 8)\n"
         "  --gi-bounces N             indirect bounces of a photon (default 4)\n"
         "sensor (laws, presets and their sources: docs/sensors.md; the default is the ideal sensor):\n"
         "  --sensor NAME              preset: ideal, davis346, dvxplorer or prophesee-gen4; it sets the\n"
         "                             defaults (and the resolution) that the options below override,\n"
         "                             whatever their order\n"
         "  --pos-thres C, --neg-thres C   ON/OFF contrast thresholds in log intensity (default 0.2)\n"
         "  --thres C                  both thresholds\n"
         "  --sigma-thres S            threshold mismatch: per-pixel thresholds drawn once from\n"
         "                             N(threshold, S), a fixed pattern (default 0)\n"
         "  --refractory S             refractory period in seconds (default 0)\n"
         "  --cutoff-hz F              photoreceptor low-pass cutoff at full brightness, falling to 7%\n"
         "                             of F for black (default 0: no filter)\n"
         "  --full-intensity I         intensity that counts as full brightness (default 1)\n"
         "  --leak-rate-hz R           leak ON events per second per pixel (default 0)\n"
         "  --leak-jitter J            relative spread of the per-pixel leak rates (default 0.1)\n"
         "  --shot-noise-rate-hz R     shot-noise events per second (ON + OFF) of a black pixel; a pixel\n"
         "                             at full brightness has R/4 (default 0)\n"
         "  --hot-pixel-fraction F     fraction of hot pixels (default 0)\n"
         "  --hot-pixel-rate-hz R      ON events per second of a hot pixel (default 100)\n"
         "  --time-res S               timestamp resolution in seconds, whole microseconds (default 1e-6)\n"
         "  --time-jitter S            std dev of Gaussian timestamp jitter in seconds (default 0)\n"
         "  --log-floor I              intensity below which the response is linear (default 0.02)\n"
         "  --seed N                   seed of the per-pixel sample phases and of the sensor's fixed\n"
         "                             pattern and noise (default 1)\n"
         "shading:\n"
         "  --ambient A                ambient light as a fraction of the base colour (default 0.02)");
}

int cmd_render(int argc, char **argv, const char *default_demo)
{
    evr_config cfg;
    render_options ro;
    const char *scene_path = NULL;
    int quiet, i, r;
    evr_config_defaults(&cfg);
    if (!render_options_init(&ro, &cfg, 0, argc)) return 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { help(); render_options_free(&ro); return 0; }
        else if ((r = parse_render_option(argc, argv, &i, &ro)) < 0) { render_options_free(&ro); return 2; }
        else if (r > 0) continue;
        else if (a[0] == '-' && a[1]) { cli_error("unknown option '%s' (see evray render --help)", a); render_options_free(&ro); return 2; }
        else if (!scene_path && !default_demo) scene_path = a;
        else { cli_error("unexpected argument '%s'", a); render_options_free(&ro); return 2; }
    }
    r = render_options_finish(&ro, argc, argv);
    cfg = ro.cfg;
    quiet = ro.quiet;
    render_options_free(&ro);
    if (!r) return 2;
    if (!scene_path && !default_demo) {
        cli_error("render needs a scene file (evray render SCENE [options]; evray demo for the built-in scene)");
        return 2;
    }

    evr_scene *scene = cli_load_scene(scene_path, default_demo);
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
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    progress_state ps;
    ps.show = !quiet && isatty(2);
    ps.started = evr_host_seconds();
    ps.duration = 0;
    ps.duration = cfg.duration;
    st = evr_sim_run(sim, on_progress, &ps, &err);
    if (ps.show) fputc('\n', stderr);
    int rc = 0;
    if (st != EVR_OK && st != EVR_ERR_INTERRUPTED) {
        cli_error("%s", err.msg);
        rc = 1;
    } else {
        if (!quiet) {
            unsigned long long ev = (unsigned long long)(stats->events_on + stats->events_off);
            printf("%s: %llu events (%llu ON, %llu OFF), %llu unique timestamps, %.3f s simulated\n",
                   cfg.out_dir, ev, (unsigned long long)stats->events_on, (unsigned long long)stats->events_off,
                   (unsigned long long)stats->unique_timestamps, stats->sim_time);
            printf("backend %s (%s)\n", stats->backend, stats->device);
            printf("%llu samples, %llu rays in %.2f s: %.2f M samples/s, %.2f M rays/s, real-time factor %.4f\n",
                   (unsigned long long)stats->samples, (unsigned long long)stats->rays, stats->wall_time,
                   stats->samples_per_second / 1e6, stats->rays_per_second / 1e6, stats->realtime_factor);
            if (ev == 0)
                printf("no events: nothing in view changed brightness by a threshold over the simulated time "
                       "(a static scene gives none with the ideal sensor)\n");
        }
        if (st == EVR_ERR_INTERRUPTED) {
            fprintf(stderr, "evray: interrupted: %s holds every event of the first %.3f s\n", cfg.out_dir, stats->sim_time);
            rc = 130;
        }
    }
    evr_sim_release(sim);
    evr_scene_release(scene);
    return rc;
}
