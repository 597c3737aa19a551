/* A cache of built kernel programs (device binaries), so that a second run with the same
 * kernels, options and device skips the OpenCL compiler's front end. Any failure here
 * only means a build from source; nothing is ever fatal. */
#include "progcache.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

static int cache_path(cl_device_id dev, const char *source, const char *options, char *path,
                      size_t n)
{
    char dir[1024];
    unsigned long long h = 14695981039346656037ULL;
    if (!cache_dir(dir, sizeof dir))
        return 0;
    h = fnv_str(h, source);
    h = fnv_str(h, options);
    h = fnv_info(h, dev, CL_DEVICE_NAME);
    h = fnv_info(h, dev, CL_DEVICE_VERSION);
    h = fnv_info(h, dev, CL_DRIVER_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_VENDOR);
    return snprintf(path, n, "%s/%016llx.bin", dir, h) < (int)n;
}

cl_program progcache_load(cl_context ctx, cl_device_id dev, const char *source, const char *options)
{
    char path[1100];
    FILE *f;
    long len;
    unsigned char *bin = NULL;
    const unsigned char *cbin;
    size_t size;
    cl_int e, status;
    cl_program p = NULL;

    if (!cache_path(dev, source, options, path, sizeof path))
        return NULL;
    f = fopen(path, "rb");
    if (!f)
        return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) <= 0 || fseek(f, 0, SEEK_SET) != 0)
        goto out_close;
    bin = malloc((size_t)len);
    if (!bin || fread(bin, 1, (size_t)len, f) != (size_t)len)
        goto out_close;
    size = (size_t)len;
    cbin = bin;
    p = clCreateProgramWithBinary(ctx, 1, &dev, &size, &cbin, &status, &e);
    if (e != CL_SUCCESS || status != CL_SUCCESS) {
        if (p)
            clReleaseProgram(p);
        p = NULL;
        goto out_close;
    }
    if (clBuildProgram(p, 1, &dev, options, NULL, NULL) != CL_SUCCESS) {
        clReleaseProgram(p);
        p = NULL;
    }
out_close:
    free(bin);
    fclose(f);
    return p;
}

/* mkdir -p for the cache folder (two levels at most: base/clwhitted) */
static void make_dirs(const char *path)
{
    char buf[1100];
    char *s;
    snprintf(buf, sizeof buf, "%s", path);
    s = strrchr(buf, '/');
    if (!s)
        return;
    *s = '\0';
    if (mkdir(buf, 0755) != 0 && errno == ENOENT) {
        char *t = strrchr(buf, '/');
        if (t) {
            *t = '\0';
            (void)mkdir(buf, 0755);
            *t = '/';
        }
        (void)mkdir(buf, 0755);
    }
}

void progcache_store(cl_program p, cl_device_id dev, const char *source, const char *options)
{
    char path[1100], tmp[1200];
    size_t size = 0;
    unsigned char *bin;
    FILE *f;
    int ok;

    if (!cache_path(dev, source, options, path, sizeof path))
        return;
    if (clGetProgramInfo(p, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, NULL) != CL_SUCCESS ||
        size == 0)
        return;
    bin = malloc(size);
    if (!bin)
        return;
    if (clGetProgramInfo(p, CL_PROGRAM_BINARIES, sizeof bin, &bin, NULL) != CL_SUCCESS)
        goto out_free;
    make_dirs(path);
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    f = fopen(tmp, "wb");
    if (!f)
        goto out_free;
    ok = fwrite(bin, 1, size, f) == size;
    if (fclose(f) != 0)
        ok = 0;
    if (!ok || rename(tmp, path) != 0)
        (void)remove(tmp);
out_free:
    free(bin);
}
