/* The host's interface to the operating system: the clock, the number of CPUs, file names,
 * whole-file reads and atomic file replacement. Every other host file goes through these for
 * such things. */
#ifndef CW_SYS_H
#define CW_SYS_H

#include <stddef.h>
#include <stdio.h>

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

/* A file read in pieces, for a reader that parses as it reads (the NFF reader keeps a
 * window of the text, not the whole file). Its failures are worded as sys_read_file words
 * them, so that a reader reports the same message either way. */
typedef struct {
    FILE *f;
    const char *path;
    size_t total;     /* bytes read so far */
    size_t max_bytes; /* the most the file may have */
    const char *what; /* the kind of file, in the size message ("a scene file") */
    int failed;       /* a read failed, or the file grew past max_bytes: see err */
    char *err;
    size_t errlen;
} sys_file;

/* Opens path to be read in pieces: when it is a regular file of 1..max_bytes bytes and
 * opens. Returns 0, or 1 for anything else (read it whole with sys_read_file, which says
 * what is wrong with it). */
int sys_file_open(sys_file *f, const char *path, size_t max_bytes, const char *what, char *err,
                  size_t errlen);
/* Reads up to n bytes into dst. Returns how many; 0 at the end of the file, or when it
 * fails (f->failed set, "path: reason" in err). */
size_t sys_file_read(sys_file *f, char *dst, size_t n);
/* "path: out of memory" in err, as sys_read_file words it. Returns -1. */
int sys_file_oom(sys_file *f);
void sys_file_close(sys_file *f);

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
