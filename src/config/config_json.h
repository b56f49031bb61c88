#ifndef EVR_CONFIG_JSON_H
#define EVR_CONFIG_JSON_H

#include "evray.h"

/* c as this library's evr_config (of any size the library knows: the fields an older caller
 * lacks get their defaults) into *out; EVR_ERR_ARG for a size it does not know. */
evr_status evr_config_current(const evr_config *c, evr_config *out, evr_error *err);

/* The configuration as JSON (malloc'ed), with the values the run actually uses. */
char *evr_config_to_json(const evr_config *c, double duration, double fps, const char *scene,
                         const char *camera, const char *backend, int pretty);

#endif
