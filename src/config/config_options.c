/* The configuration as options: values parsed strictly, options found and set by the table's
 * rows, and the options' help made from them. */
#include "config/config_table.h"
#include "evray_experimental.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FAIL(...)                                         \
    do {                                                  \
        snprintf(err->msg, sizeof err->msg, __VA_ARGS__); \
        return EVR_ERR_ARG;                               \
    } while (0)

evr_status evr_parse_double(const char *opt, const char *text, double *out, evr_error *err)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end || errno || !isfinite(v))
        FAIL("%s expects a number, got '%s'", opt, text);
    *out = v;
    return EVR_OK;
}

evr_status evr_parse_float(const char *opt, const char *text, float *out, evr_error *err)
{
    double v;
    evr_status st = evr_parse_double(opt, text, &v, err);
    if (st == EVR_OK) *out = (float)v;
    return st;
}

evr_status evr_parse_int(const char *opt, const char *text, int *out, evr_error *err)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end || errno || v < -2147483647L || v > 2147483647L)
        FAIL("%s expects an integer, got '%s'", opt, text);
    *out = (int)v;
    return EVR_OK;
}

evr_status evr_parse_u64(const char *opt, const char *text, uint64_t *out, evr_error *err)
{
    char *end;
    errno = 0;
    if (text[0] == '-') FAIL("%s expects a non-negative integer, got '%s'", opt, text);
    unsigned long long v = strtoull(text, &end, 10);
    if (end == text || *end || errno)
        FAIL("%s expects a non-negative integer, got '%s'", opt, text);
    *out = (uint64_t)v;
    return EVR_OK;
}

evr_status evr_parse_size(const char *opt, const char *text, int *w, int *h, evr_error *err)
{
    char *end, *end2;
    errno = 0;
    long a = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X')) goto bad;
    long b = strtol(end + 1, &end2, 10);
    if (end2 == end + 1 || *end2 || errno) goto bad;
    if (a < 1 || b < 1 || a > 65535 || b > 65535)
        FAIL("%s: resolution %s is out of range (1 to 65535 pixels a side)", opt, text);
    *w = (int)a;
    *h = (int)b;
    return EVR_OK;
bad:
    FAIL("%s expects WIDTHxHEIGHT (e.g. 640x480), got '%s'", opt, text);
}

int evr_config_option_takes_value(const evr_config_option *o)
{
    return o->type != EVR_OPT_FLAG && !o->no_value;
}

const char *evr_config_option_name(int i, int *takes_value, const char **help)
{
    int k, n;
    const evr_config_option *t = evr_config_table(&n);
    for (k = 0; k < n; k++) {
        /* not an option, or the program's own (-q) */
        if (!t[k].flag || (t[k].type == EVR_OPT_NONE && !t[k].parse)) continue;
        if (i-- > 0) continue;
        *takes_value = evr_config_option_takes_value(&t[k]);
        *help = t[k].help ? t[k].help : "";
        return t[k].flag;
    }
    return NULL;
}

const evr_config_option *evr_config_option_find(const char *arg, const char **name)
{
    int i, n;
    const evr_config_option *t = evr_config_table(&n);
    for (i = 0; i < n; i++) {
        const char *flag = t[i].flag;
        size_t len;
        if (!flag) continue;
        if (t[i].alias && !strcmp(arg, t[i].alias)) {
            *name = t[i].alias;
            return &t[i];
        }
        len = strlen(flag);
        /* an option with a value may be given as --name=value */
        if (!strncmp(arg, flag, len) &&
            (arg[len] == 0 || (arg[len] == '=' && evr_config_option_takes_value(&t[i])))) {
            *name = flag;
            return &t[i];
        }
    }
    return NULL;
}

static evr_status set_choice(evr_config *c, const evr_config_option *o, const char *v,
                             evr_error *err)
{
    const evr_opt_choice *ch;
    char names[128];
    for (ch = o->choices; ch->name || ch->json; ch++) {
        if (!ch->name || strcmp(ch->name, v)) continue;
        if (ch->refuse) FAIL("%s", ch->refuse);
        *(int *)evr_config_field(c, o) = ch->value;
        return EVR_OK;
    }
    evr_config_choice_names(o, names, sizeof names);
    FAIL("%s: unknown %s '%s' (%s)", o->flag, o->noun, v, names);
}

