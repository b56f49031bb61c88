#ifndef EVR_CLI_COMMANDS_H
#define EVR_CLI_COMMANDS_H

/* Each returns the process exit code: 0 success, 1 failure, 2 usage error, 130 interrupted. */
int cmd_render(int argc, char **argv, const char *default_demo);
int cmd_info(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_bench(int argc, char **argv);

#include "evray.h"
int parse_render_option(int argc, char **argv, int *i, evr_config *cfg, int *quiet);

#endif
