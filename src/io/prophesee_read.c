#include "io/prophesee_read.h"
#include "io/byte_order.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- growing event array ---- */

typedef struct {
    evr_event *ev;
    size_t n, cap;
} event_list;

static int push(event_list *l, int64_t t, unsigned x, unsigned y, int p)
{
    if (l->n == l->cap) {
        size_t ncap = l->cap ? l->cap * 2 : 1 << 16;
        evr_event *q = realloc(l->ev, ncap * sizeof *q);
        if (!q) return 0;
        l->ev = q;
        l->cap = ncap;
    }
    evr_event *e = &l->ev[l->n++];
    memset(e, 0, sizeof *e);
    e->t = t;
    e->x = (uint16_t)x;
    e->y = (uint16_t)y;
    e->p = (int8_t)(p ? 1 : 0);
    e->id = 0;
    return 1;
}

static evr_status fail(evr_error *err, const char *path, const char *why, event_list *l)
{
    snprintf(err->msg, sizeof err->msg, "%s: %s", path, why);
    free(l->ev);
    l->ev = NULL;
    return EVR_ERR_FORMAT;
}

static evr_status out_of_memory(evr_error *err, const char *path, event_list *l)
{
    snprintf(err->msg, sizeof err->msg, "out of memory reading %s", path);
    free(l->ev);
    l->ev = NULL;
    return EVR_ERR_NOMEM;
}

static evr_status done(event_list *l, evr_event **ev, size_t *n)
{
    *ev = l->ev;
    *n = l->n;
    if (!l->n) {
        free(l->ev);
        *ev = NULL;
    }
    return EVR_OK;
}

/* ---- header: lines starting with '%', up to "% end" or the first line without '%' ---- */

typedef struct {
    int evt; /* 2 or 3 from "% evt 2.0" / "% format EVT2"; 0: none */
    int width, height;
    size_t end; /* the first byte after the header */
    char encoding[32];
} header_info;

static int line_value(const char *line, size_t len, const char *key, const char **val)
{
    size_t k = strlen(key);
    if (len < k + 1 || strncmp(line, key, k) != 0 || line[k] != ' ') return 0;
    *val = line + k + 1;
    return 1;
}

static void parse_header(const unsigned char *data, size_t size, header_info *h)
{
    size_t at = 0;
    memset(h, 0, sizeof *h);
    h->width = h->height = -1;
    while (at < size && data[at] == '%') {
        const unsigned char *nl = memchr(data + at, '\n', size - at);
        size_t len = nl ? (size_t)(nl - (data + at)) : size - at;
        char line[256];
        const char *v;
        size_t m = len < sizeof line - 1 ? len : sizeof line - 1;
        memcpy(line, data + at, m);
        line[m] = 0;
        at += len + (nl ? 1 : 0);
        if (m >= 2 && line[m - 1] == '\r') line[--m] = 0;
        if (!strcmp(line, "% end")) break;
        if (m < 2) continue;
        const char *s = line + 2;
        size_t sl = m - 2;
        if (line_value(s, sl, "evt", &v)) {
            if (!strcmp(v, "2.0")) h->evt = 2;
            else if (!strcmp(v, "3.0")) h->evt = 3;
            else snprintf(h->encoding, sizeof h->encoding, "evt %s", v);
        } else if (line_value(s, sl, "format", &v)) {
            const char *hh = strstr(v, "height="), *ww = strstr(v, "width=");
            if (!strncmp(v, "EVT2;", 5) || !strcmp(v, "EVT2")) h->evt = 2;
            else if (!strncmp(v, "EVT3;", 5) || !strcmp(v, "EVT3")) h->evt = 3;
            else snprintf(h->encoding, sizeof h->encoding, "%.*s", (int)strcspn(v, ";"), v);
            if (hh) h->height = atoi(hh + 7);
            if (ww) h->width = atoi(ww + 6);
        } else if (line_value(s, sl, "geometry", &v) && h->width < 0) {
            int w, hg;
            if (sscanf(v, "%dx%d", &w, &hg) == 2) {
                h->width = w;
                h->height = hg;
            }
        } else if (line_value(s, sl, "Height", &v)) h->height = atoi(v);
        else if (line_value(s, sl, "Width", &v)) h->width = atoi(v);
    }
    h->end = at;
}

/* ---- EVT 2.0 ---- */

static evr_status parse_evt2(const char *path, const unsigned char *d, size_t size, event_list *l,
                             evr_error *err)
{
    int64_t high = -1;
    if (size % 4) return fail(err, path, "truncated EVT 2.0 stream (not whole 32-bit words)", l);
    for (size_t i = 0; i < size; i += 4) {
        uint32_t w = evr_get_le32(d + i);
        switch (w >> 28) {
        case 0x0:
        case 0x1:
            if (high < 0)
                return fail(err, path,
                            "corrupt EVT 2.0 stream (CD event before the first time-high word)", l);
            if (!push(l, high << 6 | (w >> 22 & 63), w >> 11 & 0x7ff, w & 0x7ff, (int)(w >> 28)))
                return out_of_memory(err, path, l);
            break;
        case 0x8: high = w & 0xfffffff; break;
        case 0xA:
        case 0xE:
        case 0xF: break; /* triggers and extensions: not events */
        default: {
            char why[96];
            snprintf(why, sizeof why, "corrupt EVT 2.0 stream (unknown word type 0x%X at byte %zu)",
                     (unsigned)(w >> 28), i);
            return fail(err, path, why, l);
        }
        }
    }
    return EVR_OK;
}

