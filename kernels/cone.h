/* Open cones and cylinders (cw_cone): the ray-cone test and the surface at a hit. */
#ifndef CW_CONE_H
#define CW_CONE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Ray-cone for an open cone (or cylinder) around the unit axis a from base b, radius
 * r(h) = r0 + k h for 0 <= h <= H, k = (r1 - r0) / H. With o' = o - b split into its
 * part along the axis (ho) and across it (op), and d likewise (dh, dp), a point is on the
 * surface when |op + t dp|^2 = (r0 + k (ho + t dh))^2:
 *   A t^2 + 2 B t + C = 0, A = dp.dp - k^2 dh^2, B = op.dp - k dh (r0 + k ho),
 *   C = op.op - (r0 + k ho)^2,
 * solved without cancellation like the sphere; the nearest root with 0 <= h <= H and
 * r(h) >= 0 wins. A ray parallel to the side (A = 0) has the one root -C / 2B. */
CW_INLINE int isect_cone(CW_GLOBAL const cw_cone *cn, vec3 o, vec3 d, float tmin, float tmax,
                         float *t_out)
{
    vec3 ax = v3_from4(cn->axis);
    float height = cn->axis.w, r0 = cn->base.w;
    float k = cn->slope;
    vec3 ob;
    /* Solve from the point of the ray nearest the cone's middle: far from the cone the
     * quadratic's terms grow with the distance squared and B^2 - AC cancels (a flat cone
     * seen from a few thousand radii away would vanish; on the fast path too, the thin
     * cylinders of the SPD scenes showed acne without it). The shift is added back to t. */
    vec3 mid = v3_add(v3_from4(cn->base), v3_scale(ax, 0.5f * height));
    float shift = v3_dot(v3_sub(mid, o), d);
    o = v3_add(o, v3_scale(d, shift));
    tmin -= shift;
    tmax -= shift;
    ob = v3_sub(o, v3_from4(cn->base));
    float ho = v3_dot(ob, ax), dh = v3_dot(d, ax);
    vec3 op = v3_sub(ob, v3_scale(ax, ho));
    vec3 dp = v3_sub(d, v3_scale(ax, dh));
    float rr = r0 + k * ho;
    float a = v3_dot(dp, dp) - k * k * dh * dh;
    float bb = v3_dot(op, dp) - k * dh * rr;
    float c = v3_dot(op, op) - rr * rr;
    float roots[2], disc, q, tmp;
    int i, n = 0;

    if (a == 0.0f) {
        if (bb == 0.0f)
            return 0;
        roots[0] = -c / (2.0f * bb);
        n = 1;
    } else {
        disc = bb * bb - a * c;
        if (disc < 0.0f)
            return 0;
        q = -bb - (bb >= 0.0f ? 1.0f : -1.0f) * cw_sqrt(disc);
        if (q == 0.0f)
            return 0;
        roots[0] = q / a;
        roots[1] = c / q;
        if (roots[0] > roots[1]) {
            tmp = roots[0];
            roots[0] = roots[1];
            roots[1] = tmp;
        }
        n = 2;
    }
    for (i = 0; i < n; i++) {
        float t = roots[i], h;
        if (!(t > tmin && t < tmax))
            continue;
        h = ho + t * dh;
        if (h < 0.0f || h > height || r0 + k * h < 0.0f)
            continue;
        t += shift;
        *t_out = t;
        return 1;
    }
    return 0;
}

/* The surface at a cone hit; p = o + t d is projected back onto the side. */
CW_INLINE cw_surface surface_cone(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    CW_GLOBAL const cw_cone *cn = &w->cones[hit.index];
    vec3 ax = v3_from4(cn->axis), b = v3_from4(cn->base);
    float k = cn->slope;
    vec3 pb = v3_sub(p, b);
    float h = cw_fmin(cw_fmax(v3_dot(pb, ax), 0.0f), cn->axis.w);
    vec3 radial = v3_sub(pb, v3_scale(ax, h));
    float rl = v3_len(radial);
    vec3 ru = rl > 0.0f ? v3_scale(radial, 1.0f / rl) : v3(0.0f, 0.0f, 0.0f);
    s.ng = v3_norm(v3_sub(ru, v3_scale(ax, k)));
#if !CW_FAST
    p = v3_add(b, v3_add(v3_scale(ax, h), v3_scale(ru, cn->base.w + k * h)));
    s.err = v3_scale(v3_add(v3_abs(b), v3_abs(p)), CW_GAMMA(8));
#endif
    s.ns = s.ng;
    s.flat = 0;
    s.material = cn->material;
    s.p = p;
    return s;
}

#endif
