#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_convert(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL};
    int np = 0, quiet = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            puts(
                "usage: evray convert IN OUT [--quiet]\n\n"
                "Reads every event of IN and writes them, in the same order, to OUT; each file's format\n"
                "comes from its name: .h5/.hdf5 (DSEC layout), .txt, .npy, .dat (Prophesee DAT),\n"
                ".raw (Prophesee EVT 3.0, or EVT 2.0 for a name ending in evt2.raw; reading, the\n"
                "header says which), .bag (ROS1, dvs_msgs/EventArray; reading, chunks may be bz2\n"
                "or lz4), .aedat4 (iniVation AEDAT 4.0, LZ4, or ZSTD for a name ending in\n"
                "zstd.aedat4; reading, .aedat too: the first event stream of a camera's recording).\n"
                "Width and height come from IN when it stores them, else from the largest x and y.\n"
                "What OUT's format cannot hold (a pixel or a time past its fields) is refused and\n"
                "OUT is not written.");
            return 0;
        }
        if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) quiet = 1;
        else if (a[0] == '-' && a[1]) {
            cli_error("convert: unknown option '%s'", a);
            return 2;
        } else if (np < 2) paths[np++] = a;
        else {
            cli_error("convert takes two event files");
            return 2;
        }
    }
    if (np != 2) {
        cli_error("convert needs two event files (evray convert IN OUT)");
        return 2;
    }
    evr_event *ev = NULL;
    size_t n = 0;
    int width = -1, height = -1;
    evr_error err = {{0}};
    if (evr_events_read(paths[0], &ev, &n, &width, &height, &err) != EVR_OK ||
        evr_events_write(paths[1], ev, n, width, height, &err) != EVR_OK) {
        cli_error("%s", err.msg);
        free(ev);
        return 1;
    }
    size_t with_id = 0;
    for (size_t i = 0; i < n; i++) with_id += ev[i].id != 0;
    free(ev);
    if (with_id && evr_events_format_holds_ids(paths[1]) == 0 && !quiet)
        fprintf(stderr,
                "evray: note: %s has no place for event ids: the ids of %zu events are left out\n",
                paths[1], with_id);
    if (!quiet) printf("%zu events: %s -> %s\n", n, paths[0], paths[1]);
    return 0;
}
