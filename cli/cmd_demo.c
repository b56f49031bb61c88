#include "commands.h"
#include "evray.h"
#include "options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int export_glb(const char *name, uint64_t seed, const char *path)
{
    void *glb = NULL;
    size_t n = 0;
    evr_error err = {{0}};
    char tmp[4200];
    if (evr_demo_glb_variant(name, seed, &glb, &n, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        return 1;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        cli_error("cannot write %s", path);
        free(glb);
        return 1;
    }
    int ok = fwrite(glb, 1, n, f) == n;
    ok = (fclose(f) == 0) && ok;
    free(glb);
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        cli_error("cannot write %s", path);
        return 1;
    }
    printf("wrote the '%s' scene to %s (%zu bytes)\n", name, path, n);
    return 0;
}

int cmd_demo(int argc, char **argv)
{
    const char *scene = "eye", *export_path = NULL;
    uint64_t seed = 0;
    int i, j;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            const char *const *names = evr_demo_names();
            puts(
                "usage: evray demo [--scene NAME] [--export FILE.glb | render options]\n\n"
                "Renders a built-in scene (as `evray render`, same options), or with --export writes it\n"
                "as a binary glTF file that any glTF reader (and evray render) loads.\n\n"
                "  --scene NAME    built-in scene (default eye)\n"
                "  --scene-seed N  a variant of the scene, drawn from N (0, the default: the scene\n"
                "                  itself; the eye's variants: its gaze plan and its iris)\n"
                "  --export FILE   write the scene as glTF 2.0 binary and exit\n"
                "  --list          list the built-in scenes\n"
                "  --list-variants list the scenes that take --scene-seed\n");
            fputs("scenes:", stdout);
            for (j = 0; names[j]; j++) printf(" %s", names[j]);
            fputs("\nwith variants:", stdout);
            for (j = 0; names[j]; j++)
                if (evr_demo_has_variants(names[j])) printf(" %s", names[j]);
            fputs("\n", stdout);
            return 0;
        }
        if (!strcmp(argv[i], "--list") || !strcmp(argv[i], "--list-variants")) {
            const char *const *names = evr_demo_names();
            int variants_only = !strcmp(argv[i], "--list-variants");
            for (j = 0; names[j]; j++)
                if (!variants_only || evr_demo_has_variants(names[j])) puts(names[j]);
            return 0;
        }
    }
    /* pick out --scene and --export; everything else goes to the renderer */
    char **rest = malloc(sizeof(char *) * (size_t)(argc + 1));
    int nrest = 0;
    if (!rest) return 1;
    rest[nrest++] = argv[0];
    for (i = 1; i < argc; i++) {
        if (opt_is(argv[i], "--scene")) {
            if (!(scene = opt_value(argc, argv, &i, "--scene"))) {
                free(rest);
                return 2;
            }
        } else if (opt_is(argv[i], "--scene-seed")) {
            const char *v = opt_value(argc, argv, &i, "--scene-seed");
            if (!v || !opt_u64("--scene-seed", v, &seed)) {
                free(rest);
                return 2;
            }
        } else if (opt_is(argv[i], "--export")) {
            if (!(export_path = opt_value(argc, argv, &i, "--export"))) {
                free(rest);
                return 2;
            }
        } else {
            rest[nrest++] = argv[i];
        }
    }
    rest[nrest] = NULL;
    int rc;
    if (export_path) {
        if (nrest > 1) {
            cli_error("demo --export takes no render options (got '%s')", rest[1]);
            rc = 2;
        } else {
            rc = export_glb(scene, seed, export_path);
        }
    } else {
        rc = cmd_render(nrest, rest, scene, seed);
    }
    free(rest);
    return rc;
}
