#include "run/instance_table.h"

#include <stdlib.h>
#include <string.h>

char *evr_node_path(const evr_scene *s, int node)
{
    size_t n = 1;
    int k;
    for (k = node; k >= 0; k = s->nodes[k].parent) n += strlen(s->nodes[k].name) + 1;
    char *p = malloc(n);
    if (!p) return NULL;
    size_t at = n - 1;
    p[at] = 0;
    for (k = node; k >= 0; k = s->nodes[k].parent) {
        size_t l = strlen(s->nodes[k].name);
        at -= l;
        memcpy(p + at, s->nodes[k].name, l);
        if (at > 0) p[--at] = '/';
    }
    return p;
}

int evr_instance_table_make(const evr_scene *s, evr_instance_table *t)
{
    const size_t n = (size_t)s->num_instances;
    t->n = 0;
    t->node = calloc(n + 1, sizeof *t->node);
    t->mesh = calloc(n + 1, sizeof *t->mesh);
    if (!t->node || !t->mesh) {
        evr_instance_table_free(t);
        return 0;
    }
    for (size_t i = 0; i < n; i++) {
        if (!(t->node[i] = evr_node_path(s, s->instances[i].node))) {
            evr_instance_table_free(t);
            return 0;
        }
        t->mesh[i] = s->meshes[s->instances[i].mesh].name;
        t->n = (int)i + 1;
    }
    return 1;
}

void evr_instance_table_free(evr_instance_table *t)
{
    if (t->node)
        for (int i = 0; i < t->n; i++) free(t->node[i]);
    free(t->node);
    free(t->mesh);
    t->node = NULL;
    t->mesh = NULL;
    t->n = 0;
}
