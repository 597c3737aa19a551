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
 * box test; the axis permutation, permuted origin and shear of the watertight triangle
 * test. */
typedef struct {
    vec3 o, d, ninv;  /* ninv = -1 / d, never infinite */
    int kx, ky, kz;   /* the axes that become x, y and z (z: the largest |d| component) */
    float ox, oy, oz; /* the origin's components on those axes */
    float sx, sy, sz;
} cw_rayinfo;

/* x, or +-1e-30 where |x| is smaller: 1 over it is never infinite, and the box test
 * then needs no special case for 0 */
CW_INLINE float isect_safe_den(float x)
{
    return cw_fabs(x) > 1e-30f ? x : cw_copysign(1e-30f, x);
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
    /* two vector divisions for the six quotients, each rounded as a scalar one is */
    ri.ninv = v3_div(v3(-1.0f, -1.0f, -1.0f),
                     v3(isect_safe_den(d.x), isect_safe_den(d.y), isect_safe_den(d.z)));
    ri.ox = ov[ri.kx];
    ri.oy = ov[ri.ky];
    ri.oz = ov[kz];
    {
        vec3 sh = v3_div(v3(dv[ri.kx], dv[ri.ky], 1.0f), v3(dz, dz, dz));
        ri.sx = sh.x;
        ri.sy = sh.y;
        ri.sz = sh.z;
    }
    return ri;
}

#endif
