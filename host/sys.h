/* The host's interface to the operating system: the clock, the number of CPUs, file names,
 * whole-file reads and atomic file replacement. Every other host file goes through these for
 * such things. */
#ifndef CW_SYS_H
#define CW_SYS_H

#include <stddef.h>

/* Seconds on the monotonic clock (for durations only). */
double sys_now(void);

/* The number of CPUs this process may run on (its affinity mask where the system has
 * one, else the online CPUs; at least 1). */
int sys_cpu_count(void);

/* Ends the process now with status: flushes stdout and stderr, then _exit (no atexit
 * handlers or library destructors run, nothing is freed). */
void sys_exit_now(int status);

/* 1 when the file name (after the last '/') ends in ext (".exr"), case-insensitively;
 * a name that is only the extension (".exr") does not count. */
int sys_has_ext(const char *path, const char *ext);

/* Reads a whole file into a malloc'd NUL-terminated buffer. Directories, unreadable files
 * and files over max_bytes are errors naming the path and the reason ("what" names the
 * kind of file in the size message: "a scene file"). With stop_at_nul, reading stops
 * after the first chunk holding a NUL byte (text readers reject it with its line, so
 * /dev/zero is not read forever). Returns 0, or -1 with err. */
int sys_read_file(const char *path, size_t max_bytes, int stop_at_nul, const char *what, char **out,
                  size_t *outlen, char *err, size_t errlen);

/* Atomic replacement: write into a temporary file beside the destination (created with
 * O_EXCL, never following a link; mode 0666 & ~umask), then rename it over the
 * destination, so that a failure never leaves a half-written file. */
typedef struct {
    char *tmp; /* "path.tmp-XXXXXX" */
    int fd;    /* open descriptor, or -1 once closed */
} sys_tmpfile;

/* Creates the temporary file. Returns 0, or -1 with err. */
int sys_tmp_open(sys_tmpfile *t, const char *path, char *err, size_t errlen);
/* Flushes the descriptor to disk, closes it (unless already closed) and renames the
 * temporary file over path. On failure the temporary file is removed. Returns 0 or -1. */
int sys_tmp_commit(sys_tmpfile *t, const char *path, char *err, size_t errlen);
/* Removes the temporary file (failure path), closing the descriptor if still open. */
void sys_tmp_abort(sys_tmpfile *t);

#endif
