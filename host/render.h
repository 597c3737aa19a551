/* The OpenCL renderer: device choice, program build, scene upload, passes (render.c;
 * the test hooks are in render_debug.h). */
#ifndef CW_RENDER_H
#define CW_RENDER_H

#include <stddef.h>

#include "image.h"
#include "scene.h"

typedef struct renderer renderer;

/* Lists every OpenCL platform and device on stdout (--list-devices). Returns 0, or -1
 * with err. */
int renderer_list_devices(char *err, size_t errlen);

/* Opens a device. spec: NULL or "" for the default (the first CPU device, i.e. PoCL),
 * "P:D" for platform P device D (indices as --list-devices prints them), or a substring
 * of the device name. Returns 0, or -1 with err. */
int renderer_create(renderer **out, const char *spec, char *err, size_t errlen);
void renderer_destroy(renderer *r);
const char *renderer_device_name(const renderer *r);
/* The device's compute units (PoCL's CPU device: its threads), or 0 if unknown. */
int renderer_compute_units(const renderer *r);

/* Uploads a finished scene (see scene_finish) and builds the kernels for its features. */
int renderer_set_scene(renderer *r, const scene *s, char *err, size_t errlen);
/* renderer_set_scene, which also empties the scene's primitive arrays (scene_drop_primitives)
 * as soon as it has converted them, before the BVH build: the scene's copy and the
 * renderer's are never held at once (4M triangles: peak 985 -> 745 MB). Also on failure. */
int renderer_set_scene_dropping(renderer *r, scene *s, char *err, size_t errlen);

/* renderer_set_scene_dropping in two halves, so that the first can run while the device
 * starts (the command line does it on the scene's load thread): renderer_prepare_scene
 * needs no renderer: it converts s for the kernels around the camera's eye, empties s's
 * primitive arrays (also on failure) and builds the BVH (on every core). Returns the
 * prepared scene, or NULL with err. renderer_set_prepared then builds the kernels and
 * uploads; s is the scene p was made from (its camera, lights and materials). It frees p,
 * also on failure; renderer_prep_free frees one that is not used. The image is the one
 * renderer_set_scene gives (tests/test_strategy.c). */
typedef struct render_prep render_prep;
render_prep *renderer_prepare_scene(scene *s, char *err, size_t errlen);
int renderer_set_prepared(renderer *r, render_prep *p, const scene *s, char *err, size_t errlen);
void renderer_prep_free(render_prep *p);

/* Whether a width x height render fits: the accumulation image within the device's largest
 * allocation, the device's buffers within its memory, and the host's (with the device's on
 * a device sharing the host's memory) within the memory available now. Call before the
 * work. Returns 0, or -1 with what was asked, what is available and how to reduce it. */
int renderer_check_memory(const renderer *r, int width, int height, char *err, size_t errlen);

/* Quality and mode settings. Set them before renderer_set_scene (they can change the
 * kernel build); changing them later rebuilds on the next render. */
#define RENDER_ROBUST 0 /* watertight, error-bounded intersection and ray offsets */
#define RENDER_FAST 1   /* fast relaxed math and a plain fixed epsilon */
/* Execution strategies: the same image either way (docs/model.md says where an ulp may
 * differ). */
#define RENDER_AUTO 0      /* per device: per pixel on CPU devices, else the wavefront */
#define RENDER_WAVEFRONT 1 /* a kernel launch per ray-tree level, rays queued between them */
#define RENDER_PIXEL 2     /* one work-item traces a pixel sample's whole ray tree */
typedef struct {
    int spp;       /* samples per pixel, >= 1: 1 = the pixel centre, else a deterministic
                    * stratified pattern (a ceil(sqrt(spp)) grid, cells taken in order) */
    int precision; /* RENDER_ROBUST (default) or RENDER_FAST */
    int spd;       /* SPD testing mode: rays through the (nx+1)x(ny+1) pixel corners, the
                    * four corners averaged per pixel (spp is then ignored) */
    int stats;     /* count rays on the device (compiled in only when set) */
    int strategy;  /* RENDER_AUTO (default), RENDER_WAVEFRONT or RENDER_PIXEL */
    int crop[4];   /* x0, x1, y0, y1: renderer_render renders only the pixels x0..x1-1,
                    * y0..y1-1 (row 0 at the top) of the full image, exactly as the full
                    * render gives them, into an (x1-x0) x (y1-y0) image; crop[1] == 0:
                    * the whole image. Checked against the image by renderer_set_scene. */
} render_settings;

void render_settings_default(render_settings *st);
int renderer_set_settings(renderer *r, const render_settings *st, char *err, size_t errlen);

/* The strategy the current settings render with on this device: RENDER_WAVEFRONT or
 * RENDER_PIXEL (never RENDER_AUTO), and its name ("wavefront", "pixel"). */
int renderer_strategy(const renderer *r);
const char *render_strategy_name(int strategy);
/* "auto", "wavefront", "pixel" -> RENDER_*, or -1. */
int render_strategy_parse(const char *name);

