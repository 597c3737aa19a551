/* The device side of a render: work buffers grown on demand, kernel arguments and
 * launches, and the pass that traces one sample of a band of rows in either strategy: the
 * wavefront's loop (ray generation, then per depth one intersection, one shading and one
 * shadow-ray launch) or one launch of the per-pixel kernel. */
#include "render_pass.h"

#include <stdio.h>

#include "cl_device.h"
#include "config.h"
#include "sys.h"

/* Kernel argument indices (kernels/clwhitted.cl). The kernels that take the world have
 * theirs after the world's: from CW_WORLD_NARGS on. */
enum { RAYGEN_FRAME, RAYGEN_RAYS, RAYGEN_IMAGE, RAYGEN_ROW0, RAYGEN_NROWS, RAYGEN_SX, RAYGEN_SY };
enum { INTERSECT_RAYS = CW_WORLD_NARGS, INTERSECT_HITS, INTERSECT_COUNTERS, INTERSECT_N };
enum {
    SHADE_LIGHTS = CW_WORLD_NARGS,
    SHADE_MATERIALS,
    SHADE_RAYS,
    SHADE_HITS,
    SHADE_IMAGE,
    SHADE_OUT,
    SHADE_SHADOWS,
    SHADE_COUNTERS,
    SHADE_N
};
enum { OCCLUDE_SHADOWS = CW_WORLD_NARGS, OCCLUDE_IMAGE, OCCLUDE_COUNTERS, OCCLUDE_N };
enum {
    PIXEL_LIGHTS = CW_WORLD_NARGS,
    PIXEL_MATERIALS,
    PIXEL_IMAGE,
    PIXEL_COUNTERS,
    PIXEL_ROW0,
    PIXEL_NROWS,
    PIXEL_SX,
    PIXEL_SY,
    PIXEL_FIRST
};

int rpass_fail(cl_int e, const char *call, const renderer *r, char *err, size_t errlen)
{
    return cldev_fail(e, call, r->device_name, err, errlen);
}

int rpass_need_scene(const renderer *r, char *err, size_t errlen)
{
    if (!r->have_scene) {
        snprintf(err, errlen, "no scene uploaded (call renderer_set_scene first)");
        return -1;
    }
    return 0;
}

/* ---- buffers ---------------------------------------------------------------------- */

int rpass_check_alloc(const renderer *r, const char *what, size_t bytes, char *err, size_t errlen)
{
    if ((cl_ulong)bytes > r->max_alloc) {
        snprintf(err, errlen,
                 "the %s buffer needs %zu bytes, more than the %llu bytes that device %s can "
                 "allocate at once",
                 what, bytes, (unsigned long long)r->max_alloc, r->device_name);
        return -1;
    }
    return 0;
}

/* Bytes per pixel of a render: on the device the accumulation image (rgb + count floats);
 * on the host its read back and the image's rgb floats. */
#define MEM_DEVICE_PER_PIXEL (4 * sizeof(cl_float))
#define MEM_HOST_PER_PIXEL (4 * sizeof(float) + 3 * sizeof(float))

static double gib(unsigned long long b)
{
    return (double)b / (1024.0 * 1024.0 * 1024.0);
}

int renderer_check_memory(const renderer *r, int width, int height, char *err, size_t errlen)
{
    unsigned long long px = (unsigned long long)(width + 1) * (unsigned long long)(height + 1);
    unsigned long long accum = px * MEM_DEVICE_PER_PIXEL, device = accum + CW_BAND_BYTES;
    unsigned long long host = px * MEM_HOST_PER_PIXEL, avail = sys_mem_available();
    cl_ulong global = 0;
    cl_bool unified = CL_FALSE;
    const char *fix = "reduce -W/-H (each halving of both needs a quarter)";
    if (clGetDeviceInfo(r->device, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof global, &global, NULL) !=
        CL_SUCCESS)
        global = 0;
    if (clGetDeviceInfo(r->device, CL_DEVICE_HOST_UNIFIED_MEMORY, sizeof unified, &unified, NULL) !=
        CL_SUCCESS)
        unified = CL_FALSE;
    if (accum > r->max_alloc) {
        snprintf(err, errlen,
                 "a %dx%d image needs a %.1f GiB accumulation buffer (%zu bytes per pixel); "
                 "device %s allocates at most %.1f GiB at once: %s",
                 width, height, gib(accum), MEM_DEVICE_PER_PIXEL, r->device_name, gib(r->max_alloc),
                 fix);
        return -1;
    }
    if (global > 0 && device > global) {
        snprintf(err, errlen,
                 "a %dx%d image needs %.1f GiB of device memory; device %s has %.1f GiB: %s", width,
                 height, gib(device), r->device_name, gib(global), fix);
        return -1;
    }
    if (unified)
        host += device; /* the device's memory is the host's */
    if (avail > 0 && host > avail) {
        snprintf(err, errlen,
                 "a %dx%d image needs about %.1f GiB of memory (%zu bytes per pixel%s); %.1f GiB "
                 "is available: %s",
                 width, height, gib(host),
                 MEM_HOST_PER_PIXEL + (unified ? MEM_DEVICE_PER_PIXEL : 0),
                 unified ? ", host and device" : " on the host", gib(avail), fix);
        return -1;
    }
    return 0;
}

