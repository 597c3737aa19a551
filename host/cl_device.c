/* OpenCL platforms and devices: the one enumeration (platforms as clGetPlatformIDs returns
 * them, devices of CL_DEVICE_TYPE_ALL) that numbers devices P:D for --device,
 * --list-devices and tools/cldevices; the device choice; the --list-devices listing (like
 * `clinfo -l` with the facts that matter for rendering); OpenCL error names. */
#include "cl_device.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sys.h"

#define NO_PLATFORM_HINT "(install pocl-opencl-icd: sh tools/install-deps)"

/* Whether a folder can be written, or created where it is missing: a folder made (and
 * removed) in it, else in its nearest existing parent, says so for any user, root
 * included, and for read-only file systems. */
static int dir_writable(const char *dir)
{
    char buf[1024], probe[1100];
    struct stat st;
    char *slash;
    if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf)
        return 1; /* cannot tell: no claim */
    for (;;) {
        if (stat(buf, &st) == 0) {
            if (!S_ISDIR(st.st_mode))
                return 0;
            snprintf(probe, sizeof probe, "%s/.clwhitted-probe-XXXXXX", buf);
            if (!mkdtemp(probe))
                return 0;
            (void)rmdir(probe);
            return 1;
        }
        if (errno != ENOENT || !(slash = strrchr(buf, '/')))
            return errno == ENOENT; /* a relative name: the current folder decides later */
        if (slash == buf)
            slash[1] = '\0';
        else
            *slash = '\0';
    }
}

const char *cldev_env_problem(char *buf, size_t n)
{
    const char *devs = getenv("POCL_DEVICES"), *cache = getenv("POCL_CACHE_DIR");
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    char dir[1024], shown[512];
    if (devs && *devs) {
        snprintf(buf, n,
                 "POCL_DEVICES='%s' may hide every PoCL device (unset it, or name a device type "
                 "PoCL has, such as cpu)",
                 sys_escape(shown, sizeof shown, devs));
        return buf;
    }
    if (cache && *cache)
        snprintf(dir, sizeof dir, "%s", cache);
    else if (xdg && *xdg)
        snprintf(dir, sizeof dir, "%s/pocl", xdg);
    else if (home && *home)
        snprintf(dir, sizeof dir, "%s/.cache/pocl", home);
    else {
        snprintf(buf, n,
                 "HOME is not set, so PoCL has no kernel cache folder (set "
                 "POCL_CACHE_DIR to a writable folder)");
        return buf;
    }
    if (!dir_writable(dir)) {
        snprintf(buf, n,
                 "PoCL cannot write its kernel cache folder %s (set POCL_CACHE_DIR to a writable "
                 "folder)",
                 sys_escape(shown, sizeof shown, dir));
        return buf;
    }
    return NULL;
}

/* "no OpenCL WHAT found", with the environment's problem when there is one, else the
 * install hint. */
static void none_found(const char *what, char *err, size_t errlen)
{
    char why[1024];
    if (cldev_env_problem(why, sizeof why))
        snprintf(err, errlen, "no OpenCL %s found: %s", what, why);
    else
        snprintf(err, errlen, "no OpenCL %s found " NO_PLATFORM_HINT, what);
}

int cldev_fail(cl_int e, const char *call, const char *device, char *err, size_t errlen)
{
    int named = device && device[0];
    snprintf(err, errlen, "%s failed: %s (%d)%s%s", call, cldev_error_name(e), (int)e,
             named ? " on device " : "", named ? device : "");
    return -1;
}

/* ---- enumeration ------------------------------------------------------------------ */

int cldev_platforms(cl_platform_id **out, cl_uint *count, char *err, size_t errlen)
{
    cl_uint n = 0;
    cl_int e = clGetPlatformIDs(0, NULL, &n);
    *out = NULL;
    *count = 0;
    if (e == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || (e == CL_SUCCESS && n == 0)) {
        none_found("platform", err, errlen);
        return 1;
    }
    if (e != CL_SUCCESS)
        return cldev_fail(e, "clGetPlatformIDs", NULL, err, errlen);
    *out = calloc(n, sizeof **out);
    if (!*out) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    e = clGetPlatformIDs(n, *out, NULL);
    if (e != CL_SUCCESS) {
        free(*out);
        *out = NULL;
        return cldev_fail(e, "clGetPlatformIDs", NULL, err, errlen);
    }
    *count = n;
    return 0;
}

