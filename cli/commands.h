#ifndef EVR_CLI_COMMANDS_H
#define EVR_CLI_COMMANDS_H

#include <stdint.h>
/* Each returns the process exit code: 0 success, 1 failure, 2 usage error, 130 interrupted. */
int cmd_render(int argc, char **argv, const char *default_demo, uint64_t demo_seed);
int cmd_info(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_plot(int argc, char **argv);
int cmd_still(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_dataset(int argc, char **argv);

#include "evray.h"

/* The options shared by render, demo and bench. A --sensor preset sets defaults that the other
 * options override whatever their order on the command line: parse_render_option takes each
 * option into cfg and notes where it stood; render_options_finish then starts again from base,
 * applies the preset and replays the other options over it. */
typedef struct {
    evr_config cfg;  /* the configuration (final after render_options_finish) */
    evr_config base; /* the configuration before any option */
    int quiet;
    const char *sensor;    /* the last --sensor given, NULL: none */
    unsigned char *starts; /* per argv index: 1 where a render option starts */
    int argc;
} render_options;

/* 0 when out of memory (after an error message). */
int render_options_init(render_options *ro, const evr_config *base, int quiet, int argc);
/* 1 when argv[*i] (and its value) was a render option, 0 when it is not one, -1 after an error. */
int parse_render_option(int argc, char **argv, int *i, render_options *ro);
/* Applies the preset and the options over it; 0 after an error message. */
int render_options_finish(render_options *ro, int argc, char **argv);
void render_options_free(render_options *ro);

#endif
