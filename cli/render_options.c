#include "commands.h"
#include "options.h"
#include "evray_experimental.h"

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

/* One option of the configuration table (evr_config_option_find), or -q; 1 consumed, 0 not one of
 * them, -1 error. A --sensor is noted in *sensor (render_options_finish applies its preset). */
static int one_option(int argc, char **argv, int *ip, evr_config *cfg_, int *quiet,
                      const char **sensor)
{
    evr_config cfg = *cfg_;
    evr_error err;
    int i = *ip;
    const char *a = argv[i], *v = NULL, *name;
    const evr_config_option *o;
    if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
        *quiet = 1;
        return 1;
    }
    if (!(o = evr_config_option_find(a, &name))) return 0;
    if (evr_config_option_takes_value(o) && !(v = opt_value(argc, argv, &i, name))) return -1;
    if (evr_config_option_set(&cfg, o, v, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return -1;
    }
    if (cfg.sensor != cfg_->sensor) *sensor = cfg.sensor;
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
    if (!ro->sensor) return 1; /* no preset: the options as given */
    if (evr_config_sensor(&cfg, ro->sensor, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 0;
    }
    for (i = 1; i < argc && i < ro->argc; i++) {
        if (!ro->starts[i]) continue;
        if (one_option(argc, argv, &i, &cfg, &quiet, &sensor) < 0)
            return 0; /* parsed once already */
    }
    cfg.sensor = ro->sensor;
    ro->cfg = cfg;
    return 1;
}
