/* The host's interface to the operating system. See sys.h. */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* sched_getaffinity and CPU_COUNT: the CPUs this process may use */
#endif
#include "sys.h"

#include <errno.h>
#if defined(__linux__)
#include <sched.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

double sys_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

int sys_cpu_count(void)
{
    long n;
#if defined(__linux__) && defined(CPU_COUNT)
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
        return CPU_COUNT(&set); /* taskset and cpusets leave fewer than are online */
#endif
    n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 4096 ? 4096 : (int)n;
}

void sys_exit_now(int status)
{
    fflush(stdout);
    fflush(stderr);
    _exit(status);
}

int sys_has_ext(const char *path, const char *ext)
{
    const char *base = strrchr(path, '/');
    const char *dot;
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    if (!dot || dot == base)
        return 0;
    for (; *dot && *ext; dot++, ext++) {
        char c = *dot;
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != *ext)
            return 0;
    }
    return *dot == '\0' && *ext == '\0';
}

int sys_read_file(const char *path, size_t max_bytes, int stop_at_nul, const char *what, char **out,
                  size_t *outlen, char *err, size_t errlen)
{
    struct stat st;
    FILE *f;
    char *buf = NULL;
    size_t len = 0, cap = 65536, want = 0;
    if (stat(path, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            snprintf(err, errlen, "%s: cannot read: %s", path, strerror(EISDIR));
            return -1;
        }
        if (S_ISREG(st.st_mode) && (unsigned long long)st.st_size > max_bytes) {
            snprintf(err, errlen, "%s: file too large (%lld bytes; %s may have at most %zu)", path,
                     (long long)st.st_size, what, max_bytes);
            return -1;
        }
        if (S_ISREG(st.st_mode) && st.st_size > 0)
            want = (size_t)st.st_size + 2; /* one read, then one more to see the end */
    }
    f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (want > cap)
        cap = want;
    for (;;) {
        size_t n;
        if (!buf || cap - len < 2) {
            char *nb;
            if (buf)
                cap *= 2;
            nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                snprintf(err, errlen, "%s: out of memory", path);
                return -1;
            }
            buf = nb;
        }
        n = fread(buf + len, 1, cap - len - 1, f);
        len += n;
        if (n == 0) {
            if (ferror(f)) {
                int e = errno;
                free(buf);
                fclose(f);
                snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
                return -1;
            }
            break;
        }
        if (len > max_bytes) {
            free(buf);
            fclose(f);
            snprintf(err, errlen, "%s: file too large (%s may have at most %zu bytes)", path, what,
                     max_bytes);
            return -1;
        }
        if (stop_at_nul && memchr(buf + len - n, '\0', n))
            break; /* binary: the reader reports the NUL byte and its line */
    }
    fclose(f);
    buf[len] = '\0';
    *out = buf;
    *outlen = len;
    return 0;
}

int sys_tmp_open(sys_tmpfile *t, const char *path, char *err, size_t errlen)
{
    size_t n = strlen(path);
    mode_t um;
    t->fd = -1;
    t->tmp = malloc(n + sizeof(".tmp-XXXXXX"));
    if (!t->tmp) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    memcpy(t->tmp, path, n);
    memcpy(t->tmp + n, ".tmp-XXXXXX", sizeof(".tmp-XXXXXX"));
    t->fd = mkstemp(t->tmp);
    if (t->fd < 0) {
        snprintf(err, errlen, "%s: cannot create temporary file %s: %s", path, t->tmp,
                 strerror(errno));
        free(t->tmp);
        t->tmp = NULL;
        return -1;
    }
    /* mkstemp creates the file 0600; give it the usual 0666 & ~umask. */
    um = umask(022);
    umask(um);
    (void)fchmod(t->fd, (mode_t)(0666 & ~um));
    return 0;
}

void sys_tmp_abort(sys_tmpfile *t)
{
    if (t->fd >= 0)
        close(t->fd);
    t->fd = -1;
    if (t->tmp) {
        unlink(t->tmp);
        free(t->tmp);
        t->tmp = NULL;
    }
}

int sys_tmp_commit(sys_tmpfile *t, const char *path, char *err, size_t errlen)
{
    if (t->fd >= 0) {
        int fd = t->fd;
        t->fd = -1;
        if (fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
            snprintf(err, errlen, "%s: cannot flush %s: %s", path, t->tmp, strerror(errno));
            close(fd);
            sys_tmp_abort(t);
            return -1;
        }
        if (close(fd) != 0) {
            snprintf(err, errlen, "%s: cannot close %s: %s", path, t->tmp, strerror(errno));
            sys_tmp_abort(t);
            return -1;
        }
    }
    if (rename(t->tmp, path) != 0) {
        snprintf(err, errlen, "%s: cannot rename %s over it: %s", path, t->tmp, strerror(errno));
        sys_tmp_abort(t);
        return -1;
    }
    free(t->tmp);
    t->tmp = NULL;
    return 0;
}

int sys_file_open(sys_file *f, const char *path, size_t max_bytes, const char *what, char *err,
                  size_t errlen)
{
    struct stat st;
    memset(f, 0, sizeof *f);
    f->path = path;
    f->err = err;
    f->errlen = errlen;
    f->max_bytes = max_bytes;
    f->what = what;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size <= 0 ||
        (unsigned long long)st.st_size > (unsigned long long)max_bytes)
        return 1;
    f->f = fopen(path, "rb");
    return f->f ? 0 : 1;
}

size_t sys_file_read(sys_file *f, char *dst, size_t n)
{
    size_t got;
    if (f->failed || !f->f)
        return 0;
    got = fread(dst, 1, n, f->f);
    if (got == 0 && ferror(f->f)) {
        snprintf(f->err, f->errlen, "%s: cannot read: %s", f->path, strerror(errno));
        f->failed = 1;
        return 0;
    }
    f->total += got;
    if (f->total > f->max_bytes) { /* it grew since it was opened */
        snprintf(f->err, f->errlen, "%s: file too large (%s may have at most %zu bytes)", f->path,
                 f->what, f->max_bytes);
        f->failed = 1;
        return 0;
    }
    return got;
}

int sys_file_oom(sys_file *f)
{
    snprintf(f->err, f->errlen, "%s: out of memory", f->path);
    f->failed = 1;
    return -1;
}

void sys_file_close(sys_file *f)
{
    if (f->f)
        fclose(f->f);
    f->f = NULL;
}
