#ifndef EVR_CONFIG_JSON_H
#define EVR_CONFIG_JSON_H

#include "evray.h"

/* The configuration as JSON (malloc'ed), with the values the run actually uses. */
char *evr_config_to_json(const evr_config *c, double duration, double fps, const char *scene, const char *camera,
                         const char *backend, int pretty);

#endif
