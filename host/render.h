/* The OpenCL renderer: device choice, program build, scene upload, passes. */
#ifndef CW_RENDER_H
#define CW_RENDER_H

#include <stddef.h>

#include "image.h"
#include "scene.h"
#include "types.h"

typedef struct renderer renderer;

/* Lists every OpenCL platform and device on stdout. Returns 0, or -1 with err. */
int renderer_list_devices(char *err, size_t errlen);

/* Opens a device. spec: NULL or "" for the default (the first CPU device, i.e. PoCL),
 * "P:D" for platform P device D (indices as --list-devices prints them), or a substring
 * of the device name. Returns 0, or -1 with err. */
int renderer_create(renderer **out, const char *spec, char *err, size_t errlen);
void renderer_destroy(renderer *r);
const char *renderer_device_name(const renderer *r);

/* Uploads a finished scene (see scene_finish) and builds the kernels for its features. */
int renderer_set_scene(renderer *r, const scene *s, char *err, size_t errlen);

/* Renders the whole image: ray generation, then per depth one intersection and one
 * shading pass. img is allocated here (free with image_free). */
int renderer_render(renderer *r, image *img, char *err, size_t errlen);

/* For tests: runs the ray-generation kernel and returns nx*ny rays (rays must hold that
 * many), and runs the intersection kernel on the given rays. */
int renderer_generate_rays(renderer *r, cw_ray *rays, char *err, size_t errlen);
int renderer_intersect(renderer *r, const cw_ray *rays, int n, cw_hit *hits, char *err,
                       size_t errlen);

#endif
