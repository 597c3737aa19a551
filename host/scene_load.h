/* Loading a scene file with the reader its extension names: the one place that knows
 * every reader (scene_nff.h, scene_json.h). */
#ifndef CW_SCENE_LOAD_H
#define CW_SCENE_LOAD_H

#include <stddef.h>

#include "scene.h"

/* Loads a scene, choosing the reader by extension (.nff, .json, in any case). Returns 0,
 * or -1 with "file:line: message" in err. */
int scene_load(const char *path, scene *s, char *err, size_t errlen);

/* Reads a camera file (--camera, json_camera_load) into a loaded scene s. Returns 0, or -1
 * with "file:line: message" in err. */
int scene_load_camera(const char *path, scene *s, char *err, size_t errlen);

#endif
