/* isect_: ray-primitive intersection (Shirley & Marschner 4.4) and the closest and any
 * hit over the whole group. Rays have unit directions; a hit counts when
 * tmin < t < tmax. */
#ifndef CW_INTERSECT_H
#define CW_INTERSECT_H

#include "types.h"

#ifndef CW_HAS_SPHERES
#define CW_HAS_SPHERES 1
#endif
#ifndef CW_HAS_TRIANGLES
#define CW_HAS_TRIANGLES 1
#endif
#ifndef CW_HAS_POLYGONS
#define CW_HAS_POLYGONS 1
#endif

/* The primitive arrays of a scene. */
typedef struct {
    CW_GLOBAL const cw_sphere *spheres;
    CW_GLOBAL const cw_triangle *triangles;
    CW_GLOBAL const cw_polygon *polygons;
    CW_GLOBAL const cw_float4 *poly_verts;
    int num_spheres, num_triangles, num_polygons;
} cw_world;

/* Ray-sphere. With f = o - c and unit d the quadratic is t^2 + 2bt + c = 0, b = f.d,
 * c = f.f - R^2. Its discriminant b^2 - c is computed as R^2 - |f - b d|^2 (the squared
 * distance from the centre to the line), which does not cancel for far spheres, and the
 * roots as q = -b - sign(b) sqrt(disc), t = q and c/q, which avoids cancellation too.
 * disc < 0: no hit; disc = 0: one (tangent) hit; disc > 0: two, nearest valid wins. */
CW_INLINE int isect_sphere(CW_GLOBAL const cw_sphere *s, vec3 o, vec3 d, float tmin, float tmax,
                           float *t_out)
{
    vec3 c = v3_from4(s->center);
    float r = s->center.w;
    vec3 f = v3_sub(o, c);
    float b = v3_dot(f, d);
    vec3 perp = v3_sub(f, v3_scale(d, b));
    float disc = r * r - v3_dot(perp, perp);
    float cc, q, t0, t1, tmp;

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

/* Ray-triangle with barycentric coordinates (Moeller-Trumbore form of the Cramer's rule
 * solution in 4.4.2): p = p0 + u (p1 - p0) + v (p2 - p0), hit when u >= 0, v >= 0,
 * u + v <= 1. A ray parallel to the plane (|d.n| below 1e-7 |n|, a relative bound: no
 * triangle is dropped for being small) gives no hit. */
CW_INLINE int isect_triangle(CW_GLOBAL const cw_triangle *tri, vec3 o, vec3 d, float tmin,
                             float tmax, float *t_out, float *u_out, float *v_out)
{
    vec3 p0 = v3_from4(tri->p0);
    vec3 e1 = v3_sub(v3_from4(tri->p1), p0);
    vec3 e2 = v3_sub(v3_from4(tri->p2), p0);
    vec3 pvec = v3_cross(d, e2);
    float det = v3_dot(e1, pvec);
    vec3 n = v3_cross(e1, e2);
    float inv, u, v, t;
    vec3 s, qvec;

    if (!(det * det > 1e-14f * v3_dot(n, n)))
        return 0;
    inv = 1.0f / det;
    s = v3_sub(o, p0);
    u = v3_dot(s, pvec) * inv;
    if (u < 0.0f || u > 1.0f)
        return 0;
    qvec = v3_cross(s, e1);
    v = v3_dot(d, qvec) * inv;
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

/* Ray-polygon (4.4.3): hit the plane, then the even-odd crossing test in the plane
 * projected along the dominant normal axis, which is right for non-convex polygons. */
CW_INLINE int isect_polygon(CW_GLOBAL const cw_polygon *pg, CW_GLOBAL const cw_float4 *verts,
                            vec3 o, vec3 d, float tmin, float tmax, float *t_out)
{
    vec3 n = v3_from4(pg->plane);
    float dn = v3_dot(n, d);
    float t, pa, pb, ax, ay, bx, by;
    int inside = 0, k, first = pg->first, count = pg->count;

    if (!(cw_fabs(dn) > 1e-7f))
        return 0;
    t = (pg->plane.w - v3_dot(n, o)) / dn;
    if (!(t > tmin && t < tmax))
        return 0;
    isect_project(v3_add(o, v3_scale(d, t)), pg->axis, &pa, &pb);
    isect_project(v3_from4(verts[first + count - 1]), pg->axis, &ax, &ay);
    for (k = 0; k < count; k++) {
        isect_project(v3_from4(verts[first + k]), pg->axis, &bx, &by);
        /* edge (a, b) crosses the horizontal line through the point, right of it */
        if ((ay > pb) != (by > pb)) {
            float x = ax + (pb - ay) * (bx - ax) / (by - ay);
            if (pa < x)
                inside = !inside;
        }
        ax = bx;
        ay = by;
    }
    if (!inside)
        return 0;
    *t_out = t;
    return 1;
}

/* Closest hit over the whole group (linear search). */
CW_INLINE cw_hit isect_closest(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax)
{
    cw_hit hit;
    float t, u, v;
    int k;

    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.kind = CW_PRIM_NONE;
    hit.index = -1;
    hit.pad0 = hit.pad1 = hit.pad2 = 0;
#if CW_HAS_SPHERES
    for (k = 0; k < w->num_spheres; k++) {
        if (isect_sphere(&w->spheres[k], o, d, tmin, hit.t, &t)) {
            hit.t = t;
            hit.kind = CW_PRIM_SPHERE;
            hit.index = k;
        }
    }
#endif
#if CW_HAS_TRIANGLES
    for (k = 0; k < w->num_triangles; k++) {
        if (isect_triangle(&w->triangles[k], o, d, tmin, hit.t, &t, &u, &v)) {
            hit.t = t;
            hit.u = u;
            hit.v = v;
            hit.kind = CW_PRIM_TRIANGLE;
            hit.index = k;
        }
    }
#endif
#if CW_HAS_POLYGONS
    for (k = 0; k < w->num_polygons; k++) {
        if (isect_polygon(&w->polygons[k], w->poly_verts, o, d, tmin, hit.t, &t)) {
            hit.t = t;
            hit.kind = CW_PRIM_POLYGON;
            hit.index = k;
        }
    }
#endif
    (void)u;
    (void)v;
    return hit;
}

/* Any hit in (tmin, tmax): for shadow rays, stops at the first blocker. */
CW_INLINE int isect_any(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax)
{
    float t, u, v;
    int k;
#if CW_HAS_SPHERES
    for (k = 0; k < w->num_spheres; k++)
        if (isect_sphere(&w->spheres[k], o, d, tmin, tmax, &t))
            return 1;
#endif
#if CW_HAS_TRIANGLES
    for (k = 0; k < w->num_triangles; k++)
        if (isect_triangle(&w->triangles[k], o, d, tmin, tmax, &t, &u, &v))
            return 1;
#endif
#if CW_HAS_POLYGONS
    for (k = 0; k < w->num_polygons; k++)
        if (isect_polygon(&w->polygons[k], w->poly_verts, o, d, tmin, tmax, &t))
            return 1;
#endif
    (void)t;
    (void)u;
    (void)v;
    (void)k;
    return 0;
}

#endif
