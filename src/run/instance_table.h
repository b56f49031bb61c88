/* The names of a scene's instances as the files list them (labels.h5 and events.h5's
 * /instances): id i + 1 is instance i, named by its node's path of names and its mesh. */
#ifndef EVR_RUN_INSTANCE_TABLE_H
#define EVR_RUN_INSTANCE_TABLE_H

#include "scene/scene.h"

typedef struct {
    char **node;       /* "root/child/node" */
    const char **mesh; /* the scene's own strings */
    int n;
} evr_instance_table;

/* "root/child/node": the node's path of names (malloc'd; NULL when out of memory). */
char *evr_node_path(const evr_scene *s, int node);

/* Fills t for the scene; 0 when out of memory (t then holds nothing to free). */
int evr_instance_table_make(const evr_scene *s, evr_instance_table *t);
void evr_instance_table_free(evr_instance_table *t);

#endif
