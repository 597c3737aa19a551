/* The OpenCL renderer: device discovery, program build from the scene's features,
 * scene upload, and the pass loop (ray generation, then per depth one intersection and
 * one shading launch). */
#include "render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <CL/cl.h>

#include "devscene.h"
#include "clerr.h"
#include "progcache.h"
#include "world.h"

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

extern const char cw_kernel_source[];

_Static_assert(sizeof(cw_float4) == 16, "cw_float4 must be 16 bytes");
_Static_assert(sizeof(cw_sphere) == 32, "cw_sphere layout");
_Static_assert(sizeof(cw_triangle) == 64, "cw_triangle layout");
_Static_assert(sizeof(cw_cone) == 48, "cw_cone layout");
_Static_assert(sizeof(cw_shadow_ray) == 64, "cw_shadow_ray layout");
_Static_assert(sizeof(cw_polygon) == 48, "cw_polygon layout");

_Static_assert(sizeof(cw_material) == 80, "cw_material layout");
_Static_assert(sizeof(cw_light) == 32, "cw_light layout");
_Static_assert(sizeof(cw_frame) == 192, "cw_frame layout");
_Static_assert(sizeof(cw_ray) == 64, "cw_ray layout");
_Static_assert(sizeof(cw_hit) == 32, "cw_hit layout");
_Static_assert(sizeof(cw_bvh_node) == 32, "cw_bvh_node layout");
_Static_assert(sizeof(cw_bvh4_node) == 128, "cw_bvh4_node layout");

/* What the scene uses, decided once at upload: the kernel features come from it. */
typedef struct {
    int spheres, triangles, polygons, cones; /* primitives uploaded (degenerate ones dropped) */
    int mirrors;                             /* some material has km > 0 */
    int transmitters;                        /* some material has kt > 0 */
} scene_features;

struct renderer {
    cl_device_id device;
    char device_name[256];
    cl_context ctx;
    cl_command_queue queue;
    cl_program program;
    char options[1024]; /* build options of `program` */
    cl_kernel k_raygen, k_intersect, k_shade, k_occlude;
    cl_ulong max_alloc; /* CL_DEVICE_MAX_MEM_ALLOC_SIZE */
    /* scene buffers */
    cl_mem frame, nodes, refs, spheres, triangles, normals, polygons, verts, bands, cones, lights,
        materials;
    int have_scene;
    cw_frame host_frame;
    /* work buffers, grown on demand: two ray queues (this level's, the next), hits,
     * shadow rays, the accumulation image (rgb + sample count per pixel), counters */
    cl_mem rays[2], hits, shadows, image, counters;
    size_t ray_cap[2], hit_cap, shadow_cap, image_cap;
    /* settings, stats, progress */
    render_settings settings;
    scene_features features;
    render_stats stats;
    render_progress_fn progress;
    void *progress_ctx;
};

/* Reports a failed OpenCL call with its name, the error name and the device. */
static int cl_fail(cl_int e, const char *call, const renderer *r, char *err, size_t errlen)
{
    snprintf(err, errlen, "%s failed: %s (%d)%s%s", call, cl_error_name(e), (int)e,
             r && r->device_name[0] ? " on device " : "", r ? r->device_name : "");
    return -1;
}

/* ---- devices ---------------------------------------------------------------------- */

/* Gets every platform; *out is malloc'd. */
static int get_platforms(cl_platform_id **out, cl_uint *count, char *err, size_t errlen)
{
    cl_uint n = 0;
    cl_int e = clGetPlatformIDs(0, NULL, &n);
    if (e == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || (e == CL_SUCCESS && n == 0)) {
        snprintf(err, errlen,
                 "no OpenCL platform found (install pocl-opencl-icd: "
                 "sh tools/install-deps)");
        return -1;
    }
    if (e != CL_SUCCESS)
        return cl_fail(e, "clGetPlatformIDs", NULL, err, errlen);
    *out = calloc(n, sizeof **out);
    if (!*out) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    e = clGetPlatformIDs(n, *out, NULL);
    if (e != CL_SUCCESS) {
        free(*out);
        return cl_fail(e, "clGetPlatformIDs", NULL, err, errlen);
    }
    *count = n;
    return 0;
}

/* Gets every device of a platform (none is not an error); *out is malloc'd or NULL. */
static int get_devices(cl_platform_id p, cl_device_id **out, cl_uint *count, char *err,
                       size_t errlen)
{
    cl_uint n = 0;
    cl_int e = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, NULL, &n);
    *out = NULL;
    *count = 0;
    if (e == CL_DEVICE_NOT_FOUND || (e == CL_SUCCESS && n == 0))
        return 0;
    if (e != CL_SUCCESS)
        return cl_fail(e, "clGetDeviceIDs", NULL, err, errlen);
    *out = calloc(n, sizeof **out);
    if (!*out) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    e = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, n, *out, NULL);
    if (e != CL_SUCCESS) {
        free(*out);
        *out = NULL;
        return cl_fail(e, "clGetDeviceIDs", NULL, err, errlen);
    }
    *count = n;
    return 0;
}

