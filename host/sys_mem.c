/* The host's memory, for sys.h: what a new allocation may take now (the system's
 * available memory, the address-space limit, the cgroup's limit), the page-aligned arrays a
 * CPU device uses in place, and giving memory back early. */
#include "sys.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif
#include <sys/resource.h>
#include <unistd.h>

/* The first number after `key` on a line of file path (a /proc or /sys file), in *v; 0 when
 * found. key "" reads the file's first line ("max" there is no number). */
static int read_number(const char *path, const char *key, unsigned long long *v)
{
    char line[512];
    size_t klen = strlen(key);
    int found = -1;
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    while (found != 0 && fgets(line, sizeof line, f)) {
        if (strncmp(line, key, klen) == 0 && sscanf(line + klen, " %llu", v) == 1)
            found = 0;
        if (klen == 0)
            break;
    }
    fclose(f);
    return found;
}

/* What a cgroup's memory limit leaves: the limit and the usage read from two files of the
 * folder dir (below /sys/fs/cgroup) named by a line of /proc/self/cgroup; 0 when there is no
 * limit ("max") or the files cannot be read. */
static unsigned long long cgroup_files_left(const char *root, const char *dir, const char *limit,
                                            const char *usage)
{
    char path[700];
    unsigned long long max = 0, cur = 0;
    snprintf(path, sizeof path, "/sys/fs/cgroup%s%s/%s", root, dir, limit);
    if (read_number(path, "", &max) != 0 || max == 0)
        return 0;
    snprintf(path, sizeof path, "/sys/fs/cgroup%s%s/%s", root, dir, usage);
    if (read_number(path, "", &cur) != 0)
        return 0;
    return cur < max ? max - cur : 1;
}

/* What the memory limits of this process's cgroups leave, in bytes: cgroup v2's memory.max
 * less memory.current, v1's memory.limit_in_bytes less memory.usage_in_bytes (the least of
 * those that are set); 0 when none is. */
static unsigned long long cgroup_left(void)
{
    char line[512];
    unsigned long long left = 0;
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f)) { /* "id:controllers:path" */
        char *ctl = strchr(line, ':'), *dir = ctl ? strchr(ctl + 1, ':') : NULL;
        size_t n = strlen(line);
        unsigned long long l = 0;
        if (!dir || line[n - 1] != '\n')
            continue;
        line[n - 1] = '\0';
        *dir++ = '\0';
        ctl++;
        if (strcmp(line, "0") == 0 && *ctl == '\0')
            l = cgroup_files_left("", dir, "memory.max", "memory.current");
        else if (strcmp(ctl, "memory") == 0)
            l = cgroup_files_left("/memory", dir, "memory.limit_in_bytes", "memory.usage_in_bytes");
        if (l != 0 && (left == 0 || l < left))
            left = l;
    }
    fclose(f);
    return left;
}

/* What the soft address-space limit (ulimit -v) leaves to map, in bytes; 0 when there is
 * none or the process's size cannot be read. */
static unsigned long long rlimit_left(void)
{
    struct rlimit rl;
    unsigned long long kb = 0;
    if (getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY)
        return 0;
    if (read_number("/proc/self/status", "VmSize:", &kb) != 0)
        return 0;
    return kb * 1024ULL < (unsigned long long)rl.rlim_cur
               ? (unsigned long long)rl.rlim_cur - kb * 1024ULL
               : 1;
}

static unsigned long long least_known(unsigned long long a, unsigned long long b)
{
    return a == 0 || (b != 0 && b < a) ? b : a;
}

unsigned long long sys_mem_available(void)
{
    unsigned long long kb = 0, avail = 0;
    long pages, size;
    if (read_number("/proc/meminfo", "MemAvailable:", &kb) == 0 && kb > 0) {
        avail = kb * 1024ULL;
    } else {
#ifdef _SC_AVPHYS_PAGES
        pages = sysconf(_SC_AVPHYS_PAGES);
#else
        pages = -1;
#endif
        size = sysconf(_SC_PAGESIZE);
        if (pages > 0 && size > 0)
            avail = (unsigned long long)pages * (unsigned long long)size;
    }
    return least_known(least_known(avail, rlimit_left()), cgroup_left());
}

/* A device array's header, in the 16 bytes before its aligned start: the allocation it
 * lies in and its length. The allocation is the length plus SYS_DEVICE_ALIGN plus the
 * header, so that an aligned start with the header before it always fits. */
#define DEVICE_HEADER (2 * sizeof(size_t))
_Static_assert(DEVICE_HEADER >= 2 * sizeof(void *), "the header holds a pointer and a size");

/* The aligned start of an array in the allocation at base. */
static char *device_start(char *base)
{
    uintptr_t a = ((uintptr_t)base + DEVICE_HEADER + SYS_DEVICE_ALIGN - 1) &
                  ~(uintptr_t)(SYS_DEVICE_ALIGN - 1);
    return base + (a - (uintptr_t)base);
}

/* Writes the header of the array at p: its allocation and length. */
static void *device_header(char *p, char *base, size_t bytes)
{
    memcpy(p - DEVICE_HEADER, &base, sizeof base);
    memcpy(p - sizeof(size_t), &bytes, sizeof bytes);
    return p;
}

void *sys_device_calloc(size_t n, size_t size)
{
    size_t bytes;
    char *base;
    if (size != 0 && n > (SIZE_MAX - SYS_DEVICE_ALIGN - DEVICE_HEADER) / size)
        return NULL;
    bytes = n * size;
    /* calloc: a large array comes zeroed from fresh pages, untouched until written */
    base = calloc(1, bytes + SYS_DEVICE_ALIGN + DEVICE_HEADER);
    return base ? device_header(device_start(base), base, bytes) : NULL;
}

void *sys_device_realloc(void *p, size_t n, size_t size)
{
    char *old_base, *base, *q;
    size_t old_bytes, bytes, off;
    if (!p)
        return sys_device_calloc(n, size);
    if (size != 0 && n > (SIZE_MAX - SYS_DEVICE_ALIGN - DEVICE_HEADER) / size)
        return NULL;
    bytes = n * size;
    memcpy(&old_base, (char *)p - DEVICE_HEADER, sizeof old_base);
    memcpy(&old_bytes, (char *)p - sizeof(size_t), sizeof old_bytes);
    off = (size_t)((char *)p - old_base);
    base = realloc(old_base, bytes + SYS_DEVICE_ALIGN + DEVICE_HEADER);
    if (!base)
        return NULL;
    q = device_start(base);
    /* realloc kept the bytes from base on; the array moves if its aligned start did (and
     * only then is the header written: it may lie where the old array began) */
    if ((size_t)(q - base) != off)
        memmove(q, base + off, old_bytes < bytes ? old_bytes : bytes);
    return device_header(q, base, bytes);
}

void sys_device_free(void *p)
{
    char *base;
    if (!p)
        return;
    memcpy(&base, (char *)p - DEVICE_HEADER, sizeof base);
    free(base);
}

void sys_release(void *p, size_t len)
{
#if defined(__linux__) && defined(MADV_DONTNEED)
    long size = sysconf(_SC_PAGESIZE);
    uintptr_t page = size > 0 ? (uintptr_t)size : 4096; /* whole pages inside the range */
    uintptr_t lo = ((uintptr_t)p + page - 1) & ~(page - 1);
    uintptr_t hi = ((uintptr_t)p + len) & ~(page - 1);
    if (p && hi > lo)
        (void)madvise((void *)lo, hi - lo, MADV_DONTNEED); /* errors ignored: advice only */
#else
    (void)p;
    (void)len;
#endif
}
