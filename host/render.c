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

#include "clerr.h"

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

extern const char cw_kernel_source[];

_Static_assert(sizeof(cw_float4) == 16, "cw_float4 must be 16 bytes");
_Static_assert(sizeof(cw_sphere) == 32, "cw_sphere layout");
_Static_assert(sizeof(cw_triangle) == 112, "cw_triangle layout");
_Static_assert(sizeof(cw_polygon) == 32, "cw_polygon layout");
_Static_assert(sizeof(cw_material) == 80, "cw_material layout");
_Static_assert(sizeof(cw_light) == 32, "cw_light layout");
_Static_assert(sizeof(cw_frame) == 176, "cw_frame layout");
_Static_assert(sizeof(cw_ray) == 64, "cw_ray layout");
_Static_assert(sizeof(cw_hit) == 32, "cw_hit layout");
_Static_assert(sizeof(cw_bvh_node) == 32, "cw_bvh_node layout");

struct renderer {
    cl_device_id device;
    char device_name[256];
    cl_context ctx;
    cl_command_queue queue;
    cl_program program;
    char options[1024]; /* build options of `program` */
    cl_kernel k_raygen, k_intersect, k_shade;
    /* scene buffers */
    cl_mem frame, spheres, triangles, polygons, verts, lights, materials;
    int have_scene;
    cw_frame host_frame;
    /* work buffers, grown on demand */
    cl_mem rays, hits, image, alive;
    size_t ray_cap, image_cap;
    /* settings, stats, progress */
    render_settings settings;
    char base_options[512]; /* the scene's feature options, without the settings' */
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
    release_mem(&r->spheres);
    release_mem(&r->triangles);
    release_mem(&r->polygons);
    release_mem(&r->verts);
    release_mem(&r->lights);
    release_mem(&r->materials);
    r->have_scene = 0;
}

static void release_program(renderer *r)
{
    if (r->k_raygen)
        clReleaseKernel(r->k_raygen);
    if (r->k_intersect)
        clReleaseKernel(r->k_intersect);
    if (r->k_shade)
        clReleaseKernel(r->k_shade);
    if (r->program)
        clReleaseProgram(r->program);
    r->k_raygen = r->k_intersect = r->k_shade = NULL;
    r->program = NULL;
    r->options[0] = '\0';
}

void renderer_destroy(renderer *r)
{
    if (!r)
        return;
    release_scene(r);
    release_mem(&r->rays);
    release_mem(&r->hits);
    release_mem(&r->image);
    release_mem(&r->alive);
    release_program(r);
    clReleaseCommandQueue(r->queue);
    clReleaseContext(r->ctx);
    free(r);
}

/* ---- program ---------------------------------------------------------------------- */

static int any_mirror(const scene *s)
{
    size_t i;
    for (i = 0; i < s->materials.count; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        if (m->km.x > 0 || m->km.y > 0 || m->km.z > 0)
            return 1;
    }
    return 0;
}

/* The kernel build options for a scene: every feature flag is decided here, from the
 * scene (base) and the settings. CLWHITTED_BUILD_OPTIONS, if set, is appended. */
static void scene_build_options(const scene *s, int num_polygons, char *buf, size_t n)
{
    snprintf(buf, n,
             "-cl-std=CL1.2 -Werror -DCW_HAS_SPHERES=%d -DCW_HAS_TRIANGLES=%d "
             "-DCW_HAS_POLYGONS=%d -DCW_HAS_MIRRORS=%d",
             s->spheres.count > 0, s->triangles.count > 0, num_polygons > 0,
             any_mirror(s) && s->max_depth > 1);
}

