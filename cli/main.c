/* evray: the command-line program. */
#include "commands.h"
#include "evray.h"

#include <stdio.h>
#include <string.h>

static void usage(FILE *f)
{
    fputs(
        "usage: evray [COMMAND] [OPTIONS]\n"
        "\n"
        "Simulates an event camera (DVS) looking at an animated 3D scene, with a ray tracer.\n"
        "With no command, renders the built-in eye demo into ./evray-out/.\n"
        "\n"
        "commands:\n"
        "  render SCENE [options]   render a scene file (glTF 2.0 .glb/.gltf or any format Assimp reads)\n"
        "  info SCENE               describe a scene: cameras, lights, animations, meshes, triangles\n"
        "  demo [--scene NAME] ...  render a built-in scene, or export it with --export FILE.glb\n"
        "  bench [--scene NAME] ... one run, one row of speed figures (samples/s, rays/s, real-time factor)\n"
        "  plot EVENTS [-o PNG]     event rate over time (ON/OFF per bin) and an events-per-pixel heat map\n"
        "  compare REF TEST         accuracy of an event file against a reference (precision, recall, F1)\n"
        "  still SCENE -o OUT.png   one image at one time, optionally with global illumination (--gi)\n"
        "  convert IN OUT           an event file to another format (h5, txt, npy, EVT 2.0/3.0 raw, dat, bag, aedat4)\n"
        "  dataset SPEC -o DIR      many runs (clips) from one specification, on every GPU and core or a Dask cluster\n"
        "\n"
        "  evray COMMAND --help     options of a command\n"
        "  evray --version          version of evray and its libraries\n",
        f);
}

int main(int argc, char **argv)
{
    if (argc < 2) return cmd_render(argc, argv, "eye", 0);
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h") || !strcmp(c, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(c, "--version") || !strcmp(c, "-V")) {
        printf("evray %s\n", evr_version());
        return 0;
    }
    if (!strcmp(c, "render")) return cmd_render(argc - 1, argv + 1, NULL, 0);
    if (!strcmp(c, "info")) return cmd_info(argc - 1, argv + 1);
    if (!strcmp(c, "demo")) return cmd_demo(argc - 1, argv + 1);
    if (!strcmp(c, "compare")) return cmd_compare(argc - 1, argv + 1);
    if (!strcmp(c, "bench")) return cmd_bench(argc - 1, argv + 1);
    if (!strcmp(c, "plot")) return cmd_plot(argc - 1, argv + 1);
    if (!strcmp(c, "still")) return cmd_still(argc - 1, argv + 1);
    if (!strcmp(c, "convert")) return cmd_convert(argc - 1, argv + 1);
    if (!strcmp(c, "dataset")) return cmd_dataset(argc - 1, argv + 1);
    if (c[0] == '-') return cmd_render(argc, argv, "eye", 0); /* options for the default job */
    fprintf(stderr, "evray: error: unknown command '%s' (try evray --help)\n", c);
    return 2;
}