void rpass_release(cl_mem *m)
{
    if (*m)
        clReleaseMemObject(*m);
    *m = NULL;
}

int rpass_ensure_buffer(renderer *r, cl_mem *m, size_t *cap, size_t need, const char *what,
                        char *err, size_t errlen)
{
    cl_int e;
    if (*m && *cap >= need)
        return 0;
    rpass_release(m);
    *cap = 0;
    if (need == 0)
        need = 16;
    if (rpass_check_alloc(r, what, need, err, errlen) != 0)
        return -1;
    *m = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, need, NULL, &e);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes)", what, need);
        return rpass_fail(e, call, r, err, errlen);
    }
    *cap = need;
    return 0;
}

int rpass_fill_zero(renderer *r, cl_mem m, size_t size, const char *what, char *err, size_t errlen)
{
    cl_int zero = 0;
    cl_int e = clEnqueueFillBuffer(r->queue, m, &zero, sizeof zero, 0, size, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueFillBuffer(%s)", what);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

int rpass_read(renderer *r, cl_mem m, size_t size, void *dst, const char *what, char *err,
               size_t errlen)
{
    cl_int e = clEnqueueReadBuffer(r->queue, m, CL_TRUE, 0, size, dst, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueReadBuffer(%s)", what);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

int rpass_write(renderer *r, cl_mem m, size_t size, const void *src, const char *what, char *err,
                size_t errlen)
{
    cl_int e = clEnqueueWriteBuffer(r->queue, m, CL_TRUE, 0, size, src, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueWriteBuffer(%s)", what);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

int rpass_ensure_image(renderer *r, char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    return rpass_ensure_buffer(r, &r->image, &r->image_cap, n * 4 * sizeof(cl_float), "image", err,
                               errlen) ||
           rpass_ensure_buffer(r, &r->counters, &(size_t){0}, CW_NUM_COUNTERS * sizeof(cl_int),
                               "counters", err, errlen);
}

int rpass_clear_accumulation(renderer *r, char *err, size_t errlen)
{
    return rpass_clear_rows(r, 0, r->host_frame.ny, err, errlen);
}

int rpass_clear_rows(renderer *r, int row0, int nrows, char *err, size_t errlen)
{
    size_t row_bytes = (size_t)r->host_frame.nx * 4 * sizeof(cl_float);
    cl_int zero = 0, e;
    if (rpass_ensure_image(r, err, errlen))
        return -1;
    e = clEnqueueFillBuffer(r->queue, r->image, &zero, sizeof zero, row_bytes * (size_t)row0,
                            row_bytes * (size_t)nrows, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return rpass_fail(e, "clEnqueueFillBuffer(image)", r, err, errlen);
    return 0;
}

int rpass_band_rows(const renderer *r)
{
    size_t per_ray = 2 * sizeof(cw_ray) + sizeof(cw_hit) +
                     (size_t)(r->host_frame.num_lights + 1) * sizeof(cw_shadow_ray);
    size_t rays = CW_BAND_BYTES / per_ray;
    size_t rows = rays / (size_t)r->host_frame.nx;
    if (rows < 1)
        rows = 1;
    if (rows > (size_t)r->host_frame.ny)
        rows = (size_t)r->host_frame.ny;
    return (int)rows;
}

/* ---- kernel arguments and launches ------------------------------------------------ */

static int set_arg(cl_kernel k, cl_uint i, size_t size, const void *v, const char *kname,
                   const renderer *r, char *err, size_t errlen)
{
    cl_int e = clSetKernelArg(k, i, size, v);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clSetKernelArg(%s, %u)", kname, i);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

static int set_mem(cl_kernel k, cl_uint i, cl_mem *m, const char *kname, const renderer *r,
                   char *err, size_t errlen)
{
    return set_arg(k, i, sizeof(cl_mem), m, kname, r, err, errlen);
}

/* The world arguments of the intersect, shade and occlude kernels (CW_WORLD_ARGS): the
 * frame, then each buffer of CW_WORLD_BUFFERS at its CW_WORLD_ARG_ index. */
static int set_world_args(renderer *r, cl_kernel k, const char *kname, char *err, size_t errlen)
{
    if (set_mem(k, CW_WORLD_ARG_frame, &r->world.frame, kname, r, err, errlen))
        return -1;
#define SET_WORLD_ARG(type, name, what)                                                            \
    if (set_mem(k, CW_WORLD_ARG_##name, &r->world.name, kname, r, err, errlen))                    \
        return -1;
    CW_WORLD_BUFFERS(SET_WORLD_ARG)
#undef SET_WORLD_ARG
    return 0;
}

/* The work-group size for kernel k: CW_GROUP_SIZE (64), or less where the device or the
 * kernel allows less (queried, never assumed). A fixed size also keeps PoCL from
 * specialising (and compiling) the kernel anew for every global size. */
static size_t group_size(const renderer *r, cl_kernel k)
{
    size_t kmax = 0, g = CW_GROUP_SIZE;
    if (clGetKernelWorkGroupInfo(k, r->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof kmax, &kmax,
                                 NULL) != CL_SUCCESS ||
        kmax == 0)
        kmax = 1;
    while (g > kmax)
        g /= 2;
    return g;
}

static int launch(renderer *r, cl_kernel k, size_t n, const char *kname, char *err, size_t errlen)
{
    size_t local = group_size(r, k);
    size_t global = (n + local - 1) / local * local;
    cl_int e = clEnqueueNDRangeKernel(r->queue, k, 1, NULL, &global, &local, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[128];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s, %zu work-items in groups of %zu)",
                 kname, global, local);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

/* Launched in 2-D, one work-item per pixel (no index division in the kernel). */
int rpass_raygen(renderer *r, int row0, int nrows, float sx, float sy, char *err, size_t errlen)
{
    const char *k = "cw_raygen";
    size_t global[2], local[2];
    cl_int e, crow0 = row0, cnrows = nrows;
    size_t n = (size_t)r->host_frame.nx * (size_t)nrows;
    if (rpass_ensure_buffer(r, &r->rays[0], &r->ray_cap[0], n * sizeof(cw_ray), "ray queue", err,
                            errlen))
        return -1;
    local[1] = 1;
    local[0] = group_size(r, r->k_raygen);
    global[0] = ((size_t)r->host_frame.nx + local[0] - 1) / local[0] * local[0];
    global[1] = (size_t)nrows;
    if (set_mem(r->k_raygen, RAYGEN_FRAME, &r->world.frame, k, r, err, errlen) ||
        set_mem(r->k_raygen, RAYGEN_RAYS, &r->rays[0], k, r, err, errlen) ||
        set_mem(r->k_raygen, RAYGEN_IMAGE, &r->image, k, r, err, errlen) ||
        set_arg(r->k_raygen, RAYGEN_ROW0, sizeof crow0, &crow0, k, r, err, errlen) ||
        set_arg(r->k_raygen, RAYGEN_NROWS, sizeof cnrows, &cnrows, k, r, err, errlen) ||
        set_arg(r->k_raygen, RAYGEN_SX, sizeof sx, &sx, k, r, err, errlen) ||
        set_arg(r->k_raygen, RAYGEN_SY, sizeof sy, &sy, k, r, err, errlen))
        return -1;
    e = clEnqueueNDRangeKernel(r->queue, r->k_raygen, 2, NULL, global, local, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return rpass_fail(e, "clEnqueueNDRangeKernel(cw_raygen)", r, err, errlen);
    return 0;
}

int rpass_intersect(renderer *r, cl_mem *rays, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_intersect";
    cl_kernel kn = r->k_intersect;
    if (rpass_ensure_buffer(r, &r->hits, &r->hit_cap, (size_t)n * sizeof(cw_hit), "hits", err,
                            errlen))
        return -1;
    return set_world_args(r, kn, k, err, errlen) ||
           set_mem(kn, INTERSECT_RAYS, rays, k, r, err, errlen) ||
           set_mem(kn, INTERSECT_HITS, &r->hits, k, r, err, errlen) ||
           set_mem(kn, INTERSECT_COUNTERS, &r->counters, k, r, err, errlen) ||
           set_arg(kn, INTERSECT_N, sizeof n, &n, k, r, err, errlen) ||
           launch(r, kn, (size_t)n, k, err, errlen);
}

static int run_shade(renderer *r, cl_mem *rays, cl_mem *out, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_shade";
    cl_kernel kn = r->k_shade;
    return set_world_args(r, kn, k, err, errlen) ||
           set_mem(kn, SHADE_LIGHTS, &r->lights, k, r, err, errlen) ||
           set_mem(kn, SHADE_MATERIALS, &r->materials, k, r, err, errlen) ||
           set_mem(kn, SHADE_RAYS, rays, k, r, err, errlen) ||
           set_mem(kn, SHADE_HITS, &r->hits, k, r, err, errlen) ||
           set_mem(kn, SHADE_IMAGE, &r->image, k, r, err, errlen) ||
           set_mem(kn, SHADE_OUT, out, k, r, err, errlen) ||
           set_mem(kn, SHADE_SHADOWS, &r->shadows, k, r, err, errlen) ||
           set_mem(kn, SHADE_COUNTERS, &r->counters, k, r, err, errlen) ||
           set_arg(kn, SHADE_N, sizeof n, &n, k, r, err, errlen) ||
           launch(r, kn, (size_t)n, k, err, errlen);
}

int rpass_occlude(renderer *r, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_occlude";
    cl_kernel kn = r->k_occlude;
    return set_world_args(r, kn, k, err, errlen) ||
           set_mem(kn, OCCLUDE_SHADOWS, &r->shadows, k, r, err, errlen) ||
           set_mem(kn, OCCLUDE_IMAGE, &r->image, k, r, err, errlen) ||
           set_mem(kn, OCCLUDE_COUNTERS, &r->counters, k, r, err, errlen) ||
           set_arg(kn, OCCLUDE_N, sizeof n, &n, k, r, err, errlen) ||
           launch(r, kn, (size_t)n, k, err, errlen);
}

/* The per-pixel kernel over rows [row0, row0 + nrows): CW_PIX_GROUPS work-groups per compute
 * unit, which take the launch's tiles of pixels one at a time (cw_pixel). A group has one
 * work-item on a CPU device, else up to CW_PIX_LANES: a CPU runtime runs a group's work-items
 * one after another on one thread, so that the first takes every tile the group gets and the
 * others find none left; as a group of one, PoCL compiles the kernel without its loop over
 * work-items (paired single-thread renders: teapot at 1024x1024 0.95, 11 rounds of 12
 * faster; 1M random triangles 0.98, 14 of 20; Intel's CPU runtime: no change). */
static int run_pixel(renderer *r, int row0, int nrows, float sx, float sy, cl_int first, char *err,
                     size_t errlen)
{
    const char *k = "cw_pixel";
    cl_kernel kn = r->k_pixel;
    size_t global, local = r->cpu ? 1 : group_size(r, kn);
    int units = renderer_compute_units(r);
    cl_int e, crow0 = row0, cnrows = nrows;
    if (local > CW_PIX_LANES)
        local = CW_PIX_LANES;
    global = local * CW_PIX_GROUPS * (size_t)(units > 0 ? units : 1);
    if (set_world_args(r, kn, k, err, errlen) ||
        set_mem(kn, PIXEL_LIGHTS, &r->lights, k, r, err, errlen) ||
        set_mem(kn, PIXEL_MATERIALS, &r->materials, k, r, err, errlen) ||
        set_mem(kn, PIXEL_IMAGE, &r->image, k, r, err, errlen) ||
        set_mem(kn, PIXEL_COUNTERS, &r->counters, k, r, err, errlen) ||
        set_arg(kn, PIXEL_ROW0, sizeof crow0, &crow0, k, r, err, errlen) ||
        set_arg(kn, PIXEL_NROWS, sizeof cnrows, &cnrows, k, r, err, errlen) ||
        set_arg(kn, PIXEL_SX, sizeof sx, &sx, k, r, err, errlen) ||
        set_arg(kn, PIXEL_SY, sizeof sy, &sy, k, r, err, errlen) ||
        set_arg(kn, PIXEL_FIRST, sizeof first, &first, k, r, err, errlen))
        return -1;
    e = clEnqueueNDRangeKernel(r->queue, kn, 1, NULL, &global, &local, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[128];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s, %zu work-items in groups of %zu)",
                 k, global, local);
        return rpass_fail(e, call, r, err, errlen);
    }
    return 0;
}

/* ---- the pass loop ---------------------------------------------------------------- */

/* The position of sample k (mod spp) inside its pixel: a ceil(sqrt(spp)) x rows grid of
 * cell centres, taken row by row. spp = 1: the pixel centre. */
static void sample_position(int spp, int k, float *sx, float *sy)
{
    int gx = 1, gy;
    if (spp < 1)
        spp = 1;
    while (gx * gx < spp)
        gx++;
    gy = (spp + gx - 1) / gx;
    k %= spp;
    *sx = ((float)(k % gx) + 0.5f) / (float)gx;
    *sy = ((float)(k / gx) + 0.5f) / (float)gy;
}

static unsigned long long total_rays(const render_stats *st)
{
    return st->eye_rays + st->shadow_rays + st->secondary_rays;
}

/* Adds a launch's --stats counts (the hits, the blocked shadow rays and the walks' work) to
 * the totals. */
static void add_stat_counts(renderer *r, const cl_int *counts)
{
    if (!r->settings.stats)
        return;
    r->stats.eye_hits += (unsigned long long)counts[CW_COUNT_EYE_HITS];
    r->stats.secondary_hits += (unsigned long long)counts[CW_COUNT_SECONDARY_HITS];
    r->stats.shadow_blocked += (unsigned long long)counts[CW_COUNT_BLOCKED];
    /* a launch's walk counts may pass 2^31: the kernels' int adds wrap as unsigned ones */
    r->stats.closest_nodes += (cl_uint)counts[CW_COUNT_CLOSEST_NODES];
    r->stats.closest_tests += (cl_uint)counts[CW_COUNT_CLOSEST_TESTS];
    r->stats.any_nodes += (cl_uint)counts[CW_COUNT_ANY_NODES];
    r->stats.any_tests += (cl_uint)counts[CW_COUNT_ANY_TESTS];
}

/* Reports the fraction done to the progress callback. Returns 0, or -1 with "render
 * cancelled" when the callback asks to stop. */
static int report_progress(renderer *r, double fraction, char *err, size_t errlen)
{
    if (r->progress && r->progress(r->progress_ctx, fraction, total_rays(&r->stats)) != 0) {
        snprintf(err, errlen, "render cancelled");
        return -1;
    }
    return 0;
}

/* With statistics on, waits for the queue and adds the time since *t0 to *acc. */
static int stats_lap(renderer *r, double *t0, double *acc, char *err, size_t errlen)
{
    double t;
    cl_int e;
    if (!r->settings.stats)
        return 0;
    e = clFinish(r->queue);
    if (e != CL_SUCCESS)
        return rpass_fail(e, "clFinish", r, err, errlen);
    t = sys_now();
    *acc += t - *t0;
    *t0 = t;
    return 0;
}

/* The per-pixel strategy: the band in launches of about CW_PIXEL_LAUNCH_PIXELS pixels, the
 * counters read after each (the only wait). The band's deepest ray is the number of
 * levels the wavefront runs for it: the bands are the wavefront's, so the passes are too. */
static int trace_band_pixel(renderer *r, int sample, int row0, int nrows, int first, double done,
                            double share, char *err, size_t errlen)
{
    int rows = CW_PIXEL_LAUNCH_PIXELS / r->host_frame.nx, depth = 1, y;
    float sx, sy;
    double tl = sys_now();

    if (rows < 1)
        rows = 1;
    sample_position(r->settings.spp, sample, &sx, &sy);
    if (rpass_ensure_image(r, err, errlen))
        return -1;
    for (y = row0; y < row0 + nrows; y += rows) {
        cl_int counts[CW_NUM_COUNTERS];
        int n = y + rows > row0 + nrows ? row0 + nrows - y : rows;
        if (rpass_fill_zero(r, r->counters, CW_NUM_COUNTERS * sizeof(cl_int), "counters", err,
                            errlen) ||
            run_pixel(r, y, n, sx, sy, first, err, errlen) ||
            rpass_read(r, r->counters, sizeof counts, counts, "counters", err, errlen) ||
            stats_lap(r, &tl, &r->stats.pixel_s, err, errlen))
            return -1;
        if (counts[CW_COUNT_DEPTH] > depth)
            depth = counts[CW_COUNT_DEPTH];
        r->stats.eye_rays += (unsigned long long)r->host_frame.nx * (unsigned long long)n;
        r->stats.shadow_rays += (unsigned long long)counts[CW_COUNT_SHADOWS];
        r->stats.secondary_rays += (unsigned long long)counts[CW_COUNT_RAYS];
        add_stat_counts(r, counts);
        if (report_progress(r, done + share * (double)(y + n - row0) / nrows, err, errlen))
            return -1;
    }
    r->stats.passes += depth;
    return 0;
}

/* The wavefront: the next level's rays go to the other queue. The only wait per level is
 * the read of the queue counters. */
static int trace_band_wavefront(renderer *r, int sample, int row0, int nrows, double done,
                                double share, char *err, size_t errlen)
{
    cl_int n = (cl_int)((size_t)r->host_frame.nx * (size_t)nrows);
    int cur = 0, depth, branch = r->features.transmitters ? 2 : 1;
    size_t lights = (size_t)(r->host_frame.num_lights > 0 ? r->host_frame.num_lights : 1);
    float sx, sy;

    double tl = sys_now();

    sample_position(r->settings.spp, sample, &sx, &sy);
    if (rpass_ensure_image(r, err, errlen) || rpass_raygen(r, row0, nrows, sx, sy, err, errlen) ||
        stats_lap(r, &tl, &r->stats.raygen_s, err, errlen))
        return -1;
    r->stats.eye_rays += (unsigned long long)n;
    for (depth = 1; depth <= r->host_frame.max_depth && n > 0; depth++) {
        cl_int counts[CW_NUM_COUNTERS];
        int nxt = 1 - cur;
        if (rpass_ensure_buffer(r, &r->rays[nxt], &r->ray_cap[nxt],
                                (size_t)n * (size_t)branch * sizeof(cw_ray), "ray queue", err,
                                errlen) ||
            rpass_ensure_buffer(r, &r->shadows, &r->shadow_cap,
                                (size_t)n * lights * sizeof(cw_shadow_ray), "shadow ray queue", err,
                                errlen) ||
            rpass_fill_zero(r, r->counters, CW_NUM_COUNTERS * sizeof(cl_int), "counters", err,
                            errlen) ||
            stats_lap(r, &tl, &r->stats.raygen_s, err, errlen) ||
            rpass_intersect(r, &r->rays[cur], n, err, errlen) ||
            stats_lap(r, &tl, &r->stats.intersect_s, err, errlen) ||
            run_shade(r, &r->rays[cur], &r->rays[nxt], n, err, errlen) ||
            rpass_read(r, r->counters, sizeof counts, counts, "counters", err, errlen) ||
            stats_lap(r, &tl, &r->stats.shade_s, err, errlen))
            return -1;
        if (counts[CW_COUNT_SHADOWS] > 0 &&
            (rpass_occlude(r, counts[CW_COUNT_SHADOWS], err, errlen) ||
             stats_lap(r, &tl, &r->stats.occlude_s, err, errlen)))
            return -1;
        r->stats.passes++;
        r->stats.shadow_rays += (unsigned long long)counts[CW_COUNT_SHADOWS];
        r->stats.secondary_rays += (unsigned long long)counts[CW_COUNT_RAYS];
        if (r->settings.stats) {
            /* the occlude kernel's count is read with the next level's counters; wait
             * for it here so that each level's figures are complete */
            cl_int e = clFinish(r->queue);
            if (e != CL_SUCCESS)
                return rpass_fail(e, "clFinish", r, err, errlen);
            if (rpass_read(r, r->counters, sizeof counts, counts, "counters", err, errlen))
                return -1;
            add_stat_counts(r, counts);
        }
        n = counts[CW_COUNT_RAYS];
        cur = nxt;
        if (report_progress(r,
                            done + share * (n == 0 ? 1.0 : (double)depth / r->host_frame.max_depth),
                            err, errlen))
            return -1;
    }
    return 0;
}

int rpass_trace_band(renderer *r, int sample, int row0, int nrows, int first, double done,
                     double share, char *err, size_t errlen)
{
    if (r->strategy == RENDER_PIXEL)
        return trace_band_pixel(r, sample, row0, nrows, first, done, share, err, errlen);
    if (first && rpass_clear_rows(r, row0, nrows, err, errlen))
        return -1;
    return trace_band_wavefront(r, sample, row0, nrows, done, share, err, errlen);
}
