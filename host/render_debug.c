/* The renderer's test hooks (render_debug.h): the ray-generation, intersection and
 * shadow-ray kernels run alone on given rays (the wavefront's kernels: a hook builds the
 * wavefront program whatever the strategy), and the last build options. Only the test
 * suites call them, so only they link this file out of the library. */
#include "render_debug.h"

#include <stdio.h>
#include <stdlib.h>

#include "render_impl.h"
#include "render_pass.h"

int renderer_generate_rays(renderer *r, cw_ray *rays, char *err, size_t errlen)
{
    size_t n;
    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, RENDER_WAVEFRONT, err, errlen))
        return -1;
    n = (size_t)r->host_frame.nx * (size_t)r->host_frame.ny;
    if (rpass_ensure_image(r, err, errlen) ||
        rpass_raygen(r, 0, r->host_frame.ny, 0.5f, 0.5f, err, errlen) ||
        rpass_read(r, r->rays[0], n * sizeof *rays, rays, "rays", err, errlen))
        return -1;
    return 0;
}

int renderer_intersect(renderer *r, const cw_ray *rays, int n, cw_hit *hits, char *err,
                       size_t errlen)
{
    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, RENDER_WAVEFRONT, err, errlen))
        return -1;
    if (n <= 0) {
        snprintf(err, errlen, "renderer_intersect: no rays");
        return -1;
    }
    if (rpass_ensure_image(r, err, errlen) ||
        rpass_ensure_buffer(r, &r->rays[0], &r->ray_cap[0], (size_t)n * sizeof *rays, "ray queue",
                            err, errlen) ||
        rpass_write(r, r->rays[0], (size_t)n * sizeof *rays, rays, "rays", err, errlen) ||
        rpass_intersect(r, &r->rays[0], n, err, errlen) ||
        rpass_read(r, r->hits, (size_t)n * sizeof *hits, hits, "hits", err, errlen))
        return -1;
    return 0;
}

/* Each ray adds 1 to its own pixel of a scratch image when nothing blocks it. */
int renderer_occluded(renderer *r, const cw_shadow_ray *rays, int n, int *blocked, char *err,
                      size_t errlen)
{
    cl_mem saved_image;
    size_t saved_cap, i;
    cw_shadow_ray *marked = NULL;
    float *px = NULL;
    int rc = -1;

    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, RENDER_WAVEFRONT, err, errlen))
        return -1;
    if (n <= 0) {
        snprintf(err, errlen, "renderer_occluded: no rays");
        return -1;
    }
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
    if (rpass_ensure_buffer(r, &r->image, &r->image_cap, (size_t)n * 4 * sizeof(cl_float), "image",
                            err, errlen) ||
        rpass_fill_zero(r, r->image, (size_t)n * 4 * sizeof(cl_float), "image", err, errlen) ||
        rpass_ensure_buffer(r, &r->counters, &(size_t){0}, CW_NUM_COUNTERS * sizeof(cl_int),
                            "counters", err, errlen) ||
        rpass_ensure_buffer(r, &r->shadows, &r->shadow_cap, (size_t)n * sizeof *marked,
                            "shadow ray queue", err, errlen) ||
        rpass_write(r, r->shadows, (size_t)n * sizeof *marked, marked, "shadow rays", err,
                    errlen) ||
        rpass_occlude(r, n, err, errlen) ||
        rpass_read(r, r->image, (size_t)n * 4 * sizeof *px, px, "image", err, errlen))
        goto out_restore;
    for (i = 0; i < (size_t)n; i++)
        blocked[i] = px[4 * i] == 0.0f;
    rc = 0;
out_restore:
    rpass_release(&r->image);
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

void renderer_debug_world_origin(renderer *r, int on)
{
    r->world_origin = on != 0;
}

void renderer_debug_upload_piece(renderer *r, size_t bytes)
{
    r->upload_piece = bytes;
}
