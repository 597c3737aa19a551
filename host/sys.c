/* The host's interface to the operating system. See sys.h. */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* sched_getaffinity and CPU_COUNT: the CPUs this process may use */
#endif
#include "sys.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#if defined(__linux__)
#include <sched.h>
#endif
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
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

static int sys_cpu_limit; /* 0: none */

void sys_set_cpu_limit(int n)
{
    sys_cpu_limit = n > 0 ? n : 0;
}

static int cpu_count(void)
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

int sys_pin_covers_cpus(int threads)
{
#if defined(__linux__) && defined(CPU_COUNT)
    cpu_set_t set;
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    int i;
    if (threads == 0)
        threads = online > INT_MAX ? INT_MAX : (int)online;
    if (threads < 1 || threads != online || threads > CPU_SETSIZE ||
        sched_getaffinity(0, sizeof set, &set) != 0 || CPU_COUNT(&set) != threads)
        return 0;
    for (i = 0; i < threads; i++)
        if (!CPU_ISSET(i, &set))
            return 0;
    return 1;
#else
    (void)threads;
    return 0;
#endif
}

int sys_cpu_count(void)
{
    int n = cpu_count();
    return sys_cpu_limit > 0 && sys_cpu_limit < n ? sys_cpu_limit : n;
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

/* ---- signals ---------------------------------------------------------------------- */

/* The temporary files that exist now, for the signal handler to remove, and the progress
 * line on the terminal, for it to clear. A slot is filled before it is marked used, and the
 * handler only reads: it unlinks, writes and re-raises the signal (async-signal-safe
 * calls). */
#define SIG_SLOTS 8
#define SIG_PATH 4096
static char sig_tmp[SIG_SLOTS][SIG_PATH];
static volatile sig_atomic_t sig_used[SIG_SLOTS];
static volatile sig_atomic_t sig_line_fd = -1, sig_line_len;
static pthread_mutex_t sig_lock = PTHREAD_MUTEX_INITIALIZER;

static void on_fatal_signal(int sig)
{
    static const char spaces[64] =
        "                                                               ";
    int i, fd = sig_line_fd;
    for (i = 0; i < SIG_SLOTS; i++)
        if (sig_used[i])
            (void)unlink(sig_tmp[i]);
    if (fd >= 0 && sig_line_len > 0) {
        long left = sig_line_len;
        ssize_t w = write(fd, "\r", 1);
        while (left > 0 && w > 0) {
            w = write(fd, spaces, left > 63 ? 63 : (size_t)left);
            left -= 63;
        }
        w = write(fd, "\r", 1);
        (void)w;
    }
    /* End by the signal itself, with its default action, once the handler returns (the
     * signal is blocked until then): the parent sees it (a shell: 128 + the signal, and a
     * shell loop stops on Ctrl-C), and no exit hook runs (a sanitizer's _exit hook takes
     * locks the signal may have interrupted, and hung). */
    (void)signal(sig, SIG_DFL);
    (void)raise(sig);
}

/* ---- a guarded call into a library that may crash --------------------------------- */

#define GUARD_SIGS                                                                                 \
    {                                                                                              \
        SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT                                                   \
    }
#define GUARD_NSIGS 5
static char guard_msg[1536];
static size_t guard_len;
static struct sigaction guard_old[GUARD_NSIGS];
static char guard_stack[1 << 16]; /* the handler's stack: the crash may be an overflow */
static stack_t guard_old_stack;

static void on_guarded_crash(int sig)
{
    int i;
    ssize_t w;
    (void)sig;
    for (i = 0; i < SIG_SLOTS; i++)
        if (sig_used[i])
            (void)unlink(sig_tmp[i]);
    w = write(2, guard_msg, guard_len);
    (void)w;
    _exit(1);
}

void sys_guard_begin(const char *msg)
{
    static const int sigs[] = GUARD_SIGS;
    struct sigaction sa;
    stack_t st;
    size_t i;
    guard_len = strlen(msg) < sizeof guard_msg - 1 ? strlen(msg) : sizeof guard_msg - 2;
    memcpy(guard_msg, msg, guard_len);
    guard_msg[guard_len++] = '\n';
    st.ss_sp = guard_stack;
    st.ss_size = sizeof guard_stack;
    st.ss_flags = 0;
    (void)sigaltstack(&st, &guard_old_stack);
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_guarded_crash;
    sa.sa_flags = SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (i = 0; i < GUARD_NSIGS; i++)
        (void)sigaction(sigs[i], &sa, &guard_old[i]);
}

void sys_guard_end(void)
{
    static const int sigs[] = GUARD_SIGS;
    size_t i;
    for (i = 0; i < GUARD_NSIGS; i++)
        (void)sigaction(sigs[i], &guard_old[i], NULL);
    (void)sigaltstack(&guard_old_stack, NULL);
}

void sys_signals_install(void)
{
    static const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    struct sigaction sa, old;
    size_t i;
    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    for (i = 0; i < sizeof sigs / sizeof sigs[0]; i++)
        (void)sigaddset(&sa.sa_mask, sigs[i]);
    for (i = 0; i < sizeof sigs / sizeof sigs[0]; i++) {
        /* a signal ignored by whoever started us (nohup) stays ignored */
        if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        sa.sa_handler = on_fatal_signal;
        (void)sigaction(sigs[i], &sa, NULL);
    }
    /* A closed stdout is an EPIPE from the write, handled where the write is. */
    sa.sa_handler = SIG_IGN;
    (void)sigaction(SIGPIPE, &sa, NULL);
}

void sys_signal_line(int fd, size_t len)
{
    sig_line_fd = -1;
    sig_line_len = (sig_atomic_t)(len > 4096 ? 4096 : len);
    sig_line_fd = len > 0 ? fd : -1;
}

/* Registers a temporary file for removal on a signal. Returns its slot, or -1 (no room,
 * or a path too long: the file is then only removed by the normal paths). */
static int sig_register(const char *tmp)
{
    int i, slot = -1;
    size_t n = strlen(tmp);
    if (n >= SIG_PATH)
        return -1;
    pthread_mutex_lock(&sig_lock);
    for (i = 0; i < SIG_SLOTS && slot < 0; i++)
        if (!sig_used[i]) {
            memcpy(sig_tmp[i], tmp, n + 1);
            sig_used[i] = 1;
            slot = i;
        }
    pthread_mutex_unlock(&sig_lock);
    return slot;
}

static void sig_unregister(int slot)
{
    if (slot < 0)
        return;
    pthread_mutex_lock(&sig_lock);
    sig_used[slot] = 0;
    pthread_mutex_unlock(&sig_lock);
}

/* ---- writing ----------------------------------------------------------------------- */

int sys_write_all(int fd, const void *buf, size_t n)
{
    const unsigned char *p = buf;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

const char *sys_escape(char *out, size_t outlen, const char *s)
{
    size_t o = 0;
    if (outlen == 0)
        return out;
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c < 0x20 || c == 0x7f) {
            if (o + 5 > outlen - 1)
                break;
            snprintf(out + o, 5, "\\x%02X", c);
            o += 4;
        } else {
            if (o + 1 > outlen - 1)
                break;
            out[o++] = (char)c;
        }
    }
    out[o] = '\0';
    return out;
}

