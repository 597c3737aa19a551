/* inst_: placed meshes (cw_instance), the second level of the BVH. A ray reaches a mesh's
 * own tree (traverse.h) through its instance's world-to-mesh transform, keeping its ray
 * parameter t (the direction is transformed, not normalised), so hits in the mesh compare
 * with hits in the world as they are. A hit's surface is the triangle's (triangle.h) in
 * mesh coordinates, carried to the world: the point by to_world, the normals by the
 * transpose of to_mesh's linear part (the inverse transpose of to_world's). */
#ifndef CW_INSTANCE_H
#define CW_INSTANCE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "triangle.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

#if CW_HAS_INSTANCES

/* The affine map of rows m[0..2] (xyz linear, w translation) applied to the point p. */
CW_INLINE vec3 inst_point(CW_GLOBAL const cw_float4 *m, vec3 p)
{
    return v3(v3_dot(v3_from4(m[0]), p) + m[0].w, v3_dot(v3_from4(m[1]), p) + m[1].w,
              v3_dot(v3_from4(m[2]), p) + m[2].w);
}

/* Its linear part alone, applied to the direction v. */
CW_INLINE vec3 inst_vector(CW_GLOBAL const cw_float4 *m, vec3 v)
{
    return v3(v3_dot(v3_from4(m[0]), v), v3_dot(v3_from4(m[1]), v), v3_dot(v3_from4(m[2]), v));
}

/* The ray o + t d in the mesh coordinates of instance in, with what the tests need. */
CW_INLINE cw_rayinfo inst_ray(CW_GLOBAL const cw_instance *in, vec3 o, vec3 d)
{
    return isect_rayinfo(inst_point(in->to_mesh, o), inst_vector(in->to_mesh, d));
}

/* A normal n of the mesh in world coordinates, unit length. */
CW_INLINE vec3 inst_normal(CW_GLOBAL const cw_instance *in, vec3 n)
{
    vec3 r = v3_add(
        v3_scale(v3_from4(in->to_mesh[0]), n.x),
        v3_add(v3_scale(v3_from4(in->to_mesh[1]), n.y), v3_scale(v3_from4(in->to_mesh[2]), n.z)));
    return v3_norm(r);
}

/* The surface at a hit of the ray o + t d on a triangle of instance hit.inst - 1. The
 * robust path carries the point's error bound through to_world as pbrt does for a
 * transformed point with error (3rd ed., 3.9.4), with gamma(6) for gamma(3): the ray
 * went into mesh coordinates through to_mesh, which rounds as much again. */
CW_INLINE cw_surface surface_instance(const cw_world *w, cw_hit hit, vec3 o, vec3 d)
{
    CW_GLOBAL const cw_instance *in = &w->instances[hit.inst - 1];
    vec3 pw = v3_add(o, v3_scale(d, hit.t));
    cw_surface s = surface_triangle(w, hit, inst_point(in->to_mesh, pw));
#if CW_FAST
    s.p = pw;
#else
    {
        vec3 pm = s.p, e = s.err, r[3], a[3];
        int k;
        for (k = 0; k < 3; k++) {
            r[k] = v3_from4(in->to_world[k]);
            a[k] = v3_abs(r[k]);
        }
        s.p = inst_point(in->to_world, pm);
        s.err = v3_add(
            v3_scale(v3(v3_dot(a[0], e), v3_dot(a[1], e), v3_dot(a[2], e)), 1.0f + CW_GAMMA(6)),
            v3_scale(v3(v3_dot(a[0], v3_abs(pm)) + cw_fabs(in->to_world[0].w),
                        v3_dot(a[1], v3_abs(pm)) + cw_fabs(in->to_world[1].w),
                        v3_dot(a[2], v3_abs(pm)) + cw_fabs(in->to_world[2].w)),
                     CW_GAMMA(6)));
    }
#endif
    s.ng = inst_normal(in, s.ng);
    {
        /* a smooth triangle: its vertex normals carried to the world one by one, then
         * interpolated, as a flattened copy's are (carrying the interpolated normal
         * instead weights the vertices differently under a non-uniform scale) */
        CW_GLOBAL const cw_triangle *t = &w->triangles[hit.index];
        if (t->normals >= 0) {
            float b0 = 1.0f - hit.u - hit.v;
            vec3 sn = v3_add(
                v3_scale(inst_normal(in, v3_from4(w->normals[t->normals])), b0),
                v3_add(v3_scale(inst_normal(in, v3_from4(w->normals[t->normals + 1])), hit.u),
                       v3_scale(inst_normal(in, v3_from4(w->normals[t->normals + 2])), hit.v)));
            float len = v3_len(sn);
            s.ns = len > 0.0f ? v3_scale(sn, 1.0f / len) : s.ng;
        } else {
            s.ns = s.ng;
        }
    }
    if (in->material >= 0)
        s.material = in->material;
    return s;
}

#endif

#endif