int cldev_devices(cl_platform_id p, cl_device_id **out, cl_uint *count, char *err, size_t errlen)
{
    cl_uint n = 0;
    cl_int e = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, NULL, &n);
    *out = NULL;
    *count = 0;
    if (e == CL_DEVICE_NOT_FOUND || (e == CL_SUCCESS && n == 0))
        return 0;
    if (e != CL_SUCCESS)
        return cldev_fail(e, "clGetDeviceIDs", NULL, err, errlen);
    *out = calloc(n, sizeof **out);
    if (!*out) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    e = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, n, *out, NULL);
    if (e != CL_SUCCESS) {
        free(*out);
        *out = NULL;
        return cldev_fail(e, "clGetDeviceIDs", NULL, err, errlen);
    }
    *count = n;
    return 0;
}

/* ---- device choice ---------------------------------------------------------------- */

/* Whether device d (P:D = pi:di) is the one spec names; *fallback keeps the first device
 * for a default spec that finds no CPU. Returns 0, or -1 with err. */
static int device_matches(cl_device_id d, cl_uint pi, cl_uint di, const char *spec, int by_index,
                          unsigned want_p, unsigned want_d, cl_device_id *fallback, int *found,
                          char *err, size_t errlen)
{
    char name[256] = "";
    cl_device_type type = 0;
    cl_int e = clGetDeviceInfo(d, CL_DEVICE_NAME, sizeof name, name, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    if (e != CL_SUCCESS)
        return cldev_fail(e, "clGetDeviceInfo", NULL, err, errlen);
    if (by_index) {
        *found = (pi == want_p && di == want_d);
    } else if (spec && *spec) {
        *found = strstr(name, spec) != NULL;
    } else {
        *found = (type & CL_DEVICE_TYPE_CPU) != 0;
        if (!*fallback)
            *fallback = d;
    }
    return 0;
}

int cldev_find(const char *spec, cl_device_id *out, char *err, size_t errlen)
{
    cl_platform_id *plats = NULL;
    cl_device_id *devs = NULL, fallback = NULL;
    cl_uint np = 0, nd = 0, i, j;
    unsigned want_p = 0, want_d = 0;
    int by_index = 0, found = 0, rc = -1;
    char tail;

    if (spec && *spec && sscanf(spec, "%u:%u%c", &want_p, &want_d, &tail) == 2)
        by_index = 1;
    if (cldev_platforms(&plats, &np, err, errlen) != 0)
        return -1;
    for (i = 0; i < np && !found; i++) {
        if (cldev_devices(plats[i], &devs, &nd, err, errlen) != 0)
            goto out_free_platforms;
        for (j = 0; j < nd && !found; j++) {
            if (device_matches(devs[j], i, j, spec, by_index, want_p, want_d, &fallback, &found,
                               err, errlen) != 0)
                goto out_free_devices;
            if (found)
                *out = devs[j];
        }
        free(devs);
        devs = NULL;
    }
    if (!found && !(spec && *spec) && fallback) {
        *out = fallback;
        found = 1;
    }
    if (!found) {
        if (spec && *spec)
            snprintf(err, errlen, "no OpenCL device matches '%s' (see --list-devices)", spec);
        else
            none_found("device", err, errlen);
        goto out_free_platforms;
    }
    rc = 0;
out_free_devices:
    free(devs);
out_free_platforms:
    free(plats);
    return rc;
}

/* ---- --list-devices --------------------------------------------------------------- */

static const char *type_name(cl_device_type t)
{
    if (t & CL_DEVICE_TYPE_CPU)
        return "CPU";
    if (t & CL_DEVICE_TYPE_GPU)
        return "GPU";
    if (t & CL_DEVICE_TYPE_ACCELERATOR)
        return "accelerator";
    if (t & CL_DEVICE_TYPE_CUSTOM)
        return "custom";
    return "other";
}

/* "1.5 GiB", "512 MiB": binary units, one decimal from 1 GiB on. */
static void format_bytes(char *buf, size_t n, cl_ulong bytes)
{
    if (bytes >= (cl_ulong)1 << 30)
        snprintf(buf, n, "%.1f GiB", (double)bytes / (double)((cl_ulong)1 << 30));
    else
        snprintf(buf, n, "%llu MiB", (unsigned long long)(bytes >> 20));
}

/* Keeps the informative head of a version string: up to the first double space, at most
 * four words ("OpenCL 3.0 PoCL 3.1+debian  Linux, ..." -> "OpenCL 3.0 PoCL 3.1+debian"). */
static void short_version(char *s)
{
    char *p = strstr(s, "  ");
    int words = 0;
    if (p)
        *p = '\0';
    for (p = s; *p; p++)
        if (*p == ' ' && ++words == 4) {
            *p = '\0';
            break;
        }
}

/* An info string of any length; malloc'd, or NULL on failure (with err). */
static char *device_string(cl_device_id d, cl_device_info what, const char *call, char *err,
                           size_t errlen)
{
    size_t n = 0;
    char *s;
    cl_int e = clGetDeviceInfo(d, what, 0, NULL, &n);
    if (e != CL_SUCCESS) {
        cldev_fail(e, call, NULL, err, errlen);
        return NULL;
    }
    s = malloc(n + 1);
    if (!s) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    e = clGetDeviceInfo(d, what, n, s, NULL);
    if (e != CL_SUCCESS) {
        free(s);
        cldev_fail(e, call, NULL, err, errlen);
        return NULL;
    }
    s[n] = '\0';
    return s;
}

/* Whether the device does double precision: a double FP config (OpenCL 1.2+), else the
 * cl_khr_fp64 extension. */
static int has_fp64(cl_device_id d, const char *extensions)
{
    cl_device_fp_config cfg = 0;
    const char *p = extensions;
    if (clGetDeviceInfo(d, CL_DEVICE_DOUBLE_FP_CONFIG, sizeof cfg, &cfg, NULL) == CL_SUCCESS &&
        cfg != 0)
        return 1;
    while ((p = strstr(p, "cl_khr_fp64")) != NULL) {
        char next = p[strlen("cl_khr_fp64")];
        if ((p == extensions || p[-1] == ' ') && (next == '\0' || next == ' '))
            return 1;
        p++;
    }
    return 0;
}

static int print_device(cl_device_id d, cl_uint pi, cl_uint di, char *err, size_t errlen)
{
    char *name, *cver = NULL, *ext = NULL;
    char mem[32], alloc[32];
    cl_device_type type = 0;
    cl_uint units = 0;
    cl_ulong gmem = 0, maxalloc = 0;
    cl_int e;
    int rc = -1;

    name = device_string(d, CL_DEVICE_NAME, "clGetDeviceInfo(CL_DEVICE_NAME)", err, errlen);
    if (!name)
        return -1;
    cver = device_string(d, CL_DEVICE_OPENCL_C_VERSION,
                         "clGetDeviceInfo(CL_DEVICE_OPENCL_C_VERSION)", err, errlen);
    if (cver)
        ext = device_string(d, CL_DEVICE_EXTENSIONS, "clGetDeviceInfo(CL_DEVICE_EXTENSIONS)", err,
                            errlen);
    if (!cver || !ext)
        goto out_free;
    e = clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof units, &units, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof gmem, &gmem, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof maxalloc, &maxalloc, NULL);
    if (e != CL_SUCCESS) {
        cldev_fail(e, "clGetDeviceInfo", NULL, err, errlen);
        goto out_free;
    }
    short_version(cver);
    format_bytes(mem, sizeof mem, gmem);
    format_bytes(alloc, sizeof alloc, maxalloc);
    printf("  device %u:%u  %s  %s\n", pi, di, type_name(type), name);
    printf("              %u compute units, %s memory (max alloc %s), %s, fp64 %s\n", units, mem,
           alloc, cver, has_fp64(d, ext) ? "yes" : "no");
    rc = 0;
out_free:
    free(name);
    free(cver);
    free(ext);
    return rc;
}