/* Finds the device named by spec (see render.h). */
static int find_device(const char *spec, cl_device_id *out, char *err, size_t errlen)
{
    cl_platform_id *plats = NULL;
    cl_uint np = 0, i, j;
    unsigned want_p = 0, want_d = 0;
    int by_index = 0, found = 0;
    char tail;
    cl_device_id fallback = NULL;

    if (spec && *spec && sscanf(spec, "%u:%u%c", &want_p, &want_d, &tail) == 2)
        by_index = 1;
    if (get_platforms(&plats, &np, err, errlen) != 0)
        return -1;
    for (i = 0; i < np && !found; i++) {
        cl_device_id *devs = NULL;
        cl_uint nd = 0;
        if (get_devices(plats[i], &devs, &nd, err, errlen) != 0) {
            free(plats);
            return -1;
        }
        for (j = 0; j < nd && !found; j++) {
            char name[256] = "";
            cl_device_type type = 0;
            cl_int e = clGetDeviceInfo(devs[j], CL_DEVICE_NAME, sizeof name, name, NULL);
            if (e == CL_SUCCESS)
                e = clGetDeviceInfo(devs[j], CL_DEVICE_TYPE, sizeof type, &type, NULL);
            if (e != CL_SUCCESS) {
                free(devs);
                free(plats);
                return cl_fail(e, "clGetDeviceInfo", NULL, err, errlen);
            }
            if (by_index) {
                found = (i == want_p && j == want_d);
            } else if (spec && *spec) {
                found = strstr(name, spec) != NULL;
            } else {
                found = (type & CL_DEVICE_TYPE_CPU) != 0;
                if (!fallback)
                    fallback = devs[j];
            }
            if (found)
                *out = devs[j];
        }
        free(devs);
    }
    free(plats);
    if (!found && !(spec && *spec) && fallback) {
        *out = fallback;
        found = 1;
    }
    if (!found) {
        if (spec && *spec)
            snprintf(err, errlen, "no OpenCL device matches '%s' (see --list-devices)", spec);
        else
            snprintf(err, errlen,
                     "no OpenCL device found (install pocl-opencl-icd: "
                     "sh tools/install-deps)");
        return -1;
    }
    return 0;
}

int renderer_create(renderer **out, const char *spec, char *err, size_t errlen)
{
    renderer *r = calloc(1, sizeof *r);
    cl_int e;
    if (!r) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    render_settings_default(&r->settings);
    if (find_device(spec, &r->device, err, errlen) != 0)
        goto out_free;
    e = clGetDeviceInfo(r->device, CL_DEVICE_NAME, sizeof r->device_name, r->device_name, NULL);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clGetDeviceInfo(CL_DEVICE_NAME)", r, err, errlen);
        goto out_free;
    }
    e = clGetDeviceInfo(r->device, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof r->max_alloc, &r->max_alloc,
                        NULL);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clGetDeviceInfo(memory limits)", r, err, errlen);
        goto out_free;
    }
    r->ctx = clCreateContext(NULL, 1, &r->device, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clCreateContext", r, err, errlen);
        goto out_free;
    }
    r->queue = clCreateCommandQueue(r->ctx, r->device, 0, &e);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clCreateCommandQueue", r, err, errlen);
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

static void release_mem(cl_mem *m)
{
    if (*m)
        clReleaseMemObject(*m);
    *m = NULL;
}

static void release_scene(renderer *r)
{
    release_mem(&r->frame);
    release_mem(&r->nodes);
    release_mem(&r->refs);
    release_mem(&r->spheres);
    release_mem(&r->triangles);
    release_mem(&r->normals);
    release_mem(&r->polygons);
    release_mem(&r->verts);
    release_mem(&r->bands);
    release_mem(&r->cones);
    release_mem(&r->lights);
    release_mem(&r->materials);
    r->have_scene = 0;
}

static void release_work(renderer *r)
{
    release_mem(&r->rays[0]);
    release_mem(&r->rays[1]);
    release_mem(&r->hits);
    release_mem(&r->shadows);
    release_mem(&r->image);
    release_mem(&r->counters);
    r->ray_cap[0] = r->ray_cap[1] = r->hit_cap = r->shadow_cap = r->image_cap = 0;
}

