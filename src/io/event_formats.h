/* The registry of event output formats: one row per format (its --format name, its file in the
 * run folder, the function that opens its writer, a line of help). Format i is the configuration
 * bit 1 << i (evr_config.formats), so the registry's order is the order of the public
 * EVR_FORMAT_* constants. Adding a format: its writer's .c (an evr_event_format named
 * evr_format_NAME), one line in event_formats.c, and a test. */
#ifndef EVR_IO_EVENT_FORMATS_H
#define EVR_IO_EVENT_FORMATS_H

#include "io/event_writer.h"

typedef struct {
    const char *name;  /* --format name, and run.json's */
    const char *alias; /* another --format name, or NULL */
    const char *file;  /* its file in the run folder */
    evr_status (*open)(const char *path, const evr_writer_meta *meta, evr_event_writer **out,
                       evr_error *err);
    const char *help;     /* what the file is, in a few words */
    const char *suffixes; /* file name endings that ask for it (evray convert), space-separated */
    int holds_ids;        /* it writes evr_event.id (evr_writer_meta.event_ids) */
} evr_event_format;

/* The formats, in bit order; *count is set to their number. */
const evr_event_format *const *evr_event_formats(int *count);
/* Every format's bit. */
int evr_event_formats_all(void);
/* Parses a comma-separated list of names (and "all") into format bits; opt names the option in
 * the message. */
evr_status evr_event_formats_parse(const char *opt, const char *text, int *formats, evr_error *err);

#endif