/* The longest file name in the folder of path (NAME_MAX where pathconf does not say). */
static size_t name_max(const char *path)
{
    char dir[SIG_PATH];
    const char *slash = strrchr(path, '/');
    long v;
    if (slash && (size_t)(slash - path) < sizeof dir) {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        memcpy(dir, path, n);
        dir[n] = '\0';
    } else {
        snprintf(dir, sizeof dir, ".");
    }
    v = pathconf(dir, _PC_NAME_MAX);
#ifdef NAME_MAX
    if (v <= 0)
        v = NAME_MAX;
#endif
    return v > 0 ? (size_t)v : 255;
}

#define TMP_SUFFIX ".tmp-XXXXXX"

int sys_tmp_open(sys_tmpfile *t, const char *path, char *err, size_t errlen)
{
    size_t n = strlen(path), keep = n, nmax = name_max(path);
    const char *base = strrchr(path, '/');
    size_t base_len = base ? strlen(base + 1) : n;
    struct stat st;
    mode_t um;
    t->fd = -1;
    t->slot = -1;
    /* the temporary name within NAME_MAX: the destination's name, shortened if need be */
    if (base_len + sizeof TMP_SUFFIX - 1 > nmax && nmax > sizeof TMP_SUFFIX)
        keep = n - base_len + (nmax - (sizeof TMP_SUFFIX - 1));
    t->tmp = malloc(keep + sizeof TMP_SUFFIX);
    if (!t->tmp) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    memcpy(t->tmp, path, keep);
    memcpy(t->tmp + keep, TMP_SUFFIX, sizeof TMP_SUFFIX);
    /* The name is made in the signal handler's own slot, registered before the file
     * exists: a signal at any moment finds the file's final name there once it exists
     * (before, it unlinks a name that does not exist). */
    t->slot = sig_register(t->tmp);
    t->fd = mkstemp(t->slot >= 0 ? sig_tmp[t->slot] : t->tmp);
    if (t->slot >= 0)
        memcpy(t->tmp, sig_tmp[t->slot], keep + sizeof TMP_SUFFIX);
    if (t->fd < 0) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot create temporary file %s: %s", path, t->tmp, strerror(e));
        sig_unregister(t->slot);
        t->slot = -1;
        free(t->tmp);
        t->tmp = NULL;
        errno = e;
        return -1;
    }
    if (stat(path, &st) == 0 && S_ISREG(st.st_mode)) {
        /* replacing a file keeps its permission bits */
        (void)fchmod(t->fd, st.st_mode & 0777);
        return 0;
    }
    /* mkstemp creates the file 0600; give a new file the usual 0666 & ~umask. */
    um = umask(022);
    umask(um);
    (void)fchmod(t->fd, (mode_t)(0666 & ~um));
    return 0;
}

