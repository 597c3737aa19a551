/* --list-devices: a concise listing of the OpenCL platforms and devices, like `clinfo -l`
 * with the facts that matter for rendering. The P:D indices are the enumeration order of
 * clGetPlatformIDs and clGetDeviceIDs(CL_DEVICE_TYPE_ALL), the order find_device in
 * render.c uses for --device P:D. */
#include "render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

#include "clerr.h"

static int fail(cl_int e, const char *call, char *err, size_t errlen)
{
    snprintf(err, errlen, "%s failed: %s (%d)", call, cl_error_name(e), (int)e);
    return -1;
}

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
        fail(e, call, err, errlen);
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
        fail(e, call, err, errlen);
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

    name = device_string(d, CL_DEVICE_NAME, "clGetDeviceInfo(CL_DEVICE_NAME)", err, errlen);
    if (!name)
        return -1;
    cver = device_string(d, CL_DEVICE_OPENCL_C_VERSION,
                         "clGetDeviceInfo(CL_DEVICE_OPENCL_C_VERSION)", err, errlen);
    if (cver)
        ext = device_string(d, CL_DEVICE_EXTENSIONS, "clGetDeviceInfo(CL_DEVICE_EXTENSIONS)", err,
                            errlen);
    if (!cver || !ext)
        goto fail;
    e = clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof units, &units, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof gmem, &gmem, NULL);
    if (e == CL_SUCCESS)
        e = clGetDeviceInfo(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof maxalloc, &maxalloc, NULL);
    if (e != CL_SUCCESS) {
        fail(e, "clGetDeviceInfo", err, errlen);
        goto fail;
    }
    short_version(cver);
    format_bytes(mem, sizeof mem, gmem);
    format_bytes(alloc, sizeof alloc, maxalloc);
    printf("  device %u:%u  %s  %s\n", pi, di, type_name(type), name);
    printf("              %u compute units, %s memory (max alloc %s), %s, fp64 %s\n", units, mem,
           alloc, cver, has_fp64(d, ext) ? "yes" : "no");
    free(name);
    free(cver);
    free(ext);
    return 0;
fail:
    free(name);
    free(cver);
    free(ext);
    return -1;
}

int renderer_list_devices(char *err, size_t errlen)
{
    cl_platform_id *plats = NULL;
    cl_uint np = 0, i, j;
    cl_int e = clGetPlatformIDs(0, NULL, &np);

    if (e == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || (e == CL_SUCCESS && np == 0)) {
        snprintf(err, errlen,
                 "no OpenCL platform found (install pocl-opencl-icd: "
                 "sh tools/install-deps)");
        return -1;
    }
    if (e != CL_SUCCESS)
        return fail(e, "clGetPlatformIDs", err, errlen);
    plats = calloc(np, sizeof *plats);
    if (!plats) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    e = clGetPlatformIDs(np, plats, NULL);
    if (e != CL_SUCCESS) {
        free(plats);
        return fail(e, "clGetPlatformIDs", err, errlen);
    }
    for (i = 0; i < np; i++) {
        char pname[256] = "", pver[256] = "";
        cl_device_id *devs = NULL;
        cl_uint nd = 0;
        e = clGetPlatformInfo(plats[i], CL_PLATFORM_NAME, sizeof pname, pname, NULL);
        if (e == CL_SUCCESS)
            e = clGetPlatformInfo(plats[i], CL_PLATFORM_VERSION, sizeof pver, pver, NULL);
        if (e != CL_SUCCESS) {
            free(plats);
            return fail(e, "clGetPlatformInfo", err, errlen);
        }
        short_version(pver);
        printf("platform %u: %s (%s)\n", i, pname, pver);
        e = clGetDeviceIDs(plats[i], CL_DEVICE_TYPE_ALL, 0, NULL, &nd);
        if (e == CL_DEVICE_NOT_FOUND || (e == CL_SUCCESS && nd == 0)) {
            printf("  (no devices)\n");
            continue;
        }
        if (e == CL_SUCCESS) {
            devs = calloc(nd, sizeof *devs);
            if (!devs) {
                free(plats);
                snprintf(err, errlen, "out of memory");
                return -1;
            }
            e = clGetDeviceIDs(plats[i], CL_DEVICE_TYPE_ALL, nd, devs, NULL);
        }
        if (e != CL_SUCCESS) {
            free(devs);
            free(plats);
            return fail(e, "clGetDeviceIDs", err, errlen);
        }
        for (j = 0; j < nd; j++)
            if (print_device(devs[j], i, j, err, errlen) != 0) {
                free(devs);
                free(plats);
                return -1;
            }
        free(devs);
    }
    free(plats);
    return 0;
}
