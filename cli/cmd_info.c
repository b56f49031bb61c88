#include "commands.h"
#include "evray.h"
#include "options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_info(int argc, char **argv)
{
    const char *path = NULL, *animation = NULL;
    int i, r, strict = 0, external = 0;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(
                "usage: evray info SCENE [--animation CLIP] [--strict] [--allow-external-files]\n\nDescribes a scene as evray imports it: cameras, lights, animation clips (each\n"
                "one's duration, as --duration takes it, and whether it plays), animated nodes and\n"
                "their time ranges, meshes, instances and triangles, and what evray leaves out of\n"
                "the file (warnings).\n\n" CLI_ANIMATION_HELP CLI_STRICT_HELP CLI_EXTERNAL_HELP,
                stdout);
            return 0;
        }
        if ((r = cli_is_animation_option(argc, argv, &i, &animation)) != 0) {
            if (r < 0) return 2;
            continue;
        }
        if (!strcmp(argv[i], "--strict")) {
            strict = 1;
            continue;
        }
        if (!strcmp(argv[i], "--allow-external-files")) {
            external = 1;
            continue;
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
    /* quiet: the description says which clips play and why the others do not */
    evr_scene *s = cli_load_scene(path, NULL, 0, animation, strict, external, CLI_LOAD_DESCRIBED);
    if (!s) return 1;
    char *text = evr_scene_describe(s);
    if (text) fputs(text, stdout);
    free(text);
    evr_scene_release(s);
    return text ? 0 : 1;
}