static void release_program(renderer *r)
{
    cl_kernel *ks[4];
    int i;
    ks[0] = &r->k_raygen;
    ks[1] = &r->k_intersect;
    ks[2] = &r->k_shade;
    ks[3] = &r->k_occlude;
    for (i = 0; i < 4; i++) {
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
    release_scene(r);
    release_work(r);
    release_program(r);
    clReleaseCommandQueue(r->queue);
    clReleaseContext(r->ctx);
    free(r);
}

/* ---- program ---------------------------------------------------------------------- */

/* The kernel build options for a scene: every feature flag is decided here, from what
 * the scene uses and its depth (reflection and refraction need depth > 1; SPD counting
 * turns transmitters into reflectors too). */
static void scene_build_options(const scene_features *ft, int max_depth, int spd, char *buf,
                                size_t n)
{
    int deep = max_depth > 1;
    snprintf(buf, n,
             "-cl-std=CL1.2 -Werror -DCW_HAS_SPHERES=%d -DCW_HAS_TRIANGLES=%d "
             "-DCW_HAS_POLYGONS=%d -DCW_HAS_CONES=%d -DCW_HAS_MIRRORS=%d "
             "-DCW_HAS_REFRACTION=%d",
             ft->spheres > 0, ft->triangles > 0, ft->polygons > 0, ft->cones > 0,
             deep && (ft->mirrors || (spd && ft->transmitters)), deep && ft->transmitters);
}

static void full_build_options(const renderer *r, char *buf, size_t n)
{
    const char *extra = getenv("CLWHITTED_BUILD_OPTIONS");
    char base[512];
    scene_build_options(&r->features, r->host_frame.max_depth, r->settings.spd, base, sizeof base);
    snprintf(buf, n, "%s -DCW_FAST=%d -DCW_STATS=%d%s%s%s", base,
             r->settings.precision == RENDER_FAST, r->settings.stats != 0,
             r->settings.precision == RENDER_FAST ? " -cl-fast-relaxed-math" : "", extra ? " " : "",
             extra ? extra : "");
}

static int build_program(renderer *r, const char *options, char *err, size_t errlen)
{
    const char *src = cw_kernel_source;
    cl_int e;
    double t0;

    if (r->program && strcmp(r->options, options) == 0)
        return 0;
    release_program(r);
    t0 = seconds_now();
    r->program = progcache_load(r->ctx, r->device, src, options);
    if (r->program)
        goto out_kernels;
    r->program = clCreateProgramWithSource(r->ctx, 1, &src, NULL, &e);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clCreateProgramWithSource", r, err, errlen);
    e = clBuildProgram(r->program, 1, &r->device, options, NULL, NULL);
    if (e == CL_SUCCESS)
        progcache_store(r->program, r->device, src, options);
    if (e != CL_SUCCESS) {
        size_t len = 0;
        char *log;
        cl_int e2 =
            clGetProgramBuildInfo(r->program, r->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &len);
        log = e2 == CL_SUCCESS ? malloc(len + 1) : NULL;
        if (!log)
            fprintf(stderr, "kernel build log unavailable (%s)\n", cl_error_name(e2));
        if (log && clGetProgramBuildInfo(r->program, r->device, CL_PROGRAM_BUILD_LOG, len, log,
                                         NULL) == CL_SUCCESS) {
            log[len] = '\0';
            fprintf(stderr, "kernel build log (%s, options: %s):\n%s\n", r->device_name, options,
                    log);
        }
        free(log);
        cl_fail(e, "clBuildProgram (build log above)", r, err, errlen);
        release_program(r);
        return -1;
    }
out_kernels:
    r->k_raygen = clCreateKernel(r->program, "cw_raygen", &e);
    if (e == CL_SUCCESS)
        r->k_intersect = clCreateKernel(r->program, "cw_intersect", &e);
    if (e == CL_SUCCESS)
        r->k_shade = clCreateKernel(r->program, "cw_shade", &e);
    if (e == CL_SUCCESS)
        r->k_occlude = clCreateKernel(r->program, "cw_occlude", &e);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clCreateKernel", r, err, errlen);
        release_program(r);
        return -1;
    }
    snprintf(r->options, sizeof r->options, "%s", options);
    r->stats.compile_s = seconds_now() - t0;
    return 0;
}

/* Builds the program for the scene's features and the current settings, unless built. */
static int ensure_program(renderer *r, char *err, size_t errlen)
{
    char options[1024];
    full_build_options(r, options, sizeof options);
    return build_program(r, options, err, errlen);
}

/* ---- scene upload ----------------------------------------------------------------- */

/* Checks that a buffer fits the device before asking for it, so that a scene too big
 * for the device gets a message naming the buffer rather than a driver error. */
static int check_alloc(const renderer *r, const char *what, size_t bytes, char *err, size_t errlen)
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

/* A read-only buffer holding a copy of count elements (at least one element is
 * allocated: OpenCL has no empty buffers). */
static int upload(renderer *r, cl_mem *m, const void *data, size_t count, size_t size,
                  const char *what, char *err, size_t errlen)
{
    cl_int e;
    void *zero = NULL;
    if (count == 0) {
        zero = calloc(1, size);
        if (!zero) {
            snprintf(err, errlen, "out of memory");
            return -1;
        }
        data = zero;
        count = 1;
    }
    if (count > ((size_t)-1) / size) {
        free(zero);
        snprintf(err, errlen, "the %s buffer size overflows (%zu elements)", what, count);
        return -1;
    }
    if (check_alloc(r, what, count * size, err, errlen) != 0) {
        free(zero);
        return -1;
    }
    *m = clCreateBuffer(r->ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, count * size, (void *)data,
                        &e);
    free(zero);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes)", what, count * size);
        return cl_fail(e, call, r, err, errlen);
    }
    return 0;
}

/* The view part of the frame: camera, size, depth, background and ambient. */
static void fill_view(cw_frame *f, const scene *s)
{
    const scene_camera *c = &s->camera;
    f->eye = devscene_f4(c->eye, 0);
    f->u = devscene_f4(c->u, 0);
    f->v = devscene_f4(c->v, 0);
    f->w = devscene_f4(c->w, 0);
    f->dir = devscene_f4(c->dir, 0);
    f->window.x = c->l;
    f->window.y = c->r;
    f->window.z = c->b;
    f->window.w = c->t;
    f->background = devscene_f4(s->background, 0);
    f->ambient = devscene_f4(s->ambient, 0);
    f->d = c->d;
    f->projection = c->projection == SCENE_ORTHOGRAPHIC ? CW_PROJ_ORTHOGRAPHIC
                    : c->projection == SCENE_OBLIQUE    ? CW_PROJ_OBLIQUE
                                                        : CW_PROJ_PERSPECTIVE;
    f->nx = s->width;
    f->ny = s->height;
    f->max_depth = s->max_depth;
}

