/* The device side of a render (see render_pass.c). For render.c and render_debug.c. */
#ifndef CW_RENDER_PASS_H
#define CW_RENDER_PASS_H

#include <stddef.h>

#include "render_impl.h"

/* Writes "CALL failed: NAME (CODE) on device DEVICE" to err. Returns -1. */
int rpass_fail(cl_int e, const char *call, const renderer *r, char *err, size_t errlen);

/* -1 with err unless a scene is uploaded. */
int rpass_need_scene(const renderer *r, char *err, size_t errlen);

/* Checks that a buffer fits the device before asking for it, so that a scene too big
 * for the device gets a message naming the buffer ("what") rather than a driver error. */
int rpass_check_alloc(const renderer *r, const char *what, size_t bytes, char *err, size_t errlen);

/* Releases *m (if any) and sets it to NULL. */
void rpass_release(cl_mem *m);

/* Makes *m a read-write buffer of at least need bytes (contents not kept); *cap is its
 * size. Returns 0, or -1 with err. */
int rpass_ensure_buffer(renderer *r, cl_mem *m, size_t *cap, size_t need, const char *what,
                        char *err, size_t errlen);
int rpass_fill_zero(renderer *r, cl_mem m, size_t size, const char *what, char *err, size_t errlen);
int rpass_read(renderer *r, cl_mem m, size_t size, void *dst, const char *what, char *err,
               size_t errlen);
int rpass_write(renderer *r, cl_mem m, size_t size, const void *src, const char *what, char *err,
                size_t errlen);

/* The accumulation image (nx * ny pixels of rgb + sample count) and the counters;
 * rpass_clear_accumulation also zeroes the image. */
int rpass_ensure_image(renderer *r, char *err, size_t errlen);
int rpass_clear_accumulation(renderer *r, char *err, size_t errlen);
/* Zeroes rows [row0, row0 + nrows) of the accumulation image (allocating it if need be). */
int rpass_clear_rows(renderer *r, int row0, int nrows, char *err, size_t errlen);

/* Rows per band: the wavefront's ray queues, hits and shadow rays stay within about 64 MB.
 * The per-pixel strategy uses the same bands (so that its pass counts are the wavefront's)
 * and launches each in parts of about 64k pixels. */
int rpass_band_rows(const renderer *r);

/* The kernel launches: eye rays for rows [row0, row0 + nrows) at sample position (sx, sy)
 * into rays[0]; the closest hits of n rays into hits; n shadow rays from shadows into the
 * image. */
int rpass_raygen(renderer *r, int row0, int nrows, float sx, float sy, char *err, size_t errlen);
int rpass_intersect(renderer *r, cl_mem *rays, cl_int n, char *err, size_t errlen);
int rpass_occlude(renderer *r, cl_int n, char *err, size_t errlen);

/* Traces sample number `sample` for rows [row0, row0 + nrows) into the accumulation image,
 * with the program's strategy: the wavefront (ray generation, then per depth level one
 * intersect, one shade and one occlude launch) or per-pixel launches. With `first` the
 * band's pixels start empty, whatever the image held (the first sample needs no clear
 * before it: the per-pixel kernel writes each pixel instead of adding to it, the
 * wavefront, which adds to a pixel from several rays, clears the band's rows first);
 * else the sample is added to them. Progress is reported after each level or launch as
 * done + share * (the band's part done). */
int rpass_trace_band(renderer *r, int sample, int row0, int nrows, int first, double done,
                     double share, char *err, size_t errlen);

#endif
