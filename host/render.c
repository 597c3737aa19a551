/* The renderer: opens a device, builds the kernel program for the scene's features,
 * uploads the scene, and renders: whole images (every sample of every band, or the SPD
 * corner procedure) and the preview's progressive samples, read back from the
 * accumulation image. The scene's conversion, BVH and upload are in render_scene.c, the
 * passes in render_pass.c. */
#include "render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

#include "cl_device.h"
#include "cl_program.h"
#include "config.h"
#include "render_impl.h"
#include "render_pass.h"
#include "render_rows.h"
#include "render_scene.h"
#include "sys.h"
#include "world.h"

_Static_assert(sizeof(cw_float4) == 16, "cw_float4 must be 16 bytes");
_Static_assert(sizeof(cw_sphere) == 16, "cw_sphere layout");
_Static_assert(sizeof(cw_triangle) == 64, "cw_triangle layout");
_Static_assert(sizeof(cw_tri8) == 384, "cw_tri8 layout");
_Static_assert(sizeof(cw_sph4) == 96, "cw_sph4 layout");
_Static_assert(sizeof(cw_cone) == 48, "cw_cone layout");
_Static_assert(sizeof(cw_shadow_ray) == 64, "cw_shadow_ray layout");
_Static_assert(sizeof(cw_polygon) == 48, "cw_polygon layout");

_Static_assert(sizeof(cw_material) == 80, "cw_material layout");
_Static_assert(sizeof(cw_light) == 32, "cw_light layout");
_Static_assert(sizeof(cw_frame) == 192, "cw_frame layout");
_Static_assert(sizeof(cw_ray) == 64, "cw_ray layout");
_Static_assert(sizeof(cw_hit) == 32, "cw_hit layout");
_Static_assert(sizeof(cw_bvhw_node) == 32 * CW_BVH_WIDTH, "cw_bvhw_node layout");
_Static_assert(CW_MAX_DEPTH <= CW_PIX_STACK,
               "the per-pixel kernel's ray stack holds max_depth rays");
_Static_assert(CW_COUNT_DEPTH < CW_NUM_COUNTERS, "counters");

int renderer_list_devices(char *err, size_t errlen)
{
    return cldev_print_list(err, errlen);
}

/* ---- device ----------------------------------------------------------------------- */

int renderer_create(renderer **out, const char *spec, char *err, size_t errlen)
{
    renderer *r = calloc(1, sizeof *r);
    cl_device_type type = 0;
    cl_uint units = 0;
    cl_int e;
    if (!r) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    render_settings_default(&r->settings);
    if (cldev_find(spec, &r->device, err, errlen) != 0)
        goto out_free;
    e = clGetDeviceInfo(r->device, CL_DEVICE_NAME, sizeof r->device_name, r->device_name, NULL);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clGetDeviceInfo(CL_DEVICE_NAME)", r, err, errlen);
        goto out_free;
    }
    e = clGetDeviceInfo(r->device, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof r->max_alloc, &r->max_alloc,
                        NULL);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clGetDeviceInfo(memory limits)", r, err, errlen);
        goto out_free;
    }
    e = clGetDeviceInfo(r->device, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clGetDeviceInfo(CL_DEVICE_TYPE)", r, err, errlen);
        goto out_free;
    }
    r->cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    if (clGetDeviceInfo(r->device, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof units, &units, NULL) ==
        CL_SUCCESS)
        r->units = (int)units;
    r->ctx = clCreateContext(NULL, 1, &r->device, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clCreateContext", r, err, errlen);
        goto out_free;
    }
    r->queue = clCreateCommandQueue(r->ctx, r->device, 0, &e);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clCreateCommandQueue", r, err, errlen);
        goto out_release_context;
    }
    *out = r;
    return 0;

out_release_context:
    clReleaseContext(r->ctx);
out_free:
    free(r);
    return -1;
}

const char *renderer_device_name(const renderer *r)
{
    return r->device_name;
}

static void release_work(renderer *r)
{
    rpass_release(&r->rays[0]);
    rpass_release(&r->rays[1]);
    rpass_release(&r->hits);
    rpass_release(&r->shadows);
    rpass_release(&r->image);
    rpass_release(&r->counters);
    r->ray_cap[0] = r->ray_cap[1] = r->hit_cap = r->shadow_cap = r->image_cap = 0;
}

