#include "io/json.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void evr_json_init(evr_json *j, int pretty)
{
    memset(j, 0, sizeof *j);
    j->pretty = pretty != 0;
}

void evr_json_free(evr_json *j)
{
    free(j->buf);
    j->buf = NULL;
    j->len = j->cap = 0;
}

static void put(evr_json *j, const char *s, size_t n)
{
    if (j->failed) return;
    if (j->len + n + 1 > j->cap) {
        size_t cap = j->cap ? j->cap : 256;
        while (cap < j->len + n + 1) cap *= 2;
        char *p = realloc(j->buf, cap);
        if (!p) {
            j->failed = 1;
            return;
        }
        j->buf = p;
        j->cap = cap;
    }
    memcpy(j->buf + j->len, s, n);
    j->len += n;
    j->buf[j->len] = 0;
}

static void puts_(evr_json *j, const char *s) { put(j, s, strlen(s)); }

static void newline_indent(evr_json *j, int depth)
{
    static const char spaces[] = "                                ";
    if (!j->pretty) return;
    put(j, "\n", 1);
    for (int i = 0; i < depth; i++) put(j, spaces, 2);
}

/* Writes what must come before a member of the innermost container (comma, line break). */
static void separate(evr_json *j)
{
    int d = j->depth - 1;
    if (j->count[d]) put(j, ",", 1);
    j->count[d] = 1;
    newline_indent(j, j->depth);
}

/* Checks that a value may come now and writes what precedes it. */
static int begin_value(evr_json *j)
{
    if (j->failed) return 0;
    if (j->done) {
        j->failed = 1;
        return 0;
    }
    if (j->depth == 0) return 1;
    if (j->kind[j->depth - 1] == '{') {
        if (!j->after_key) {
            j->failed = 1;
            return 0;
        }
        j->after_key = 0;
        return 1;
    }
    separate(j);
    return 1;
}

static void end_value(evr_json *j)
{
    if (j->depth == 0) j->done = 1;
}

static void open_(evr_json *j, char kind)
{
    char c = kind;
    if (!begin_value(j)) return;
    if (j->depth >= EVR_JSON_MAX_DEPTH) {
        j->failed = 1;
        return;
    }
    put(j, &c, 1);
    j->kind[j->depth] = (unsigned char)kind;
    j->count[j->depth] = 0;
    j->depth++;
}

static void close_(evr_json *j, char kind)
{
    if (j->failed) return;
    if (j->depth == 0 || j->after_key || j->kind[j->depth - 1] != (unsigned char)kind) {
        j->failed = 1;
        return;
    }
    j->depth--;
    if (j->count[j->depth]) newline_indent(j, j->depth);
    put(j, kind == '{' ? "}" : "]", 1);
    end_value(j);
}

void evr_json_begin_object(evr_json *j) { open_(j, '{'); }
void evr_json_end_object(evr_json *j) { close_(j, '{'); }
void evr_json_begin_array(evr_json *j) { open_(j, '['); }
void evr_json_end_array(evr_json *j) { close_(j, '['); }

static void quoted(evr_json *j, const char *s)
{
    static const char hex[] = "0123456789abcdef";
    const char *run = s;
    put(j, "\"", 1);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        const char *esc = NULL;
        char u[7];
        if (c == '"') esc = "\\\"";
        else if (c == '\\') esc = "\\\\";
        else if (c == '\n') esc = "\\n";
        else if (c == '\r') esc = "\\r";
        else if (c == '\t') esc = "\\t";
        else if (c == '\b') esc = "\\b";
        else if (c == '\f') esc = "\\f";
        else if (c < 0x20 || c == 0x7f) {
            u[0] = '\\';
            u[1] = 'u';
            u[2] = '0';
            u[3] = '0';
            u[4] = hex[c >> 4];
            u[5] = hex[c & 15];
            u[6] = 0;
            esc = u;
        }
        if (esc) {
            put(j, run, (size_t)(s - run));
            puts_(j, esc);
            run = s + 1;
        }
    }
    put(j, run, (size_t)(s - run));
    put(j, "\"", 1);
}

void evr_json_key(evr_json *j, const char *name)
{
    if (j->failed) return;
    if (j->depth == 0 || j->kind[j->depth - 1] != '{' || j->after_key || !name) {
        j->failed = 1;
        return;
    }
    separate(j);
    quoted(j, name);
    puts_(j, j->pretty ? ": " : ":");
    j->after_key = 1;
}

void evr_json_string(evr_json *j, const char *s)
{
    if (!s) {
        evr_json_null(j);
        return;
    }
    if (!begin_value(j)) return;
    quoted(j, s);
    end_value(j);
}

/* printf's %g follows LC_NUMERIC; JSON wants a point whatever the locale. */
static void put_number_text(evr_json *j, char *t)
{
    for (char *c = t; *c; c++)
        if (*c == ',') *c = '.';
    puts_(j, t);
}

void evr_json_number(evr_json *j, double v)
{
    char t[40];
    if (!isfinite(v)) {
        evr_json_null(j);
        return;
    }
    if (!begin_value(j)) return;
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(t, sizeof t, "%.*g", prec, v);
        if (prec == 17 || strtod(t, NULL) == v) break;
    }
    put_number_text(j, t);
    end_value(j);
}

void evr_json_float(evr_json *j, float v)
{
    char t[40];
    if (!isfinite(v)) {
        evr_json_null(j);
        return;
    }
    if (!begin_value(j)) return;
    for (int prec = 6; prec <= 9; prec++) {
        snprintf(t, sizeof t, "%.*g", prec, (double)v);
        if (prec == 9 || strtof(t, NULL) == v) break;
    }
    put_number_text(j, t);
    end_value(j);
}

void evr_json_integer(evr_json *j, int64_t v)
{
    char t[32];
    if (!begin_value(j)) return;
    snprintf(t, sizeof t, "%" PRId64, v);
    puts_(j, t);
    end_value(j);
}

void evr_json_unsigned(evr_json *j, uint64_t v)
{
    char t[32];
    if (!begin_value(j)) return;
    snprintf(t, sizeof t, "%" PRIu64, v);
    puts_(j, t);
    end_value(j);
}

void evr_json_boolean(evr_json *j, int v)
{
    if (!begin_value(j)) return;
    puts_(j, v ? "true" : "false");
    end_value(j);
}

void evr_json_null(evr_json *j)
{
    if (!begin_value(j)) return;
    puts_(j, "null");
    end_value(j);
}

char *evr_json_take(evr_json *j)
{
    char *text = NULL;
    int pretty = j->pretty;
    if (!j->failed && j->done && j->depth == 0) {
        text = j->buf;
        j->buf = NULL;
    }
    evr_json_free(j);
    evr_json_init(j, pretty);
    return text;
}
