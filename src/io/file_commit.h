/* A file written under a temporary name (its path plus ".tmp"): created, and completed by closing
 * it and, if everything went well, syncing it and renaming it to its final name, otherwise
 * removing it. */
#ifndef EVR_IO_FILE_COMMIT_H
#define EVR_IO_FILE_COMMIT_H

#include <stdint.h>
#include <stdio.h>
#include "evray.h"

/* path + ".tmp", allocated (NULL when out of memory). */
char *evr_file_tmp_name(const char *path);

/* Creates (truncates) tmp for writing; NULL with a message naming who when it cannot. */
FILE *evr_file_create(const char *tmp, const char *who, evr_error *err);

/* Gives up a file: closes and removes it. */
void evr_file_discard(FILE *f, const char *tmp);

/* Makes the file tmp durable under the name path: room claimed past its end is freed
 * (io/file_room.h), tmp's data is synced to the disk, then its folder, then tmp is renamed to
 * path and the folder synced again, so that after a power loss path is either absent (or its
 * earlier self) or complete. 0, or -1 with errno set. */
int evr_file_publish(const char *tmp, const char *path);

/* Syncs the folder that holds path (after creating, renaming or removing a file in it). 0, or -1
 * with errno set. */
int evr_folder_sync(const char *path);

/* Closes f and publishes tmp as path (evr_file_publish) when everything went well; otherwise
 * removes tmp. st is the status so far (an earlier failure keeps its message); who names the writer in
 * messages. Returns the final status. */
evr_status evr_file_commit(FILE *f, const char *tmp, const char *path, evr_status st,
                           const char *who, evr_error *err);

/* The end of a failed run for a file written as one stream of appends (and, at most, a header
 * rewritten in place): closes f (what stdio holds goes out, if it can), makes tmp hold exactly
 * the stream's first keep bytes and publishes it as path. The stream was meant to be stream_end
 * bytes long, of which the last tail_len are in tail (not written yet, or their write failed);
 * the bytes the file lacks are written from there. head (head_len bytes, may be 0) is written
 * over the start (a header that depends on keep). Fails, removing tmp, when the file lacks
 * bytes that tail does not hold or cannot be written. */
evr_status evr_file_salvage(FILE *f, const char *tmp, const char *path, uint64_t keep,
                            uint64_t stream_end, const unsigned char *tail, size_t tail_len,
                            const void *head, size_t head_len, const char *who, evr_error *err);

#endif
