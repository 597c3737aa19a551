/* Loading a scene file with the reader its extension names: the one place that knows
 * every reader (scene_nff.h, scene_json.h); and the command line's changes to its camera
 * (a camera file, --look-from and the like). */
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

/* The camera changes of the command line (--look-from, --look-at, --up, --fov), and
 * --flatten. */
typedef struct {
    int has_eye, has_at, has_up, has_fov; /* which were given */
    vec3d eye, at;                        /* the eye and the point it looks at */
    vec3f up;                             /* not zero */
    double fov_deg;                       /* the vertical field of view, 0 < fov < 180 */
    int flatten; /* every placed mesh copied into world triangles (no instances) */
} scene_view;

/* Applies v to a loaded scene's camera (before scene_finish): the eye moves to v->eye;
 * it looks at v->at, or along the scene's view direction when no point is given; up is
 * v->up, or the scene's world up (scene_camera_world_up); a field of view makes the window
 * follow from it and the final image size, as a JSON "fov" (perspective cameras only).
 * Returns 0, or -1 with the reason (the look-at point at the eye, up parallel to the
 * view, a field of view for another projection) in err. */
int scene_apply_view(scene *s, const scene_view *v, char *err, size_t errlen);

/* What clwhitted and clwhitted-mpi do with a scene file: scene_load, then the camera file
 * (camera_file; NULL: none), then the view (NULL: none; with view->flatten, every instance
 * flattened), then scene_finish at the given size and depth (0: the scene's own). Returns
 * 0, or -1 with err. */
int scene_load_for_render(const char *path, const char *camera_file, const scene_view *view,
                          int width, int height, int depth, scene *s, char *err, size_t errlen);

#endif
