/* Running a reader in a child process (child_job.c says why). */
#ifndef EVR_IO_CHILD_JOB_H
#define EVR_IO_CHILD_JOB_H

#include <stddef.h>

/* A reading job: non-NULL on success; on failure NULL and one line into msg. */
typedef const void *(*evr_child_job)(void *ctx, char *msg, size_t cap);

/* Runs fn(ctx) in a child process, at most timeout_s seconds: 1 when it succeeded there, 0 when
 * it failed (msg: its line), -1 when it crashed or hung (msg says so, naming `reader`: "Assimp"),
 * -2 when no child could be made (run it here). */
int evr_child_job_run(evr_child_job fn, void *ctx, const char *reader, int timeout_s, char *msg,
                      size_t cap);

#endif
