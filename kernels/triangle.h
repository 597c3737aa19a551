/* Triangles (cw_triangle), flat or smooth (vertex normals): the ray-triangle test and the
 * surface at a hit. */
#ifndef CW_TRIANGLE_H
#define CW_TRIANGLE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

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

/* The surface at a triangle hit: the point from the barycentric coordinates (u, v), the
 * shading normal interpolated from the vertex normals of a smooth triangle. */
CW_INLINE cw_surface surface_triangle(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    CW_GLOBAL const cw_triangle *t = &w->triangles[hit.index];
    vec3 p0 = v3_from4(t->p0), p1 = v3_from4(t->p1), p2 = v3_from4(t->p2);
    float b0 = 1.0f - hit.u - hit.v;
    s.ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    s.flat = CW_REF(CW_PRIM_TRIANGLE, hit.index) + 1;
#if !CW_FAST
    {
        vec3 q0 = v3_scale(p0, b0), q1 = v3_scale(p1, hit.u), q2 = v3_scale(p2, hit.v);
        p = v3_add(q0, v3_add(q1, q2));
        s.err = v3_scale(v3_add(v3_abs(q0), v3_add(v3_abs(q1), v3_abs(q2))), CW_GAMMA(7));
    }
#endif
    if (t->normals >= 0) {
        vec3 sn = v3_add(v3_scale(v3_from4(w->normals[t->normals]), b0),
                         v3_add(v3_scale(v3_from4(w->normals[t->normals + 1]), hit.u),
                                v3_scale(v3_from4(w->normals[t->normals + 2]), hit.v)));
        float len = v3_len(sn);
        s.ns = len > 0.0f ? v3_scale(sn, 1.0f / len) : s.ng;
    } else {
        s.ns = s.ng;
    }
    s.material = t->material;
    s.p = p;
    return s;
}

#endif
