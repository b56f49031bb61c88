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

/* ---- numbers and sizes as options give them ---- */
/* Each returns EVR_ERR_ARG with "OPT expects ..., got 'TEXT'" when text is not a whole valid
 * value (finite numbers; integers within their type; size WIDTHxHEIGHT, 1 to 65535 a side). */
evr_status evr_parse_double(const char *opt, const char *text, double *out, evr_error *err);
evr_status evr_parse_float(const char *opt, const char *text, float *out, evr_error *err);
evr_status evr_parse_int(const char *opt, const char *text, int *out, evr_error *err);
evr_status evr_parse_u64(const char *opt, const char *text, uint64_t *out, evr_error *err);
evr_status evr_parse_size(const char *opt, const char *text, int *w, int *h, evr_error *err);

/* ---- the configuration's options (the table: src/config_table.c) ---- */
typedef struct evr_config_option evr_config_option;
/* The option that arg starts ("--res", "--res=640x480", "-o"); *name is set to the name it used
 * (the option or its short alias). NULL when arg is none of them. */
const evr_config_option *evr_config_option_find(const char *arg, const char **name);
int evr_config_option_takes_value(const evr_config_option *o);
/* Sets what the option sets from value (NULL for an option without one); strings are kept as
 * given, not copied. EVR_ERR_ARG with a one-line message when value is not valid for it. */
evr_status evr_config_option_set(evr_config *c, const evr_config_option *o, const char *value, evr_error *err);
/* The options' help, by section, as `evray render --help` shows it (malloc'ed; NULL: no memory). */
char *evr_config_options_help(void);

#ifdef __cplusplus
}
#endif
#endif
