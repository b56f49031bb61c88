/* Opening an input file: only a regular file is read. A FIFO would block the open or the reads
 * for ever, a device such as /dev/zero never ends and /dev/random never repeats: a scene,
 * a texture, a buffer or an event file that names one is refused at once, with one line. */
#ifndef EVR_IO_FILE_READ_H
#define EVR_IO_FILE_READ_H

#include <stdio.h>

/* Opens path for reading ("rb") when it is a regular file (after symbolic links). NULL when it
 * cannot be opened or is not a regular file: *why then says why in a few words ("No such file or
 * directory", "it is a FIFO, not a regular file"; a static string). */
FILE *evr_fopen_regular(const char *path, const char **why);

/* 1 when path names a regular file (after symbolic links); else 0 and *why as above. */
int evr_is_regular_file(const char *path, const char **why);

#endif
