/* The scene on the device (see render_scene.c): what render.c uses of it. */
#ifndef CW_RENDER_SCENE_H
#define CW_RENDER_SCENE_H

#include "render_impl.h"
#include "scene.h"

/* Releases the scene's device buffers (frame, world arrays, lights, materials). */
void rscene_release(renderer *r);

/* The view part of frame f (camera, window, image size, depth, background, ambient) from
 * s, relative to the local origin. */
void rscene_fill_view(cw_frame *f, const scene *s, vec3d origin);

#endif
