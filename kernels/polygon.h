/* Planar polygons (cw_polygon, convex or not), with their vertex array and edge bands:
 * the ray-polygon test, the projected vertices the host stores, and the surface at a hit. */
#ifndef CW_POLYGON_H
#define CW_POLYGON_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

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

/* The surface at a polygon hit; p = o + t d is projected back onto the plane. */
CW_INLINE cw_surface surface_polygon(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    CW_GLOBAL const cw_polygon *pg = &w->polygons[hit.index];
    vec3 n = v3_from4(pg->plane);
    s.ng = n;
    s.flat = CW_REF(CW_PRIM_POLYGON, hit.index) + 1;
#if !CW_FAST
    p = v3_sub(p, v3_scale(n, v3_dot(n, p) - pg->plane.w));
    s.err = v3_scale(
        v3_add(v3_abs(p), v3(cw_fabs(pg->plane.w), cw_fabs(pg->plane.w), cw_fabs(pg->plane.w))),
        CW_GAMMA(8));
#endif
    s.ns = s.ng;
    s.material = pg->material;
    s.p = p;
    return s;
}

#endif
