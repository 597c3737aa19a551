/* isect_: ray-primitive intersection (Shirley & Marschner 4.4) for spheres, triangles,
 * polygons and open cones. Rays have unit directions; a hit counts when tmin < t < tmax.
 *
 * Two builds: the robust path (default) and the fast path (CW_FAST=1, with
 * -cl-fast-relaxed-math): textbook formulas with a plain epsilon. */
#ifndef CW_INTERSECT_H
#define CW_INTERSECT_H

#include "types.h"
#include "world.h"

#ifndef CW_HAS_SPHERES
#define CW_HAS_SPHERES 1
#endif
#ifndef CW_HAS_TRIANGLES
#define CW_HAS_TRIANGLES 1
#endif
#ifndef CW_HAS_POLYGONS
#define CW_HAS_POLYGONS 1
#endif
#ifndef CW_HAS_CONES
#define CW_HAS_CONES 1
#endif
#ifndef CW_FAST
#define CW_FAST 0
#endif

/* Finite stand-ins for infinity: the fast path is built with -cl-fast-relaxed-math,
 * which lets the compiler assume no value is infinite. */
#define CW_FAR 1e30f /* tmax of camera and secondary rays */

/* A ray with what the tests need precomputed once: the inverse direction for the box
 * test, and the axis permutation and shear of the watertight triangle test. */
typedef struct {
    vec3 o, d, inv;
    int kx, ky, kz;
    float sx, sy, sz;
} cw_rayinfo;

