/* The JSON reader (io/json_read.h): a recursive-descent parse into one array of values. */
#include "io/json_read.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int j_new(evr_jdoc *d, unsigned char type)
{
    if (d->n == d->cap) {
        int ncap = d->cap ? d->cap * 2 : 256;
        evr_jdoc_value *nv = realloc(d->v, (size_t)ncap * sizeof *nv);
        if (!nv) {
            d->failed = 1;
            return -1;
        }
        d->v = nv;
        d->cap = ncap;
    }
    memset(&d->v[d->n], 0, sizeof d->v[d->n]);
    d->v[d->n].type = type;
    d->v[d->n].first = d->v[d->n].next = -1;
    return d->n++;
}

static void j_ws(evr_jdoc *d)
{
    while (d->pos < d->len) {
        char c = d->text[d->pos];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r') break;
        d->pos++;
    }
}

/* Scans a string starting at the opening quote; sets the raw span. */
static int j_string_span(evr_jdoc *d, size_t *off, size_t *len)
{
    size_t p = d->pos + 1;
    while (p < d->len && d->text[p] != '"') {
        if (d->text[p] == '\\') p++;
        p++;
    }
    if (p >= d->len) return 0;
    *off = d->pos + 1;
    *len = p - *off;
    d->pos = p + 1;
    return 1;
}

static int j_number(evr_jdoc *d, double *out)
{
    size_t p = d->pos;
    double mant = 0.0, sign = 1.0;
    int exp10 = 0, esign = 1, e = 0, digits = 0;
    if (p < d->len && d->text[p] == '-') {
        sign = -1.0;
        p++;
    }
    while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') {
        mant = mant * 10.0 + (d->text[p] - '0');
        p++;
        digits++;
    }
    if (p < d->len && d->text[p] == '.') {
        p++;
        while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') {
            mant = mant * 10.0 + (d->text[p] - '0');
            exp10--;
            p++;
            digits++;
        }
    }
    if (!digits) return 0;
    if (p < d->len && (d->text[p] == 'e' || d->text[p] == 'E')) {
        p++;
        if (p < d->len && (d->text[p] == '+' || d->text[p] == '-')) {
            if (d->text[p] == '-') esign = -1;
            p++;
        }
        if (p >= d->len || d->text[p] < '0' || d->text[p] > '9') return 0;
        while (p < d->len && d->text[p] >= '0' && d->text[p] <= '9') {
            if (e < 10000) e = e * 10 + (d->text[p] - '0');
            p++;
        }
    }
    *out = sign * mant * pow(10.0, (double)(exp10 + esign * e));
    d->pos = p;
    return 1;
}

static int j_value(evr_jdoc *d, int depth);

static int j_container(evr_jdoc *d, int depth, int is_obj)
{
    int self = j_new(d, is_obj ? EVR_JDOC_OBJECT : EVR_JDOC_ARRAY), last = -1;
    if (self < 0) return -1;
    d->v[self].off = d->pos;
    d->pos++; /* '{' or '[' */
    j_ws(d);
    if (d->pos < d->len && d->text[d->pos] == (is_obj ? '}' : ']')) {
        d->pos++;
        d->v[self].len = d->pos - d->v[self].off;
        return self;
    }
    for (;;) {
        size_t koff = 0, klen = 0;
        int child;
        j_ws(d);
        if (is_obj) {
            if (d->pos >= d->len || d->text[d->pos] != '"' || !j_string_span(d, &koff, &klen))
                return -1;
            j_ws(d);
            if (d->pos >= d->len || d->text[d->pos] != ':') return -1;
            d->pos++;
        }
        child = j_value(d, depth + 1);
        if (child < 0) return -1;
        d->v[child].key_off = koff;
        d->v[child].key_len = klen;
        if (last < 0) d->v[self].first = child;
        else d->v[last].next = child;
        last = child;
        d->v[self].count++;
        j_ws(d);
        if (d->pos >= d->len) return -1;
        if (d->text[d->pos] == ',') {
            d->pos++;
            continue;
        }
        if (d->text[d->pos] == (is_obj ? '}' : ']')) {
            d->pos++;
            d->v[self].len = d->pos - d->v[self].off;
            return self;
        }
        return -1;
    }
}