int renderer_set_scene(renderer *r, const scene *s, char *err, size_t errlen)
{
    devscene ds;
    cw_frame *f = &r->host_frame;
    int rc = -1;
    double t0;

    release_scene(r);
    memset(f, 0, sizeof *f);
    r->stats.build_s = r->stats.compile_s = r->stats.upload_s = 0;
    if (devscene_convert(s, &ds, err, errlen) != 0)
        goto out_free;
    r->features.spheres = ds.nsph;
    r->features.triangles = ds.ntri;
    r->features.polygons = ds.npg;
    r->features.cones = ds.ncone;
    r->features.mirrors = ds.mirrors;
    r->features.transmitters = ds.transmitters;
    t0 = seconds_now();
    if (devscene_build_bvh(&ds, err, errlen) != 0)
        goto out_free;
    r->stats.build_s = seconds_now() - t0;

    fill_view(f, s);
    f->num_lights = (int)s->lights.count;
    f->num_nodes = ds.tree4.num_nodes;
    f->spd_rays = r->settings.spd;

    if (ensure_program(r, err, errlen) != 0)
        goto out_free;
    t0 = seconds_now();
    if (upload(r, &r->frame, f, 1, sizeof *f, "frame", err, errlen) ||
        upload(r, &r->nodes, ds.tree4.nodes, (size_t)ds.tree4.num_nodes, sizeof(cw_bvh4_node),
               "BVH nodes", err, errlen) ||
        upload(r, &r->refs, ds.refs, (size_t)ds.tree.num_refs, sizeof(int), "BVH references", err,
               errlen) ||
        upload(r, &r->spheres, ds.sph, (size_t)ds.nsph, sizeof *ds.sph, "spheres", err, errlen) ||
        upload(r, &r->triangles, ds.tri, (size_t)ds.ntri, sizeof *ds.tri, "triangles", err,
               errlen) ||
        upload(r, &r->normals, ds.normals, (size_t)ds.nnorm, sizeof *ds.normals, "vertex normals",
               err, errlen) ||
        upload(r, &r->polygons, ds.pg, (size_t)ds.npg, sizeof *ds.pg, "polygons", err, errlen) ||
        upload(r, &r->verts, ds.verts, s->poly_verts.count, sizeof *ds.verts, "polygon vertices",
               err, errlen) ||
        upload(r, &r->bands, ds.bands, ds.nbands, sizeof *ds.bands, "polygon edge bands", err,
               errlen) ||
        upload(r, &r->cones, ds.cones, (size_t)ds.ncone, sizeof *ds.cones, "cones", err, errlen) ||
        upload(r, &r->lights, ds.lights, s->lights.count, sizeof *ds.lights, "lights", err,
               errlen) ||
        upload(r, &r->materials, ds.mats, s->materials.count, sizeof *ds.mats, "materials", err,
               errlen)) {
        release_scene(r);
        goto out_free;
    }
    r->have_scene = 1;
    r->stats.upload_s = seconds_now() - t0;
    rc = 0;
out_free:
    devscene_free(&ds);
    return rc;
}

/* ---- passes ----------------------------------------------------------------------- */

/* Makes *m a read-write buffer of at least need bytes (contents not kept). */
static int ensure_buffer(renderer *r, cl_mem *m, size_t *cap, size_t need, const char *what,
                         char *err, size_t errlen)
{
    cl_int e;
    if (*m && *cap >= need)
        return 0;
    release_mem(m);
    *cap = 0;
    if (need == 0)
        need = 16;
    if (check_alloc(r, what, need, err, errlen) != 0)
        return -1;
    *m = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, need, NULL, &e);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes)", what, need);
        return cl_fail(e, call, r, err, errlen);
    }
    *cap = need;
    return 0;
}

static int set_arg(cl_kernel k, cl_uint i, size_t size, const void *v, const char *kname,
                   const renderer *r, char *err, size_t errlen)
{
    cl_int e = clSetKernelArg(k, i, size, v);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clSetKernelArg(%s, %u)", kname, i);
        return cl_fail(e, call, r, err, errlen);
    }
    return 0;
}

static int set_mem(cl_kernel k, cl_uint i, cl_mem *m, const char *kname, const renderer *r,
                   char *err, size_t errlen)
{
    return set_arg(k, i, sizeof(cl_mem), m, kname, r, err, errlen);
}

/* Sets the frame and scene arguments shared by the intersect, shade and occlude kernels:
 * indices 0..CW_WORLD_NARGS-1 (CW_WORLD_ARGS). */
static int set_world_args(renderer *r, cl_kernel k, const char *kname, char *err, size_t errlen)
{
    cl_mem *m[CW_WORLD_NARGS];
    cl_uint i;
    m[0] = &r->frame;
    m[1] = &r->nodes;
    m[2] = &r->refs;
    m[3] = &r->spheres;
    m[4] = &r->triangles;
    m[5] = &r->normals;
    m[6] = &r->polygons;
    m[7] = &r->verts;
    m[8] = &r->bands;
    m[9] = &r->cones;
    for (i = 0; i < CW_WORLD_NARGS; i++)
        if (set_mem(k, i, m[i], kname, r, err, errlen))
            return -1;
    return 0;
}

/* The work-group size for kernel k: 64, or less where the device or the kernel allows
 * less (queried, never assumed). A fixed size also keeps PoCL from specialising (and
 * compiling) the kernel anew for every global size. */
static size_t group_size(const renderer *r, cl_kernel k)
{
    size_t kmax = 0, g = 64;
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
        return cl_fail(e, call, r, err, errlen);
    }
    return 0;
}

