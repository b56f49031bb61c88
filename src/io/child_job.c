/* A job run in a child process, for the third-party readers that crash, hang and leak on
 * malformed files: Assimp's importers of the formats other than glTF (a glTF is checked before
 * Assimp reads it: scene/import_gltf_validate.c; tests/fuzz/fuzz_scene_assimp.c finds PLY files
 * that crash or hang Assimp, Collada and STL files that leak, in minutes) and HDF5 1.10 (a 26 KB
 * file makes it divide by zero: tests/fuzz/fuzz_events_h5.c). A file is read once in a child
 * first: a crash or a hang there is one error line, a failure is the reader's message without
 * its leaks, and only a file the child read completely is read again in the caller's process.
 * The child shares nothing but a pipe (a status byte and the message), and leaves with _exit. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "io/child_job.h"

/* Set by a sanitizer runtime (the fuzz builds); absent otherwise. */
extern void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

static void child(evr_child_job fn, void *ctx, int fd)
{
    static const int deadly[] = {SIGSEGV, SIGBUS,  SIGFPE, SIGILL,
                                 SIGABRT, SIGALRM, SIGINT, SIGTERM};
    char msg[512];
    int null = open("/dev/null", O_WRONLY), k;
    /* The child dies of its crash as it is: no handler of the caller's (a fuzzer's would save
     * the input as a crash of its own, which the parent has contained) */
    for (k = 0; k < (int)(sizeof deadly / sizeof *deadly); k++) signal(deadly[k], SIG_DFL);
    if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(NULL);
    /* Assimp's own assertion messages: the parent says what happened, in one line */
    if (null >= 0) {
        dup2(null, 1);
        dup2(null, 2);
        close(null);
    }
    msg[0] = 0;
    msg[1] = 0;
    msg[0] = fn(ctx, msg + 1, sizeof msg - 1) ? '1' : '0';
    (void)!write(fd, msg, 1 + strlen(msg + 1));
    _exit(0);
}

/* Milliseconds since an arbitrary start. */
static long long now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

int evr_child_job_run(evr_child_job fn, void *ctx, const char *reader, int timeout_s, char *msg,
                      size_t cap)
{
    int fds[2], status = 0, got_status = 0;
    char buf[512];
    size_t have = 0;
    long long end = now_ms() + 1000LL * timeout_s;
    pid_t pid;
    msg[0] = 0;
    if (pipe(fds) != 0) return -2;
    pid = fork(); /* the child leaves by _exit: what the caller has buffered is not written twice */
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return -2;
    }
    if (pid == 0) {
        close(fds[0]);
        child(fn, ctx, fds[1]);
    }
    close(fds[1]);
    for (;;) {
        struct pollfd p;
        long long left = end - now_ms();
        ssize_t n;
        if (left <= 0) break;
        p.fd = fds[0];
        p.events = POLLIN;
        if (poll(&p, 1, (int)(left > 1000 ? 1000 : left)) < 0 && errno != EINTR) break;
        if (!(p.revents & (POLLIN | POLLHUP))) continue;
        n = read(fds[0], buf + have, sizeof buf - 1 - have);
        if (n > 0 && (have += (size_t)n) < sizeof buf - 1) continue;
        if (n < 0 && errno == EINTR) continue;
        break; /* the end of the pipe: the child has left */
    }
    close(fds[0]);
    buf[have] = 0;
    if (now_ms() >= end && waitpid(pid, &status, WNOHANG) == 0) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        snprintf(msg, cap, "%s took longer than %d s reading it (a malformed file?)", reader,
                 timeout_s);
        return -1;
    }
    while (!got_status) {
        if (waitpid(pid, &status, 0) == pid) got_status = 1;
        else if (errno != EINTR) break;
    }
    if (got_status && WIFSIGNALED(status)) {
        snprintf(msg, cap, "%s crashed reading it (signal %d: %s): the file is malformed", reader,
                 WTERMSIG(status), strsignal(WTERMSIG(status)));
        return -1;
    }
    if (have < 1) {
        snprintf(msg, cap, "%s stopped reading it without a word: the file is malformed", reader);
        return -1;
    }
    snprintf(msg, cap, "%s", buf + 1);
    return buf[0] == '1' ? 1 : 0;
}
