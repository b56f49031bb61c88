#include "commands.h"
#include "options.h"

#include <string.h>

/* One option shared by render, demo and bench: returns 1 when argv[*i] (and its value) was
 * consumed, 0 when it is not a render option, -1 after printing an error. */
int parse_render_option(int argc, char **argv, int *ip, evr_config *cfg_, int *quiet)
{
    evr_config cfg = *cfg_;
    int i = *ip;
    const char *a = argv[i], *v;
#define VAL(name) if (!(v = opt_value(argc, argv, &i, name))) return -1
    if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) *quiet = 1;
    else if (!strcmp(a, "--force")) cfg.force = 1;
    else if (!strcmp(a, "--no-preview")) cfg.preview_window = 0.0;
    else if (!strcmp(a, "-o")) { VAL("-o"); cfg.out_dir = v; }
    else if (opt_is(a, "--out")) { VAL("--out"); cfg.out_dir = v; }
    else if (opt_is(a, "--format")) { VAL("--format"); if (!opt_formats(v, &cfg.formats)) return -1; }
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