evr_status evr_config_option_set(evr_config *c, const evr_config_option *o, const char *v,
                                 evr_error *err)
{
    void *f = evr_config_field(c, o);
    double num = 0.0;
    evr_status st = EVR_OK;
    int i = 0;
    float x = 0.0f;
    double d = 0.0;
    uint64_t u = 0;
    if (o->parse) return o->parse(c, v, err);
    if (o->type == EVR_OPT_FLAG) {
        *(int *)f = 1;
        return EVR_OK;
    }
    if (o->type == EVR_OPT_NONE) return EVR_OK; /* the program's own (-q) */
    if (!v) FAIL("%s needs a value", o->flag);
    switch (o->type) {
    case EVR_OPT_STRING: *(const char **)f = v; return EVR_OK;
    case EVR_OPT_CHOICE: return set_choice(c, o, v, err);
    case EVR_OPT_INT:
        st = evr_parse_int(o->flag, v, &i, err);
        num = i;
        break;
    case EVR_OPT_FLOAT:
        st = evr_parse_float(o->flag, v, &x, err);
        num = x;
        break;
    case EVR_OPT_DOUBLE:
        st = evr_parse_double(o->flag, v, &d, err);
        num = d;
        break;
    case EVR_OPT_INT64:
    case EVR_OPT_U32:
    case EVR_OPT_U64:
        st = evr_parse_u64(o->flag, v, &u, err);
        num = (double)u;
        break;
    default: break;
    }
    if (st != EVR_OK) return st;
    /* the stricter check of a value given on the command line, before it is stored */
    if (o->cli_what &&
        (!(num >= o->cli_lo) || !(num <= o->cli_hi) || (o->cli_lo_open && num == o->cli_lo)))
        FAIL(o->cli_what, o->flag, v);
    switch (o->type) {
    case EVR_OPT_INT: *(int *)f = i; break;
    case EVR_OPT_FLOAT: *(float *)f = x; break;
    case EVR_OPT_DOUBLE: *(double *)f = d; break;
    case EVR_OPT_INT64: *(int64_t *)f = u > (uint64_t)INT64_MAX ? INT64_MAX : (int64_t)u; break;
    case EVR_OPT_U32: *(uint32_t *)f = (uint32_t)u; break;
    case EVR_OPT_U64: *(uint64_t *)f = u; break;
    default: break;
    }
    return EVR_OK;
}

/* Appends to a growing string; 0 when out of memory. */
typedef struct {
    char *s;
    size_t len, cap;
} text_buf;

static int append(text_buf *b, const char *fmt, const char *x, const char *y)
{
    int n = snprintf(NULL, 0, fmt, x, y);
    if (n < 0) return 0;
    if (b->len + (size_t)n + 1 > b->cap) {
        size_t cap = (b->cap ? b->cap * 2 : 4096) + (size_t)n;
        char *s = realloc(b->s, cap);
        if (!s) return 0;
        b->s = s;
        b->cap = cap;
    }
    snprintf(b->s + b->len, b->cap - b->len, fmt, x, y);
    b->len += (size_t)n;
    return 1;
}

#define HELP_COLUMN 26 /* label width; the text starts three columns later */

char *evr_config_options_help(void)
{
    int i, n, ok = 1;
    const evr_config_option *t = evr_config_table(&n);
    text_buf b = {NULL, 0, 0};
    char generated[512], line[512];
    for (i = 0; i < n && ok; i++) {
        const char *text = t[i].help, *p;
        if (!t[i].label) continue; /* a field without an option, or listed with the row before */
        if (t[i].section) ok = append(&b, "%s:\n", t[i].section, NULL);
        if (t[i].help_text) {
            t[i].help_text(generated, sizeof generated);
            text = generated;
        }
        /* a label too wide for its column is followed by three spaces */
        ok = ok && append(&b, strlen(t[i].label) > HELP_COLUMN ? "  %s   " : "  %-26s ", t[i].label,
                          NULL);
        for (p = text; ok && p;) {
            const char *nl = strchr(p, '\n');
            size_t len = nl ? (size_t)(nl - p) : strlen(p);
            if (len >= sizeof line) len = sizeof line - 1;
            memcpy(line, p, len);
            line[len] = 0;
            ok = append(&b, p == text ? "%s\n" : "%29s%s\n", p == text ? line : "",
                        p == text ? NULL : line);
            p = nl ? nl + 1 : NULL;
        }
    }
    if (!ok) {
        free(b.s);
        return NULL;
    }
    return b.s;
}
