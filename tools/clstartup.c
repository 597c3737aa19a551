/* clstartup: the OpenCL start-up floor of a clwhitted run. It finds the device that
 * clwhitted would use (the same --device SPEC rule, host/cl_device.c), creates its context
 * and command queue, prints how long each step took and exits the way a successful
 * clwhitted render does (sys_exit_now: no teardown). tools/bench times its whole process:
 * what no clwhitted run can be faster than (with PoCL, loading its LLVM).
 * Usage: clstartup [SPEC]. Exit status 0, or 1 with a message when a step fails. */
#include <stdio.h>

#include <CL/cl.h>

#include "cl_device.h"
#include "sys.h"

int main(int argc, char **argv)
{
    char err[512], name[256];
    const char *spec = argc > 1 ? argv[1] : NULL;
    cl_device_id dev;
    cl_context ctx;
    cl_command_queue q;
    cl_int e;
    double t0 = sys_now(), t1, t2, t3;

    if (argc > 2) {
        fprintf(stderr, "usage: clstartup [SPEC]  (SPEC as clwhitted --device)\n");
        return 2;
    }
    if (cldev_find(spec, &dev, err, sizeof err) != 0) {
        fprintf(stderr, "clstartup: %s\n", err);
        return 1;
    }
    t1 = sys_now();
    ctx = clCreateContext(NULL, 1, &dev, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        cldev_fail(e, "clCreateContext", NULL, err, sizeof err);
        fprintf(stderr, "clstartup: %s\n", err);
        return 1;
    }
    t2 = sys_now();
    q = clCreateCommandQueue(ctx, dev, 0, &e);
    if (e != CL_SUCCESS) {
        cldev_fail(e, "clCreateCommandQueue", NULL, err, sizeof err);
        fprintf(stderr, "clstartup: %s\n", err);
        return 1;
    }
    t3 = sys_now();
    (void)q;
    if (clGetDeviceInfo(dev, CL_DEVICE_NAME, sizeof name, name, NULL) != CL_SUCCESS)
        snprintf(name, sizeof name, "?");
    name[sizeof name - 1] = '\0';
    printf("clstartup: %s: platform and device %.1f ms, context %.1f ms, queue %.1f ms\n", name,
           (t1 - t0) * 1e3, (t2 - t1) * 1e3, (t3 - t2) * 1e3);
    sys_exit_now(0);
    return 0;
}
