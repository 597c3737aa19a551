/* The renderer's test hooks: single kernels run on given rays, and the build options. The
 * test suites use them; the clwhitted binary does not link them (render_debug.c). */
#ifndef CW_RENDER_DEBUG_H
#define CW_RENDER_DEBUG_H

#include <stddef.h>

#include "render.h"
#include "types.h"

/* Runs the ray-generation kernel and returns nx*ny rays (rays must hold that many). */
int renderer_generate_rays(renderer *r, cw_ray *rays, char *err, size_t errlen);

/* Runs the intersection kernel (closest hit over the BVH) on the given rays; a ray's skip
 * field (1 + a primitive reference, 0 for none) must be set. */
int renderer_intersect(renderer *r, const cw_ray *rays, int n, cw_hit *hits, char *err,
                       size_t errlen);

/* Runs the shadow-ray (any hit) kernel on n shadow rays (origin.w = tmax) and sets
 * blocked[i] to 1 when something lies on ray i, else 0. */
int renderer_occluded(renderer *r, const cw_shadow_ray *rays, int n, int *blocked, char *err,
                      size_t errlen);

/* on = 1: the scenes uploaded from now on keep 0 as their local origin, so that the
 * kernels see plain float world coordinates (as before the local origin): for the test
 * that shows what the local origin is for, and for the suites that trace rays given in
 * world coordinates through the hooks above. on = 0: the camera's eye (the default). */
void renderer_debug_world_origin(renderer *r, int on);

/* The scenes uploaded from now on: every array of more than `bytes` bytes is written in
 * pieces of that many, each given back once uploaded (0: CW_UPLOAD_PIECE, the default). */
void renderer_debug_upload_piece(renderer *r, size_t bytes);

/* The build options of the kernel program built last ("" before any build). */
const char *renderer_build_options(const renderer *r);

#endif
