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
/* Caps what sys_cpu_count returns at n (n >= 1; --threads); n <= 0 lifts the cap. */
void sys_set_cpu_limit(int n);
/* Whether `threads` threads (0: one per online CPU) pinned one per CPU, thread i to CPU i
 * (PoCL's POCL_AFFINITY), would cover every online CPU and stay inside this process's
 * affinity mask: 1 only when the threads are as many as the online CPUs, those are CPUs
 * 0 .. threads - 1, and no taskset or cpuset has narrowed the mask; 0 otherwise and where
 * there is no mask. */
int sys_pin_covers_cpus(int threads);

/* The memory available to a new allocation now, in bytes (sys_mem.c, as the device arrays
 * and sys_release below): MemAvailable of /proc/meminfo (else the free pages), or less where
 * the address-space limit (ulimit -v, less the process's size) or a cgroup's memory limit
 * (v2 memory.max less memory.current, v1 memory.limit_in_bytes less memory.usage_in_bytes)
 * leaves less; 0 when unknown. */
unsigned long long sys_mem_available(void);

/* Gives the memory of [p, p + len), part of an allocation whose content is no longer
 * needed, back to the system now (the whole pages inside it; Linux's MADV_DONTNEED): it
 * stays allocated, reads as zeros, and is freed as usual. Advice only: elsewhere nothing
 * happens. */
void sys_release(void *p, size_t len);

/* Memory for a scene array that a CPU OpenCL device may use where it is, without a copy
 * (CL_MEM_USE_HOST_PTR: host/render.c): zeroed like calloc, its start aligned to
 * SYS_DEVICE_ALIGN bytes (a page: what CPU runtimes ask for such a buffer, and whole cache
 * lines for the nodes and blocks the walks read). NULL when out of memory or when n * size
 * overflows. Free only with sys_device_free; resize only with sys_device_realloc. */
#define SYS_DEVICE_ALIGN 4096
void *sys_device_calloc(size_t n, size_t size);
/* Resizes p (from sys_device_calloc or this; NULL: a new zeroed array) to n * size bytes,
 * keeping the content up to the smaller size and the alignment; a larger array's new part
 * is not zeroed. NULL when out of memory (p is then left as it was) or on overflow. */
void *sys_device_realloc(void *p, size_t n, size_t size);
void sys_device_free(void *p);

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
    char *tmp; /* "path.tmp-XXXXXX" (the name shortened to fit NAME_MAX) */
    int fd;    /* open descriptor, or -1 once closed */
    int slot;  /* its place in the signal handler's list, or -1 */
} sys_tmpfile;

/* Creates the temporary file: beside path, named after it with the name cut so that the
 * whole stays within the folder's NAME_MAX; when path exists, with its permission bits.
 * Until it is committed or aborted, SIGINT, SIGTERM and SIGHUP remove it (once
 * sys_signals_install has run). Returns 0, or -1 with err. */
int sys_tmp_open(sys_tmpfile *t, const char *path, char *err, size_t errlen);
/* Flushes the descriptor to disk, closes it (unless already closed) and renames the
 * temporary file over path. On failure the temporary file is removed. Returns 0 or -1. */
int sys_tmp_commit(sys_tmpfile *t, const char *path, char *err, size_t errlen);
/* Removes the temporary file (failure path), closing the descriptor if still open. */
void sys_tmp_abort(sys_tmpfile *t);

/* Whether a file can be written at path, before any work: the folder exists and takes a new
 * file (a temporary file is created there and removed), the name fits, and path is not a
 * folder, not a special file and not read-only (a read-only file is never replaced).
 * Returns 0, or -1 with "path: reason" in err. */
int sys_check_output(const char *path, char *err, size_t errlen);

/* Writes all n bytes to fd (retrying short writes and EINTR). Returns 0 or -1 (errno). */
int sys_write_all(int fd, const void *buf, size_t n);

/* Copies s into out for a message, with control characters written as \xNN (untrusted
 * text such as paths never reaches the terminal raw); cut short to fit. Returns out. */
const char *sys_escape(char *out, size_t outlen, const char *s);

/* Signals: SIGINT, SIGTERM and SIGHUP (unless ignored at start) remove the temporary files
 * of sys_tmp_open, clear the progress line and end the process with 128 + the signal;
 * SIGPIPE is ignored (a write to a closed pipe fails with EPIPE instead). */
void sys_signals_install(void);
/* The progress line the handler clears: len characters on fd (len 0: none). */
void sys_signal_line(int fd, size_t len);

/* A guard around a call into a library that may crash on bad input (assimp, on some
 * malformed files): from begin to end, a fatal signal (SIGSEGV, SIGBUS, SIGFPE, SIGILL,
 * SIGABRT) in any thread removes the temporary files, writes msg and a newline to stderr
 * and ends the process with status 1. The handler runs on its own stack in the calling
 * thread. One guarded window at a time; end restores the previous handlers. */
void sys_guard_begin(const char *msg);
void sys_guard_end(void);

#endif
