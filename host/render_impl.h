/* The renderer's insides (struct renderer), for render.c, render_scene.c, render_pass.c,
 * render_rows.c and render_debug.c only: everything else sees the opaque type of render.h. */
#ifndef CW_RENDER_IMPL_H
#define CW_RENDER_IMPL_H

#include <stddef.h>

#include <CL/cl.h>

#include "cl_program.h"
#include "render.h"
#include "types.h"
#include "world.h"

/* The scene's device buffers that every kernel taking the world gets as its first
 * CW_WORLD_NARGS arguments: the frame, then one per CW_WORLD_BUFFERS line (generated). */
typedef struct {
    cl_mem frame;
#define RENDER_WORLD_FIELD(type, name, what) cl_mem name;
    CW_WORLD_BUFFERS(RENDER_WORLD_FIELD)
#undef RENDER_WORLD_FIELD
} render_world;

struct renderer {
    cl_device_id device;
    char device_name[256];
    cl_context ctx;
    cl_command_queue queue;
    cl_ulong max_alloc; /* CL_DEVICE_MAX_MEM_ALLOC_SIZE */
    int cpu;            /* CL_DEVICE_TYPE_CPU: RENDER_AUTO picks the per-pixel kernel */
    int units;          /* CL_DEVICE_MAX_COMPUTE_UNITS, 0 if unknown */
    cl_program program;
    char options[1024]; /* build options of `program` */
    int strategy;       /* of `program`: RENDER_WAVEFRONT (the four wavefront kernels) or
                         * RENDER_PIXEL (k_pixel) */
    cl_kernel k_raygen, k_intersect, k_shade, k_occlude, k_pixel;
    /* scene buffers: the world, and the lights and materials of the shading kernel */
    render_world world;
    cl_mem lights, materials;
    int have_scene;
    cw_frame host_frame;
    /* the local origin of the uploaded scene (its camera's eye then): the kernels see every
     * position, the eye of each later view included, relative to it; world_origin (a test
     * hook) keeps it at 0, the plain float conversion of world coordinates */
    vec3d origin;
    int world_origin;
    /* the pieces big scene arrays are uploaded in (0: CW_UPLOAD_PIECE; a test hook) */
    size_t upload_piece;
    clprog_features features;
    /* work buffers, grown on demand: two ray queues (this level's, the next), hits,
     * shadow rays, the accumulation image (rgb + sample count per pixel), counters */
    cl_mem rays[2], hits, shadows, image, counters;
    size_t ray_cap[2], hit_cap, shadow_cap, image_cap;
    /* settings, stats, progress */
    render_settings settings;
    render_stats stats;
    render_progress_fn progress;
    void *progress_ctx;
};

/* Builds the program for the scene's features, the current settings and the given
 * strategy (RENDER_WAVEFRONT or RENDER_PIXEL), unless built (render.c): renders ask for
 * renderer_strategy(r), the test hooks for the wavefront. Returns 0, or -1 with err. */
int renderer_ensure_program(renderer *r, int strategy, char *err, size_t errlen);

#endif
