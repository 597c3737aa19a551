/* Geometry on the scene model that the readers, the scene checks, the POV-Ray exporter and
 * the renderer share: vec3f arithmetic, Newell's normal, the plane of a polygon, the one
 * zero-area rule for polygons, the degeneracy test for triangles and the camera basis. */
#ifndef CW_SCENE_GEOM_H
#define CW_SCENE_GEOM_H

#include "scene.h"

vec3f vec3f_make(float x, float y, float z);
vec3f vec3f_sub(vec3f a, vec3f b);
vec3f vec3f_cross(vec3f a, vec3f b);
float vec3f_dot(vec3f a, vec3f b);
float vec3f_length(vec3f a);
/* Returns 0 and the unit vector, or -1 when a is zero or not finite. */
int vec3f_normalize(vec3f a, vec3f *out);

/* Positions (double precision): a + s * d, a - b, and the float vector a - b (the
 * direction between two positions, or a position relative to a local origin). */
vec3d vec3d_make(double x, double y, double z);
vec3d vec3d_add_scaled(vec3d a, vec3f d, double s);
vec3d vec3d_sub(vec3d a, vec3d b);
vec3f vec3d_diff(vec3d a, vec3d b);

/* Newell's normal of a polygon, not normalised: its length is twice the area. The
 * vertices are taken relative to origin (NULL: the world's). */
void scene_newell(const vec3d *v, int n, const vec3d *origin, double out[3]);

/* The plane the renderer uses for a polygon: the unit Newell normal, the mean offset
 * n.x = offset of the vertices, and the dominant axis of the normal (dropped for the 2-D
 * inside test), in coordinates relative to origin (NULL: world coordinates). Returns 0, or
 * -1 when the normal is zero or not finite. */
int scene_polygon_plane(const vec3d *v, int n, const vec3d *origin, double normal[3],
                        double *offset, int *axis);

/* The zero-area rule for polygons (both readers reject such a polygon): a polygon has no
 * area when the length of its Newell normal (twice its area) is not above 1e-12 times the
 * square of its bounding-box diagonal, or is not finite: collinear or coincident vertices,
 * relative to the polygon's size, so that the units of the scene do not matter.
 * scene_area accumulates a polygon vertex by vertex, for a reader that does not keep the
 * vertices together; the sums are those of scene_newell. */
typedef struct {
    double normal[3];    /* Newell's normal of the vertices so far */
    double len;          /* |normal|, set by scene_area_zero */
    double lo[3], hi[3]; /* bounding box of the vertices */
    vec3d first, prev;
    long count; /* vertices added */
} scene_area;

void scene_area_init(scene_area *a);
void scene_area_add(scene_area *a, vec3d v);
/* Closes the polygon (the edge from the last vertex to the first) and applies the rule:
 * 1 when it has no area, else 0. Call it once, after the last vertex. */
int scene_area_zero(scene_area *a);
/* The diagonal of the bounding box. */
double scene_area_size(const scene_area *a);
/* The rule for the n vertices at v. */
int scene_polygon_zero_area(const vec3d *v, int n);

/* 1 when the triangle with the float vertices p (as the kernels get them) has no area in
 * float arithmetic: the cross product of its edges, as the kernels compute it, is exactly
 * zero (coincident or collinear vertices). Such a triangle has no normal and is left out
 * of rendering. */
int scene_triangle_degenerate(const vec3f p[3]);

/* Builds u, v, w from a view direction (eye towards look-at) and an up vector, as in
 * Shirley & Marschner: w = -view/|view|, u = up x w / |up x w|, v = w x u.
 * Returns -1 when the view is zero or up is parallel to it. */
int scene_camera_basis(scene_camera *c, vec3f view, vec3f up);

/* The world's up as far as a camera basis tells it (the readers keep no "up" vector,
 * only that it lies in the v-w plane): of the X, Y, Z axes perpendicular to u, the one
 * nearest v (signed towards it) if within 87 degrees of it, else v itself. The preview
 * orbits about it; --look-from and --look-at without --up keep it. */
vec3f scene_camera_world_up(const scene_camera *c);

#endif
