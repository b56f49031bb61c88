#include "options.h"
#include "evray_experimental.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cli_error(const char *fmt, ...)
{
    va_list ap;
    fputs("evray: error: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

/* The library parses; the program says what went wrong. */
#define REPORT(call)                  \
    do {                              \
        evr_error err;                \
        if ((call) != EVR_OK) {       \
            cli_error("%s", err.msg); \
            return 0;                 \
        }                             \
        return 1;                     \
    } while (0)

int opt_double(const char *opt, const char *text, double *out)
{
    REPORT(evr_parse_double(opt, text, out, &err));
}
int opt_float(const char *opt, const char *text, float *out)
{
    REPORT(evr_parse_float(opt, text, out, &err));
}
int opt_int(const char *opt, const char *text, int *out)
{
    REPORT(evr_parse_int(opt, text, out, &err));
}
int opt_u64(const char *opt, const char *text, uint64_t *out)
{
    REPORT(evr_parse_u64(opt, text, out, &err));
}
int opt_size(const char *opt, const char *text, int *w, int *h)
{
    REPORT(evr_parse_size(opt, text, w, h, &err));
}
int opt_formats(const char *text, int *formats)
{
    REPORT(evr_formats_parse("--format", text, formats, &err));
}

int opt_is(const char *arg, const char *name)
{
    size_t n = strlen(name);
    return !strncmp(arg, name, n) && (arg[n] == 0 || arg[n] == '=');
}

const char *opt_value(int argc, char **argv, int *i, const char *name)
{
    const char *a = argv[*i];
    size_t n = strlen(name);
    if (a[n] == '=') return a + n + 1;
    if (*i + 1 >= argc) {
        cli_error("%s needs a value", name);
        return NULL;
    }
    (*i)++;
    return argv[*i];
}

evr_scene *cli_load_scene(const char *path, const char *demo, uint64_t demo_seed,
                          const char *animation, int strict, int allow_external, int quiet)
{
    evr_error err = {{0}};
    evr_scene *scene = NULL;
    evr_load_options opts;
    evr_status st;
    evr_load_options_defaults(&opts);
    opts.animation = animation;
    opts.strict = strict;
    opts.allow_external = allow_external;
    if (path) {
        st = evr_scene_load_with(path, &opts, &scene, &err);
    } else { /* a built-in scene goes through the same importer, from memory */
        void *glb = NULL;
        size_t n = 0;
        st = evr_demo_glb_variant(demo, demo_seed, &glb, &n, &err);
        if (st == EVR_OK) st = evr_scene_load_memory_with(glb, n, "glb", &opts, &scene, &err);
        free(glb);
    }
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        return NULL;
    }
    if (quiet == CLI_LOAD_DESCRIBED) return scene; /* evray info lists both */
    const char *notice = evr_scene_notice(scene);
    if (notice && !quiet) fprintf(stderr, "evray: note: %s\n", notice);
    /* what evray does not render of the file, one line each, even when quiet */
    for (const char *w = evr_scene_warnings(scene), *nl; (nl = strchr(w, '\n')) != NULL; w = nl + 1)
        fprintf(stderr, "evray: warning: %.*s\n", (int)(nl - w), w);
    return scene;
}

int cli_is_animation_option(int argc, char **argv, int *i, const char **animation)
{
    if (!opt_is(argv[*i], "--animation")) return 0;
    *animation = opt_value(argc, argv, i, "--animation");
    return *animation ? 1 : -1;
}

void cli_warn_photon_drops(const evr_stats *s)
{
    const unsigned long long kept = s->photons_stored, dropped = s->photon_collisions;
    if (dropped == 0 || (double)dropped <= 0.01 * (double)(kept + dropped)) return;
    fprintf(stderr,
            "evray: warning: %llu of %llu photons (%.1f%%) found their pixel of the photon buffer "
            "full (--photon-layers %d) and were left out of the indirect light; more layers (at "
            "most 4096) or fewer --photons keep them\n",
            dropped, kept + dropped, 100.0 * (double)dropped / (double)(kept + dropped),
            s->photon_layers);
}