static void full_build_options(const renderer *r, char *buf, size_t n)
{
    const char *extra = getenv("CLWHITTED_BUILD_OPTIONS");
    snprintf(buf, n, "%s -DCW_FAST=%d -DCW_STATS=%d%s%s%s", r->base_options,
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
    r->program = clCreateProgramWithSource(r->ctx, 1, &src, NULL, &e);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clCreateProgramWithSource", r, err, errlen);
    e = clBuildProgram(r->program, 1, &r->device, options, NULL, NULL);
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
    r->k_raygen = clCreateKernel(r->program, "cw_raygen", &e);
    if (e == CL_SUCCESS)
        r->k_intersect = clCreateKernel(r->program, "cw_intersect", &e);
    if (e == CL_SUCCESS)
        r->k_shade = clCreateKernel(r->program, "cw_shade", &e);
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

static cw_float4 f4(vec3f v, float w)
{
    cw_float4 r;
    r.x = v.x;
    r.y = v.y;
    r.z = v.z;
    r.w = w;
    return r;
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

static int convert_polygons(const scene *s, cw_polygon **out, int *count, char *err, size_t errlen)
{
    size_t i, n = s->polygons.count;
    int k = 0;
    cw_polygon *pg = calloc(n ? n : 1, sizeof *pg);
    if (!pg) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    for (i = 0; i < n; i++) {
        const scene_polygon *sp = &SCENE_AT(s->polygons, scene_polygon, i);
        const vec3f *v = &SCENE_AT(s->poly_verts, vec3f, sp->first);
        double nn[3], off;
        int axis;
        if (scene_polygon_plane(v, sp->count, nn, &off, &axis) != 0)
            continue; /* degenerate: no area, cannot be hit */
        pg[k].plane.x = (float)nn[0];
        pg[k].plane.y = (float)nn[1];
        pg[k].plane.z = (float)nn[2];
        pg[k].plane.w = (float)off;
        pg[k].first = sp->first;
        pg[k].count = sp->count;
        pg[k].material = sp->material;
        pg[k].axis = axis;
        k++;
    }
    *out = pg;
    *count = k;
    return 0;
}

/* The view part of the frame: camera, size, depth, background and ambient. */
static void fill_view(cw_frame *f, const scene *s)
{
    const scene_camera *c = &s->camera;
    f->eye = f4(c->eye, 0);
    f->u = f4(c->u, 0);
    f->v = f4(c->v, 0);
    f->w = f4(c->w, 0);
    f->dir = f4(c->dir, 0);
    f->window.x = c->l;
    f->window.y = c->r;
    f->window.z = c->b;
    f->window.w = c->t;
    f->background = f4(s->background, 0);
    f->ambient = f4(s->ambient, 0);
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
    size_t i;
    int npoly = 0, rc = -1;
    cw_sphere *sph = NULL;
    cw_triangle *tri = NULL;
    cw_polygon *pg = NULL;
    cw_float4 *verts = NULL;
    cw_light *lights = NULL;
    cw_material *mats = NULL;
    cw_frame *f = &r->host_frame;
    double t0, t1;

    release_scene(r);
    memset(f, 0, sizeof *f);
    sph = calloc(s->spheres.count + 1, sizeof *sph);
    tri = calloc(s->triangles.count + 1, sizeof *tri);
    verts = calloc(s->poly_verts.count + 1, sizeof *verts);
    lights = calloc(s->lights.count + 1, sizeof *lights);
    mats = calloc(s->materials.count + 1, sizeof *mats);
    if (!sph || !tri || !verts || !lights || !mats) {
        snprintf(err, errlen, "out of memory");
        goto out_free;
    }
    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *ss = &SCENE_AT(s->spheres, scene_sphere, i);
        sph[i].center = f4(ss->center, ss->radius);
        sph[i].material = ss->material;
    }
    for (i = 0; i < s->triangles.count; i++) {
        const scene_triangle *st = &SCENE_AT(s->triangles, scene_triangle, i);
        tri[i].p0 = f4(st->p[0], 0);
        tri[i].p1 = f4(st->p[1], 0);
        tri[i].p2 = f4(st->p[2], 0);
        tri[i].n0 = f4(st->n[0], 0);
        tri[i].n1 = f4(st->n[1], 0);
        tri[i].n2 = f4(st->n[2], 0);
        tri[i].smooth = st->has_normals;
        tri[i].material = st->material;
    }
    for (i = 0; i < s->poly_verts.count; i++)
        verts[i] = f4(SCENE_AT(s->poly_verts, vec3f, i), 0);
    if (convert_polygons(s, &pg, &npoly, err, errlen) != 0)
        goto out_free;
    for (i = 0; i < s->lights.count; i++) {
        const scene_light *sl = &SCENE_AT(s->lights, scene_light, i);
        lights[i].position = f4(sl->position, 0);
        lights[i].intensity = f4(sl->intensity, 0);
    }
    for (i = 0; i < s->materials.count; i++) {
        const scene_material *sm = &SCENE_AT(s->materials, scene_material, i);
        mats[i].ka = f4(sm->ka, sm->p);
        mats[i].kd = f4(sm->kd, 0);
        mats[i].ks = f4(sm->ks, 0);
        mats[i].km = f4(sm->km, 0);
        mats[i].kt = f4(sm->kt, sm->ior);
    }

    fill_view(f, s);
    f->num_spheres = (int)s->spheres.count;
    f->num_triangles = (int)s->triangles.count;
    f->num_polygons = npoly;
    f->num_lights = (int)s->lights.count;

    scene_build_options(s, npoly, r->base_options, sizeof r->base_options);
    t0 = seconds_now();
    if (ensure_program(r, err, errlen) != 0)
        goto out_free;
    t1 = seconds_now();
    if (upload(r, &r->frame, f, 1, sizeof *f, "frame", err, errlen) ||
        upload(r, &r->spheres, sph, s->spheres.count, sizeof *sph, "spheres", err, errlen) ||
        upload(r, &r->triangles, tri, s->triangles.count, sizeof *tri, "triangles", err, errlen) ||
        upload(r, &r->polygons, pg, (size_t)npoly, sizeof *pg, "polygons", err, errlen) ||
        upload(r, &r->verts, verts, s->poly_verts.count, sizeof *verts, "polygon vertices", err,
               errlen) ||
        upload(r, &r->lights, lights, s->lights.count, sizeof *lights, "lights", err, errlen) ||
        upload(r, &r->materials, mats, s->materials.count, sizeof *mats, "materials", err,
               errlen)) {
        release_scene(r);
        goto out_free;
    }
    r->have_scene = 1;
    r->stats.upload_s = seconds_now() - t1;
    (void)t0;
    rc = 0;
out_free:
    free(sph);
    free(tri);
    free(pg);
    free(verts);
    free(lights);
    free(mats);
    return rc;
}

/* ---- passes ----------------------------------------------------------------------- */

/* Makes the work buffers hold n rays and hits and an n-pixel image. */
static int ensure_work(renderer *r, size_t n, char *err, size_t errlen)
{
    cl_int e;
    if (!r->alive) {
        r->alive = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, sizeof(cl_int), NULL, &e);
        if (e != CL_SUCCESS)
            return cl_fail(e, "clCreateBuffer(alive counter)", r, err, errlen);
    }
    if (n > r->ray_cap) {
        release_mem(&r->rays);
        release_mem(&r->hits);
        release_mem(&r->image);
        r->ray_cap = 0;
        r->rays = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, n * sizeof(cw_ray), NULL, &e);
        if (e != CL_SUCCESS)
            return cl_fail(e, "clCreateBuffer(rays)", r, err, errlen);
        r->hits = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, n * sizeof(cw_hit), NULL, &e);
        if (e != CL_SUCCESS)
            return cl_fail(e, "clCreateBuffer(hits)", r, err, errlen);
        r->image = clCreateBuffer(r->ctx, CL_MEM_READ_WRITE, n * sizeof(cl_float4), NULL, &e);
        if (e != CL_SUCCESS)
            return cl_fail(e, "clCreateBuffer(image)", r, err, errlen);
        r->ray_cap = n;
    }
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