static int j_value(evr_jdoc *d, int depth)
{
    int idx;
    char c;
    if (depth > EVR_JDOC_MAX_DEPTH) return -1;
    j_ws(d);
    if (d->pos >= d->len) return -1;
    c = d->text[d->pos];
    if (c == '{' || c == '[') return j_container(d, depth, c == '{');
    if (c == '"') {
        size_t off, len;
        if (!j_string_span(d, &off, &len)) return -1;
        if ((idx = j_new(d, EVR_JDOC_STRING)) < 0) return -1;
        d->v[idx].off = off;
        d->v[idx].len = len;
        return idx;
    }
    if (c == 't' && d->len - d->pos >= 4 && !memcmp(d->text + d->pos, "true", 4)) {
        d->pos += 4;
        if ((idx = j_new(d, EVR_JDOC_BOOL)) >= 0) d->v[idx].num = 1;
        return idx;
    }
    if (c == 'f' && d->len - d->pos >= 5 && !memcmp(d->text + d->pos, "false", 5)) {
        d->pos += 5;
        return j_new(d, EVR_JDOC_BOOL);
    }
    if (c == 'n' && d->len - d->pos >= 4 && !memcmp(d->text + d->pos, "null", 4)) {
        d->pos += 4;
        return j_new(d, EVR_JDOC_NULL);
    }
    {
        double num;
        size_t start = d->pos;
        if (!j_number(d, &num)) return -1;
        if ((idx = j_new(d, EVR_JDOC_NUMBER)) >= 0) {
            d->v[idx].num = num;
            d->v[idx].off = start;
            d->v[idx].len = d->pos - start;
        }
        return idx;
    }
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static size_t put_utf8(char *out, size_t o, size_t cap, unsigned cp)
{
    char tmp[4];
    size_t n, i;
    if (cp < 0x80) {
        tmp[0] = (char)cp;
        n = 1;
    } else if (cp < 0x800) {
        tmp[0] = (char)(0xC0 | (cp >> 6));
        tmp[1] = (char)(0x80 | (cp & 0x3F));
        n = 2;
    } else if (cp < 0x10000) {
        tmp[0] = (char)(0xE0 | (cp >> 12));
        tmp[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        tmp[2] = (char)(0x80 | (cp & 0x3F));
        n = 3;
    } else {
        tmp[0] = (char)(0xF0 | (cp >> 18));
        tmp[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
        tmp[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
        tmp[3] = (char)(0x80 | (cp & 0x3F));
        n = 4;
    }
    for (i = 0; i < n && o + 1 < cap; i++) out[o++] = tmp[i];
    return o;
}

static unsigned read_hex4(const char *s, size_t len, size_t i, int *ok)
{
    unsigned v = 0;
    int k;
    if (i + 4 > len) {
        *ok = 0;
        return 0;
    }
    for (k = 0; k < 4; k++) {
        int h = hexval(s[i + (size_t)k]);
        if (h < 0) {
            *ok = 0;
            return 0;
        }
        v = v * 16 + (unsigned)h;
    }
    return v;
}

/* Decodes a raw JSON string (escapes, \u with surrogate pairs) into out (truncated, 0-ended). */
static void j_decode(const char *s, size_t len, char *out, size_t cap)
{
    size_t i = 0, o = 0;
    while (i < len && o + 1 < cap) {
        char c = s[i++];
        if (c != '\\' || i >= len) {
            out[o++] = c;
            continue;
        }
        c = s[i++];
        switch (c) {
        case 'b': out[o++] = '\b'; break;
        case 'f': out[o++] = '\f'; break;
        case 'n': out[o++] = '\n'; break;
        case 'r': out[o++] = '\r'; break;
        case 't': out[o++] = '\t'; break;
        case 'u': {
            int ok = 1;
            unsigned cp = read_hex4(s, len, i, &ok);
            if (!ok) break;
            i += 4;
            if (cp >= 0xD800 && cp < 0xDC00 && i + 6 <= len && s[i] == '\\' && s[i + 1] == 'u') {
                unsigned lo = read_hex4(s, len, i + 2, &ok);
                if (ok && lo >= 0xDC00 && lo < 0xE000) {
                    cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                    i += 6;
                }
            }
            o = put_utf8(out, o, cap, cp);
            break;
        }
        default: out[o++] = c; break; /* \" \\ \/ */
        }
    }
    out[o] = 0;
}

int evr_jdoc_parse(evr_jdoc *d, const char *text, size_t len)
{
    memset(d, 0, sizeof *d);
    d->text = text;
    d->len = len;
    return j_value(d, 0);
}

void evr_jdoc_free(evr_jdoc *d)
{
    free(d->v);
    d->v = NULL;
    d->n = d->cap = 0;
}

int evr_jdoc_type(const evr_jdoc *d, int v) { return v >= 0 ? d->v[v].type : -1; }

int evr_jdoc_get(const evr_jdoc *d, int obj, const char *key)
{
    int c;
    size_t klen = strlen(key);
    if (obj < 0 || d->v[obj].type != EVR_JDOC_OBJECT) return -1;
    for (c = d->v[obj].first; c >= 0; c = d->v[c].next) {
        const evr_jdoc_value *v = &d->v[c];
        if (v->key_len == klen && !memcmp(d->text + v->key_off, key, klen)) return c;
        if (v->key_len > klen && memchr(d->text + v->key_off, '\\', v->key_len)) {
            char buf[128];
            j_decode(d->text + v->key_off, v->key_len, buf, sizeof buf);
            if (!strcmp(buf, key)) return c;
        }
    }
    return -1;
}

int evr_jdoc_first(const evr_jdoc *d, int v) { return v >= 0 ? d->v[v].first : -1; }

int evr_jdoc_next(const evr_jdoc *d, int c) { return c >= 0 ? d->v[c].next : -1; }

int evr_jdoc_count(const evr_jdoc *d, int arr)
{
    return (arr >= 0 && d->v[arr].type == EVR_JDOC_ARRAY) ? d->v[arr].count : 0;
}

int *evr_jdoc_elements(const evr_jdoc *d, int arr)
{
    int n = evr_jdoc_count(d, arr), i = 0, c;
    int *out = malloc(sizeof *out * ((size_t)n + 1));
    if (!out) return NULL;
    for (c = n ? evr_jdoc_first(d, arr) : -1; c >= 0; c = evr_jdoc_next(d, c)) out[i++] = c;
    return out;
}

double evr_jdoc_number(const evr_jdoc *d, int v, double def)
{
    return (v >= 0 && d->v[v].type == EVR_JDOC_NUMBER) ? d->v[v].num : def;
}

int evr_jdoc_string(const evr_jdoc *d, int v, char *out, size_t cap)
{
    if (v < 0 || d->v[v].type != EVR_JDOC_STRING) {
        out[0] = 0;
        return 0;
    }
    j_decode(d->text + d->v[v].off, d->v[v].len, out, cap);
    return 1;
}
