/* Completing a file written under a temporary name: close it and, if everything went well, rename
 * it to its final name; otherwise remove it. */
#ifndef EVR_IO_FILE_COMMIT_H
#define EVR_IO_FILE_COMMIT_H

#include <stdio.h>
#include "evray.h"

/* st is the status so far (an earlier failure keeps its message); who names the writer in
 * messages. Returns the final status. */
evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st, const char *who, evr_error *err);

#endif