/* Sets the frame and world arguments shared by the intersection and shading kernels:
 * indices 0..4. */
static int set_world_args(renderer *r, cl_kernel k, const char *kname, char *err, size_t errlen)
{
    return set_arg(k, 0, sizeof(cl_mem), &r->frame, kname, r, err, errlen) ||
           set_arg(k, 1, sizeof(cl_mem), &r->spheres, kname, r, err, errlen) ||
           set_arg(k, 2, sizeof(cl_mem), &r->triangles, kname, r, err, errlen) ||
           set_arg(k, 3, sizeof(cl_mem), &r->polygons, kname, r, err, errlen) ||
           set_arg(k, 4, sizeof(cl_mem), &r->verts, kname, r, err, errlen);
}

static int launch(renderer *r, cl_kernel k, size_t n, const char *kname, char *err, size_t errlen)
{
    size_t global = (n + 63) / 64 * 64;
    cl_int e = clEnqueueNDRangeKernel(r->queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s)", kname);
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

/* One eye ray per pixel of rows [row0, row0 + nrows), launched in 2-D (no index division
 * in the kernel); (sx, sy) is the sample's position inside the pixel. Each pixel's
 * accumulated sample count (image .w) goes up by one. */
static int run_raygen(renderer *r, int row0, int nrows, float sx, float sy, char *err,
                      size_t errlen)
{
    const char *k = "cw_raygen";
    size_t global[2];
    cl_int e;
    cl_int crow0 = row0, cnrows = nrows;
    global[0] = ((size_t)r->host_frame.nx + 7) / 8 * 8;
    global[1] = ((size_t)nrows + 7) / 8 * 8;
    if (set_arg(r->k_raygen, 0, sizeof(cl_mem), &r->frame, k, r, err, errlen) ||
        set_arg(r->k_raygen, 1, sizeof(cl_mem), &r->rays, k, r, err, errlen) ||
        set_arg(r->k_raygen, 2, sizeof(cl_mem), &r->image, k, r, err, errlen) ||
        set_arg(r->k_raygen, 3, sizeof crow0, &crow0, k, r, err, errlen) ||
        set_arg(r->k_raygen, 4, sizeof cnrows, &cnrows, k, r, err, errlen) ||
        set_arg(r->k_raygen, 5, sizeof sx, &sx, k, r, err, errlen) ||
        set_arg(r->k_raygen, 6, sizeof sy, &sy, k, r, err, errlen))
        return -1;
    e = clEnqueueNDRangeKernel(r->queue, r->k_raygen, 2, NULL, global, NULL, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueNDRangeKernel(cw_raygen)", r, err, errlen);
    return 0;
}

static int run_intersect(renderer *r, cl_int n, char *err, size_t errlen)
{
    return set_world_args(r, r->k_intersect, "cw_intersect", err, errlen) ||
           set_arg(r->k_intersect, 5, sizeof(cl_mem), &r->rays, "cw_intersect", r, err, errlen) ||
           set_arg(r->k_intersect, 6, sizeof(cl_mem), &r->hits, "cw_intersect", r, err, errlen) ||
           set_arg(r->k_intersect, 7, sizeof n, &n, "cw_intersect", r, err, errlen) ||
           launch(r, r->k_intersect, (size_t)n, "cw_intersect", err, errlen);
}

static int run_shade(renderer *r, cl_int n, char *err, size_t errlen)
{
    const char *k = "cw_shade";
    return set_world_args(r, r->k_shade, k, err, errlen) ||
           set_arg(r->k_shade, 5, sizeof(cl_mem), &r->lights, k, r, err, errlen) ||
           set_arg(r->k_shade, 6, sizeof(cl_mem), &r->materials, k, r, err, errlen) ||
           set_arg(r->k_shade, 7, sizeof(cl_mem), &r->rays, k, r, err, errlen) ||
           set_arg(r->k_shade, 8, sizeof(cl_mem), &r->hits, k, r, err, errlen) ||
           set_arg(r->k_shade, 9, sizeof(cl_mem), &r->image, k, r, err, errlen) ||
           set_arg(r->k_shade, 10, sizeof(cl_mem), &r->alive, k, r, err, errlen) ||
           set_arg(r->k_shade, 11, sizeof n, &n, k, r, err, errlen) ||
           launch(r, r->k_shade, (size_t)n, k, err, errlen);
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

static int clear_accumulation(renderer *r, char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    return ensure_work(r, n, err, errlen) ||
           fill_zero(r, r->image, n * sizeof(cl_float4), "image", err, errlen);
}

/* Traces one sample for a band of rows: ray generation, then per depth one intersection
 * and one shading pass. progress: report after each pass, with the fraction done before
 * this band (done) and the band's share (share). */
static int trace_band(renderer *r, int sample, int row0, int nrows, double done, double share,
                      char *err, size_t errlen)
{
    size_t n = (size_t)r->host_frame.nx * (size_t)nrows;
    float sx, sy;
    int depth;

    sample_position(r->settings.spp, sample, &sx, &sy);
    if (run_raygen(r, row0, nrows, sx, sy, err, errlen))
        return -1;
    r->stats.eye_rays += n;
    for (depth = 1; depth <= r->host_frame.max_depth; depth++) {
        cl_int alive = 0;
        if (fill_zero(r, r->alive, sizeof(cl_int), "alive counter", err, errlen) ||
            run_intersect(r, (cl_int)n, err, errlen) || run_shade(r, (cl_int)n, err, errlen) ||
            read_buffer(r, r->alive, sizeof alive, &alive, "alive counter", err, errlen))
            return -1;
        r->stats.passes++;
        if (depth < r->host_frame.max_depth)
            r->stats.secondary_rays += (unsigned long long)alive;
        if (r->progress &&
            r->progress(r->progress_ctx,
                        done + share * (alive == 0 ? 1.0 : (double)depth / r->host_frame.max_depth),
                        r->stats.eye_rays + r->stats.secondary_rays) != 0) {
            snprintf(err, errlen, "render cancelled");
            return -1;
        }
        if (alive == 0)
            break;
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
    if (ensure_work(r, (size_t)r->host_frame.nx * (size_t)r->host_frame.ny, err, errlen))
        return -1;
    return trace_band(r, sample, row0, nrows, 0.0, 1.0, err, errlen);
}

int renderer_read(renderer *r, image *img, char *err, size_t errlen)
{
    size_t n, i;
    cl_float4 *px = NULL;

    if (need_scene(r, err, errlen))
        return -1;
    n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    if (ensure_work(r, n, err, errlen))
        return -1;
    px = malloc(n * sizeof *px);
    if (!px) {
        snprintf(err, errlen, "out of memory for a %zu-pixel image", n);
        return -1;
    }
    if (read_buffer(r, r->image, n * sizeof *px, px, "image", err, errlen))
        goto out_free;
    if (image_alloc(img, r->host_frame.nx, r->host_frame.ny) != 0) {
        snprintf(err, errlen, "out of memory for a %zu-pixel image", n);
        goto out_free;
    }
    for (i = 0; i < n; i++) {
        float w = px[i].s[3] > 0 ? 1.0f / px[i].s[3] : 0.0f;
        img->rgb[3 * i + 0] = px[i].s[0] * w;
        img->rgb[3 * i + 1] = px[i].s[1] * w;
        img->rgb[3 * i + 2] = px[i].s[2] * w;
    }
    free(px);
    return 0;
out_free:
    free(px);
    return -1;
}

int renderer_render(renderer *r, image *img, char *err, size_t errlen)
{
    int k, spp = r->settings.spp < 1 ? 1 : r->settings.spp;
    double t0;

    if (need_scene(r, err, errlen) || ensure_program(r, err, errlen))
        return -1;
    if (r->settings.spd) {
        snprintf(err, errlen, "SPD mode is not implemented yet");
        return -1;
    }
    t0 = seconds_now();
    r->stats.eye_rays = r->stats.eye_hits = 0;
    r->stats.shadow_rays = r->stats.shadow_blocked = 0;
    r->stats.secondary_rays = r->stats.secondary_hits = 0;
    r->stats.passes = 0;
    if (clear_accumulation(r, err, errlen))
        return -1;
    for (k = 0; k < spp; k++)
        if (trace_band(r, k, 0, r->host_frame.ny, (double)k / spp, 1.0 / spp, err, errlen))
            return -1;
    if (renderer_read(r, img, err, errlen))
        return -1;
    r->stats.trace_s = seconds_now() - t0;
    return 0;
}

int renderer_set_view(renderer *r, const scene *s, char *err, size_t errlen)
{
    cw_frame *f = &r->host_frame;
    cl_int e;
    if (need_scene(r, err, errlen))
        return -1;
    if (s->width < 1 || s->height < 1) {
        snprintf(err, errlen, "renderer_set_view: bad image size %dx%d", s->width, s->height);
        return -1;
    }
    fill_view(f, s);
    /* the mirror feature depends on the depth */
    scene_build_options(s, f->num_polygons, r->base_options, sizeof r->base_options);
    e = clEnqueueWriteBuffer(r->queue, r->frame, CL_TRUE, 0, sizeof *f, f, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueWriteBuffer(frame)", r, err, errlen);
    return clear_accumulation(r, err, errlen);
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
    if (need_scene(r, err, errlen))
        return -1;
    if (ensure_program(r, err, errlen))
        return -1;
    n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    if (ensure_work(r, n, err, errlen) ||
        run_raygen(r, 0, r->host_frame.ny, 0.5f, 0.5f, err, errlen) ||
        read_buffer(r, r->rays, n * sizeof *rays, rays, "rays", err, errlen))
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
    if (ensure_work(r, (size_t)n, err, errlen))
        return -1;
    e = clEnqueueWriteBuffer(r->queue, r->rays, CL_TRUE, 0, (size_t)n * sizeof *rays, rays, 0, NULL,
                             NULL);
    if (e != CL_SUCCESS)
        return cl_fail(e, "clEnqueueWriteBuffer(rays)", r, err, errlen);
    if (run_intersect(r, n, err, errlen) ||
        read_buffer(r, r->hits, (size_t)n * sizeof *hits, hits, "hits", err, errlen))
        return -1;
    return 0;
}
