/* evray dataset: many runs from one specification. The runner is the Python package's
 * evray/dataset.py (jobs, a Dask cluster, the manifest); this command hands it the arguments and
 * this program's own path, so that every clip runs the same evray. */
#include "commands.h"
#include "options.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The runner beside the program: a build in the source tree (build/evray) finds
 * python/evray/dataset.py one or two folders up. */
static int find_script(const char *exe, char *out, size_t n)
{
    const char *env = getenv("EVRAY_DATASET_SCRIPT");
    if (env && *env) {
        snprintf(out, n, "%s", env);
        return access(out, R_OK) == 0;
    }
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", exe);
    char *slash = strrchr(dir, '/');
    if (!slash) return 0;
    *slash = '\0';
    static const char *const up[] = {"/../python/evray/dataset.py",
                                     "/../../python/evray/dataset.py"};
    for (size_t i = 0; i < sizeof up / sizeof up[0]; i++) {
        if ((size_t)snprintf(out, n, "%s%s", dir, up[i]) >= n) continue;
        if (access(out, R_OK) == 0) return 1;
    }
    return 0;
}

int cmd_dataset(int argc, char **argv)
{
    char exe[PATH_MAX], script[PATH_MAX + 64];
    const ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (len <= 0) {
        cli_error("dataset: cannot find this program's own path");
        return 1;
    }
    exe[len] = '\0';
    const int have_script = find_script(exe, script, sizeof script);
    /* python3 [SCRIPT | -m evray.dataset] --evray EXE ARGS... (a later --evray of ARGS wins) */
    char **args = malloc(sizeof(char *) * (size_t)(argc + 6));
    if (!args) return 1;
    int k = 0;
    args[k++] = "python3";
    if (have_script) {
        args[k++] = script;
    } else {
        args[k++] = "-m";
        args[k++] = "evray.dataset";
    }
    args[k++] = "--evray";
    args[k++] = exe;
    for (int i = 1; i < argc; i++) args[k++] = argv[i];
    args[k] = NULL;
    fflush(NULL);
    execvp("python3", args);
    cli_error("dataset: cannot run python3 (%s); the dataset runner is Python (Debian: apt-get "
              "install python3)",
              strerror(errno));
    free(args);
    return 1;
}
