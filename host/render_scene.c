/* The scene on the device: a finished scene converted for the kernels around its local
 * origin, its BVH built (renderer_prepare_scene, which needs no device), then the kernels
 * for its features and the upload of its arrays (renderer_set_prepared; renderer_set_scene
 * does both), and the frame's view. */
#include "render_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

#include "config.h"
#include "devscene.h"
#include "render_pass.h"
#include "scene_geom.h"
#include "sys.h"
#include "world.h"

void rscene_release(renderer *r)
{
    rpass_release(&r->world.frame);
#define RELEASE_WORLD(type, name, what) rpass_release(&r->world.name);
    CW_WORLD_BUFFERS(RELEASE_WORLD)
#undef RELEASE_WORLD
    rpass_release(&r->lights);
    rpass_release(&r->materials);
    r->have_scene = 0;
}

/* Writes a big host array into buffer m a piece at a time, each piece's memory given back
 * as soon as the device holds its copy (sys_release): the host copy and the device copy of
 * a scene array are never both whole, so the peak memory of the upload is the scene's plus
 * one piece rather than plus its largest array. */
static int upload_pieces(renderer *r, cl_mem m, void *data, size_t bytes, size_t piece,
                         const char *what, char *err, size_t errlen)
{
    for (size_t off = 0; off < bytes; off += piece) {
        size_t len = bytes - off < piece ? bytes - off : piece;
        cl_int e =
            clEnqueueWriteBuffer(r->queue, m, CL_TRUE, off, len, (char *)data + off, 0, NULL, NULL);
        if (e != CL_SUCCESS) {
            char call[96];
            snprintf(call, sizeof call, "clEnqueueWriteBuffer(%s, %zu bytes)", what, len);
            return rpass_fail(e, call, r, err, errlen);
        }
        sys_release((char *)data + off, len);
    }
    return 0;
}

/* A read-only buffer holding a copy of count elements (at least one element is
 * allocated: OpenCL has no empty buffers). A host array the caller frees right after
 * (release) and larger than a piece (CW_UPLOAD_PIECE, or the test hook's) is written in
 * pieces (upload_pieces). */
static int upload(renderer *r, cl_mem *m, const void *data, size_t count, size_t size, int release,
                  const char *what, char *err, size_t errlen)
{
    size_t piece;
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
    if (rpass_check_alloc(r, what, count * size, err, errlen) != 0) {
        free(zero);
        return -1;
    }
    piece = r->upload_piece ? r->upload_piece : CW_UPLOAD_PIECE;
    release = release && !zero && count * size > piece;
    *m = clCreateBuffer(r->ctx, CL_MEM_READ_ONLY | (release ? 0 : CL_MEM_COPY_HOST_PTR),
                        count * size, release ? NULL : (void *)data, &e);
    free(zero);
    if (e != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes)", what, count * size);
        return rpass_fail(e, call, r, err, errlen);
    }
    r->stats.upload_copied += (unsigned long long)(count * size);
    return release ? upload_pieces(r, *m, (void *)data, count * size, piece, what, err, errlen) : 0;
}

static void CL_CALLBACK free_device_array(cl_mem m, void *array)
{
    (void)m;
    sys_device_free(array);
}

/* A scene array of `bytes` from sys_device_calloc as the memory of its buffer, where
 * the device is a CPU one: CL_MEM_USE_HOST_PTR, so that the device reads the array where
 * the host built it, with no copy and no second set of pages to fault in (1M random
 * triangles: 124 MB not copied, 27,000 page faults fewer, the upload's 0.09 s gone). The buffer
 * then owns the array: it is freed when the buffer is destroyed. Returns 1 when the buffer was made
 * so (the caller must forget the array), 0 when the array is to be copied instead (another kind of
 * device, the test hook of upload pieces, an empty array), -1 on error (the array is still the
 * caller's). */