CW_INLINE float isect_axis(vec3 v, int k)
{
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

CW_INLINE float isect_safe_inv(float x)
{
    /* 1/x, but never infinite: the box test then needs no special case for 0 */
    return 1.0f / (cw_fabs(x) > 1e-30f ? x : cw_copysign(1e-30f, x));
}

CW_INLINE cw_rayinfo isect_rayinfo(vec3 o, vec3 d)
{
    cw_rayinfo ri;
    float ax = cw_fabs(d.x), ay = cw_fabs(d.y), az = cw_fabs(d.z), dz;
    int tmp;
    ri.o = o;
    ri.d = d;
    ri.inv = v3(isect_safe_inv(d.x), isect_safe_inv(d.y), isect_safe_inv(d.z));
    ri.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    ri.kx = ri.kz == 2 ? 0 : ri.kz + 1;
    ri.ky = ri.kx == 2 ? 0 : ri.kx + 1;
    dz = isect_axis(d, ri.kz);
    if (dz < 0.0f) { /* keep the winding */
        tmp = ri.kx;
        ri.kx = ri.ky;
        ri.ky = tmp;
    }
    ri.sx = isect_axis(d, ri.kx) / dz;
    ri.sy = isect_axis(d, ri.ky) / dz;
    ri.sz = 1.0f / dz;
    return ri;
}

/* Ray-sphere. With f = o - c and unit d the quadratic is t^2 + 2bt + c = 0, b = f.d,
 * c = f.f - R^2.
 * Robust: the discriminant b^2 - c is computed as R^2 - |f - b d|^2 (the squared distance
 * from the centre to the line), which does not cancel for far or tiny spheres, and the
 * roots as q = -b - sign(b) sqrt(disc), t = q and c/q, which avoids cancellation too.
 * Fast: the textbook b^2 - c and (-b -+ sqrt(disc)).
 * disc < 0: no hit; disc = 0: one (tangent) hit; disc > 0: two, nearest valid wins. */
CW_INLINE int isect_sphere(CW_GLOBAL const cw_sphere *s, vec3 o, vec3 d, float tmin, float tmax,
                           float *t_out)
{
    vec3 c = v3_from4(s->center);
    float r = s->center.w;
    vec3 f = v3_sub(o, c);
    float b = v3_dot(f, d);
    float cc, t0, t1, tmp;
#if CW_FAST
    float disc = b * b - (v3_dot(f, f) - r * r), sq;
    if (disc < 0.0f)
        return 0;
    sq = cw_sqrt(disc);
    t0 = -b - sq;
    t1 = -b + sq;
    (void)cc;
    (void)tmp;
#else
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
#endif
    if (t0 > tmin && t0 < tmax) {
        *t_out = t0;
        return 1;
    }
    if (t1 > tmin && t1 < tmax) {
        *t_out = t1;
        return 1;
    }
    return 0;
}

#if CW_FAST
/* Ray-triangle, fast path: Moeller-Trumbore with a plain determinant epsilon. */
CW_INLINE int isect_triangle(CW_GLOBAL const cw_triangle *tri, const cw_rayinfo *ri, float tmin,
                             float tmax, float *t_out, float *u_out, float *v_out)
{
    vec3 p0 = v3_from4(tri->p0);
    vec3 e1 = v3_sub(v3_from4(tri->p1), p0);
    vec3 e2 = v3_sub(v3_from4(tri->p2), p0);
    vec3 pvec = v3_cross(ri->d, e2);
    float det = v3_dot(e1, pvec);
    float inv, u, v, t;
    vec3 s, qvec;

    if (cw_fabs(det) < 1e-9f)
        return 0;
    inv = 1.0f / det;
    s = v3_sub(ri->o, p0);
    u = v3_dot(s, pvec) * inv;
    if (u < 0.0f || u > 1.0f)
        return 0;
    qvec = v3_cross(s, e1);
    v = v3_dot(ri->d, qvec) * inv;
    if (v < 0.0f || u + v > 1.0f)
        return 0;
    t = v3_dot(e2, qvec) * inv;
    if (!(t > tmin && t < tmax))
        return 0;
    *t_out = t;
    *u_out = u;
    *v_out = v;
    return 1;
}
#else
/* Ray-triangle, robust path: the watertight test of Woop, Benthin and Wald (JCGT 2013).
 * The vertices are moved to the ray origin, permuted so that the ray's largest direction
 * component is z, and sheared so that the ray becomes the +z axis; the 2-D edge
 * functions U, V, W then decide inside/outside. A point on a shared edge gets the same
 * edge function value (negated) from both triangles, so a ray never passes between
 * them; zero counts as inside for both. No determinant epsilon: only an exactly
 * degenerate projection (det = 0: a degenerate triangle or a ray in its plane) misses.
 * (u, v): the barycentric weights of p1 and p2. */
CW_INLINE int isect_triangle(CW_GLOBAL const cw_triangle *tri, const cw_rayinfo *ri, float tmin,
                             float tmax, float *t_out, float *u_out, float *v_out)
{
    vec3 a = v3_sub(v3_from4(tri->p0), ri->o);
    vec3 b = v3_sub(v3_from4(tri->p1), ri->o);
    vec3 c = v3_sub(v3_from4(tri->p2), ri->o);
    float az = isect_axis(a, ri->kz), bz = isect_axis(b, ri->kz), cz = isect_axis(c, ri->kz);
    float ax = isect_axis(a, ri->kx) - ri->sx * az;
    float ay = isect_axis(a, ri->ky) - ri->sy * az;
    float bx = isect_axis(b, ri->kx) - ri->sx * bz;
    float by = isect_axis(b, ri->ky) - ri->sy * bz;
    float cx = isect_axis(c, ri->kx) - ri->sx * cz;
    float cy = isect_axis(c, ri->ky) - ri->sy * cz;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    float det, tt, inv;

    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return 0;
    det = u + v + w;
    if (det == 0.0f)
        return 0;
    tt = u * (ri->sz * az) + v * (ri->sz * bz) + w * (ri->sz * cz);
    inv = 1.0f / det;
    tt *= inv;
    if (!(tt > tmin && tt < tmax))
        return 0;
    *t_out = tt;
    *u_out = v * inv;
    *v_out = w * inv;
    return 1;
}
#endif

/* 2-D coordinates of p with the polygon's dominant axis dropped. */
CW_INLINE void isect_project(vec3 p, int axis, float *a, float *b)
{
    if (axis == 0) {
        *a = p.y;
        *b = p.z;
    } else if (axis == 1) {
        *a = p.z;
        *b = p.x;
    } else {
        *a = p.x;
        *b = p.y;
    }
}

/* A polygon vertex as the kernels store it: its 2-D coordinates in the polygon's plane
 * projected along the dominant normal axis (that axis dropped), in x and y. The host
 * stores them so; the intersection test then needs no projection per edge. */
CW_INLINE cw_float4 isect_polygon_vertex(vec3 p, int axis)
{
    float a, b;
    cw_float4 r;
    isect_project(p, axis, &a, &b);
    r.x = a;
    r.y = b;
    r.z = 0.0f;
    r.w = 0.0f;
    return r;
}

/* Ray-polygon (4.4.3): hit the plane, then the even-odd crossing test in the plane
 * projected along the dominant normal axis, which is right for non-convex polygons.
 * verts: projected vertices (isect_polygon_vertex). */
CW_INLINE int isect_polygon(CW_GLOBAL const cw_polygon *pg, CW_GLOBAL const cw_float4 *verts,
                            CW_GLOBAL const int *bands, vec3 o, vec3 d, float tmin, float tmax,
                            float *t_out)
{
    vec3 n = v3_from4(pg->plane);
    float dn = v3_dot(n, d);
    float t, pa, pb, ax, ay;
    int inside = 0, k, first = pg->first, count = pg->count;

    if (dn == 0.0f)
        return 0;
    t = (pg->plane.w - v3_dot(n, o)) / dn;
    if (!(t > tmin && t < tmax))
        return 0;
    isect_project(v3_add(o, v3_scale(d, t)), pg->axis, &pa, &pb);
    if (pg->band_count > 0) {
        /* only the edges of the point's band can cross its horizontal line */
        int b = (int)((pb - pg->band_lo) * pg->band_scale), m, e0, e1;
        if (!(b >= 0 && b < pg->band_count))
            return 0;
        e0 = bands[pg->band_first + 2 * b];
        e1 = e0 + bands[pg->band_first + 2 * b + 1];
        for (m = e0; m < e1; m++) {
            int kb = bands[m], ka = kb == first ? first + count - 1 : kb - 1;
            float bx = verts[kb].x, by = verts[kb].y;
            ax = verts[ka].x;
            ay = verts[ka].y;
            if ((ay > pb) != (by > pb)) {
                float lhs = (pa - ax) * (by - ay), rhs = (pb - ay) * (bx - ax);
                if (by > ay ? lhs < rhs : lhs > rhs)
                    inside = !inside;
            }
        }
    } else {
        ax = verts[first + count - 1].x;
        ay = verts[first + count - 1].y;
        for (k = first; k < first + count; k++) {
            float bx = verts[k].x, by = verts[k].y;
            /* edge (a, b) crosses the horizontal line through the point, right of it:
             * pa < ax + (pb - ay)(bx - ax)/(by - ay), without the division */
            if ((ay > pb) != (by > pb)) {
                float lhs = (pa - ax) * (by - ay), rhs = (pb - ay) * (bx - ax);
                if (by > ay ? lhs < rhs : lhs > rhs)
                    inside = !inside;
            }
            ax = bx;
            ay = by;
        }
    }
    if (!inside)
        return 0;
    *t_out = t;
    return 1;
}

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
#if !CW_FAST
    /* Solve from the point of the ray nearest the cone's middle: far from the cone the
     * quadratic's terms grow with the distance squared and B^2 - AC cancels (a flat cone
     * seen from a few thousand radii away would vanish). The shift is added back to t. */
    vec3 mid = v3_add(v3_from4(cn->base), v3_scale(ax, 0.5f * height));
    float shift = v3_dot(v3_sub(mid, o), d);
    o = v3_add(o, v3_scale(d, shift));
    tmin -= shift;
    tmax -= shift;
#endif
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
#if !CW_FAST
        t += shift;
#endif
        *t_out = t;
        return 1;
    }
    return 0;
}

#endif
