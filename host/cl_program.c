/* The kernel program: its build options (from the scene's features and the settings), and
 * its build: from the cache of built programs (progcache.c) when it holds them, else from
 * the embedded source with the build log on failure. */
#include "cl_program.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cl_device.h"
#include "progcache.h"

extern const char cw_kernel_source[];

void clprog_options(const clprog_features *ft, int max_depth, int spd, int fast, int stats,
                    int pixel, char *buf, size_t n)
{
    const char *extra = getenv("CLWHITTED_BUILD_OPTIONS");
    int deep = max_depth > 1;
    snprintf(buf, n,
             "-cl-std=CL1.2 -Werror -DCW_HAS_SPHERES=%d -DCW_HAS_TRIANGLES=%d "
             "-DCW_HAS_POLYGONS=%d -DCW_HAS_CONES=%d -DCW_HAS_INSTANCES=%d -DCW_HAS_MIRRORS=%d "
             "-DCW_HAS_REFRACTION=%d -DCW_FAST=%d -DCW_STATS=%d -DCW_PIXEL=%d%s%s%s",
             ft->spheres > 0, ft->triangles > 0, ft->polygons > 0, ft->cones > 0,
             ft->instances > 0 && ft->triangles > 0,
             deep && (ft->mirrors || (spd && ft->transmitters)), deep && ft->transmitters,
             fast != 0, stats != 0, pixel != 0, fast ? " -cl-fast-relaxed-math" : "",
             extra ? " " : "", extra ? extra : "");
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
        char why[1024];
        log[len] = '\0';
        fprintf(stderr, "kernel build log (%s, options: %s):\n%s\n", device_name, options, log);
        if (strspn(log, " \t\r\n") == strlen(log) && cldev_env_problem(why, sizeof why))
            fprintf(stderr, "clwhitted: the build log is empty: %s\n", why);
    }
    free(log);
}

int clprog_build(cl_context ctx, cl_device_id dev, const char *device_name, const char *options,
                 cl_program *out, int *cached, char *err, size_t errlen)
{
    const char *src = cw_kernel_source;
    cl_program p;
    cl_int e;

    p = progcache_load(ctx, dev, src, options);
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
    progcache_store(p, dev, src, options);
    *out = p;
    return 0;
}
