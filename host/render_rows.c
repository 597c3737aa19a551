/* Renders in row bands for a front end that splits one image over processes (clwhitted-mpi):
 * every sample (or the SPD corner rays) of a band of the accumulation image, read back as
 * floats, and the image made from a whole accumulation. render.c's whole-image render
 * makes its image with the same resolve functions, so the two give the same bits. */
#include "render.h"

#include <stdio.h>
#include <string.h>

#include "par.h"
#include "render_impl.h"
#include "render_pass.h"
#include "render_rows.h"
#include "sys.h"

void rrows_spd_frame(const cw_frame *f, cw_frame *corners)
{
    float pu = (f->window.y - f->window.x) / (float)f->cam_nx;
    float pv = (f->window.w - f->window.z) / (float)f->cam_ny;
    *corners = *f;
    corners->nx = f->nx + 1;
    corners->ny = f->ny + 1;
    corners->cam_nx = f->cam_nx + 1;
    corners->cam_ny = f->cam_ny + 1;
    corners->window.x = f->window.x - 0.5f * pu;
    corners->window.y = f->window.y + 0.5f * pu;
    corners->window.z = f->window.z - 0.5f * pv;
    corners->window.w = f->window.w + 0.5f * pv;
}

/* The rows [y0, y1) of a resolve (see rrows_resolve_mean and rrows_resolve_spd). */
static void resolve_mean_rows(const float *px, image *img, int y0, int y1)
{
    size_t i, end = (size_t)y1 * (size_t)img->width;
    for (i = (size_t)y0 * (size_t)img->width; i < end; i++) {
        float w = px[4 * i + 3] > 0 ? 1.0f / px[4 * i + 3] : 0.0f;
        img->rgb[3 * i + 0] = px[4 * i + 0] * w;
        img->rgb[3 * i + 1] = px[4 * i + 1] * w;
        img->rgb[3 * i + 2] = px[4 * i + 2] * w;
    }
}

static void resolve_spd_rows(const float *px, image *img, int y0, int y1)
{
    int i, j, nx = img->width, cx = nx + 1;
    for (j = y0; j < y1; j++)
        for (i = 0; i < nx; i++) {
            const float *c00 = &px[4 * (j * cx + i)], *c01 = &px[4 * (j * cx + i + 1)];
            const float *c10 = &px[4 * ((j + 1) * cx + i)], *c11 = &px[4 * ((j + 1) * cx + i + 1)];
            int c;
            for (c = 0; c < 3; c++)
                img->rgb[3 * (j * nx + i) + c] = 0.25f * (c00[c] + c01[c] + c10[c] + c11[c]);
        }
}

/* A resolve in jobs of RESOLVE_ROWS rows on the CPU's threads (par.c): at 2048x2048 it
 * took 36 ms on one, most of it the first touch of the image's 48 MB. */
#define RESOLVE_ROWS 64

typedef struct {
    const float *px;
    image *img;
    int spd;
} resolve_ctx;

static int resolve_job(void *ctx, int job, int thread)
{
    const resolve_ctx *c = ctx;
    int y0 = job * RESOLVE_ROWS, y1 = y0 + RESOLVE_ROWS;
    (void)thread;
    if (y1 > c->img->height)
        y1 = c->img->height;
    if (c->spd)
        resolve_spd_rows(c->px, c->img, y0, y1);
    else
        resolve_mean_rows(c->px, c->img, y0, y1);
    return 0;
}

static void resolve(const float *px, image *img, int spd)
{
    resolve_ctx c;
    int jobs = (img->height + RESOLVE_ROWS - 1) / RESOLVE_ROWS;
    c.px = px;
    c.img = img;
    c.spd = spd;
    (void)par_ordered(jobs, sys_cpu_count(), jobs, resolve_job, NULL, &c);
}

void rrows_resolve_mean(const float *px, image *img)
{
    resolve(px, img, 0);
}

void rrows_resolve_spd(const float *px, image *img)
{
    resolve(px, img, 1);
}

