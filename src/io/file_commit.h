/* A file written under a temporary name (its path plus ".tmp"): created, and completed by closing
 * it and, if everything went well, renaming it to its final name, otherwise removing it. */
#ifndef EVR_IO_FILE_COMMIT_H
#define EVR_IO_FILE_COMMIT_H

#include <stdio.h>
#include "evray.h"

/* path + ".tmp", allocated (NULL when out of memory). */
char *evr_file_tmp_name(const char *path);

/* Creates (truncates) tmp for writing; NULL with a message naming who when it cannot. */
FILE *evr_file_create(const char *tmp, const char *who, evr_error *err);

/* Gives up a file: closes and removes it. */
void evr_file_discard(FILE *f, const char *tmp);

/* st is the status so far (an earlier failure keeps its message); who names the writer in
 * messages. Returns the final status. */
evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st,
                           const char *who, evr_error *err);

#endif
