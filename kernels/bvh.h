/* bvh_: closest-hit and any-hit traversal of the flattened bounding volume hierarchy
 * built on the host (host/bvh.c). Depth-first layout: an interior node's first child is
 * the next node, its second child is node.start; leaves hold node.count references
 * from node.start on. Children are visited nearer first; a stack of 64 entries is
 * enough for the builder's depth bound. */
#ifndef CW_BVH_KERNEL_H
#define CW_BVH_KERNEL_H

#include "intersect.h"
#include "types.h"

#define CW_BVH_STACK 64

/* Tests the ray against one referenced primitive; on a hit closer than *tmax, records
 * it in *hit and lowers *tmax. */
CW_INLINE void bvh_test_ref(const cw_world *w, int ref, const cw_rayinfo *ri, float tmin,
                            float *tmax, cw_hit *hit)
{
    int kind = CW_REF_KIND(ref), index = CW_REF_INDEX(ref);
    float t = 0.0f, u = 0.0f, v = 0.0f;
    int got = 0;
#if CW_HAS_SPHERES
    if (kind == CW_PRIM_SPHERE)
        got = isect_sphere(&w->spheres[index], ri->o, ri->d, tmin, *tmax, &t);
#endif
#if CW_HAS_TRIANGLES
    if (kind == CW_PRIM_TRIANGLE)
        got = isect_triangle(&w->triangles[index], ri, tmin, *tmax, &t, &u, &v);
#endif
#if CW_HAS_POLYGONS
    if (kind == CW_PRIM_POLYGON)
        got = isect_polygon(&w->polygons[index], w->poly_verts, ri->o, ri->d, tmin, *tmax, &t);
#endif
#if CW_HAS_CONES
    if (kind == CW_PRIM_CONE)
        got = isect_cone(&w->cones[index], ri->o, ri->d, tmin, *tmax, &t);
#endif
    if (got) {
        *tmax = t;
        hit->t = t;
        hit->u = u;
        hit->v = v;
        hit->kind = kind;
        hit->index = index;
    }
}

/* Closest hit in (tmin, tmax), never the primitive skip - 1 (skip = 0: none). */
CW_INLINE void bvh_closest(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax, int skip,
                           CW_GLOBAL cw_hit *out)
{
    cw_hit hit;
    cw_rayinfo ri = isect_rayinfo(o, d);
    int stack[CW_BVH_STACK];
    float stack_t[CW_BVH_STACK];
    int sp = 0, node = 0, k;
    float t_best = tmax;

    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.kind = CW_PRIM_NONE;
    hit.index = -1;
    hit.pad0 = hit.pad1 = hit.pad2 = 0;
    if (w->num_nodes == 0 || isect_box(&w->nodes[0], &ri, tmin, t_best) == CW_MISS) {
        *out = hit;
        return;
    }
    for (;;) {
        CW_GLOBAL const cw_bvh_node *nd = &w->nodes[node];
        if (nd->count > 0) {
            for (k = nd->start; k < nd->start + nd->count; k++) {
                int ref = w->refs[k];
                if (ref + 1 != skip)
                    bvh_test_ref(w, ref, &ri, tmin, &t_best, &hit);
            }
        } else {
            int c0 = node + 1, c1 = nd->start;
            float t0 = isect_box(&w->nodes[c0], &ri, tmin, t_best);
            float t1 = isect_box(&w->nodes[c1], &ri, tmin, t_best);
            if (t0 != CW_MISS && t1 != CW_MISS) {
                if (t1 < t0) {
                    int ci = c0;
                    float tt = t0;
                    c0 = c1;
                    c1 = ci;
                    t0 = t1;
                    t1 = tt;
                }
                stack[sp] = c1;
                stack_t[sp] = t1;
                sp++;
                node = c0;
                continue;
            }
            if (t0 != CW_MISS) {
                node = c0;
                continue;
            }
            if (t1 != CW_MISS) {
                node = c1;
                continue;
            }
        }
        /* pop the next node still nearer than the closest hit */
        for (;;) {
            if (sp == 0) {
                *out = hit;
                return;
            }
            sp--;
            if (stack_t[sp] <= t_best)
                break;
        }
        node = stack[sp];
    }
}

/* Any hit in (tmin, tmax), never the primitive skip - 1: for shadow rays. */
CW_INLINE int bvh_any(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax, int skip)
{
    cw_rayinfo ri = isect_rayinfo(o, d);
    int stack[CW_BVH_STACK];
    int sp = 0, node = 0, k;
    cw_hit hit;
    float t_lim;

    if (w->num_nodes == 0)
        return 0;
    stack[sp++] = 0;
    while (sp > 0) {
        CW_GLOBAL const cw_bvh_node *nd;
        node = stack[--sp];
        nd = &w->nodes[node];
        if (isect_box(nd, &ri, tmin, tmax) == CW_MISS)
            continue;
        if (nd->count > 0) {
            for (k = nd->start; k < nd->start + nd->count; k++) {
                int ref = w->refs[k];
                if (ref + 1 == skip)
                    continue;
                t_lim = tmax;
                hit.kind = CW_PRIM_NONE;
                bvh_test_ref(w, ref, &ri, tmin, &t_lim, &hit);
                if (hit.kind != CW_PRIM_NONE)
                    return 1;
            }
        } else {
            /* the child on the side the ray starts from first: near blockers end it soonest */
            int axis = -nd->count;
            float da = axis == 0 ? ri.d.x : (axis == 1 ? ri.d.y : ri.d.z);
            int near = da >= 0.0f ? node + 1 : nd->start;
            stack[sp++] = da >= 0.0f ? nd->start : node + 1;
            stack[sp++] = near;
        }
    }
    return 0;
}

#endif
