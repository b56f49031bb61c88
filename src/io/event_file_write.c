/* evr_events_write: a whole event array to a file of the format its name says (evray convert). */
#include "io/event_formats.h"
#include "evray_experimental.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

#define WRITE_BLOCK ((size_t)1 << 20) /* events per write() call */

static int ends_with(const char *s, const char *end)
{
    size_t ls = strlen(s), le = strlen(end);
    if (ls < le) return 0;
    for (size_t i = 0; i < le; i++)
        if (tolower((unsigned char)s[ls - le + i]) != end[i]) return 0;
    return 1;
}

/* The registered format whose longest suffix ends the file name; NULL: none. */
static const evr_event_format *format_of(const char *path)
{
    int count;
    const evr_event_format *const *formats = evr_event_formats(&count), *best = NULL;
    size_t best_len = 0;
    for (int i = 0; i < count; i++) {
        const char *p = formats[i]->suffixes;
        while (p && *p) {
            char suffix[32];
            size_t n = strcspn(p, " ");
            if (n > 0 && n < sizeof suffix) {
                memcpy(suffix, p, n);
                suffix[n] = 0;
                if (n > best_len && ends_with(path, suffix)) {
                    best = formats[i];
                    best_len = n;
                }
            }
            p += n;
            p += strspn(p, " ");
        }
    }
    return best;
}

int evr_events_format_holds_ids(const char *path)
{
    const evr_event_format *f = path ? format_of(path) : NULL;
    return f ? f->holds_ids : -1;
}

evr_status evr_events_write(const char *path, const evr_event *ev, size_t n, int width, int height,
                            evr_error *err)
{
    const evr_event_format *f = path ? format_of(path) : NULL;
    evr_writer_meta meta;
    evr_event_writer *w = NULL;
    evr_status st;
    if (!f) {
        char known[256] = "";
        int count;
        const evr_event_format *const *formats = evr_event_formats(&count);
        for (int i = 0; i < count; i++) {
            size_t len = strlen(known);
            snprintf(known + len, sizeof known - len, "%s%s (%s)", i ? ", " : "",
                     formats[i]->suffixes, formats[i]->name);
        }
        snprintf(err->msg, sizeof err->msg,
                 "%s: unknown event file type (expected a name ending in %s)",
                 path ? path : "(none)", known);
        return EVR_ERR_ARG;
    }
    memset(&meta, 0, sizeof meta);
    meta.width = width;
    meta.height = height;
    for (size_t i = 0; i < n; i++) {
        if (ev[i].id && f->holds_ids) meta.event_ids = 1; /* kept where the format holds them */
        if (ev[i].t > meta.max_t_us) meta.max_t_us = ev[i].t;
        if (width <= 0 && ev[i].x >= meta.width) meta.width = ev[i].x + 1;
        if (height <= 0 && ev[i].y >= meta.height) meta.height = ev[i].y + 1;
    }
    if (meta.width <= 0) meta.width = 1;
    if (meta.height <= 0) meta.height = 1;
    st = f->open(path, &meta, &w, err);
    if (st != EVR_OK) return st;
    for (size_t at = 0; at < n && st == EVR_OK; at += WRITE_BLOCK) {
        size_t len = n - at < WRITE_BLOCK ? n - at : WRITE_BLOCK;
        st = w->write(w, ev + at, len, err);
    }
    if (st != EVR_OK) {
        w->abort(w);
        return st;
    }
    return w->finish(w, n ? meta.max_t_us + 1 : 0, err);
}
