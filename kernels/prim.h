/* prim_: the one place that dispatches over the primitive kinds (CW_PRIM_* in types.h),
 * for the traversal (prim_intersect) and for shading (prim_surface). Each kind's own code
 * is in its header; a kind whose CW_HAS_* feature is 0 is compiled out of both. */
#ifndef CW_PRIM_H
#define CW_PRIM_H

#include "cone.h"
#include "flags.h"
#include "instance.h"
#include "isect.h"
#include "polygon.h"
#include "sphere.h"
#include "surface.h"
#include "triangle.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Tests the ray against one referenced primitive (a CW_REF); on a hit closer than *tmax,
 * records it in *hit and lowers *tmax. Always inlined: the per-pixel kernel calls it from
 * both traversals, where a call would keep the hit in memory. */
CW_FORCE_INLINE void prim_intersect(const cw_world *w, int ref, const cw_rayinfo *ri, float tmin,
                                    float *tmax, cw_hit *hit)
{
    int kind = CW_REF_KIND(ref), index = CW_REF_INDEX(ref);
    float t = 0.0f, u = 0.0f, v = 0.0f;
    int got = 0;
    switch (kind) {
#if CW_HAS_SPHERES
    case CW_PRIM_SPHERE:
        got = isect_sphere(&w->spheres[index], ri->o, ri->d, tmin, *tmax, &t);
        break;
#endif
#if CW_HAS_TRIANGLES
    case CW_PRIM_TRIANGLE:
        got = isect_triangle(&w->triangles[index], ri, tmin, *tmax, &t, &u, &v);
        break;
#endif
#if CW_HAS_POLYGONS
    case CW_PRIM_POLYGON:
        got = isect_polygon(&w->polygons[index], w->poly_verts, w->poly_bands, ri->o, ri->d, tmin,
                            *tmax, &t);
        break;
#endif
#if CW_HAS_CONES
    case CW_PRIM_CONE:
        got = isect_cone(&w->cones[index], ri->o, ri->d, tmin, *tmax, &t);
        break;
#endif
    default:
        break;
    }
    if (got) {
        *tmax = t;
        hit->t = t;
        hit->u = u;
        hit->v = v;
        hit->kind = kind;
        hit->index = index;
        hit->inst = 0; /* the world's, until an instance's walk marks it (traverse.h) */
        hit->block = 0;
    }
}

#if CW_HAS_SPHERES || CW_HAS_TRIANGLES
/* Records a hit at t (u, v) on primitive `index` of a kind kept in blocks, found in lane
 * `lane` of block `block`, in *hit, and lowers *tmax to t. */
CW_FORCE_INLINE void prim_block_hit(cw_hit *hit, float *tmax, float t, float u, float v, int kind,
                                    int index, int block, int lane)
{
    *tmax = t;
    hit->t = t;
    hit->u = u;
    hit->v = v;
    hit->kind = kind;
    hit->index = index;
    hit->inst = 0;
    hit->block = block + 1;
    hit->lane = lane;
}
#endif

#if CW_HAS_TRIANGLES
/* Tests the ray against the eight triangles of block `block` in one test (a leaf of triangles
 * only, cw_tri8), never the primitive skip - 1; on a hit closer than *tmax, records it in *hit
 * (its block and lane there) and lowers *tmax: what prim_intersect does for each of them in
 * lane order. */
CW_FORCE_INLINE void prim_tri8(const cw_world *w, int block, const cw_rayinfo *ri, float tmin,
                               int skip, float *tmax, cw_hit *hit)
{
    CW_GLOBAL const cw_tri8 *b = &w->tri_blocks[block];
    float t = 0.0f, u = 0.0f, v = 0.0f;
    int lane = isect_tri8(b, ri, tmin, *tmax, skip, &t, &u, &v);
    if (lane >= 0)
        prim_block_hit(hit, tmax, t, u, v, CW_PRIM_TRIANGLE, b->index[lane], block, lane);
}
#endif

#if CW_HAS_SPHERES
/* The spheres of block `block` and, where two is set, of the next block too, in one test (a
 * leaf of spheres only, cw_sph4): on a hit closer than *tmax, records it in *hit and lowers
 * *tmax. */
CW_FORCE_INLINE void prim_sph8(const cw_world *w, int block, int two, const cw_rayinfo *ri,
                               float tmin, float *tmax, cw_hit *hit)
{
    CW_GLOBAL const cw_sph4 *b0 = &w->sph_blocks[block];
    CW_GLOBAL const cw_sph4 *b1 = two ? b0 + 1 : b0;
    float t = 0.0f;
    int lane = isect_sph8(b0, b1, two ? 255u : 15u, ri->o, ri->d, tmin, *tmax, &t);
    if (lane >= 0)
        prim_block_hit(hit, tmax, t, 0.0f, 0.0f, CW_PRIM_SPHERE,
                       (lane < 4 ? b0 : b1)->index[lane & 3], block + (lane >> 2), lane & 3);
}
#endif

/* The surface at a hit (not a miss) of the ray o + t d: the kind's surface_* function,
 * given the point o + t d. */
CW_INLINE cw_surface prim_surface(const cw_world *w, cw_hit hit, vec3 o, vec3 d)
{
    cw_surface s;
    vec3 p = v3_add(o, v3_scale(d, hit.t));
    switch (hit.kind) {
#if CW_HAS_SPHERES
    case CW_PRIM_SPHERE:
        s = surface_sphere(w, hit, p);
        break;
#endif
#if CW_HAS_TRIANGLES
    case CW_PRIM_TRIANGLE:
#if CW_HAS_INSTANCES
        if (hit.inst != 0) {
            s = surface_instance(w, hit, o, d);
            break;
        }
#endif
        s = surface_triangle(w, hit, p);
        break;
#endif
#if CW_HAS_POLYGONS
    case CW_PRIM_POLYGON:
        s = surface_polygon(w, hit, p);
        break;
#endif
#if CW_HAS_CONES
    case CW_PRIM_CONE:
        s = surface_cone(w, hit, p);
        break;
#endif
    default: /* a kind compiled out is never hit */
        s.p = p;
        s.ng = s.ns = v3(0.0f, 0.0f, 1.0f);
        s.err = v3(0.0f, 0.0f, 0.0f);
        s.flat = 0;
        s.material = 0;
        break;
    }
#if CW_FAST
    s.err = v3(0.0f, 0.0f, 0.0f);
#endif
    s.inst = hit.inst;
    return s;
}

#endif
