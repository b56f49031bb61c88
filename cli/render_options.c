#include "commands.h"
#include "options.h"

#include <stdlib.h>
#include <string.h>

int render_options_init(render_options *ro, const evr_config *base, int quiet, int argc)
{
    memset(ro, 0, sizeof *ro);
    ro->cfg = *base;
    ro->base = *base;
    ro->quiet = quiet;
    ro->argc = argc;
    ro->starts = calloc((size_t)argc + 1, 1);
    if (!ro->starts) {
        cli_error("out of memory");
        return 0;
    }
    return 1;
}

void render_options_free(render_options *ro)
{
    free(ro->starts);
    ro->starts = NULL;
}

/* Parses the sensor options; 1 consumed, 0 not one of them, -1 error. */
static int sensor_option(int argc, char **argv, int *ip, evr_config *cfg, const char **sensor)
{
    int i = *ip;
    const char *a = argv[i], *v;
    float f;
    double d;
#define VAL(name) if (!(v = opt_value(argc, argv, &i, name))) return -1
    if (opt_is(a, "--sensor")) {
        const char *const *names = evr_sensor_names();
        int k;
        VAL("--sensor");
        for (k = 0; names[k] && strcmp(names[k], v); k++) {}
        if (!names[k]) { cli_error("--sensor: unknown sensor '%s' (ideal, davis346, dvxplorer, prophesee-gen4)", v); return -1; }
        *sensor = names[k];
    }
    else if (opt_is(a, "--sigma-thres")) { VAL("--sigma-thres"); if (!opt_float("--sigma-thres", v, &f)) return -1; cfg->sigma_thres = f; }
    else if (opt_is(a, "--cutoff-hz")) { VAL("--cutoff-hz"); if (!opt_float("--cutoff-hz", v, &f)) return -1; cfg->cutoff_hz = f; }
    else if (opt_is(a, "--full-intensity")) { VAL("--full-intensity"); if (!opt_float("--full-intensity", v, &f)) return -1; cfg->full_intensity = f; }
    else if (opt_is(a, "--leak-rate-hz")) { VAL("--leak-rate-hz"); if (!opt_float("--leak-rate-hz", v, &f)) return -1; cfg->leak_rate = f; }
    else if (opt_is(a, "--leak-jitter")) { VAL("--leak-jitter"); if (!opt_float("--leak-jitter", v, &f)) return -1; cfg->leak_jitter = f; }
    else if (opt_is(a, "--shot-noise-rate-hz")) { VAL("--shot-noise-rate-hz"); if (!opt_float("--shot-noise-rate-hz", v, &f)) return -1; cfg->shot_rate = f; }
    else if (opt_is(a, "--hot-pixel-fraction")) { VAL("--hot-pixel-fraction"); if (!opt_float("--hot-pixel-fraction", v, &f)) return -1; cfg->hot_fraction = f; }
    else if (opt_is(a, "--hot-pixel-rate-hz")) { VAL("--hot-pixel-rate-hz"); if (!opt_float("--hot-pixel-rate-hz", v, &f)) return -1; cfg->hot_rate = f; }
    else if (opt_is(a, "--time-res")) { VAL("--time-res"); if (!opt_double("--time-res", v, &d)) return -1; cfg->time_res = d; }
    else if (opt_is(a, "--time-jitter")) { VAL("--time-jitter"); if (!opt_double("--time-jitter", v, &d)) return -1; cfg->time_jitter = d; }
    else return 0;
#undef VAL
    *ip = i;
    return 1;
}