static int need_scene(const renderer *r, char *err, size_t errlen)
{
    if (!r->have_scene) {
        snprintf(err, errlen, "no scene uploaded (call renderer_set_scene first)");
        return -1;
    }
    return 0;
}

static int fill_zero(renderer *r, cl_mem m, size_t size, const char *what, char *err, size_t errlen)
{
    cl_int zero = 0;
    cl_int e = clEnqueueFillBuffer(r->queue, m, &zero, sizeof zero, 0, size, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueFillBuffer(%s)", what);
        return cl_fail(e, call, r, err, errlen);
    }
    return 0;
}

static int read_buffer(renderer *r, cl_mem m, size_t size, void *dst, const char *what, char *err,
                       size_t errlen)
{
    cl_int e = clEnqueueReadBuffer(r->queue, m, CL_TRUE, 0, size, dst, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueReadBuffer(%s)", what);
        return cl_fail(e, call, r, err, errlen);
    }
    return 0;
}

/* The accumulation image (nx * ny pixels of rgb + sample count) and the counters. */
static int ensure_image(renderer *r, char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    return ensure_buffer(r, &r->image, &r->image_cap, n * 4 * sizeof(cl_float), "image", err,
                         errlen) ||
           ensure_buffer(r, &r->counters, &(size_t){0}, CW_NUM_COUNTERS * sizeof(cl_int),
                         "counters", err, errlen);
}

static int clear_accumulation(renderer *r, char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    return ensure_image(r, err, errlen) ||
           fill_zero(r, r->image, n * 4 * sizeof(cl_float), "image", err, errlen);
}

/* Rows per band: a band's ray queues, hits and shadow rays stay within about 64 MB. */
static int band_rows(const renderer *r)
{
    size_t per_ray = 2 * sizeof(cw_ray) + sizeof(cw_hit) +
                     (size_t)(r->host_frame.num_lights + 1) * sizeof(cw_shadow_ray);
    size_t rays = ((size_t)64 << 20) / per_ray;
    size_t rows = rays / (size_t)r->host_frame.nx;
    if (rows < 1)
        rows = 1;
    if (rows > (size_t)r->host_frame.ny)
        rows = (size_t)r->host_frame.ny;
    return (int)rows;
}

/* One eye ray per pixel of rows [row0, row0 + nrows), launched in 2-D (no index division
 * in the kernel); (sx, sy) is the sample's position inside the pixel. */
