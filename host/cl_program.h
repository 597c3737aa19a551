/* The kernel program (see cl_program.c). */
#ifndef CW_CL_PROGRAM_H
#define CW_CL_PROGRAM_H

#include <stddef.h>

#include <CL/cl.h>

/* What the scene uses, decided once at upload: the kernel features come from it. */
typedef struct {
    int spheres, triangles, polygons, cones; /* primitives uploaded (degenerate ones dropped) */
    int instances;                           /* placed meshes (the two-level BVH) */
    int mirrors;                             /* some material has km > 0 */
    int transmitters;                        /* some material has kt > 0 */
} clprog_features;

/* The build options of the kernel program, every one decided here: the feature flags
 * from what the scene uses and its depth (reflection and refraction need depth > 1; SPD
 * counting turns transmitters into reflectors too), the settings (fast: the fast relaxed
 * path; stats: ray counting; pixel: the per-pixel kernel rather than the wavefront's, each
 * program holding only its strategy's kernels), then CLWHITTED_BUILD_OPTIONS when set. */
void clprog_options(const clprog_features *ft, int max_depth, int spd, int fast, int stats,
                    int pixel, char *buf, size_t n);

/* Builds the embedded kernel source with options for dev: from the binary cache when it
 * holds the program (*cached = 1), else from source (*cached = 0; then caching its
 * binary). When the build fails, the build log goes to stderr and err names the device
 * (device_name). Returns 0 with *out, or -1 with err. */
int clprog_build(cl_context ctx, cl_device_id dev, const char *device_name, const char *options,
                 cl_program *out, int *cached, char *err, size_t errlen);

#endif