static void release_program(renderer *r)
{
    cl_kernel *ks[5];
    int i;
    ks[0] = &r->k_raygen;
    ks[1] = &r->k_intersect;
    ks[2] = &r->k_shade;
    ks[3] = &r->k_occlude;
    ks[4] = &r->k_pixel;
    for (i = 0; i < 5; i++) {
        if (*ks[i])
            clReleaseKernel(*ks[i]);
        *ks[i] = NULL;
    }
    if (r->program)
        clReleaseProgram(r->program);
    r->program = NULL;
    r->options[0] = '\0';
}

void renderer_destroy(renderer *r)
{
    if (!r)
        return;
    rscene_release(r);
    release_work(r);
    release_program(r);
    clReleaseCommandQueue(r->queue);
    clReleaseContext(r->ctx);
    free(r);
}

/* ---- program ---------------------------------------------------------------------- */

/* The kernels of the program's strategy. */
static cl_int create_kernels(renderer *r, int strategy)
{
    cl_int e;
    if (strategy == RENDER_PIXEL) {
        r->k_pixel = clCreateKernel(r->program, "cw_pixel", &e);
        return e;
    }
    r->k_raygen = clCreateKernel(r->program, "cw_raygen", &e);
    if (e == CL_SUCCESS)
        r->k_intersect = clCreateKernel(r->program, "cw_intersect", &e);
    if (e == CL_SUCCESS)
        r->k_shade = clCreateKernel(r->program, "cw_shade", &e);
    if (e == CL_SUCCESS)
        r->k_occlude = clCreateKernel(r->program, "cw_occlude", &e);
    return e;
}

int renderer_ensure_program(renderer *r, int strategy, char *err, size_t errlen)
{
    char options[sizeof r->options];
    cl_int e;
    double t0;

    clprog_options(&r->features, r->host_frame.max_depth, r->settings.spd,
                   r->settings.precision == RENDER_FAST, r->settings.stats,
                   strategy == RENDER_PIXEL, options, sizeof options);
    if (r->program && strcmp(r->options, options) == 0)
        return 0;
    release_program(r);
    t0 = sys_now();
    if (clprog_build(r->ctx, r->device, r->device_name, options, &r->program,
                     &r->stats.program_cached, err, errlen) != 0)
        return -1;
    e = create_kernels(r, strategy);
    if (e != CL_SUCCESS) {
        rpass_fail(e, "clCreateKernel", r, err, errlen);
        release_program(r);
        return -1;
    }
    snprintf(r->options, sizeof r->options, "%s", options);
    r->strategy = strategy;
    r->stats.compile_s = sys_now() - t0;
    return 0;
}

/* ---- rendering and read back ------------------------------------------------------ */

int renderer_trace(renderer *r, int sample, int row0, int nrows, char *err, size_t errlen)
{
    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, renderer_strategy(r), err, errlen))
        return -1;
    if (sample < 0 || row0 < 0 || nrows < 1 || row0 + nrows > r->host_frame.ny) {
        snprintf(err, errlen, "renderer_trace: sample %d, rows %d..%d outside the %d-row image",
                 sample, row0, row0 + nrows - 1, r->host_frame.ny);
        return -1;
    }
    return rpass_trace_band(r, sample, row0, nrows, 0, 0.0, 1.0, err, errlen);
}

/* img (allocated here at width x height) from the accumulation image, nx * ny rgb + count
 * floats of the frame now uploaded: the mean of each pixel's samples, or with spd the
 * average of each pixel's four corners (render_rows.c). The accumulation is mapped, which on
 * a CPU device reads the buffer's own memory in place (a read into a new host array cost
 * 45 ms at 2048x2048: its first touch and the copy). On failure img is left empty. */
static int resolve_accumulation(renderer *r, image *img, int width, int height, int spd, char *err,
                                size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    const char *call;
    cl_int e;
    float *px;
    if (rpass_ensure_image(r, err, errlen))
        return -1;
    if (image_alloc(img, width, height) != 0) {
        snprintf(err, errlen, "out of memory for a %dx%d image", width, height);
        return -1;
    }
    px = clEnqueueMapBuffer(r->queue, r->image, CL_TRUE, CL_MAP_READ, 0, n * 4 * sizeof *px, 0,
                            NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        call = "clEnqueueMapBuffer(image)";
        goto out_free_image;
    }
    if (spd)
        rrows_resolve_spd(px, img);
    else
        rrows_resolve_mean(px, img);
    e = clEnqueueUnmapMemObject(r->queue, r->image, px, 0, NULL, NULL);
    if (e == CL_SUCCESS)
        return 0;
    call = "clEnqueueUnmapMemObject(image)";
out_free_image:
    image_free(img);
    return rpass_fail(e, call, r, err, errlen);
}