static int run_raygen(renderer *r, int row0, int nrows, float sx, float sy, char *err,
                      size_t errlen)
{
    const char *k = "cw_raygen";
    size_t global[2], local[2];
    cl_int e, crow0 = row0, cnrows = nrows;
    size_t n = (size_t)r->host_frame.nx * (size_t)nrows;
    if (ensure_buffer(r, &r->rays[0], &r->ray_cap[0], n * sizeof(cw_ray), "ray queue", err, errlen))
        return -1;
    local[1] = 1;
    local[0] = group_size(r, r->k_raygen);
    global[0] = ((size_t)r->host_frame.nx + local[0] - 1) / local[0] * local[0];
    global[1] = (size_t)nrows;
    if (set_mem(r->k_raygen, 0, &r->frame, k, r, err, errlen) ||
        set_mem(r->k_raygen, 1, &r->rays[0], k, r, err, errlen) ||
        set_mem(r->k_raygen, 2, &r->image, k, r, err, errlen) ||
        set_arg(r->k_raygen, 3, sizeof crow0, &crow0, k, r, err, errlen) ||
        set_arg(r->k_raygen, 4, sizeof cnrows, &cnrows, k, r, err, errlen) ||
        set_arg(r->k_raygen, 5, sizeof sx, &sx, k, r, err, errlen) ||
        set_arg(r->k_raygen, 6, sizeof sy, &sy, k, r, err, errlen))
        return -1;
    e = clEnqueueNDRangeKernel(r->queue, r->k_raygen, 2, NULL, global, local, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueNDRangeKernel(cw_raygen)", r, err, errlen);
    return 0;
}

static int run_intersect(renderer *r, cl_mem *rays, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_intersect";
    if (ensure_buffer(r, &r->hits, &r->hit_cap, (size_t)n * sizeof(cw_hit), "hits", err, errlen))
        return -1;
    return set_world_args(r, r->k_intersect, k, err, errlen) ||
           set_mem(r->k_intersect, CW_WORLD_NARGS + 0, rays, k, r, err, errlen) ||
           set_mem(r->k_intersect, CW_WORLD_NARGS + 1, &r->hits, k, r, err, errlen) ||
           set_mem(r->k_intersect, CW_WORLD_NARGS + 2, &r->counters, k, r, err, errlen) ||
           set_arg(r->k_intersect, CW_WORLD_NARGS + 3, sizeof n, &n, k, r, err, errlen) ||
           launch(r, r->k_intersect, (size_t)n, k, err, errlen);
}

static int run_shade(renderer *r, cl_mem *rays, cl_mem *out, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_shade";
    return set_world_args(r, r->k_shade, k, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 0, &r->lights, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 1, &r->materials, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 2, rays, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 3, &r->hits, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 4, &r->image, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 5, out, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 6, &r->shadows, k, r, err, errlen) ||
           set_mem(r->k_shade, CW_WORLD_NARGS + 7, &r->counters, k, r, err, errlen) ||
           set_arg(r->k_shade, CW_WORLD_NARGS + 8, sizeof n, &n, k, r, err, errlen) ||
           launch(r, r->k_shade, (size_t)n, k, err, errlen);
}

static int run_occlude(renderer *r, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_occlude";
    return set_world_args(r, r->k_occlude, k, err, errlen) ||
           set_mem(r->k_occlude, CW_WORLD_NARGS + 0, &r->shadows, k, r, err, errlen) ||
           set_mem(r->k_occlude, CW_WORLD_NARGS + 1, &r->image, k, r, err, errlen) ||
           set_mem(r->k_occlude, CW_WORLD_NARGS + 2, &r->counters, k, r, err, errlen) ||
           set_arg(r->k_occlude, CW_WORLD_NARGS + 3, sizeof n, &n, k, r, err, errlen) ||
           launch(r, r->k_occlude, (size_t)n, k, err, errlen);
}

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

/* With statistics on, waits for the queue and adds the time since *t0 to *acc. */
static int stats_lap(renderer *r, double *t0, double *acc, char *err, size_t errlen)
{
    double t;
    cl_int e;
    if (!r->settings.stats)
        return 0;
    e = clFinish(r->queue);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clFinish", r, err, errlen);
    t = seconds_now();
    *acc += t - *t0;
    *t0 = t;
    return 0;
}

/* Traces one sample for a band of rows: ray generation, then per level one intersect,
 * one shade and one occlude launch, the next level's rays going to the other queue.
 * The only wait per level is the read of the queue counters. progress: reported after
 * each level, with the fraction done before this band (done) and the band's share. */
static int trace_band(renderer *r, int sample, int row0, int nrows, double done, double share,
                      char *err, size_t errlen)
{
    cl_int n = (cl_int)((size_t)r->host_frame.nx * (size_t)nrows);
    int cur = 0, depth, branch = r->features.transmitters ? 2 : 1;
    size_t lights = (size_t)(r->host_frame.num_lights > 0 ? r->host_frame.num_lights : 1);
    float sx, sy;

    double tl = seconds_now();

    sample_position(r->settings.spp, sample, &sx, &sy);
    if (ensure_image(r, err, errlen) || run_raygen(r, row0, nrows, sx, sy, err, errlen) ||
        stats_lap(r, &tl, &r->stats.raygen_s, err, errlen))
        return -1;
    r->stats.eye_rays += (unsigned long long)n;
    for (depth = 1; depth <= r->host_frame.max_depth && n > 0; depth++) {
        cl_int counts[CW_NUM_COUNTERS];
        int nxt = 1 - cur;
        if (ensure_buffer(r, &r->rays[nxt], &r->ray_cap[nxt],
                          (size_t)n * (size_t)branch * sizeof(cw_ray), "ray queue", err, errlen) ||
            ensure_buffer(r, &r->shadows, &r->shadow_cap,
                          (size_t)n * lights * sizeof(cw_shadow_ray), "shadow ray queue", err,
                          errlen) ||
            fill_zero(r, r->counters, CW_NUM_COUNTERS * sizeof(cl_int), "counters", err, errlen) ||
            stats_lap(r, &tl, &r->stats.raygen_s, err, errlen) ||
            run_intersect(r, &r->rays[cur], n, err, errlen) ||
            stats_lap(r, &tl, &r->stats.intersect_s, err, errlen) ||
            run_shade(r, &r->rays[cur], &r->rays[nxt], n, err, errlen) ||
            read_buffer(r, r->counters, sizeof counts, counts, "counters", err, errlen) ||
            stats_lap(r, &tl, &r->stats.shade_s, err, errlen))
            return -1;
        if (counts[CW_COUNT_SHADOWS] > 0 &&
            (run_occlude(r, counts[CW_COUNT_SHADOWS], err, errlen) ||
             stats_lap(r, &tl, &r->stats.occlude_s, err, errlen)))
            return -1;
        r->stats.passes++;
        r->stats.shadow_rays += (unsigned long long)counts[CW_COUNT_SHADOWS];
        r->stats.secondary_rays += (unsigned long long)counts[CW_COUNT_RAYS];
        if (r->settings.stats) {
            /* the occlude kernel's count is read with the next level's counters; wait
             * for it here so that each level's figures are complete */
            cl_int blocked = 0;
            cl_int e = clFinish(r->queue);
            if (e != CL_SUCCESS)
                return cl_fail(e, "clFinish", r, err, errlen);
            if (read_buffer(r, r->counters, sizeof counts, counts, "counters", err, errlen))
                return -1;
            blocked = counts[CW_COUNT_BLOCKED];
            r->stats.eye_hits += (unsigned long long)counts[CW_COUNT_EYE_HITS];
            r->stats.secondary_hits += (unsigned long long)counts[CW_COUNT_SECONDARY_HITS];
            r->stats.shadow_blocked += (unsigned long long)blocked;
        }
        n = counts[CW_COUNT_RAYS];
        cur = nxt;
        if (r->progress &&
            r->progress(r->progress_ctx,
                        done + share * (n == 0 ? 1.0 : (double)depth / r->host_frame.max_depth),
                        total_rays(&r->stats)) != 0) {
            snprintf(err, errlen, "render cancelled");
            return -1;
        }
    }
    return 0;
}

int renderer_trace(renderer *r, int sample, int row0, int nrows, char *err, size_t errlen)
{
    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    if (sample < 0 || row0 < 0 || nrows < 1 || row0 + nrows > r->host_frame.ny) {
        snprintf(err, errlen, "renderer_trace: sample %d, rows %d..%d outside the %d-row image",
                 sample, row0, row0 + nrows - 1, r->host_frame.ny);
        return -1;
    }
    return trace_band(r, sample, row0, nrows, 0.0, 1.0, err, errlen);
}

/* Reads the accumulation image back as nx * ny rgb + count floats. */
static float *read_accumulation(renderer *r, char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    float *px;
    if (ensure_image(r, err, errlen))
        return NULL;
    px = malloc(n * 4 * sizeof *px);
    if (!px) {
        snprintf(err, errlen, "out of memory for a %zu-pixel image", n);
        return NULL;
    }
    if (read_buffer(r, r->image, n * 4 * sizeof *px, px, "image", err, errlen)) {
        free(px);
        return NULL;
    }
    return px;
}

int renderer_read(renderer *r, image *img, char *err, size_t errlen)
{
    size_t n, i;
    float *px;

    if (need_scene(r, err, errlen))
        return -1;
    px = read_accumulation(r, err, errlen);
    if (!px)
        return -1;
    n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    if (image_alloc(img, r->host_frame.nx, r->host_frame.ny) != 0) {
        snprintf(err, errlen, "out of memory for a %zu-pixel image", n);
        free(px);
        return -1;
    }
    for (i = 0; i < n; i++) {
        float w = px[4 * i + 3] > 0 ? 1.0f / px[4 * i + 3] : 0.0f;
        img->rgb[3 * i + 0] = px[4 * i + 0] * w;
        img->rgb[3 * i + 1] = px[4 * i + 1] * w;
        img->rgb[3 * i + 2] = px[4 * i + 2] * w;
    }
    free(px);
    return 0;
}

static int write_frame(renderer *r, char *err, size_t errlen)
{
    cl_int e = clEnqueueWriteBuffer(r->queue, r->frame, CL_TRUE, 0, sizeof r->host_frame,
                                    &r->host_frame, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueWriteBuffer(frame)", r, err, errlen);
    return 0;
}

/* Every sample of every band into the (cleared) accumulation image. */
static int trace_all(renderer *r, int spp, char *err, size_t errlen)
{
    int k, row0, rows = band_rows(r), ny = r->host_frame.ny;
    if (clear_accumulation(r, err, errlen))
        return -1;
    for (k = 0; k < spp; k++)
        for (row0 = 0; row0 < ny; row0 += rows) {
            int nr = row0 + rows > ny ? ny - row0 : rows;
            double done = ((double)k + (double)row0 / ny) / spp;
            if (trace_band(r, k, row0, nr, done, (double)nr / ny / spp, err, errlen))
                return -1;
        }
    return 0;
}

/* The SPD procedure: rays through the (nx+1) x (ny+1) pixel corners, the four corners of
 * each pixel averaged. The corners are the centres of an (nx+1) x (ny+1) image whose
 * window is half a pixel wider on every side. */
static int render_spd(renderer *r, image *img, char *err, size_t errlen)
{
    cw_frame saved = r->host_frame;
    cw_frame *f = &r->host_frame;
    float pu = (saved.window.y - saved.window.x) / (float)saved.nx;
    float pv = (saved.window.w - saved.window.z) / (float)saved.ny;
    float *px = NULL;
    int i, j, rc = -1, cx = saved.nx + 1;

    f->nx = saved.nx + 1;
    f->ny = saved.ny + 1;
    f->window.x = saved.window.x - 0.5f * pu;
    f->window.y = saved.window.y + 0.5f * pu;
    f->window.z = saved.window.z - 0.5f * pv;
    f->window.w = saved.window.w + 0.5f * pv;
    if (write_frame(r, err, errlen) || trace_all(r, 1, err, errlen))
        goto out_restore;
    px = read_accumulation(r, err, errlen);
    if (!px)
        goto out_restore;
    if (image_alloc(img, saved.nx, saved.ny) != 0) {
        snprintf(err, errlen, "out of memory for a %dx%d image", saved.nx, saved.ny);
        goto out_restore;
    }
    for (j = 0; j < saved.ny; j++)
        for (i = 0; i < saved.nx; i++) {
            const float *c00 = &px[4 * (j * cx + i)], *c01 = &px[4 * (j * cx + i + 1)];
            const float *c10 = &px[4 * ((j + 1) * cx + i)], *c11 = &px[4 * ((j + 1) * cx + i + 1)];
            int c;
            for (c = 0; c < 3; c++)
                img->rgb[3 * (j * saved.nx + i) + c] = 0.25f * (c00[c] + c01[c] + c10[c] + c11[c]);
        }
    rc = 0;
out_restore:
    free(px);
    r->host_frame = saved;
    if (write_frame(r, err, errlen) != 0)
        rc = -1;
    return rc;
}

int renderer_render(renderer *r, image *img, char *err, size_t errlen)
{
    int spp = r->settings.spp < 1 ? 1 : r->settings.spp, rc;
    double t0;

    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    t0 = seconds_now();
    r->stats.eye_rays = r->stats.eye_hits = 0;
    r->stats.shadow_rays = r->stats.shadow_blocked = 0;
    r->stats.secondary_rays = r->stats.secondary_hits = 0;
    r->stats.passes = 0;
    r->stats.raygen_s = r->stats.intersect_s = r->stats.shade_s = r->stats.occlude_s = 0;
    if (r->settings.spd)
        rc = render_spd(r, img, err, errlen);
    else
        rc = trace_all(r, spp, err, errlen) || renderer_read(r, img, err, errlen) ? -1 : 0;
    r->stats.trace_s = seconds_now() - t0;
    return rc;
}

int renderer_set_view(renderer *r, const scene *s, char *err, size_t errlen)
{
    if (need_scene(r, err, errlen))
        return -1;
    if (s->width < 1 || s->height < 1 || s->max_depth < 1) {
        snprintf(err, errlen, "renderer_set_view: bad image size %dx%d or depth %d", s->width,
                 s->height, s->max_depth);
        return -1;
    }
    fill_view(&r->host_frame, s);
    return write_frame(r, err, errlen) || clear_accumulation(r, err, errlen);
}

void render_settings_default(render_settings *st)
{
    memset(st, 0, sizeof *st);
    st->spp = 1;
    st->precision = RENDER_ROBUST;
}

int renderer_set_settings(renderer *r, const render_settings *st, char *err, size_t errlen)
{
    if (st->spp < 1 || st->spp > 65536) {
        snprintf(err, errlen, "samples per pixel must be in 1..65536, got %d", st->spp);
        return -1;
    }
    if (st->precision != RENDER_ROBUST && st->precision != RENDER_FAST) {
        snprintf(err, errlen, "unknown precision setting %d", st->precision);
        return -1;
    }
    r->settings = *st;
    if (r->have_scene && r->host_frame.spd_rays != (st->spd != 0)) {
        r->host_frame.spd_rays = st->spd != 0;
        return write_frame(r, err, errlen);
    }
    return 0;
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

int renderer_generate_rays(renderer *r, cw_ray *rays, char *err, size_t errlen)
{
    size_t n;
    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    if (ensure_image(r, err, errlen) ||
        run_raygen(r, 0, r->host_frame.ny, 0.5f, 0.5f, err, errlen) ||
        read_buffer(r, r->rays[0], n * sizeof *rays, rays, "rays", err, errlen))
        return -1;
    return 0;
}

int renderer_intersect(renderer *r, const cw_ray *rays, int n, cw_hit *hits, char *err,
                       size_t errlen)
{
    cl_int e;
    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    if (n <= 0) {
        snprintf(err, errlen, "renderer_intersect: no rays");
        return -1;
    }
    if (ensure_image(r, err, errlen) ||
        ensure_buffer(r, &r->rays[0], &r->ray_cap[0], (size_t)n * sizeof *rays, "ray queue", err,
                      errlen))
        return -1;
    e = clEnqueueWriteBuffer(r->queue, r->rays[0], CL_TRUE, 0, (size_t)n * sizeof *rays, rays, 0,
                             NULL, NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueWriteBuffer(rays)", r, err, errlen);
    if (run_intersect(r, &r->rays[0], n, err, errlen) ||
        read_buffer(r, r->hits, (size_t)n * sizeof *hits, hits, "hits", err, errlen))
        return -1;
    return 0;
}

int renderer_occluded(renderer *r, const cw_shadow_ray *rays, int n, int *blocked, char *err,
                      size_t errlen)
{
    cl_mem saved_image;
    size_t saved_cap, i;
    cw_shadow_ray *marked = NULL;
    float *px = NULL;
    cl_int e;
    int rc = -1;

    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    if (n <= 0) {
        snprintf(err, errlen, "renderer_occluded: no rays");
        return -1;
    }
    /* each ray adds 1 to its own pixel of a scratch image when nothing blocks it */
    marked = malloc((size_t)n * sizeof *marked);
    px = malloc((size_t)n * 4 * sizeof *px);
    if (!marked || !px) {
        snprintf(err, errlen, "out of memory");
        goto out_free;
    }
    for (i = 0; i < (size_t)n; i++) {
        marked[i] = rays[i];
        marked[i].pixel = (int)i;
        marked[i].block = 1; /* each ray its own shading point */
        marked[i].color.x = 1.0f;
        marked[i].color.y = marked[i].color.z = 0.0f;
    }
    saved_image = r->image;
    saved_cap = r->image_cap;
    r->image = NULL;
    r->image_cap = 0;
    if (ensure_buffer(r, &r->image, &r->image_cap, (size_t)n * 4 * sizeof(cl_float), "image", err,
                      errlen) ||
        fill_zero(r, r->image, (size_t)n * 4 * sizeof(cl_float), "image", err, errlen) ||
        ensure_buffer(r, &r->counters, &(size_t){0}, CW_NUM_COUNTERS * sizeof(cl_int), "counters",
                      err, errlen) ||
        ensure_buffer(r, &r->shadows, &r->shadow_cap, (size_t)n * sizeof *marked,
                      "shadow ray queue", err, errlen))
        goto out_restore;
    e = clEnqueueWriteBuffer(r->queue, r->shadows, CL_TRUE, 0, (size_t)n * sizeof *marked, marked,
                             0, NULL, NULL);
    if (e != CL_SUCCESS) {
        cl_fail(e, "clEnqueueWriteBuffer(shadow rays)", r, err, errlen);
        goto out_restore;
    }
    if (run_occlude(r, n, err, errlen) ||
        read_buffer(r, r->image, (size_t)n * 4 * sizeof *px, px, "image", err, errlen))
        goto out_restore;
    for (i = 0; i < (size_t)n; i++)
        blocked[i] = px[4 * i] == 0.0f;
    rc = 0;
out_restore:
    release_mem(&r->image);
    r->image = saved_image;
    r->image_cap = saved_cap;
out_free:
    free(marked);
    free(px);
    return rc;
}

const char *renderer_build_options(const renderer *r)
{
    return r->options;
}