void renderer_reset_trace_stats(renderer *r)
{
    r->stats.eye_rays = r->stats.eye_hits = 0;
    r->stats.shadow_rays = r->stats.shadow_blocked = 0;
    r->stats.secondary_rays = r->stats.secondary_hits = 0;
    r->stats.closest_nodes = r->stats.closest_tests = r->stats.any_nodes = r->stats.any_tests = 0;
    r->stats.passes = 0;
    r->stats.raygen_s = r->stats.intersect_s = r->stats.shade_s = r->stats.occlude_s = 0;
    r->stats.pixel_s = 0;
    r->stats.trace_s = 0;
}

void renderer_accum_size(const renderer *r, int *width, int *height)
{
    int extra = r->settings.spd ? 1 : 0;
    *width = r->host_frame.nx + extra;
    *height = r->host_frame.ny + extra;
}

/* Traces every sample into rows [row0, row0 + nrows) of the accumulation in the
 * whole-image render's order (sample by sample, each in bands; the first starts them
 * empty), reads them back. */
static int rows_trace(renderer *r, int spp, int row0, int nrows, float *acc, char *err,
                      size_t errlen)
{
    size_t row_bytes = (size_t)r->host_frame.nx * 4 * sizeof(cl_float);
    int k, y, band = rpass_band_rows(r);
    cl_int e;

    for (k = 0; k < spp; k++)
        for (y = row0; y < row0 + nrows; y += band) {
            int n = y + band > row0 + nrows ? row0 + nrows - y : band;
            double done = ((double)k + (double)(y - row0) / nrows) / spp;
            if (rpass_trace_band(r, k, y, n, k == 0, done, (double)n / nrows / spp, err, errlen))
                return -1;
        }
    e = clEnqueueReadBuffer(r->queue, r->image, CL_TRUE, row_bytes * (size_t)row0,
                            row_bytes * (size_t)nrows, acc, 0, NULL, NULL);
    if (e != CL_SUCCESS)
        return rpass_fail(e, "clEnqueueReadBuffer(image rows)", r, err, errlen);
    return 0;
}

int renderer_render_rows(renderer *r, int row0, int nrows, float *acc, char *err, size_t errlen)
{
    cw_frame saved = r->host_frame;
    int spp = r->settings.spp < 1 ? 1 : r->settings.spp, w, h, rc = -1;
    double t0 = sys_now();

    if (rpass_need_scene(r, err, errlen) ||
        renderer_ensure_program(r, renderer_strategy(r), err, errlen))
        return -1;
    renderer_accum_size(r, &w, &h);
    if (row0 < 0 || nrows < 1 || row0 + nrows > h) {
        snprintf(err, errlen, "renderer_render_rows: rows %d..%d outside the %d-row image", row0,
                 row0 + nrows - 1, h);
        return -1;
    }
    if (r->settings.spd) {
        rrows_spd_frame(&saved, &r->host_frame);
        spp = 1;
        if (rpass_write(r, r->world.frame, sizeof r->host_frame, &r->host_frame, "frame", err,
                        errlen))
            goto out_restore;
    }
    rc = rows_trace(r, spp, row0, nrows, acc, err, errlen);
out_restore:
    if (r->settings.spd) {
        r->host_frame = saved;
        if (rpass_write(r, r->world.frame, sizeof r->host_frame, &r->host_frame, "frame", err,
                        errlen))
            rc = -1;
    }
    r->stats.trace_s += sys_now() - t0;
    return rc;
}

int renderer_resolve(const renderer *r, const float *acc, image *img, char *err, size_t errlen)
{
    if (image_alloc(img, r->host_frame.nx, r->host_frame.ny) != 0) {
        snprintf(err, errlen, "out of memory for a %dx%d image", r->host_frame.nx,
                 r->host_frame.ny);
        return -1;
    }
    if (r->settings.spd)
        rrows_resolve_spd(acc, img);
    else
        rrows_resolve_mean(acc, img);
    return 0;
}