/* The platform's line, then a line pair per device. */
static int print_platform(cl_platform_id p, cl_uint pi, char *err, size_t errlen)
{
    char pname[256] = "", pver[256] = "";
    cl_device_id *devs = NULL;
    cl_uint nd = 0, j;
    int rc = 0;
    cl_int e = clGetPlatformInfo(p, CL_PLATFORM_NAME, sizeof pname, pname, NULL);
    if (e == CL_SUCCESS)
        e = clGetPlatformInfo(p, CL_PLATFORM_VERSION, sizeof pver, pver, NULL);
    if (e != CL_SUCCESS)
        return cldev_fail(e, "clGetPlatformInfo", NULL, err, errlen);
    short_version(pver);
    printf("platform %u: %s (%s)\n", pi, pname, pver);
    if (cldev_devices(p, &devs, &nd, err, errlen) != 0)
        return -1;
    if (nd == 0)
        printf("  (no devices)\n");
    for (j = 0; j < nd && rc == 0; j++)
        rc = print_device(devs[j], pi, j, err, errlen);
    free(devs);
    return rc;
}

int cldev_print_list(char *err, size_t errlen)
{
    cl_platform_id *plats = NULL;
    cl_uint np = 0, i;
    int rc = 0;
    if (cldev_platforms(&plats, &np, err, errlen) != 0)
        return -1;
    for (i = 0; i < np && rc == 0; i++)
        rc = print_platform(plats[i], i, err, errlen);
    free(plats);
    return rc;
}

