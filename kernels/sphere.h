/* Spheres (cw_sphere): the ray-sphere test and the surface at a hit. */
#ifndef CW_SPHERE_H
#define CW_SPHERE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Ray-sphere. With f = o - c and unit d the quadratic is t^2 + 2bt + c = 0, b = f.d,
 * c = f.f - R^2. The discriminant b^2 - c is computed as R^2 - |f - b d|^2 (the squared
 * distance from the centre to the line), which does not cancel for far or tiny spheres,
 * and the roots as q = -b - sign(b) sqrt(disc), t = q and c/q, which avoids cancellation
 * too (Haines et al., Ray Tracing Gems, ch. 7). Both paths: the textbook b^2 - c loses
 * the small spheres of the SPD scenes to acne on the fast path, for a saving of 3 flops.
 * disc < 0: no hit; disc = 0: one (tangent) hit; disc > 0: two, nearest valid wins.
 * A negative radius (NFF) makes the sphere visible from inside only: of the two roots only
 * the larger one, where the ray leaves the sphere, is a hit, so a ray from outside passes
 * the near side and meets the inside of the far side. One sign test per ray and sphere,
 * on every ray (shadow rays too), on both paths. */
CW_INLINE int isect_sphere(CW_GLOBAL const cw_sphere *s, vec3 o, vec3 d, float tmin, float tmax,
                           float *t_out)
{
    vec3 c = v3_from4(s->center);
    float r = s->center.w; /* < 0: visible from inside only */
    vec3 f = v3_sub(o, c);
    float b = v3_dot(f, d);
    float cc, t0, t1, tmp;
    vec3 perp = v3_sub(f, v3_scale(d, b));
    float disc = r * r - v3_dot(perp, perp);
    float q;
    if (disc < 0.0f)
        return 0;
    cc = v3_dot(f, f) - r * r;
    q = -b - (b >= 0.0f ? 1.0f : -1.0f) * cw_sqrt(disc);
    if (q == 0.0f) /* ray starts at the centre of a zero-radius sphere */
        return 0;
    t0 = q;
    t1 = cc / q;
    if (t0 > t1) {
        tmp = t0;
        t0 = t1;
        t1 = tmp;
    }
    if (t0 > tmin && t0 < tmax && r > 0.0f) {
        *t_out = t0;
        return 1;
    }
    if (t1 > tmin && t1 < tmax) {
        *t_out = t1;
        return 1;
    }
    return 0;
}

/* The surface at a sphere hit; p = o + t d is projected back onto the sphere. The
 * geometric normal points outwards for an inside-only sphere too (refraction tells a ray
 * entering its inside by it, as for any sphere). */
CW_INLINE cw_surface surface_sphere(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    CW_GLOBAL const cw_sphere *sp = &w->spheres[hit.index];
    vec3 c = v3_from4(sp->center);
    vec3 n = v3_norm(v3_sub(p, c));
    s.ng = n;
#if !CW_FAST
    {
        float r = cw_fabs(sp->center.w);
        p = v3_add(c, v3_scale(n, r));
        /* c is exact input: the error is that of r n (normalisation) and of the sum */
        s.err = v3_add(v3_scale(v3_abs(p), CW_GAMMA(2)),
                       v3_scale(v3(1.0f, 1.0f, 1.0f), CW_GAMMA(6) * r));
    }
#endif
    s.ns = s.ng;
    s.flat = 0;
    s.material = sp->material;
    s.p = p;
    return s;
}

#endif