int sys_check_output(const char *path, char *err, size_t errlen)
{
    char dir[SIG_PATH];
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    struct stat st;
    sys_tmpfile t;
    if (slash && (size_t)(slash - path) >= sizeof dir) {
        snprintf(err, errlen, "%s: %s", path, strerror(ENAMETOOLONG));
        return -1;
    }
    if (slash) {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        memcpy(dir, path, n);
        dir[n] = '\0';
    } else {
        snprintf(dir, sizeof dir, ".");
    }
    if (!*base) {
        snprintf(err, errlen, "%s: no file name", path);
        return -1;
    }
    if (strlen(base) > name_max(path)) {
        snprintf(err, errlen, "%s: file name too long (%zu bytes; at most %zu here)", path,
                 strlen(base), name_max(path));
        return -1;
    }
    if (stat(dir, &st) != 0) {
        snprintf(err, errlen, "%s: cannot write there: folder %s: %s", path, dir, strerror(errno));
        return -1;
    }
    if (!S_ISDIR(st.st_mode)) {
        snprintf(err, errlen, "%s: cannot write there: %s is not a folder", path, dir);
        return -1;
    }
    if (stat(path, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            snprintf(err, errlen, "%s: is a folder", path);
            return -1;
        }
        if (!S_ISREG(st.st_mode)) {
            snprintf(err, errlen, "%s: exists and is not a regular file (not replaced)", path);
            return -1;
        }
        if (!(st.st_mode & S_IWUSR)) {
            snprintf(err, errlen,
                     "%s: the file is read-only (not replaced; chmod u+w it or "
                     "choose another name)",
                     path);
            return -1;
        }
    }
    /* the folder takes a new file: create and remove the temporary file the write will use */
    if (sys_tmp_open(&t, path, err, errlen) != 0) {
        snprintf(err, errlen, "%s: cannot write in folder %s: %s", path, dir, strerror(errno));
        return -1;
    }
    sys_tmp_abort(&t);
    return 0;
}

void sys_tmp_abort(sys_tmpfile *t)
{
    if (t->fd >= 0)
        close(t->fd);
    t->fd = -1;
    if (t->tmp) {
        unlink(t->tmp);
        sig_unregister(t->slot);
        t->slot = -1;
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
    sig_unregister(t->slot);
    t->slot = -1;
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
