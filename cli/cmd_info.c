#include "commands.h"
#include "evray.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            puts(
                "usage: evray info SCENE\n\nDescribes a scene as evray imports it: cameras, lights, animations and\n"
                "their time ranges, meshes, instances and triangles.");
            return 0;
        }
        if (argv[i][0] == '-') {
            fprintf(stderr, "evray: error: info: unknown option '%s'\n", argv[i]);
            return 2;
        }
        if (path) {
            fprintf(stderr, "evray: error: info takes one scene file\n");
            return 2;
        }
        path = argv[i];
    }
    if (!path) {
        fprintf(stderr, "evray: error: info needs a scene file (evray info SCENE)\n");
        return 2;
    }
    evr_scene *s = NULL;
    evr_error err = {{0}};
    if (evr_scene_load(path, &s, &err) != EVR_OK) {
        fprintf(stderr, "evray: error: %s\n", err.msg);
        return 1;
    }
    char *text = evr_scene_describe(s);
    if (text) fputs(text, stdout);
    free(text);
    evr_scene_release(s);
    return text ? 0 : 1;
}