static int upload_in_place(renderer *r, cl_mem *m, void *data, size_t bytes, const char *what,
                           char *err, size_t errlen)
{
    char call[96];
    cl_int e;
    if (bytes == 0 || !r->cpu || r->upload_piece || (uintptr_t)data % SYS_DEVICE_ALIGN != 0)
        return 0;
    if (rpass_check_alloc(r, what, bytes, err, errlen) != 0)
        return -1;
    *m = clCreateBuffer(r->ctx, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes, data, &e);
    if (e != CL_SUCCESS) {
        *m = NULL;
        snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes, in place)", what, bytes);
        return rpass_fail(e, call, r, err, errlen);
    }
    e = clSetMemObjectDestructorCallback(*m, free_device_array, data);
    if (e != CL_SUCCESS) {
        rpass_release(m); /* never used: the array is the caller's again */
        snprintf(call, sizeof call, "clSetMemObjectDestructorCallback(%s)", what);
        return rpass_fail(e, call, r, err, errlen);
    }
    r->stats.upload_in_place += (unsigned long long)bytes;
    return 1;
}

/* Makes every buffer of CW_WORLD_BUFFERS in list order from the devscene's arrays (the
 * frame is uploaded first by the caller): on a CPU device the array itself, handed over to
 * its buffer (upload_in_place), else a copy, each host array freed once its buffer holds
 * it. Either way the scene is never in memory twice over. */
