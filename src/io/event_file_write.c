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

/* The registry's name of the format a file name asks for; NULL: none. */
static const char *format_of(const char *path)
{
    if (ends_with(path, ".h5") || ends_with(path, ".hdf5")) return "h5";
    if (ends_with(path, ".txt")) return "txt";
    if (ends_with(path, ".npy")) return "npy";
    if (ends_with(path, ".dat")) return "dat";
    if (ends_with(path, "evt2.raw")) return "evt2";
    if (ends_with(path, ".raw")) return "evt3"; /* the IMX636 cameras' default */
    return NULL;
}

evr_status evr_events_write(const char *path, const evr_event *ev, size_t n, int width, int height,
                            evr_error *err)
{
    const char *name = path ? format_of(path) : NULL;
    const evr_event_format *const *formats;
    const evr_event_format *f = NULL;
    evr_writer_meta meta;
    evr_event_writer *w = NULL;
    evr_status st;
    int count;
    if (!name) {
        snprintf(
            err->msg, sizeof err->msg,
            "%s: unknown event file type (expected .h5, .hdf5, .txt, .npy, .dat, .raw: EVT 3.0, "
            "or a name ending in evt2.raw: EVT 2.0)",
            path ? path : "(none)");
        return EVR_ERR_ARG;
    }
    formats = evr_event_formats(&count);
    for (int i = 0; i < count; i++)
        if (!strcmp(formats[i]->name, name)) f = formats[i];
    if (!f) {
        snprintf(err->msg, sizeof err->msg, "%s: format %s is not in this build", path, name);
        return EVR_ERR_ARG;
    }
    memset(&meta, 0, sizeof meta);
    meta.width = width;
    meta.height = height;
    for (size_t i = 0; i < n; i++) {
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
