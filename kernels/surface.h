/* The surface at a hit, as shading needs it: each primitive header computes it for its
 * kind (surface_sphere ...), prim_surface (prim.h) picks the kind. */
#ifndef CW_SURFACE_H
#define CW_SURFACE_H

#include "flags.h"
#include "vecmath.h"

/* gamma(n) of Higham (n u / (1 - n u), u = 2^-24), doubled: OpenCL allows a few ulps of
 * error in division and sqrt where IEEE rounds correctly. */
#define CW_GAMMA(n) ((float)(n)*1.19209304e-7f)

/* Where a ray hit: the point, its unit geometric normal (as the primitive defines it,
 * not turned to the ray), the unit shading normal, and a bound on the point's
 * absolute error per coordinate (the fast path: 0). The point is recomputed from the
 * primitive where that is more accurate than o + t d (pbrt, 3rd ed., 3.9). */
typedef struct {
    vec3 p, ng, ns, err;
    int flat;     /* 1 + reference of the primitive if it is flat (triangle, polygon), else 0
                   * (the fast path: 0) */
    int inst;     /* 1 + the instance of a mesh triangle (cw_hit.inst); 0: the world's */
    int material; /* index into the material array */
} cw_surface;

#endif
