/* isect_: what every ray-primitive test shares (Shirley & Marschner 4.4). Rays have unit
 * directions; a hit counts when tmin < t < tmax. cw_rayinfo holds what the tests need
 * precomputed once per ray. The tests themselves are in the primitive headers (sphere.h,
 * triangle.h, polygon.h, cone.h); prim.h dispatches over the kinds.
 *
 * Two builds: the robust path (default) and the fast path (CW_FAST=1, with
 * -cl-fast-relaxed-math): textbook formulas with a plain epsilon. */
#ifndef CW_ISECT_H
#define CW_ISECT_H

#include "flags.h"
#include "types.h"
#include "vecmath.h"

/* Finite stand-ins for infinity: the fast path is built with -cl-fast-relaxed-math,
 * which lets the compiler assume no value is infinite. */
#define CW_FAR 1e30f /* tmax of camera and secondary rays */

/* A ray with what the tests need precomputed once: the negated inverse direction for the
 * box test, and the axis permutation, permuted origin and shear of the watertight triangle
 * test. */
typedef struct {
    vec3 o, d, ninv;  /* ninv = -1 / d, never infinite */
    int kx, ky, kz;   /* the axes that become x, y and z (z: the largest |d| component) */
    float ox, oy, oz; /* the origin's components on those axes */
    float sx, sy, sz;
} cw_rayinfo;

CW_INLINE float isect_safe_inv(float x)
{
    /* 1/x, but never infinite: the box test then needs no special case for 0 */
    return 1.0f / (cw_fabs(x) > 1e-30f ? x : cw_copysign(1e-30f, x));
}

/* The axes are picked by selects and the components read from small arrays, without a
 * branch: a ray's direction is as good as random to a branch predictor. */
CW_INLINE cw_rayinfo isect_rayinfo(vec3 o, vec3 d)
{
    cw_rayinfo ri;
    float ax = cw_fabs(d.x), ay = cw_fabs(d.y), az = cw_fabs(d.z), dz;
    float dv[3] = {d.x, d.y, d.z}, ov[3] = {o.x, o.y, o.z};
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1, flip;
    dz = dv[kz];
    flip = dz < 0.0f; /* keep the winding: swap x and y */
    ri.kx = flip ? ky : kx;
    ri.ky = flip ? kx : ky;
    ri.kz = kz;
    ri.o = o;
    ri.d = d;
    ri.ninv = v3(-isect_safe_inv(d.x), -isect_safe_inv(d.y), -isect_safe_inv(d.z));
    ri.ox = ov[ri.kx];
    ri.oy = ov[ri.ky];
    ri.oz = ov[kz];
    ri.sx = dv[ri.kx] / dz;
    ri.sy = dv[ri.ky] / dz;
    ri.sz = 1.0f / dz;
    return ri;
}

#endif