static int one_option(int argc, char **argv, int *ip, evr_config *cfg_, int *quiet, const char **sensor)
{
    evr_config cfg = *cfg_;
    int i = *ip, r;
    const char *a = argv[i], *v;
    if ((r = sensor_option(argc, argv, &i, &cfg, sensor)) != 0) {
        if (r < 0) return -1;
        *cfg_ = cfg;
        *ip = i;
        return 1;
    }
#define VAL(name) if (!(v = opt_value(argc, argv, &i, name))) return -1
    if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) *quiet = 1;
    else if (!strcmp(a, "--force")) cfg.force = 1;
    else if (!strcmp(a, "--no-preview")) cfg.preview_window = 0.0;
    else if (!strcmp(a, "-o")) { VAL("-o"); cfg.out_dir = v; }
    else if (opt_is(a, "--out")) { VAL("--out"); cfg.out_dir = v; }
    else if (opt_is(a, "--format")) { VAL("--format"); if (!opt_formats(v, &cfg.formats)) return -1; }
    else if (opt_is(a, "--frames-out")) { VAL("--frames-out"); if (!v[0]) { cli_error("--frames-out needs a folder"); return -1; } cfg.frames_out = v; }
    else if (opt_is(a, "--frames-fps")) { VAL("--frames-fps"); if (!opt_double("--frames-fps", v, &cfg.frames_fps)) return -1;
            if (!(cfg.frames_fps > 0)) { cli_error("--frames-fps must be a positive number (got %s)", v); return -1; } }
    else if (opt_is(a, "--frames-exposure")) { VAL("--frames-exposure"); if (!opt_float("--frames-exposure", v, &cfg.frames_exposure)) return -1;
            if (!(cfg.frames_exposure > 0)) { cli_error("--frames-exposure must be a positive number (got %s)", v); return -1; } }
    else if (opt_is(a, "--frames-max")) { VAL("--frames-max"); if (!opt_float("--frames-max", v, &cfg.frames_max)) return -1;
            if (!(cfg.frames_max > 0)) { cli_error("--frames-max must be a positive intensity (got %s)", v); return -1; } }
    else if (opt_is(a, "--preview-window")) { VAL("--preview-window"); if (!opt_double(a, v, &cfg.preview_window)) return -1; }
    else if (opt_is(a, "--res")) { VAL("--res"); if (!opt_size("--res", v, &cfg.width, &cfg.height)) return -1; }
    else if (opt_is(a, "--camera")) { VAL("--camera"); cfg.camera = v; }
    else if (opt_is(a, "--duration")) { VAL("--duration"); if (!opt_double("--duration", v, &cfg.duration)) return -1;
            if (cfg.duration <= 0) { cli_error("--duration must be a positive number of seconds (got %s)", v); return -1; } }
    else if (opt_is(a, "--start")) { VAL("--start"); if (!opt_double("--start", v, &cfg.start)) return -1; }
    else if (opt_is(a, "--fps")) { VAL("--fps"); if (!opt_double("--fps", v, &cfg.fps)) return -1;
            if (cfg.fps <= 0) { cli_error("--fps must be a positive number (got %s)", v); return -1; } }
    else if (opt_is(a, "--samples-per-frame")) { VAL("--samples-per-frame"); if (!opt_int("--samples-per-frame", v, &cfg.samples_per_frame)) return -1; }
    else if (opt_is(a, "--backend")) { VAL("--backend");
        if (!strcmp(v, "auto")) cfg.backend = EVR_BACKEND_AUTO;
            else if (!strcmp(v, "cpu")) cfg.backend = EVR_BACKEND_CPU;
            else if (!strcmp(v, "cuda")) cfg.backend = EVR_BACKEND_CUDA;
            else { cli_error("--backend: unknown backend '%s' (auto, cpu, cuda)", v); return -1; } }
    else if (opt_is(a, "--gpu-bvh")) { VAL("--gpu-bvh");
            if (!strcmp(v, "bvh4")) cfg.gpu_bvh = 4;
            else if (!strcmp(v, "cw8")) cfg.gpu_bvh = 8;
            else { cli_error("--gpu-bvh: unknown layout '%s' (bvh4, cw8)", v); return -1; } }
    else if (opt_is(a, "--gpu-event-capacity")) { VAL("--gpu-event-capacity");
            uint64_t cap;
            if (!opt_u64("--gpu-event-capacity", v, &cap)) return -1;
            cfg.gpu_event_capacity = cap > ((uint64_t)1 << 40) ? ((int64_t)1 << 40) : (int64_t)cap; }
    else if (!strcmp(a, "--no-skip")) cfg.no_skip = 1;
    else if (opt_is(a, "--sampling")) { VAL("--sampling");
            if (!strcmp(v, "uniform")) cfg.sampling = EVR_SAMPLING_UNIFORM;
            else if (!strcmp(v, "adaptive")) cfg.sampling = EVR_SAMPLING_ADAPTIVE;
            else { cli_error("--sampling: unknown sampling '%s' (uniform, adaptive)", v); return -1; } }
    else if (opt_is(a, "--adapt-frac")) { VAL("--adapt-frac"); if (!opt_float("--adapt-frac", v, &cfg.adapt_frac)) return -1;
            if (!(cfg.adapt_frac > 0.0f) || !(cfg.adapt_frac <= 1.0f)) { cli_error("--adapt-frac must be in (0, 1] (got %s)", v); return -1; } }
    else if (opt_is(a, "--min-dt")) { VAL("--min-dt"); if (!opt_double("--min-dt", v, &cfg.min_dt)) return -1;
            if (!(cfg.min_dt >= 1e-6) || !(cfg.min_dt <= 1.0)) { cli_error("--min-dt must be between 1e-6 and 1 seconds (got %s)", v); return -1; } }
    else if (opt_is(a, "--max-dt")) { VAL("--max-dt"); if (!opt_double("--max-dt", v, &cfg.max_dt)) return -1;
            if (!(cfg.max_dt > 0.0) || !(cfg.max_dt <= 1.0)) { cli_error("--max-dt must be a number of seconds in (0, 1] (got %s)", v); return -1; } }
    else if (opt_is(a, "--gi")) { VAL("--gi");
            if (!strcmp(v, "none")) cfg.gi = 0;
            else if (!strcmp(v, "photon")) cfg.gi = 1;
            else if (!strcmp(v, "path")) { cli_error("--gi path renders one image: use evray still (render takes none or photon)"); return -1; }
            else { cli_error("--gi: unknown mode '%s' (none, photon)", v); return -1; } }
    else if (opt_is(a, "--photons")) { VAL("--photons");
            uint64_t n;
            if (!opt_u64("--photons", v, &n)) return -1;
            if (n > (1u << 30)) { cli_error("--photons: at most 2^30 photons per pass (got %s)", v); return -1; }
            cfg.photons = (uint32_t)n; }
    else if (opt_is(a, "--gather-radius")) { VAL("--gather-radius"); if (!opt_float("--gather-radius", v, &cfg.gather_radius)) return -1; }
    else if (opt_is(a, "--gather-max")) { VAL("--gather-max"); if (!opt_int("--gather-max", v, &cfg.gather_max)) return -1; }
    else if (opt_is(a, "--gather-window")) { VAL("--gather-window"); if (!opt_int("--gather-window", v, &cfg.gather_window)) return -1; }
    else if (opt_is(a, "--photon-layers")) { VAL("--photon-layers"); if (!opt_int("--photon-layers", v, &cfg.photon_layers)) return -1; }
    else if (opt_is(a, "--gi-bounces")) { VAL("--gi-bounces"); if (!opt_int("--gi-bounces", v, &cfg.gi_bounces)) return -1; }
    else if (opt_is(a, "--threads")) { VAL("--threads"); if (!opt_int("--threads", v, &cfg.threads)) return -1; }
    else if (opt_is(a, "--pos-thres")) { VAL("--pos-thres"); if (!opt_float("--pos-thres", v, &cfg.pos_thres)) return -1; }
    else if (opt_is(a, "--neg-thres")) { VAL("--neg-thres"); if (!opt_float("--neg-thres", v, &cfg.neg_thres)) return -1; }
    else if (opt_is(a, "--thres")) { VAL("--thres"); if (!opt_float("--thres", v, &cfg.pos_thres)) return -1; cfg.neg_thres = cfg.pos_thres; }
    else if (opt_is(a, "--refractory")) { VAL("--refractory"); if (!opt_float("--refractory", v, &cfg.refractory)) return -1; }
    else if (opt_is(a, "--log-floor")) { VAL("--log-floor"); if (!opt_float("--log-floor", v, &cfg.log_floor)) return -1; }
    else if (opt_is(a, "--ambient")) { VAL("--ambient"); if (!opt_float("--ambient", v, &cfg.ambient)) return -1; }
    else if (opt_is(a, "--seed")) { VAL("--seed"); if (!opt_u64("--seed", v, &cfg.seed)) return -1; }
    else return 0;
#undef VAL
    *cfg_ = cfg;
    *ip = i;
    return 1;
}

int parse_render_option(int argc, char **argv, int *ip, render_options *ro)
{
    int start = *ip, r = one_option(argc, argv, ip, &ro->cfg, &ro->quiet, &ro->sensor);
    if (r > 0 && start < ro->argc) ro->starts[start] = 1;
    return r;
}

int render_options_finish(render_options *ro, int argc, char **argv)
{
    evr_config cfg = ro->base;
    evr_error err;
    const char *sensor = NULL;
    int quiet = ro->quiet, i;
    if (!ro->sensor) return 1;   /* no preset: the options as given */
    if (evr_config_sensor(&cfg, ro->sensor, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 0;
    }
    for (i = 1; i < argc && i < ro->argc; i++) {
        if (!ro->starts[i]) continue;
        if (one_option(argc, argv, &i, &cfg, &quiet, &sensor) < 0) return 0;   /* parsed once already */
    }
    cfg.sensor = ro->sensor;
    ro->cfg = cfg;
    return 1;
}
