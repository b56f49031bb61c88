#include "options.h"
#include "evray_experimental.h"

#include <errno.h>
#include <math.h>
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

int opt_double(const char *opt, const char *text, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end || errno || !isfinite(v)) {
        cli_error("%s expects a number, got '%s'", opt, text);
        return 0;
    }
    *out = v;
    return 1;
}

int opt_float(const char *opt, const char *text, float *out)
{
    double v;
    if (!opt_double(opt, text, &v)) return 0;
    *out = (float)v;
    return 1;
}

int opt_int(const char *opt, const char *text, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end || errno || v < -2147483647L || v > 2147483647L) {
        cli_error("%s expects an integer, got '%s'", opt, text);
        return 0;
    }
    *out = (int)v;
    return 1;
}

int opt_u64(const char *opt, const char *text, uint64_t *out)
{
    char *end;
    errno = 0;
    if (text[0] == '-') {
        cli_error("%s expects a non-negative integer, got '%s'", opt, text);
        return 0;
    }
    unsigned long long v = strtoull(text, &end, 10);
    if (end == text || *end || errno) {
        cli_error("%s expects a non-negative integer, got '%s'", opt, text);
        return 0;
    }
    *out = (uint64_t)v;
    return 1;
}

int opt_size(const char *opt, const char *text, int *w, int *h)
{
    char *end, *end2;
    errno = 0;
    long a = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X')) goto bad;
    long b = strtol(end + 1, &end2, 10);
    if (end2 == end + 1 || *end2 || errno) goto bad;
    if (a < 1 || b < 1 || a > 65535 || b > 65535) {
        cli_error("%s: resolution %s is out of range (1 to 65535 pixels a side)", opt, text);
        return 0;
    }
    *w = (int)a;
    *h = (int)b;
    return 1;
bad:
    cli_error("%s expects WIDTHxHEIGHT (e.g. 640x480), got '%s'", opt, text);
    return 0;
}

int opt_formats(const char *text, int *formats)
{
    evr_error err;
    if (evr_formats_parse("--format", text, formats, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 0;
    }
    return 1;
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

evr_scene *cli_load_scene(const char *path, const char *demo)
{
    evr_error err = {{0}};
    evr_scene *scene = NULL;
    evr_status st = path ? evr_scene_load(path, &scene, &err) : evr_demo_load(demo, &scene, &err);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        return NULL;
    }
    return scene;
}
