/* evray's experimental interface: NOT a stable API. What the evray program needs beyond evray.h
 * (the configuration table for its options and --help, the output formats, event files, the
 * built-in scenes' internals for benchmarks, one-image renders). Names and types here may change
 * in any release without notice; programs that want to keep compiling use evray.h only. */
#ifndef EVRAY_EXPERIMENTAL_H
#define EVRAY_EXPERIMENTAL_H

#include "evray.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- event output formats (the registry: src/io/event_formats.c) ---- */
/* Format i (configuration bit 1 << i): its --format name and its file in the run folder; NULL
 * past the last. */
const char *evr_format_name(int i);
const char *evr_format_file(int i);
/* A comma-separated list of format names (and "all") as configuration bits; opt names the
 * option in the message. */
evr_status evr_formats_parse(const char *opt, const char *text, int *formats, evr_error *err);

#ifdef __cplusplus
}
#endif
#endif