int renderer_read(renderer *r, image *img, char *err, size_t errlen)
{
    if (rpass_need_scene(r, err, errlen))
        return -1;
    return resolve_accumulation(r, img, r->host_frame.nx, r->host_frame.ny, 0, err, errlen);
}

static int write_frame(renderer *r, char *err, size_t errlen)
{
    return rpass_write(r, r->world.frame, sizeof r->host_frame, &r->host_frame, "frame", err,
                       errlen);
}

/* Every sample of every band into the accumulation image, the first sample starting
 * each band empty (rpass_trace_band's `first`): with the per-pixel kernel nothing is
 * cleared (a clear of the whole image cost 40 ms at 2048x2048 on one thread, 64 MB filled
 * and first touched; the kernel's first writes take that touch on all its threads). */
static int trace_all(renderer *r, int spp, char *err, size_t errlen)
{
    int k, row0, rows = rpass_band_rows(r), ny = r->host_frame.ny;
    for (k = 0; k < spp; k++)
        for (row0 = 0; row0 < ny; row0 += rows) {
            int nr = row0 + rows > ny ? ny - row0 : rows;
            double done = ((double)k + (double)row0 / ny) / spp;
            if (rpass_trace_band(r, k, row0, nr, k == 0, done, (double)nr / ny / spp, err, errlen))
                return -1;
        }
    return 0;
}

/* The SPD procedure: rays through the (nx+1) x (ny+1) pixel corners (rrows_spd_frame),
 * the four corners of each pixel averaged. */
static int render_spd(renderer *r, image *img, char *err, size_t errlen)
{
    cw_frame saved = r->host_frame;
    int rc = -1;

    rrows_spd_frame(&saved, &r->host_frame);
    if (write_frame(r, err, errlen) == 0 && trace_all(r, 1, err, errlen) == 0)
        rc = resolve_accumulation(r, img, saved.nx, saved.ny, 1, err, errlen);
    r->host_frame = saved;
    if (write_frame(r, err, errlen) != 0)
        rc = -1;
    return rc;
}

int render_check_crop(const render_settings *st, int width, int height, char *err, size_t errlen)
{
    const int *c = st->crop;
    if (c[1] == 0)
        return 0;
    if (c[0] < 0 || c[0] >= c[1] || c[1] > width || c[2] < 0 || c[2] >= c[3] || c[3] > height) {
        snprintf(err, errlen,
                 "--crop %d,%d,%d,%d is not inside the %dx%d image (X0 < X1 <= %d, Y0 < Y1 <= %d)",
                 c[0], c[1], c[2], c[3], width, height, width, height);
        return -1;
    }
    return 0;
}

/* Traces one row once, as a first sample (its pixels start empty): the first launch, where
 * a driver may compile the kernel for the device, timed apart (stats.warmup_s). No
 * progress report, and the counts are reset by the caller. */
static int warm_up(renderer *r, char *err, size_t errlen)
{
    render_progress_fn fn = r->progress;
    double t0 = sys_now();
    int rc;
    r->progress = NULL;
    rc = rpass_trace_band(r, 0, 0, 1, 1, 0.0, 0.0, err, errlen);
    r->progress = fn;
    if (rc == 0) {
        cl_int e = clFinish(r->queue);
        if (e != CL_SUCCESS)
            return rpass_fail(e, "clFinish", r, err, errlen);
    }
    r->stats.warmup_s = sys_now() - t0;
    return rc;
}

/* The frame of settings.crop's window of the full frame f (see cw_frame). */
static void crop_frame(cw_frame *f, const int *crop)
{
    f->cam_x0 = crop[0];
    f->cam_y0 = f->cam_ny - crop[3];
    f->nx = crop[1] - crop[0];
    f->ny = crop[3] - crop[2];
}

