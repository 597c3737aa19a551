/* The preview's interactive camera: orbit, pan, zoom, fly, reset, projection toggle and
 * resize (square pixels), as plain math on scene_camera. Needs no display: the preview
 * (host/preview_input.c) maps input to these calls, tests/test_viewcam.c checks them. */
#ifndef CW_VIEWCAM_H
#define CW_VIEWCAM_H

#include <stddef.h>

#include "scene.h"

typedef struct {
    scene_camera cam; /* the current camera; its window fits width x height */
    int width, height;
    vec3d pivot;   /* the orbit centre (look-at point), at distance `dist` along -w */
    float dist;    /* eye to pivot */
    vec3f up;      /* world up: the orbit axis, always perpendicular to cam.u */
    vec3f dir_cam; /* the oblique ray direction in camera coordinates (u, v, w) */
    float persp_d; /* image-plane distance used when switching to perspective */
    float min_dist;

    /* the scene's camera, for reset */
    scene_camera home;
    int home_width, home_height;
    vec3d home_pivot;
    float home_dist;
    vec3f home_up;
    vec3f home_dir_cam;
} viewcam;

/* Starts from a finished scene's camera and size. The scene has no look-at point (the
 * readers keep only the basis), so the pivot is the point on the view axis nearest the
 * centre of the scene's bounding box (at least 1e-3 of the box size in front of the eye).
 * The "up" vector is lost too (u = up x w keeps only that it lies in the v-w plane), so
 * world up, the orbit axis (scene_camera_world_up), is: of the X, Y, Z axes perpendicular to u, the
 * one nearest v (signed towards it) if within 87 degrees of it, else v itself. A scene whose "up"
 * is an axis thus orbits with a level horizon (unless it looks down more steeply than 45 degrees
 * with u along an axis, where the other axis is nearer v). */
void viewcam_init(viewcam *vc, const scene *s);

/* A new image size: keeps the window's vertical extent and centre, and sets the horizontal
 * extent for square pixels. */
void viewcam_set_size(viewcam *vc, int width, int height);

/* Orbits the eye around the pivot: yaw radians about world up (positive: counter-clockwise
 * seen from above, i.e. the eye moves towards +u), then pitch radians (positive: the eye
 * moves up), the elevation clamped to +-89.5 degrees. The distance is kept; no roll. */
void viewcam_orbit(viewcam *vc, float yaw, float pitch);

/* Pans by a pointer motion of (dx, dy) pixels (x right, y down): the point under the
 * pointer at the pivot's depth follows the pointer. Moves eye and pivot. */
void viewcam_pan(viewcam *vc, float dx, float dy);

/* Zooms by `steps` (positive: closer): perspective moves the eye towards the pivot by a
 * factor 0.85 per step (not closer than min_dist); orthographic and oblique shrink the
 * window about its centre by 0.85 per step. */
void viewcam_zoom(viewcam *vc, float steps);

/* Flies: moves eye and pivot by `forward` along the view (-w), `right` along u and
 * `upward` along world up, in world units. */
void viewcam_fly(viewcam *vc, float forward, float right, float upward);

/* Back to the scene's camera, at the current size. */
void viewcam_reset(viewcam *vc);

/* Switches the projection, keeping the picture's framing at the pivot's depth:
 * perspective <-> parallel scales the window by dist/d; entering oblique shifts the window
 * so that the pivot stays at the same place in the picture (and leaving shifts it back).
 * The oblique direction is the scene's (in camera coordinates) if it was oblique, else
 * (0.3, -0.3, -1) in (u, v, w), normalised. */
void viewcam_set_projection(viewcam *vc, enum scene_projection p);
/* perspective -> orthographic -> oblique -> perspective */
enum scene_projection viewcam_next_projection(enum scene_projection p);
const char *viewcam_projection_name(enum scene_projection p);

/* World units per pixel at the pivot's depth. */
float viewcam_pixel_size(const viewcam *vc);

/* Writes the camera and size into s (camera, width, height; nothing else). */
void viewcam_apply(const viewcam *vc, scene *s);

/* The camera as JSON scene members that the JSON reader accepts:
 * "image": {...}, "max_depth": N, "camera": {...} with an explicit window, inside { }.
 * Returns 0, or -1 if buf is too small. */
int viewcam_to_json(const viewcam *vc, int max_depth, char *buf, size_t n);

#endif
