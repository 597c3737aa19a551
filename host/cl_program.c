/* The kernel program: its build options (from the scene's features and the settings), its
 * build from the embedded source with the build log on failure, and a cache of built
 * programs (device binaries, CL_PROGRAM_BINARIES) so that a second run with the same
 * kernels, options and device skips the OpenCL compiler's front end. The cache lives in
 * CLWHITTED_CACHE_DIR (default $XDG_CACHE_HOME/clwhitted or ~/.cache/clwhitted; an empty
 * value turns it off), one file per (kernel source, build options, device, driver); any
 * failure there only means a build from source, never an error. */
#include "cl_program.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cl_device.h"
#include "sys.h"

extern const char cw_kernel_source[];

void clprog_options(const clprog_features *ft, int max_depth, int spd, int fast, int stats,
                    int pixel, char *buf, size_t n)
{
    const char *extra = getenv("CLWHITTED_BUILD_OPTIONS");
    int deep = max_depth > 1;
    snprintf(buf, n,
             "-cl-std=CL1.2 -Werror -DCW_HAS_SPHERES=%d -DCW_HAS_TRIANGLES=%d "
             "-DCW_HAS_POLYGONS=%d -DCW_HAS_CONES=%d -DCW_HAS_MIRRORS=%d "
             "-DCW_HAS_REFRACTION=%d -DCW_FAST=%d -DCW_STATS=%d -DCW_PIXEL=%d%s%s%s",
             ft->spheres > 0, ft->triangles > 0, ft->polygons > 0, ft->cones > 0,
             deep && (ft->mirrors || (spd && ft->transmitters)), deep && ft->transmitters,
             fast != 0, stats != 0, pixel != 0, fast ? " -cl-fast-relaxed-math" : "",
             extra ? " " : "", extra ? extra : "");
}

/* ---- binary cache ----------------------------------------------------------------- */

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

/* The cache key: a hash of everything that decides the binary. The kernel source and the
 * build options; the implementation (platform name, vendor and version: two OpenCL
 * runtimes on the same CPU report the same device name) and the device within it (name,
 * vendor, device and OpenCL C versions); the driver version, so that a driver update
 * never loads a binary of the old one; and OCLGRIND_BUILD_OPTIONS, which Oclgrind adds
 * to the options behind the API's back. */
static unsigned long long cache_key(cl_device_id dev, const char *source, const char *options)
{
    unsigned long long h = 14695981039346656037ULL;
    const char *og = getenv("OCLGRIND_BUILD_OPTIONS");
    cl_platform_id plat = NULL;
    if (clGetDeviceInfo(dev, CL_DEVICE_PLATFORM, sizeof plat, &plat, NULL) != CL_SUCCESS)
        plat = NULL;
    h = fnv_str(h, source);
    h = fnv_str(h, options);
    h = fnv_platform(h, plat, CL_PLATFORM_NAME);
    h = fnv_platform(h, plat, CL_PLATFORM_VENDOR);
    h = fnv_platform(h, plat, CL_PLATFORM_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_NAME);
    h = fnv_info(h, dev, CL_DEVICE_VENDOR);
    h = fnv_info(h, dev, CL_DEVICE_VERSION);
    h = fnv_info(h, dev, CL_DEVICE_OPENCL_C_VERSION);
    h = fnv_info(h, dev, CL_DRIVER_VERSION);
    return fnv_str(h, og ? og : "");
}

/* DIR/KEY.bin, KEY the hash of the source, the options and the device's identity. */
static int cache_path(cl_device_id dev, const char *source, const char *options, char *path,
                      size_t n)
{
    char dir[1024];
    if (!cache_dir(dir, sizeof dir))
        return 0;
    return snprintf(path, n, "%s/%016llx.bin", dir, cache_key(dev, source, options)) < (int)n;
}

/* A program built from the cached binary, or NULL (no entry, or it did not load or
 * build: the caller then builds from source). */
static cl_program cache_load(cl_context ctx, cl_device_id dev, const char *source,
                             const char *options)
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

/* Writes all of buf to fd. Returns 0 or -1. */
static int write_all(int fd, const unsigned char *buf, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, buf, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        buf += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Saves the binary of a program built from source (atomic replacement; failures are
 * ignored). */
static void cache_store(cl_program p, cl_device_id dev, const char *source, const char *options)
{
    char path[1100], err[1300];
    size_t size = 0;
    unsigned char *bin;
    sys_tmpfile t;

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
    if (sys_tmp_open(&t, path, err, sizeof err) != 0)
        goto out_free;
    if (write_all(t.fd, bin, size) != 0) {
        sys_tmp_abort(&t);
        goto out_free;
    }
    (void)sys_tmp_commit(&t, path, err, sizeof err); /* removes the temporary file on failure */
out_free:
    free(bin);
}

/* ---- build ------------------------------------------------------------------------ */

/* The build log of a failed build on stderr. */
static void print_build_log(cl_program p, cl_device_id dev, const char *device_name,
                            const char *options)
{
    size_t len = 0;
    char *log;
    cl_int e = clGetProgramBuildInfo(p, dev, CL_PROGRAM_BUILD_LOG, 0, NULL, &len);
    log = e == CL_SUCCESS ? malloc(len + 1) : NULL;
    if (!log)
        fprintf(stderr, "kernel build log unavailable (%s)\n", cldev_error_name(e));
    if (log && clGetProgramBuildInfo(p, dev, CL_PROGRAM_BUILD_LOG, len, log, NULL) == CL_SUCCESS) {
        log[len] = '\0';
        fprintf(stderr, "kernel build log (%s, options: %s):\n%s\n", device_name, options, log);
    }
    free(log);
}

int clprog_build(cl_context ctx, cl_device_id dev, const char *device_name, const char *options,
                 cl_program *out, int *cached, char *err, size_t errlen)
{
    const char *src = cw_kernel_source;
    cl_program p;
    cl_int e;

    p = cache_load(ctx, dev, src, options);
    *cached = p != NULL;
    if (p) {
        *out = p;
        return 0;
    }
    p = clCreateProgramWithSource(ctx, 1, &src, NULL, &e);
    if (e != CL_SUCCESS)
        return cldev_fail(e, "clCreateProgramWithSource", device_name, err, errlen);
    e = clBuildProgram(p, 1, &dev, options, NULL, NULL);
    if (e != CL_SUCCESS) {
        print_build_log(p, dev, device_name, options);
        clReleaseProgram(p);
        return cldev_fail(e, "clBuildProgram (build log above)", device_name, err, errlen);
    }
    cache_store(p, dev, src, options);
    *out = p;
    return 0;
}