int renderer_render(renderer *r, image *img, char *err, size_t errlen)
{
    int spp = r->settings.spp < 1 ? 1 : r->settings.spp, rc = -1;
    cw_frame full = r->host_frame;
    char restore_err[256];
    double t0;

    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, renderer_strategy(r), err, errlen) ||
        render_check_crop(&r->settings, full.cam_nx, full.cam_ny, err, errlen))
        return -1;
    if (r->settings.crop[1] != 0) {
        crop_frame(&r->host_frame, r->settings.crop);
        if (write_frame(r, err, errlen) != 0)
            goto out_restore;
    }
    rc = warm_up(r, err, errlen);
    if (rc != 0)
        goto out_restore;
    t0 = sys_now();
    renderer_reset_trace_stats(r);
    if (r->settings.spd)
        rc = render_spd(r, img, err, errlen);
    else
        rc = trace_all(r, spp, err, errlen) || renderer_read(r, img, err, errlen) ? -1 : 0;
    r->stats.trace_s = sys_now() - t0;
    if (r->settings.crop[1] == 0)
        return rc;
out_restore:
    r->host_frame = full;
    if (rc == 0)
        rc = write_frame(r, err, errlen) != 0 ? -1 : 0;
    else
        write_frame(r, restore_err, sizeof restore_err); /* the first error is the one */
    return rc;
}

int renderer_set_view(renderer *r, const scene *s, char *err, size_t errlen)
{
    if (rpass_need_scene(r, err, errlen))
        return -1;
    if (s->width < 1 || s->height < 1 || s->max_depth < 1) {
        snprintf(err, errlen, "renderer_set_view: bad image size %dx%d or depth %d", s->width,
                 s->height, s->max_depth);
        return -1;
    }
    rscene_fill_view(&r->host_frame, s, r->origin);
    return write_frame(r, err, errlen) || rpass_clear_accumulation(r, err, errlen);
}

/* ---- settings, statistics, progress ----------------------------------------------- */

void render_settings_default(render_settings *st)
{
    memset(st, 0, sizeof *st);
    st->spp = 1;
    st->precision = RENDER_ROBUST;
}

int renderer_set_settings(renderer *r, const render_settings *st, char *err, size_t errlen)
{
    if (st->spp < 1 || st->spp > CW_MAX_SPP) {
        snprintf(err, errlen, "samples per pixel must be in 1..%d, got %d", CW_MAX_SPP, st->spp);
        return -1;
    }
    if (st->precision != RENDER_ROBUST && st->precision != RENDER_FAST) {
        snprintf(err, errlen, "unknown precision setting %d", st->precision);
        return -1;
    }
    if (st->strategy != RENDER_AUTO && st->strategy != RENDER_WAVEFRONT &&
        st->strategy != RENDER_PIXEL) {
        snprintf(err, errlen, "unknown strategy setting %d", st->strategy);
        return -1;
    }
    r->settings = *st;
    if (r->have_scene && r->host_frame.spd_rays != (st->spd != 0)) {
        r->host_frame.spd_rays = st->spd != 0;
        return write_frame(r, err, errlen);
    }
    return 0;
}

int renderer_strategy(const renderer *r)
{
    if (r->settings.strategy != RENDER_AUTO)
        return r->settings.strategy;
    return r->cpu ? RENDER_PIXEL : RENDER_WAVEFRONT;
}

/* The strategies' names, by RENDER_AUTO, RENDER_WAVEFRONT, RENDER_PIXEL. */
static const char *const strategy_names[] = {"auto", "wavefront", "pixel"};

const char *render_strategy_name(int strategy)
{
    return strategy >= 0 && strategy < 3 ? strategy_names[strategy] : "auto";
}

static double per_ray(unsigned long long count, unsigned long long rays)
{
    return rays > 0 ? (double)count / (double)rays : 0.0;
}

void render_format_walk(const render_stats *st, char *buf, size_t n)
{
    unsigned long long closest = st->eye_rays + st->secondary_rays;
    snprintf(buf, n,
             "walk: closest-hit rays %.2f nodes, %.2f tests each; shadow rays %.2f nodes, "
             "%.2f tests each (one test: up to eight primitives of a leaf)",
             per_ray(st->closest_nodes, closest), per_ray(st->closest_tests, closest),
             per_ray(st->any_nodes, st->shadow_rays), per_ray(st->any_tests, st->shadow_rays));
}

int render_strategy_parse(const char *name)
{
    int k;
    for (k = 0; k < 3; k++)
        if (strcmp(name, strategy_names[k]) == 0)
            return k;
    return -1;
}

int renderer_compute_units(const renderer *r)
{
    return r->units;
}

void renderer_get_stats(const renderer *r, render_stats *st)
{
    *st = r->stats;
}

void renderer_set_progress(renderer *r, render_progress_fn fn, void *ctx)
{
    r->progress = fn;
    r->progress_ctx = ctx;
}