/* ---- error names ------------------------------------------------------------------ */

const char *cldev_error_name(cl_int err)
{
    switch (err) {
        /* clang-format off */
#define E(x) case x: return #x;
    E(CL_SUCCESS)
    E(CL_DEVICE_NOT_FOUND)
    E(CL_DEVICE_NOT_AVAILABLE)
    E(CL_COMPILER_NOT_AVAILABLE)
    E(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    E(CL_OUT_OF_RESOURCES)
    E(CL_OUT_OF_HOST_MEMORY)
    E(CL_PROFILING_INFO_NOT_AVAILABLE)
    E(CL_MEM_COPY_OVERLAP)
    E(CL_IMAGE_FORMAT_MISMATCH)
    E(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    E(CL_BUILD_PROGRAM_FAILURE)
    E(CL_MAP_FAILURE)
    E(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    E(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    E(CL_COMPILE_PROGRAM_FAILURE)
    E(CL_LINKER_NOT_AVAILABLE)
    E(CL_LINK_PROGRAM_FAILURE)
    E(CL_DEVICE_PARTITION_FAILED)
    E(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    E(CL_INVALID_VALUE)
    E(CL_INVALID_DEVICE_TYPE)
    E(CL_INVALID_PLATFORM)
    E(CL_INVALID_DEVICE)
    E(CL_INVALID_CONTEXT)
    E(CL_INVALID_QUEUE_PROPERTIES)
    E(CL_INVALID_COMMAND_QUEUE)
    E(CL_INVALID_HOST_PTR)
    E(CL_INVALID_MEM_OBJECT)
    E(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    E(CL_INVALID_IMAGE_SIZE)
    E(CL_INVALID_SAMPLER)
    E(CL_INVALID_BINARY)
    E(CL_INVALID_BUILD_OPTIONS)
    E(CL_INVALID_PROGRAM)
    E(CL_INVALID_PROGRAM_EXECUTABLE)
    E(CL_INVALID_KERNEL_NAME)
    E(CL_INVALID_KERNEL_DEFINITION)
    E(CL_INVALID_KERNEL)
    E(CL_INVALID_ARG_INDEX)
    E(CL_INVALID_ARG_VALUE)
    E(CL_INVALID_ARG_SIZE)
    E(CL_INVALID_KERNEL_ARGS)
    E(CL_INVALID_WORK_DIMENSION)
    E(CL_INVALID_WORK_GROUP_SIZE)
    E(CL_INVALID_WORK_ITEM_SIZE)
    E(CL_INVALID_GLOBAL_OFFSET)
    E(CL_INVALID_EVENT_WAIT_LIST)
    E(CL_INVALID_EVENT)
    E(CL_INVALID_OPERATION)
    E(CL_INVALID_GL_OBJECT)
    E(CL_INVALID_BUFFER_SIZE)
    E(CL_INVALID_MIP_LEVEL)
    E(CL_INVALID_GLOBAL_WORK_SIZE)
    E(CL_INVALID_PROPERTY)
    E(CL_INVALID_IMAGE_DESCRIPTOR)
    E(CL_INVALID_COMPILER_OPTIONS)
    E(CL_INVALID_LINKER_OPTIONS)
    E(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef E
        /* clang-format on */
    case -1001:
        return "CL_PLATFORM_NOT_FOUND_KHR";
    default:
        return "unknown OpenCL error";
    }
}
