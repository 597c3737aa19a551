/* cldevices: lists the OpenCL devices in the order clwhitted numbers them (platforms as
 * clGetPlatformIDs returns them, devices of CL_DEVICE_TYPE_ALL), one tab-separated line
 * each, with the limits and capabilities that portability depends on:
 *   P:D  type  name  platform  device-version  C-version  fp64  max-work-group
 *   local-mem-bytes  max-alloc-bytes  compute-units  driver-version
 * fp64 is "yes" when the device reports cl_khr_fp64 (or a non-zero double config), else
 * "no". Exit status: 0, or 1 when the OpenCL runtime cannot be queried (no platform is
 * not an error: nothing is printed). The enumeration is clwhitted's own (host/cl_device.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

#include "cl_device.h"

static void info_str(cl_device_id d, cl_device_info what, char *buf, size_t n)
{
    size_t i;
    if (clGetDeviceInfo(d, what, n, buf, NULL) != CL_SUCCESS)
        snprintf(buf, n, "?");
    buf[n - 1] = '\0';
    for (i = 0; buf[i]; i++) /* keep the output one line of tab-separated fields */
        if (buf[i] == '\t' || buf[i] == '\n' || buf[i] == '\r')
            buf[i] = ' ';
}

static const char *type_name(cl_device_type t)
{
    if (t & CL_DEVICE_TYPE_CPU) /* the order clwhitted --list-devices uses */
        return "CPU";
    if (t & CL_DEVICE_TYPE_GPU)
        return "GPU";
    if (t & CL_DEVICE_TYPE_ACCELERATOR)
        return "ACCELERATOR";
    return "OTHER";
}

int main(void)
{
    char err[512];
    cl_uint np = 0, p;
    cl_platform_id *plats;
    int rc = cldev_platforms(&plats, &np, err, sizeof err);
    if (rc == 1) /* no platform: nothing to list */
        return 0;
    if (rc != 0) {
        fprintf(stderr, "cldevices: %s\n", err);
        return 1;
    }
    for (p = 0; p < np; p++) {
        char pname[256];
        cl_uint nd = 0, d;
        cl_device_id *devs;
        if (clGetPlatformInfo(plats[p], CL_PLATFORM_NAME, sizeof pname, pname, NULL) != CL_SUCCESS)
            snprintf(pname, sizeof pname, "?");
        pname[sizeof pname - 1] = '\0';
        if (cldev_devices(plats[p], &devs, &nd, err, sizeof err) != 0)
            continue; /* a platform that cannot list its devices lists none */
        for (d = 0; d < nd; d++) {
            char name[256], ver[256], cver[256], drv[256], ext[8192];
            cl_device_type type = 0;
            size_t wg = 0;
            cl_ulong local = 0, alloc = 0;
            cl_uint units = 0;
            cl_device_fp_config dbl = 0;
            info_str(devs[d], CL_DEVICE_NAME, name, sizeof name);
            info_str(devs[d], CL_DEVICE_VERSION, ver, sizeof ver);
            info_str(devs[d], CL_DEVICE_OPENCL_C_VERSION, cver, sizeof cver);
            info_str(devs[d], CL_DRIVER_VERSION, drv, sizeof drv);
            info_str(devs[d], CL_DEVICE_EXTENSIONS, ext, sizeof ext);
            clGetDeviceInfo(devs[d], CL_DEVICE_TYPE, sizeof type, &type, NULL);
            clGetDeviceInfo(devs[d], CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof wg, &wg, NULL);
            clGetDeviceInfo(devs[d], CL_DEVICE_LOCAL_MEM_SIZE, sizeof local, &local, NULL);
            clGetDeviceInfo(devs[d], CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof alloc, &alloc, NULL);
            clGetDeviceInfo(devs[d], CL_DEVICE_MAX_COMPUTE_UNITS, sizeof units, &units, NULL);
            if (clGetDeviceInfo(devs[d], CL_DEVICE_DOUBLE_FP_CONFIG, sizeof dbl, &dbl, NULL) !=
                CL_SUCCESS)
                dbl = 0;
            printf("%u:%u\t%s\t%s\t%s\t%s\t%s\t%s\t%zu\t%llu\t%llu\t%u\t%s\n", p, d,
                   type_name(type), name, pname, ver, cver,
                   (strstr(ext, "cl_khr_fp64") || dbl) ? "yes" : "no", wg,
                   (unsigned long long)local, (unsigned long long)alloc, units, drv);
        }
        free(devs);
    }
    free(plats);
    return 0;
}