static int upload_world(renderer *r, devscene *ds, char *err, size_t errlen)
{
    devscene_world a;
    int in_place;
    devscene_world_arrays(ds, &a);
#define UPLOAD_WORLD(type, name, what)                                                             \
    in_place = upload_in_place(r, &r->world.name, (void *)a.name, a.n_##name * sizeof(type), what, \
                               err, errlen);                                                       \
    if (in_place < 0 || (!in_place && upload(r, &r->world.name, a.name, a.n_##name, sizeof(type),  \
                                             1, what, err, errlen)))                               \
        return -1;                                                                                 \
    if (in_place)                                                                                  \
        devscene_take_array(ds, CW_WORLD_ARG_##name);                                              \
    else                                                                                           \
        devscene_free_array(ds, CW_WORLD_ARG_##name);
    CW_WORLD_BUFFERS(UPLOAD_WORLD)
#undef UPLOAD_WORLD
    return 0;
}

/* The view part of the frame: camera, size, depth, background and ambient. */
void rscene_fill_view(cw_frame *f, const scene *s, vec3d origin)
{
    const scene_camera *c = &s->camera;
    f->eye = devscene_f4(vec3d_diff(c->eye, origin), 0);
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
    f->nx = f->cam_nx = s->width;
    f->ny = f->cam_ny = s->height;
    f->cam_x0 = f->cam_y0 = 0;
    f->max_depth = s->max_depth;
}

/* A scene converted for the kernels, its BVH built: what renderer_set_scene does before it
 * needs the device (renderer_prepare_scene). */
struct render_prep {
    devscene ds;
    vec3d origin;     /* the local origin the arrays are relative to */
    int world_origin; /* made with renderer_debug_world_origin's origin (0, 0, 0) */
    double build_s;
};

/* Converts s for the kernels around the local origin (the camera's eye, or with
 * world_origin (0, 0, 0): docs/model.md, "Far from the origin") and builds its BVH into p;
 * with drop (== s), the scene's primitive arrays are emptied once converted. Returns 0, or
 * -1 with err and p freed. */
static int prepare(const scene *s, scene *drop, int world_origin, struct render_prep *p, char *err,
                   size_t errlen)
{
    int converted;
    double t0;
    p->world_origin = world_origin;
    p->origin = world_origin ? vec3d_make(0, 0, 0) : s->camera.eye;
    converted = devscene_convert(s, &p->origin, &p->ds, err, errlen) == 0;
    if (drop)
        scene_drop_primitives(drop);
    if (!converted)
        goto out_free;
    t0 = sys_now();
    if (devscene_build_bvh(&p->ds, err, errlen) != 0)
        goto out_free;
    p->build_s = sys_now() - t0;
    return 0;
out_free:
    devscene_free(&p->ds);
    return -1;
}

/* Puts the prepared scene p (made from s) on the device: the kernels for its features, its
 * arrays. p->ds is not freed here. */
static int set_prepared(renderer *r, struct render_prep *p, const scene *s, char *err,
                        size_t errlen)
{
    devscene *ds = &p->ds;
    cw_frame *f = &r->host_frame;
    double t0;

    rscene_release(r);
    memset(f, 0, sizeof *f);
    r->stats.build_s = r->stats.compile_s = r->stats.upload_s = 0;
    r->stats.upload_in_place = r->stats.upload_copied = 0;
    if (p->world_origin != r->world_origin) {
        snprintf(err, errlen,
                 "the scene was prepared for another local origin than the "
                 "renderer's (renderer_debug_world_origin)");
        return -1;
    }
    r->origin = p->origin;
    r->features.spheres = ds->nsph;
    r->features.triangles = ds->ntri;
    r->features.polygons = ds->npg;
    r->features.cones = ds->ncone;
    r->features.instances = ds->ninst;
    r->features.mirrors = ds->mirrors;
    r->features.transmitters = ds->transmitters;
    r->stats.build_s = p->build_s;
    r->stats.spheres = ds->nsph;
    r->stats.triangles = ds->ntri;
    r->stats.polygons = ds->npg;
    r->stats.cones = ds->ncone;
    r->stats.instances = ds->ninst;
    r->stats.meshes = 0;
    for (int m = 0; m < ds->nmesh; m++)
        r->stats.meshes += ds->meshes[m].root >= 0;
    r->stats.nodes = ds->tree_wide.num_nodes;

    rscene_fill_view(f, s, r->origin);
    f->num_lights = (int)s->lights.count;
    f->num_nodes = ds->tree_wide.num_nodes;
    f->spd_rays = r->settings.spd;

    if (renderer_ensure_program(r, renderer_strategy(r), err, errlen) != 0)
        return -1;
    t0 = sys_now();
    if (upload(r, &r->world.frame, f, 1, sizeof *f, 0, "frame", err, errlen) ||
        upload_world(r, ds, err, errlen) ||
        upload(r, &r->lights, ds->lights, s->lights.count, sizeof *ds->lights, 0, "lights", err,
               errlen) ||
        upload(r, &r->materials, ds->mats, s->materials.count, sizeof *ds->mats, 0, "materials",
               err, errlen)) {
        rscene_release(r);
        return -1;
    }
    r->have_scene = 1;
    r->stats.upload_s = sys_now() - t0;
    return 0;
}

/* renderer_set_scene; with drop (== s), the scene's primitive arrays are emptied once
 * converted. */
static int set_scene(renderer *r, const scene *s, scene *drop, char *err, size_t errlen)
{
    struct render_prep p;
    int rc;
    if (prepare(s, drop, r->world_origin, &p, err, errlen) != 0) {
        rscene_release(r);
        return -1;
    }
    rc = set_prepared(r, &p, s, err, errlen);
    devscene_free(&p.ds);
    return rc;
}

int renderer_set_scene(renderer *r, const scene *s, char *err, size_t errlen)
{
    return set_scene(r, s, NULL, err, errlen);
}

int renderer_set_scene_dropping(renderer *r, scene *s, char *err, size_t errlen)
{
    return set_scene(r, s, s, err, errlen);
}

render_prep *renderer_prepare_scene(scene *s, char *err, size_t errlen)
{
    render_prep *p = calloc(1, sizeof *p);
    if (!p) {
        scene_drop_primitives(s);
        snprintf(err, errlen, "out of memory for the prepared scene");
        return NULL;
    }
    if (prepare(s, s, 0, p, err, errlen) != 0) {
        free(p);
        return NULL;
    }
    return p;
}

int renderer_set_prepared(renderer *r, render_prep *p, const scene *s, char *err, size_t errlen)
{
    int rc = set_prepared(r, p, s, err, errlen);
    renderer_prep_free(p);
    return rc;
}

void renderer_prep_free(render_prep *p)
{
    if (!p)
        return;
    devscene_free(&p->ds);
    free(p);
}