/* Checks a crop window against a width x height image. Returns 0, or -1 with err. */
int render_check_crop(const render_settings *st, int width, int height, char *err, size_t errlen);

/* Ray counts (when settings.stats) and times of the last renderer_set_scene and
 * renderer_render, in seconds. */
typedef struct {
    unsigned long long eye_rays, eye_hits;
    unsigned long long shadow_rays, shadow_blocked;
    unsigned long long secondary_rays, secondary_hits;
    /* the BVH walks' work (settings.stats): nodes visited and primitive tests made (one test:
     * up to eight primitives of a leaf) by the closest-hit walks (eye and secondary rays)
     * and by the shadow rays' any-hit walks (shadow cache tests included) */
    unsigned long long closest_nodes, closest_tests, any_nodes, any_tests;
    double build_s;   /* acceleration structure build on the host */
    double compile_s; /* kernel program build (0 when the program was already built) */
    double warmup_s;  /* renderer_render's first launch on one row, before the clock of
                       * trace_s starts: where a driver compiles the kernel for the device
                       * (PoCL does) */
    double upload_s;  /* buffer creation and upload */
    /* what the last renderer_set_scene put on the device: bytes of scene arrays a CPU device
     * uses where the host built them (no copy: render.c, upload_world), and bytes copied
     * (the other arrays, and always the frame, lights and materials) */
    unsigned long long upload_in_place, upload_copied;
    double trace_s; /* last renderer_render */
    int passes;     /* ray-tree levels traced by the last render, summed over its bands
                     * and samples (the wavefront's kernel passes; the same count per pixel) */
    /* the last kernel program build loaded clwhitted's binary cache */
    int program_cached;
    /* with settings.stats only (the host then waits for each kernel): time in each kernel,
     * the wavefront's four or the per-pixel kernel */
    double raygen_s, intersect_s, shade_s, occlude_s, pixel_s;
    /* what the last renderer_set_scene uploaded: primitives (degenerate ones left out;
     * triangles counts a placed mesh's once), instances and the meshes they place, the
     * BVH's nodes (both levels) */
    int spheres, triangles, polygons, cones, instances, meshes, nodes;
} render_stats;

/* The --stats line of the BVH walks' work, from st: per closest-hit ray (eye and secondary)
 * and per shadow ray, the nodes visited and the primitive tests made. */
void render_format_walk(const render_stats *st, char *buf, size_t n);
void renderer_get_stats(const renderer *r, render_stats *st);

/* Progress callback: called during renderer_render after each batch of work with the
 * fraction done (0..1] and the number of rays traced so far (camera, shadow and secondary
 * rays). Returning non-zero cancels the render (renderer_render then fails with
 * "render cancelled"). fn NULL: no callback. */
typedef int (*render_progress_fn)(void *ctx, double fraction, unsigned long long rays);
void renderer_set_progress(renderer *r, render_progress_fn fn, void *ctx);

/* Renders the whole image with the current settings: every sample of every row, then
 * reads it back. img is allocated here (free with image_free). */
int renderer_render(renderer *r, image *img, char *err, size_t errlen);

/* Progressive rendering (the preview window uses these).
 * renderer_set_view takes the camera, image size, maximum depth and background of s (a
 * finished scene with the same geometry as the uploaded one: only those fields are read)
 * and clears the accumulation buffer. Cheap: no upload, no rebuild.
 * renderer_trace adds sample number `sample` (0-based; of the pattern for settings.spp,
 * wrapping around past spp) for image rows [row0, row0 + nrows), row 0 at the top, to the
 * accumulation buffer. It only enqueues work and waits for it: call it with a few rows at a
 * time to stay responsive.
 * renderer_read returns the accumulated image, each pixel divided by the number of
 * samples it received (pixels with none are black). */
int renderer_set_view(renderer *r, const scene *s, char *err, size_t errlen);
int renderer_trace(renderer *r, int sample, int row0, int nrows, char *err, size_t errlen);
int renderer_read(renderer *r, image *img, char *err, size_t errlen);

/* Splitting one render over processes (clwhitted-mpi): each renders bands of rows of the
 * accumulation image, one process puts them together and makes the image. The result is
 * the whole-image render's bit for bit with the per-pixel strategy (each pixel's samples
 * are added in the same order); the wavefront's transmitted light is added atomically,
 * in no fixed order, by every render.
 * renderer_accum_size: the accumulation image's size, the image's (one more each way with
 * settings.spd: the pixel corners).
 * renderer_render_rows: every sample (or the corner rays) of accumulation rows
 * [row0, row0 + nrows), read back into acc as nrows * width * 4 floats (rgb and the sample
 * count per pixel). Ray counts and trace_s add up over calls until
 * renderer_reset_trace_stats (which renderer_render calls).
 * renderer_resolve: the image (allocated here) from a whole accumulation image. */
void renderer_accum_size(const renderer *r, int *width, int *height);
int renderer_render_rows(renderer *r, int row0, int nrows, float *acc, char *err, size_t errlen);
int renderer_resolve(const renderer *r, const float *acc, image *img, char *err, size_t errlen);
void renderer_reset_trace_stats(renderer *r);

#endif
