/* The cache of built kernel programs (device binaries, CL_PROGRAM_BINARIES), so that a
 * second run with the same kernels, options and device skips the OpenCL compiler. It lives
 * in CLWHITTED_CACHE_DIR (default $XDG_CACHE_HOME/clwhitted or ~/.cache/clwhitted; an empty
 * value turns it off), one file per (kernel source, build options, device, driver).
 *
 * Nothing found there reaches the driver unchecked: a file is read only when it is a
 * regular file (opened without following a link and without blocking, then fstat) of at
 * most CW_PROGCACHE_MAX_BYTES, and used only when its own header verifies (magic, format
 * version, device and driver identity, build key, payload length, CRC32 of the header and of
 * the payload). Anything else gives one warning and a build from source that replaces the
 * entry. A cache folder writable by others is used only when it belongs to the user. Any
 * failure here only means a build from source, never an error. */
#include "progcache.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "config.h"
#include "sys.h"

#ifndef O_NOFOLLOW
#define O_NOFOLLOW 0
#endif
#ifndef O_CLOEXEC
#define O_CLOEXEC 0
#endif

/* ---- key --------------------------------------------------------------------------- */

/* FNV-1a, 64 bits */
static unsigned long long fnv(unsigned long long h, const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= (unsigned char)s[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static unsigned long long fnv_str(unsigned long long h, const char *s)
{
    return fnv(h, s, strlen(s) + 1); /* the NUL separates the fields */
}

static unsigned long long fnv_info(unsigned long long h, cl_device_id dev, cl_device_info what)
{
    char buf[512];
    size_t n = 0;
    if (clGetDeviceInfo(dev, what, sizeof buf - 1, buf, &n) != CL_SUCCESS)
        n = 0;
    buf[n < sizeof buf ? n : sizeof buf - 1] = '\0';
    return fnv_str(h, buf);
}

static unsigned long long fnv_platform(unsigned long long h, cl_platform_id plat,
                                       cl_platform_info what)
{
    char buf[512];
    size_t n = 0;
    if (!plat || clGetPlatformInfo(plat, what, sizeof buf - 1, buf, &n) != CL_SUCCESS)
        n = 0;
    buf[n < sizeof buf ? n : sizeof buf - 1] = '\0';
    return fnv_str(h, buf);
}

/* The device and driver identity: everything about the device that can change its
 * binaries. The implementation (platform name, vendor and version: two OpenCL runtimes on
 * the same CPU report the same device name) and the device within it (name, vendor, device
 * and OpenCL C versions), and the driver version, so that a driver update never loads a
 * binary of the old one. A new driver or device gives a new key, hence a new entry. */
static unsigned long long progcache_identity(cl_device_id dev)
{
    unsigned long long h = 14695981039346656037ULL;
    cl_platform_id plat = NULL;
    if (clGetDeviceInfo(dev, CL_DEVICE_PLATFORM, sizeof plat, &plat, NULL) != CL_SUCCESS)
        plat = NULL;
    h = fnv_platform(h, plat, CL_PLATFORM_NAME);
    h = fnv_platform(h, plat, CL_PLATFORM_VENDOR);
    h = fnv_platform(h, plat, CL_PLATFORM_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_NAME);
    h = fnv_info(h, dev, CL_DEVICE_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_OPENCL_C_VERSION);
    h = fnv_info(h, dev, CL_DRIVER_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_VENDOR);
    return h;
}

/* The build key: the kernel source, the build options, and OCLGRIND_BUILD_OPTIONS, which
 * Oclgrind adds to the options behind the API's back. */
void progcache_key_of(cl_device_id dev, const char *source, const char *options, progcache_key *k)
{
    unsigned long long h = 14695981039346656037ULL;
    const char *og = getenv("OCLGRIND_BUILD_OPTIONS");
    h = fnv_str(h, source);
    h = fnv_str(h, options);
    h = fnv_str(h, og ? og : "");
    k->build = h;
    k->device = progcache_identity(dev);
}

/* ---- header ------------------------------------------------------------------------ */

static void put32(unsigned char *p, unsigned long v)
{
    int i;
    for (i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put64(unsigned char *p, unsigned long long v)
{
    int i;
    for (i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static unsigned long get32(const unsigned char *p)
{
    return (unsigned long)p[0] | (unsigned long)p[1] << 8 | (unsigned long)p[2] << 16 |
           (unsigned long)p[3] << 24;
}

static unsigned long long get64(const unsigned char *p)
{
    return (unsigned long long)get32(p) | (unsigned long long)get32(p + 4) << 32;
}

/* CRC32 of any length (zlib's takes an unsigned int length). */
static unsigned long crc_of(const unsigned char *p, size_t n)
{
    uLong c = crc32(0L, Z_NULL, 0);
    while (n > 0) {
        uInt step = n > 0x40000000u ? 0x40000000u : (uInt)n;
        c = crc32(c, p, step);
        p += step;
        n -= step;
    }
    return (unsigned long)c;
}

/* Layout: magic[8], version u32, header bytes u32, device u64, build u64, payload length
 * u64, payload CRC32 u32, header CRC32 u32 (of the 44 bytes before it). */
void progcache_header(const progcache_key *k, const unsigned char *payload, size_t len,
                      unsigned char *h)
{
    memcpy(h, PROGCACHE_MAGIC, 8);
    put32(h + 8, PROGCACHE_VERSION);
    put32(h + 12, PROGCACHE_HEADER_BYTES);
    put64(h + 16, k->device);
    put64(h + 24, k->build);
    put64(h + 32, (unsigned long long)len);
    put32(h + 40, crc_of(payload, len));
    put32(h + 44, crc_of(h, 44));
}

int progcache_check(const unsigned char *file, size_t len, const progcache_key *k, char *why,
                    size_t whylen)
{
    const char *reason = NULL;
    if (len < PROGCACHE_HEADER_BYTES)
        reason = "shorter than its header";
    else if (memcmp(file, PROGCACHE_MAGIC, 8) != 0)
        reason = "not a clwhitted cache file";
    else if (get32(file + 44) != crc_of(file, 44))
        reason = "header checksum mismatch";
    else if (get32(file + 8) != PROGCACHE_VERSION || get32(file + 12) != PROGCACHE_HEADER_BYTES)
        reason = "another cache format version";
    else if (get64(file + 16) != k->device)
        reason = "built for another device or driver";
    else if (get64(file + 24) != k->build)
        reason = "built from other kernels or options";
    else if (get64(file + 32) != (unsigned long long)(len - PROGCACHE_HEADER_BYTES))
        reason = "truncated or extended";
    else if (get32(file + 40) !=
             crc_of(file + PROGCACHE_HEADER_BYTES, len - PROGCACHE_HEADER_BYTES))
        reason = "payload checksum mismatch";
    else if (len == PROGCACHE_HEADER_BYTES)
        reason = "empty payload";
    if (!reason)
        return 0;
    snprintf(why, whylen, "%s", reason);
    return -1;
}

/* ---- folder and path --------------------------------------------------------------- */

/* The cache folder: CLWHITTED_CACHE_DIR ("" turns the cache off), else
 * $XDG_CACHE_HOME/clwhitted, else $HOME/.cache/clwhitted. 0 when there is none. */
static int cache_dir(char *dir, size_t n)
{
    const char *env = getenv("CLWHITTED_CACHE_DIR"), *base;
    if (env)
        return *env && snprintf(dir, n, "%s", env) < (int)n;
    if ((base = getenv("XDG_CACHE_HOME")) && *base)
        return snprintf(dir, n, "%s/clwhitted", base) < (int)n;
    if ((base = getenv("HOME")) && *base)
        return snprintf(dir, n, "%s/.cache/clwhitted", base) < (int)n;
    return 0;
}

/* Whether the folder may be used: a folder that others can write to (where they could
 * plant entries) only when it is the user's own. Warns once per process. */
static int dir_trusted(const char *dir)
{
    static int warned;
    struct stat st;
    char shown[1200];
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
        return 1; /* nothing there yet: it will be created 0755, or the open fails */
    if (!(st.st_mode & (S_IWGRP | S_IWOTH)) || st.st_uid == geteuid())
        return 1;
    if (!warned) {
        sys_escape(shown, sizeof shown, dir);
        fprintf(stderr,
                "clwhitted: warning: not using the kernel cache folder %s: others may write to "
                "it and it is not yours (set CLWHITTED_CACHE_DIR to a folder of your own)\n",
                shown);
        warned = 1;
    }
    return 0;
}

/* DIR/KEY.bin, KEY the hash of the build key and the device's identity. 0 when there is
 * no cache (turned off, no folder, or a folder not to be trusted). */
static int cache_path(const progcache_key *k, char *dir, size_t ndir, char *path, size_t n)
{
    unsigned long long h = fnv(k->build, (const char *)&k->device, sizeof k->device);
    if (!cache_dir(dir, ndir) || !dir_trusted(dir))
        return 0;
    return snprintf(path, n, "%s/%016llx.bin", dir, h) < (int)n;
}

/* ---- load -------------------------------------------------------------------------- */

/* Reads the entry at path into *buf (a regular file of at most CW_PROGCACHE_MAX_BYTES).
 * Returns 0 with *buf and *len, 1 when there is no entry, or -1 with why. */
static int read_entry(const char *path, unsigned char **buf, size_t *len, char *why, size_t n)
{
    struct stat st;
    unsigned char *b;
    size_t got = 0;
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT)
            return 1;
        snprintf(why, n, "%s", errno == ELOOP ? "a symbolic link" : strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        snprintf(why, n, "not a regular file");
        close(fd);
        return -1;
    }
    if (st.st_size <= 0 || (unsigned long long)st.st_size > CW_PROGCACHE_MAX_BYTES) {
        snprintf(why, n, "size %lld bytes (at most %lld)", (long long)st.st_size,
                 (long long)CW_PROGCACHE_MAX_BYTES);
        close(fd);
        return -1;
    }
    b = malloc((size_t)st.st_size);
    if (!b) {
        close(fd);
        snprintf(why, n, "out of memory");
        return -1;
    }
    while (got < (size_t)st.st_size) {
        ssize_t r = read(fd, b + got, (size_t)st.st_size - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    close(fd);
    if (got != (size_t)st.st_size) {
        free(b);
        snprintf(why, n, "read failed");
        return -1;
    }
    *buf = b;
    *len = got;
    return 0;
}

static void warn_entry(const char *path, const char *why)
{
    char shown[1200];
    sys_escape(shown, sizeof shown, path);
    fprintf(stderr, "clwhitted: warning: ignoring the kernel cache file %s (%s); rebuilding it\n",
            shown, why);
}

cl_program progcache_load(cl_context ctx, cl_device_id dev, const char *source, const char *options)
{
    char dir[1024], path[1100], why[160];
    unsigned char *file = NULL;
    const unsigned char *bin;
    size_t len = 0, size;
    cl_int e, status;
    cl_program p = NULL;
    progcache_key k;
    int rc;

    progcache_key_of(dev, source, options, &k);
    if (!cache_path(&k, dir, sizeof dir, path, sizeof path))
        return NULL;
    rc = read_entry(path, &file, &len, why, sizeof why);
    if (rc == 1)
        return NULL;
    if (rc != 0 || progcache_check(file, len, &k, why, sizeof why) != 0) {
        warn_entry(path, why);
        goto out_free;
    }
    size = len - PROGCACHE_HEADER_BYTES;
    bin = file + PROGCACHE_HEADER_BYTES;
    p = clCreateProgramWithBinary(ctx, 1, &dev, &size, &bin, &status, &e);
    if (e != CL_SUCCESS || status != CL_SUCCESS) {
        if (p)
            clReleaseProgram(p);
        p = NULL;
        warn_entry(path, "the OpenCL driver refused the binary");
        goto out_free;
    }
    if (clBuildProgram(p, 1, &dev, options, NULL, NULL) != CL_SUCCESS) {
        clReleaseProgram(p);
        p = NULL;
        warn_entry(path, "the OpenCL driver could not build the binary");
    }
out_free:
    free(file);
    return p;
}

/* ---- store ------------------------------------------------------------------------- */

/* mkdir -p for the cache folder (two levels at most: base/clwhitted) */
static void make_dirs(const char *dir)
{
    char buf[1100];
    char *t;
    snprintf(buf, sizeof buf, "%s", dir);
    if (mkdir(buf, 0755) == 0 || errno != ENOENT)
        return;
    t = strrchr(buf, '/');
    if (t && t != buf) {
        *t = '\0';
        (void)mkdir(buf, 0755);
        *t = '/';
    }
    (void)mkdir(buf, 0755);
}

void progcache_store(cl_program p, cl_device_id dev, const char *source, const char *options)
{
    char dir[1024], path[1100], err[1300];
    unsigned char head[PROGCACHE_HEADER_BYTES];
    size_t size = 0;
    unsigned char *bin;
    sys_tmpfile t;
    progcache_key k;

    progcache_key_of(dev, source, options, &k);
    if (!cache_dir(dir, sizeof dir))
        return;
    make_dirs(dir);
    if (!cache_path(&k, dir, sizeof dir, path, sizeof path))
        return;
    if (clGetProgramInfo(p, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, NULL) != CL_SUCCESS ||
        size == 0 || size > CW_PROGCACHE_MAX_BYTES - PROGCACHE_HEADER_BYTES)
        return;
    bin = malloc(size);
    if (!bin)
        return;
    if (clGetProgramInfo(p, CL_PROGRAM_BINARIES, sizeof bin, &bin, NULL) != CL_SUCCESS)
        goto out_free;
    progcache_header(&k, bin, size, head);
    if (sys_tmp_open(&t, path, err, sizeof err) != 0)
        goto out_free;
    if (sys_write_all(t.fd, head, sizeof head) != 0 || sys_write_all(t.fd, bin, size) != 0) {
        sys_tmp_abort(&t);
        goto out_free;
    }
    (void)sys_tmp_commit(&t, path, err, sizeof err); /* removes the temporary file on failure */
out_free:
    free(bin);
}