/* ---- EVT 3.0 ---- */

static evr_status parse_evt3(const char *path, const unsigned char *d, size_t size, event_list *l,
                             evr_error *err)
{
    int64_t loops = 0;
    int high = -1, low = 0, y = -1, base_x = -1, pol = 0;
    char why[112];
    if (size % 2) return fail(err, path, "truncated EVT 3.0 stream (not whole 16-bit words)", l);
    for (size_t i = 0; i < size; i += 2) {
        uint32_t w = evr_get_le16(d + i), type = w >> 12, v = w & 0xfff;
        int64_t t = (loops << 24) | (int64_t)(high < 0 ? 0 : high) << 12 | low;
        if ((type == 0x2 || type == 0x4 || type == 0x5) && (high < 0 || y < 0)) {
            snprintf(why, sizeof why,
                     "corrupt EVT 3.0 stream (event before the first %s word at byte %zu)",
                     high < 0 ? "time-high" : "y", i);
            return fail(err, path, why, l);
        }
        if ((type == 0x4 || type == 0x5) && base_x < 0) {
            snprintf(why, sizeof why,
                     "corrupt EVT 3.0 stream (vector before its base x at byte %zu)", i);
            return fail(err, path, why, l);
        }
        switch (type) {
        case 0x0: y = (int)(v & 0x7ff); break;
        case 0x2:
            if (!push(l, t, v & 0x7ff, (unsigned)y, (int)(v >> 11)))
                return out_of_memory(err, path, l);
            break;
        case 0x3:
            base_x = (int)(v & 0x7ff);
            pol = (int)(v >> 11);
            break;
        case 0x4:
        case 0x5: {
            int bits = type == 0x4 ? 12 : 8;
            for (int b = 0; b < bits; b++)
                if (v >> b & 1 && !push(l, t, (unsigned)(base_x + b), (unsigned)y, pol))
                    return out_of_memory(err, path, l);
            base_x += bits;
            break;
        }
        case 0x6: low = (int)v; break;
        case 0x8:
            if (high >= 0 && (int)v < high) loops++; /* the 24-bit time wrapped */
            high = (int)v;
            break;
        case 0x7:
        case 0xA:
        case 0xE:
        case 0xF: break; /* continued data, triggers and extensions: not events */
        default:
            snprintf(why, sizeof why, "corrupt EVT 3.0 stream (unknown word type 0x%X at byte %zu)",
                     (unsigned)type, i);
            return fail(err, path, why, l);
        }
    }
    return EVR_OK;
}

evr_status evr_raw_parse(const char *path, const unsigned char *data, size_t size, evr_event **ev,
                         size_t *n, int *width, int *height, evr_error *err)
{
    header_info h;
    event_list l = {NULL, 0, 0};
    evr_status st;
    parse_header(data, size, &h);
    if (h.end == 0) return fail(err, path, "not a Prophesee RAW file (no '%' header lines)", &l);
    if (h.evt == 0) {
        char why[128];
        if (h.encoding[0])
            snprintf(why, sizeof why, "unsupported RAW encoding '%s' (EVT 2.0 and 3.0 are read)",
                     h.encoding);
        else
            snprintf(why, sizeof why, "not a Prophesee RAW file (no '%% evt' or '%% format' line)");
        return fail(err, path, why, &l);
    }
    st = h.evt == 2 ? parse_evt2(path, data + h.end, size - h.end, &l, err)
                    : parse_evt3(path, data + h.end, size - h.end, &l, err);
    if (st != EVR_OK) return st;
    if (width) *width = h.width;
    if (height) *height = h.height;
    return done(&l, ev, n);
}

/* ---- DAT ---- */

evr_status evr_dat_parse(const char *path, const unsigned char *data, size_t size, evr_event **ev,
                         size_t *n, int *width, int *height, evr_error *err)
{
    header_info h;
    event_list l = {NULL, 0, 0};
    parse_header(data, size, &h);
    if (h.end == 0) return fail(err, path, "not a Prophesee DAT file (no '%' header lines)", &l);
    if (size - h.end < 2) return fail(err, path, "truncated DAT file (no event type and size)", &l);
    const unsigned type = data[h.end], esize = data[h.end + 1];
    if ((type != 0x0C && type != 0x00) || esize != 8) {
        char why[112];
        snprintf(
            why, sizeof why,
            "unsupported DAT events (type 0x%02X, size %u; CD events 0x0C of 8 bytes are read)",
            type, esize);
        return fail(err, path, why, &l);
    }
    const unsigned char *d = data + h.end + 2;
    size_t len = size - h.end - 2;
    if (len % 8) return fail(err, path, "truncated DAT file (not whole 8-byte events)", &l);
    for (size_t i = 0; i < len; i += 8) {
        uint32_t a = evr_get_le32(d + i + 4);
        if (!push(&l, evr_get_le32(d + i), a & 0x3fff, a >> 14 & 0x3fff, (int)(a >> 28)))
            return out_of_memory(err, path, &l);
    }
    if (width) *width = h.width;
    if (height) *height = h.height;
    return done(&l, ev, n);
}
