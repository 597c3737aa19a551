/* Affine transforms in double precision (scene_xform, scene.h): the placements of meshes.
 * Readers build them from translations, rotations, scales or a matrix and compose them;
 * scene_mesh.c applies them to flatten a mesh into world triangles; devscene.c turns an
 * instance's into the kernels' float world-to-mesh transform. All composition is in
 * double precision. */
#ifndef CW_XFORM_H
#define CW_XFORM_H

#include "scene.h"

void xform_identity(scene_xform *x);
void xform_translate(scene_xform *x, double tx, double ty, double tz);
void xform_scale(scene_xform *x, double sx, double sy, double sz);
/* A rotation by deg degrees about the axis (ax, ay, az) through the origin, right-handed
 * (counter-clockwise looking down the axis towards the origin). Returns -1 when the axis
 * is zero or not finite. */
int xform_rotate(scene_xform *x, double ax, double ay, double az, double deg);
/* From a row-major 4x4 matrix m[16] acting on column vectors; the last row must be
 * 0 0 0 1 (no projection). Returns -1 otherwise. */
int xform_from_matrix(scene_xform *x, const double m[16]);

/* out = a after b: out(p) = a(b(p)). out may be a or b. */
void xform_compose(scene_xform *out, const scene_xform *a, const scene_xform *b);
/* The inverse; returns -1 when x is not finite or singular (a determinant of zero, or so
 * small relative to the size of its entries that the inverse is not finite). */
int xform_invert(const scene_xform *x, scene_xform *out);
int xform_is_identity(const scene_xform *x);

vec3d xform_point(const scene_xform *x, vec3d p);
/* The linear part alone (directions). */
void xform_vector(const scene_xform *x, const double v[3], double out[3]);
/* A surface normal: the inverse transpose of the linear part times n, normalised. Returns
 * -1 when the result is zero or x is singular. */
int xform_normal(const scene_xform *x, vec3f n, vec3f *out);
/* The determinant of the linear part (negative: the transform mirrors, so it reverses a
 * triangle's vertex order). */
double xform_det(const scene_xform *x);

#endif
