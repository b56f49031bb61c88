#include "io/event_reader.h"
#include "io/aedat4_read.h"
#include "io/prophesee_read.h"
#include "io/rosbag_read.h"
#include "io/byte_order.h"
#include "io/file_read.h"
#include "io/h5_read.h"

#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define READ_BLOCK ((size_t)1 << 20) /* events per block read from HDF5 and NPY files */

static int ext_is(const char *path, const char *ext)
{
    size_t lp = strlen(path), le = strlen(ext);
    if (lp <= le || path[lp - le - 1] != '.') return 0;
    for (size_t i = 0; i < le; i++)
        if (tolower((unsigned char)path[lp - le + i]) != ext[i]) return 0;
    return 1;
}

/* ---- whole-file read (text and NumPy) ---- */

evr_status evr_file_slurp(const char *path, char **data, size_t *size, evr_error *err)
{
    const char *why = NULL;
    FILE *f = evr_fopen_regular(path, &why);
    char *buf = NULL;
    size_t len = 0, cap = 0;
    if (!f) {
        snprintf(err->msg, sizeof err->msg, "cannot open %s: %s", path, why);
        return EVR_ERR_IO;
    }
    for (;;) {
        if (cap - len < 65536) {
            size_t ncap = cap ? cap * 2 : 1 << 20;
            char *p = realloc(buf, ncap + 1);
            if (!p) {
                free(buf);
                fclose(f);
                snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
                return EVR_ERR_NOMEM;
            }
            buf = p;
            cap = ncap;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        snprintf(err->msg, sizeof err->msg, "cannot read %s", path);
        return EVR_ERR_IO;
    }
    buf[len] = 0;
    *data = buf;
    *size = len;
    return EVR_OK;
}

/* ---- text ---- */

static const char *skip_blanks(const char *s)
{
    while (*s == ' ' || *s == '\t' || *s == '\r') s++;
    return s;
}

/* Seconds as decimal text to integer microseconds, exactly for up to six decimals (more are
 * rounded); exponent forms go through strtod. */
static int parse_seconds(const char **sp, int64_t *out)
{
    const char *s = *sp;
    int neg = 0, digits = 0;
    uint64_t whole = 0, frac = 0;
    int nfrac = 0, round_up = 0;
    if (*s == '-' || *s == '+') neg = *s++ == '-';
    while (isdigit((unsigned char)*s)) {
        if (whole > UINT64_MAX / 10 / 1000000) return 0;
        whole = whole * 10 + (uint64_t)(*s++ - '0');
        digits++;
    }
    if (*s == '.') {
        s++;
        while (isdigit((unsigned char)*s)) {
            if (nfrac < 6) frac = frac * 10 + (uint64_t)(*s - '0');
            else if (nfrac == 6) round_up = *s >= '5';
            nfrac++;
            digits++;
            s++;
        }
    }
    if (!digits) return 0;
    if (*s == 'e' || *s == 'E') { /* rare: let strtod do it */
        char *end;
        double v = strtod(*sp, &end);
        if (end == *sp || !isfinite(v) || fabs(v) > 9.2e12) return 0;
        *out = (int64_t)llround(v * 1e6);
        *sp = end;
        return 1;
    }
    for (int i = nfrac; i < 6; i++) frac *= 10;
    uint64_t us = whole * 1000000u + frac + (uint64_t)round_up;
    if (us > (uint64_t)INT64_MAX) return 0;
    *out = neg ? -(int64_t)us : (int64_t)us;
    *sp = s;
    return 1;
}

static int parse_long(const char **sp, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(*sp, &end, 10);
    if (end == *sp || errno) return 0;
    *out = v;
    *sp = end;
    return 1;
}

static evr_status read_txt(const char *path, evr_event **ev, size_t *n, evr_error *err)
{
    char *data;
    size_t size, count = 0, cap = 0, line = 0;
    evr_event *out = NULL;
    evr_status st = evr_file_slurp(path, &data, &size, err);
    if (st != EVR_OK) return st;
    const char *s = data;
    while (*s) {
        const char *eol = strchr(s, '\n');
        const char *next = eol ? eol + 1 : s + strlen(s);
        int64_t t;
        long x, y, p, id = 0;
        line++;
        s = skip_blanks(s);
        if (*s == '\n' || *s == 0 || *s == '#') {
            s = next;
            continue;
        }
        if (!parse_seconds(&s, &t) || (s = skip_blanks(s), !parse_long(&s, &x)) ||
            (s = skip_blanks(s), !parse_long(&s, &y)) ||
            (s = skip_blanks(s), !parse_long(&s, &p)) ||
            (s = skip_blanks(s), *s != '\n' && *s != 0 && *s != '\r' && !parse_long(&s, &id)) ||
            (s = skip_blanks(s), *s != '\n' && *s != 0) || x < 0 || x > 65535 || y < 0 ||
            y > 65535 || id < 0 || id > EVR_MAX_EVENT_ID) {
            snprintf(err->msg, sizeof err->msg, "%s:%zu: expected \"t x y p\" (and an event id)",
                     path, line);
            st = EVR_ERR_FORMAT;
            goto done;
        }
        if (count == cap) {
            size_t ncap = cap ? cap * 2 : 4096;
            evr_event *q = realloc(out, ncap * sizeof *q);
            if (!q) {
                snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
                st = EVR_ERR_NOMEM;
                goto done;
            }
            out = q;
            cap = ncap;
        }
        memset(&out[count], 0, sizeof out[count]);
        out[count].t = t;
        out[count].x = (uint16_t)x;
        out[count].y = (uint16_t)y;
        out[count].p = p > 0 ? 1 : 0;
        out[count].id = (uint16_t)id;
        count++;
        s = next;
    }
done:
    free(data);
    if (st != EVR_OK) {
        free(out);
        return st;
    }
    if (count == 0) {
        free(out);
        out = NULL;
    }
    *ev = out;
    *n = count;
    return EVR_OK;
}

/* ---- NumPy ---- */

typedef struct {
    size_t offset;
    int size; /* bytes: 1, 2, 4 or 8 */
    int is_signed;
    int big_endian;
    int found;
} npy_field;

/* Parses a quoted Python string literal ('...' or "...") into out. */
static const char *py_string(const char *s, char *out, size_t cap)
{
    char q;
    size_t n = 0;
    s = skip_blanks(s);
    if (*s != '\'' && *s != '"') return NULL;
    q = *s++;
    while (*s && *s != q) {
        if (n + 1 >= cap) return NULL;
        out[n++] = *s++;
    }
    if (*s != q) return NULL;
    out[n] = 0;
    return s + 1;
}

/* Parses a type string such as '<i8', '|u1', '>u2', 'b1'; returns 0 for non-integer types. */
static int npy_type(const char *t, npy_field *f)
{
    f->big_endian = 0;
    if (*t == '<' || *t == '|' || *t == '=') t++;
    else if (*t == '>') {
        f->big_endian = 1;
        t++;
    }
    if ((*t != 'i' && *t != 'u' && *t != 'b') || !t[1] || t[2]) return 0;
    f->is_signed = *t == 'i';
    f->size = t[1] - '0';
    return f->size == 1 || f->size == 2 || f->size == 4 || f->size == 8;
}

static int64_t npy_get(const unsigned char *rec, const npy_field *f)
{
    uint64_t v = 0;
    for (int b = 0; b < f->size; b++) {
        int shift = f->big_endian ? 8 * (f->size - 1 - b) : 8 * b;
        v |= (uint64_t)rec[f->offset + (size_t)b] << shift;
    }
    if (f->is_signed && f->size < 8 && (v >> (8 * f->size - 1)) & 1)
        v |= ~(uint64_t)0 << (8 * f->size);
    return (int64_t)v;
}

static evr_status npy_bad(evr_error *err, const char *path, const char *why)
{
    snprintf(err->msg, sizeof err->msg, "%s: not an event array (%s)", path, why);
    return EVR_ERR_FORMAT;
}

static evr_status read_npy(const char *path, evr_event **ev, size_t *n, evr_error *err)
{
    char *data, *header = NULL;
    size_t size, hlen, start, itemsize = 0;
    npy_field fields[5]; /* t, x, y, p and (optional) id */
    static const char *const names[5] = {"t", "x", "y", "p", "id"};
    evr_event *out = NULL;
    uint64_t count = 0;
    evr_status st = evr_file_slurp(path, &data, &size, err);
    const unsigned char *u = (const unsigned char *)data;
    const char *s;

    if (st != EVR_OK) return st;
    memset(fields, 0, sizeof fields);
    if (size < 10 || memcmp(data, "\x93NUMPY", 6) != 0) {
        st = npy_bad(err, path, "no NumPy magic");
        goto done;
    }
    if (u[6] == 1) {
        hlen = evr_get_le16(u + 8);
        start = 10;
    } else if ((u[6] == 2 || u[6] == 3) && size >= 12) {
        hlen = evr_get_le32(u + 8);
        start = 12;
    } else {
        st = npy_bad(err, path, "unknown format version");
        goto done;
    }
    if (hlen > size - start) {
        st = npy_bad(err, path, "truncated header");
        goto done;
    }
    header = malloc(hlen + 1);
    if (!header) {
        snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
        st = EVR_ERR_NOMEM;
        goto done;
    }
    memcpy(header, data + start, hlen);
    header[hlen] = 0;
    start += hlen;

    /* descr: a list of ('name', 'type') pairs */
    s = strstr(header, "'descr'");
    if (!s) {
        st = npy_bad(err, path, "no descr");
        goto done;
    }
    s = skip_blanks(s + 7);
    if (*s != ':') {
        st = npy_bad(err, path, "bad descr");
        goto done;
    }
    s = skip_blanks(s + 1);
    if (*s != '[') {
        st = npy_bad(err, path, "not a structured array");
        goto done;
    }
    s++;
    for (;;) {
        char name[64], type[16];
        npy_field f;
        s = skip_blanks(s);
        if (*s == ',') s = skip_blanks(s + 1);
        if (*s == ']') break;
        if (*s != '(') {
            st = npy_bad(err, path, "bad descr");
            goto done;
        }
        s = py_string(s + 1, name, sizeof name);
        if (s) s = skip_blanks(s);
        if (s && *s == ',') s = py_string(s + 1, type, sizeof type);
        else s = NULL;
        if (s) s = skip_blanks(s);
        if (!s || *s != ')') {
            st = npy_bad(err, path, "unsupported field (nested or shaped)");
            goto done;
        }
        s++;
        memset(&f, 0, sizeof f);
        int is_int = npy_type(type, &f);
        if (!is_int) {
            /* other fields are skipped, but their size must be known */
            const char *tt = type + (strchr("<>|=", type[0]) && type[0] ? 1 : 0);
            int sz = 0;
            if (tt[0] && isdigit((unsigned char)tt[1])) sz = atoi(tt + 1) * (tt[0] == 'U' ? 4 : 1);
            if (sz <= 0) {
                st = npy_bad(err, path, "unknown field type");
                goto done;
            }
            f.size = sz;
        }
        for (int k = 0; k < 5; k++) {
            if (strcmp(name, names[k]) == 0) {
                if (!is_int) {
                    st = npy_bad(err, path, "a field t, x, y, p or id is not an integer");
                    goto done;
                }
                fields[k] = f;
                fields[k].offset = itemsize;
                fields[k].found = 1;
            }
        }
        itemsize += (size_t)f.size;
    }
    for (int k = 0; k < 4; k++)
        if (!fields[k].found) {
            st = npy_bad(err, path, "fields t, x, y, p missing");
            goto done;
        }

    s = strstr(header, "'shape'");
    if (!s) {
        st = npy_bad(err, path, "no shape");
        goto done;
    }
    s = skip_blanks(s + 7);
    if (*s == ':') s = skip_blanks(s + 1);
    if (*s != '(') {
        st = npy_bad(err, path, "bad shape");
        goto done;
    }
    s = skip_blanks(s + 1);
    {
        char *end;
        errno = 0;
        unsigned long long v = strtoull(s, &end, 10);
        if (end == s || errno) {
            st = npy_bad(err, path, "shape is not 1-D");
            goto done;
        }
        s = skip_blanks(end);
        if (*s == ',') s = skip_blanks(s + 1);
        if (*s != ')') {
            st = npy_bad(err, path, "shape is not 1-D");
            goto done;
        }
        count = v;
    }
    if (itemsize == 0 || count > (size - start) / itemsize) {
        st = npy_bad(err, path, "file shorter than its shape");
        goto done;
    }
    if (count) {
        out = malloc((size_t)count * sizeof *out);
        if (!out) {
            snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
            st = EVR_ERR_NOMEM;
            goto done;
        }
    }
    for (size_t i = 0; i < (size_t)count; i++) {
        const unsigned char *rec = u + start + i * itemsize;
        int64_t x = npy_get(rec, &fields[1]), y = npy_get(rec, &fields[2]);
        if (x < 0 || x > 65535 || y < 0 || y > 65535) {
            st = npy_bad(err, path, "coordinate out of range");
            goto done;
        }
        memset(&out[i], 0, sizeof out[i]);
        out[i].t = npy_get(rec, &fields[0]);
        out[i].x = (uint16_t)x;
        out[i].y = (uint16_t)y;
        out[i].p = npy_get(rec, &fields[3]) > 0 ? 1 : 0;
        const int64_t id = fields[4].found ? npy_get(rec, &fields[4]) : 0;
        if (id < 0 || id > EVR_MAX_EVENT_ID) {
            st = npy_bad(err, path, "event id out of range");
            goto done;
        }
        out[i].id = (uint16_t)id;
    }
done:
    free(header);
    free(data);
    if (st != EVR_OK) {
        free(out);
        return st;
    }
    *ev = out;
    *n = (size_t)count;
    return EVR_OK;
}

/* ---- HDF5 ---- */

static evr_status read_h5(const char *path, evr_event **ev, size_t *n, int *width, int *height,
                          evr_error *err)
{
    /* events/id (the run's --event-ids) is read where the file has it */
    static const char *const names[5] = {"events/x", "events/y", "events/t", "events/p",
                                         "events/id"};
    hid_t file = -1, ds[5] = {-1, -1, -1, -1, -1};
    hsize_t count = 0;
    evr_event *out = NULL;
    uint16_t *bx = NULL, *by = NULL;
    int64_t *bt = NULL;
    int8_t *bp = NULL;
    uint32_t *bi = NULL;
    int nds = 4;
    evr_status st = EVR_OK;
    const char *what = NULL;
    int w = -1, h = -1;

    if ((st = evr_h5_regular(path, err)) != EVR_OK) return st;
    H5E_BEGIN_TRY
    {
        file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
        if (file < 0) {
            what = "cannot open as HDF5";
            st = EVR_ERR_IO;
        }
        if (st == EVR_OK && H5Lexists(file, "events", H5P_DEFAULT) > 0 &&
            H5Lexists(file, "events/id", H5P_DEFAULT) > 0)
            nds = 5;
        H5Eclear2(H5E_DEFAULT);
        for (int k = 0; k < nds && st == EVR_OK; k++) {
            hid_t space;
            hsize_t dims[1];
            ds[k] = H5Dopen2(file, names[k], H5P_DEFAULT);
            if (ds[k] < 0) {
                what = "no events/x, events/y, events/t, events/p datasets";
                st = EVR_ERR_FORMAT;
                break;
            }
            space = H5Dget_space(ds[k]);
            if (space < 0 || H5Sget_simple_extent_ndims(space) != 1 ||
                H5Sget_simple_extent_dims(space, dims, NULL) != 1) {
                what = "event datasets are not 1-D";
                st = EVR_ERR_FORMAT;
            } else if (k == 0) count = dims[0];
            else if (dims[0] != count) {
                what = "event datasets differ in length";
                st = EVR_ERR_FORMAT;
            }
            if (space >= 0) H5Sclose(space);
        }
        if (st == EVR_OK) {
            w = evr_h5_int_attr(file, "width");
            h = evr_h5_int_attr(file, "height");
            H5Eclear2(H5E_DEFAULT);
            if (count) {
                size_t block = count < READ_BLOCK ? (size_t)count : READ_BLOCK;
                out = (size_t)count <= SIZE_MAX / sizeof *out ? malloc((size_t)count * sizeof *out)
                                                              : NULL;
                bx = malloc(block * sizeof *bx);
                by = malloc(block * sizeof *by);
                bt = malloc(block * sizeof *bt);
                bp = malloc(block * sizeof *bp);
                if (nds == 5) bi = malloc(block * sizeof *bi);
                if (!out || !bx || !by || !bt || !bp || (nds == 5 && !bi)) {
                    st = EVR_ERR_NOMEM;
                    what = "out of memory";
                }
            }
        }
        for (hsize_t at = 0; st == EVR_OK && at < count; at += READ_BLOCK) {
            hsize_t start[1] = {at}, cnt[1] = {count - at < READ_BLOCK ? count - at : READ_BLOCK};
            hid_t types[5] = {H5T_NATIVE_UINT16, H5T_NATIVE_UINT16, H5T_NATIVE_INT64,
                              H5T_NATIVE_INT8, H5T_NATIVE_UINT32};
            void *bufs[5] = {bx, by, bt, bp, bi};
            hid_t mspace = H5Screate_simple(1, cnt, NULL);
            for (int k = 0; k < nds && st == EVR_OK; k++) {
                hid_t fspace = H5Dget_space(ds[k]);
                if (mspace < 0 || fspace < 0 ||
                    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0 ||
                    H5Dread(ds[k], types[k], mspace, fspace, H5P_DEFAULT, bufs[k]) < 0) {
                    what = "cannot read the events";
                    st = EVR_ERR_FORMAT;
                }
                if (fspace >= 0) H5Sclose(fspace);
            }
            if (mspace >= 0) H5Sclose(mspace);
            for (size_t i = 0; st == EVR_OK && i < (size_t)cnt[0]; i++) {
                evr_event *e = &out[(size_t)at + i];
                if (nds == 5 && bi[i] > EVR_MAX_EVENT_ID) {
                    what = "events/id holds an id past 65535";
                    st = EVR_ERR_FORMAT;
                    break;
                }
                memset(e, 0, sizeof *e);
                e->t = bt[i];
                e->x = bx[i];
                e->y = by[i];
                e->p = bp[i] > 0 ? 1 : 0;
                e->id = nds == 5 ? (uint16_t)bi[i] : 0;
            }
        }
        if (st != EVR_OK && st != EVR_ERR_NOMEM) evr_h5_fail(err, what, path, st);
        for (int k = 0; k < 5; k++)
            if (ds[k] >= 0) H5Dclose(ds[k]);
        if (file >= 0) H5Fclose(file);
        H5Eclear2(H5E_DEFAULT);
    }
    H5E_END_TRY;
    free(bx);
    free(by);
    free(bt);
    free(bp);
    free(bi);
    if (st != EVR_OK) {
        if (st == EVR_ERR_NOMEM)
            snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
        free(out);
        return st;
    }
    *ev = out;
    *n = (size_t)count;
    if (width) *width = w;
    if (height) *height = h;
    return EVR_OK;
}

evr_status evr_h5_read_ms_to_idx(const char *path, uint64_t **idx, size_t *n, evr_error *err)
{
    hid_t file = -1, ds = -1, space = -1;
    hsize_t dims[1] = {0};
    uint64_t *out = NULL;
    evr_status st = EVR_OK;
    const char *what = NULL;
    *idx = NULL;
    *n = 0;
    if ((st = evr_h5_regular(path, err)) != EVR_OK) return st;
    H5E_BEGIN_TRY
    {
        file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
        if (file < 0) {
            what = "cannot open as HDF5";
            st = EVR_ERR_IO;
        }
        if (st == EVR_OK && (ds = H5Dopen2(file, "ms_to_idx", H5P_DEFAULT)) < 0) {
            what = "no ms_to_idx dataset";
            st = EVR_ERR_FORMAT;
        }
        if (st == EVR_OK) {
            space = H5Dget_space(ds);
            if (space < 0 || H5Sget_simple_extent_ndims(space) != 1 ||
                H5Sget_simple_extent_dims(space, dims, NULL) != 1) {
                what = "ms_to_idx is not 1-D";
                st = EVR_ERR_FORMAT;
            }
        }
        if (st == EVR_OK && dims[0]) {
            out = malloc((size_t)dims[0] * sizeof *out);
            if (!out) st = EVR_ERR_NOMEM;
            else if (H5Dread(ds, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
                what = "cannot read ms_to_idx";
                st = EVR_ERR_FORMAT;
            }
        }
        if (st != EVR_OK && st != EVR_ERR_NOMEM) evr_h5_fail(err, what, path, st);
        if (space >= 0) H5Sclose(space);
        if (ds >= 0) H5Dclose(ds);
        if (file >= 0) H5Fclose(file);
        H5Eclear2(H5E_DEFAULT);
    }
    H5E_END_TRY;
    if (st != EVR_OK) {
        if (st == EVR_ERR_NOMEM)
            snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
        free(out);
        return st;
    }
    *idx = out;
    *n = (size_t)dims[0];
    return EVR_OK;
}

/* An HDF5 event file is read in a child process first (io/h5_read.h says why). */
typedef struct {
    const char *path;
    evr_error err;
} h5_probe;

static const void *h5_probe_run(void *ctx, char *msg, size_t cap)
{
    h5_probe *p = ctx;
    evr_event *ev = NULL;
    uint64_t *idx = NULL;
    size_t n = 0;
    int w, h;
    if (read_h5(p->path, &ev, &n, &w, &h, &p->err) != EVR_OK) {
        snprintf(msg, cap, "%s", p->err.msg);
        return NULL;
    }
    free(ev);
    if (evr_h5_read_ms_to_idx(p->path, &idx, &n, &p->err) == EVR_OK) free(idx); /* optional */
    return p;
}

static evr_status read_h5_isolated(const char *path, evr_event **ev, size_t *n, int *width,
                                   int *height, evr_error *err)
{
    h5_probe p;
    evr_status st;
    if ((st = evr_h5_regular(path, err)) != EVR_OK) return st;
    p.path = path;
    p.err.msg[0] = 0;
    if ((st = evr_h5_isolated(h5_probe_run, &p, path, err)) != EVR_OK) return st;
    return read_h5(path, ev, n, width, height, err);
}

evr_status evr_events_read(const char *path, evr_event **ev, size_t *n, int *width, int *height,
                           evr_error *err)
{
    evr_status st;
    *ev = NULL;
    *n = 0;
    if (width) *width = -1;
    if (height) *height = -1;
    if (!path) {
        snprintf(err->msg, sizeof err->msg, "no event file given");
        return EVR_ERR_ARG;
    }
    if (ext_is(path, "h5") || ext_is(path, "hdf5"))
        return read_h5_isolated(path, ev, n, width, height, err);
    if (ext_is(path, "txt")) st = read_txt(path, ev, n, err);
    else if (ext_is(path, "npy")) st = read_npy(path, ev, n, err);
    else if (ext_is(path, "raw") || ext_is(path, "dat") || ext_is(path, "bag") ||
             ext_is(path, "aedat4") || ext_is(path, "aedat")) {
        char *data;
        size_t size;
        st = evr_file_slurp(path, &data, &size, err);
        if (st != EVR_OK) return st;
        if (ext_is(path, "raw"))
            st = evr_raw_parse(path, (const unsigned char *)data, size, ev, n, width, height, err);
        else if (ext_is(path, "bag"))
            st = evr_rosbag_parse(path, (const unsigned char *)data, size, ev, n, width, height,
                                  err);
        else if (ext_is(path, "aedat4") || ext_is(path, "aedat"))
            st = evr_aedat4_parse(path, (const unsigned char *)data, size, ev, n, width, height,
                                  err);
        else st = evr_dat_parse(path, (const unsigned char *)data, size, ev, n, width, height, err);
        free(data);
    } else {
        snprintf(
            err->msg, sizeof err->msg,
            "%s: unknown event file type (expected .h5, .hdf5, .txt, .npy, .raw, .dat, .bag or "
            ".aedat4)",
            path);
        return EVR_ERR_ARG;
    }
    return st;
}
