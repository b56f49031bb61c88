/* The event output formats: the one list that --format, the run folder's writers, run.json and
 * the help are made from. */
#include "io/event_formats.h"
#include "evray_experimental.h"

#include <stdio.h>
#include <string.h>

/* Defined beside each writer. */
extern const evr_event_format evr_format_h5, evr_format_txt, evr_format_npy, evr_format_evt2,
    evr_format_evt3, evr_format_dat, evr_format_rosbag, evr_format_aedat4, evr_format_aedat4_zstd;

/* Format i is configuration bit 1 << i: new formats go at the end. */
static const evr_event_format *const formats[] = {
    &evr_format_h5,          /* h5_writer.c */
    &evr_format_txt,         /* txt_writer.c */
    &evr_format_npy,         /* npy_writer.c */
    &evr_format_evt2,        /* evt2_writer.c */
    &evr_format_evt3,        /* evt3_writer.c */
    &evr_format_dat,         /* dat_writer.c */
    &evr_format_rosbag,      /* rosbag_writer.c */
    &evr_format_aedat4,      /* aedat4_writer.c */
    &evr_format_aedat4_zstd, /* aedat4_writer.c */
};

#define NUM_FORMATS ((int)(sizeof formats / sizeof formats[0]))

const evr_event_format *const *evr_event_formats(int *count)
{
    *count = NUM_FORMATS;
    return formats;
}

int evr_event_formats_all(void) { return (1 << NUM_FORMATS) - 1; }

evr_status evr_event_formats_parse(const char *opt, const char *text, int *out, evr_error *err)
{
    char buf[256], names[256] = "";
    int f = 0, i;
    size_t len = 0;
    if (strlen(text) >= sizeof buf) {
        snprintf(err->msg, sizeof err->msg, "%s: value too long", opt);
        return EVR_ERR_ARG;
    }
    strcpy(buf, text);
    char *tok = buf, *next;
    for (; tok; tok = next) {
        next = strchr(tok, ',');
        if (next) *next++ = 0;
        if (!strcmp(tok, "all")) {
            f |= evr_event_formats_all();
            continue;
        }
        for (i = 0; i < NUM_FORMATS; i++)
            if (!strcmp(tok, formats[i]->name) ||
                (formats[i]->alias && !strcmp(tok, formats[i]->alias)))
                break;
        if (i == NUM_FORMATS) {
            for (i = 0; i < NUM_FORMATS; i++)
                len += (size_t)snprintf(names + len, sizeof names - len, "%s, ", formats[i]->name);
            snprintf(err->msg, sizeof err->msg, "%s: unknown format '%s' (%sall; comma-separated)",
                     opt, tok, names);
            return EVR_ERR_ARG;
        }
        f |= 1 << i;
    }
    *out = f;
    return EVR_OK;
}

const char *evr_format_name(int i) { return i >= 0 && i < NUM_FORMATS ? formats[i]->name : NULL; }
const char *evr_format_file(int i) { return i >= 0 && i < NUM_FORMATS ? formats[i]->file : NULL; }

evr_status evr_formats_parse(const char *opt, const char *text, int *out, evr_error *err)
{
    return evr_event_formats_parse(opt, text, out, err);
}
