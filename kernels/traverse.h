/* bvh_: closest-hit and any-hit traversal of the 4-wide bounding volume hierarchy
 * (cw_bvh4_node), built on the host as a binary SAH tree (host/bvh.c) and collapsed so
 * that one 4-wide box test covers up to four children; the primitives of a leaf are
 * tested through prim_intersect (prim.h). The traversal stack holds CW_BVH_STACK entries;
 * the host checks that its tree never needs more. (The host's builder, host/bvh.h, shares
 * the bvh_ prefix: no function name is in both.) */
#ifndef CW_TRAVERSE_H
#define CW_TRAVERSE_H

#include "flags.h"
#include "isect.h"
#include "prim.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* The four child boxes of a node against [tmin, tmax] at once: entry and exit distances
 * per lane; a lane is hit when entry <= exit. The robust path widens the exit by
 * 1 + 2 gamma(3) (Ize 2013). */
CW_INLINE void bvh_box4(CW_GLOBAL const cw_bvh4_node *nd, const cw_rayinfo *ri, float tmin,
                        float tmax, v4 *t_enter, v4 *t_exit)
{
    v4 ox = v4_splat(ri->o.x), oy = v4_splat(ri->o.y), oz = v4_splat(ri->o.z);
    v4 ix = v4_splat(ri->inv.x), iy = v4_splat(ri->inv.y), iz = v4_splat(ri->inv.z);
    v4 tx0 = v4_mul(v4_sub(nd->lo_x, ox), ix), tx1 = v4_mul(v4_sub(nd->hi_x, ox), ix);
    v4 ty0 = v4_mul(v4_sub(nd->lo_y, oy), iy), ty1 = v4_mul(v4_sub(nd->hi_y, oy), iy);
    v4 tz0 = v4_mul(v4_sub(nd->lo_z, oz), iz), tz1 = v4_mul(v4_sub(nd->hi_z, oz), iz);
    *t_enter = v4_max(v4_max(v4_min(tx0, tx1), v4_min(ty0, ty1)),
                      v4_max(v4_min(tz0, tz1), v4_splat(tmin)));
    *t_exit = v4_min(v4_min(v4_max(tx0, tx1), v4_max(ty0, ty1)),
                     v4_min(v4_max(tz0, tz1), v4_splat(tmax)));
#if !CW_FAST
    *t_exit = v4_mul(*t_exit, v4_splat(1.0000004f));
#endif
}

/* Closest hit in (tmin, tmax), never the primitive skip - 1 (skip = 0: none), written to
 * *out. Leaf children are tested as they are found; interior children are visited nearest
 * first, the others stacked with their entry distance and skipped when a closer hit has
 * been found by the time they come off the stack. (*out is private memory: the hit is
 * written through a pointer rather than returned, for Oclgrind; see docs/portability.md.) */
CW_INLINE void bvh_closest(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax, int skip,
                           cw_hit *out)
{
    cw_hit hit;
    cw_rayinfo ri = isect_rayinfo(o, d);
    int stack[CW_BVH_STACK];
    float stack_t[CW_BVH_STACK];
    int sp = 0, node = 0, i, k;
    float t_best = tmax;

    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.kind = CW_PRIM_NONE;
    hit.index = -1;
    hit.pad0 = hit.pad1 = hit.pad2 = 0;
    if (w->num_nodes == 0) {
        *out = hit;
        return;
    }
    for (;;) {
        CW_GLOBAL const cw_bvh4_node *nd = &w->nodes[node];
        int ci[4], n = 0;
        float ct[4];
        v4 te, tx;
        bvh_box4(nd, &ri, tmin, t_best, &te, &tx);
        for (i = 0; i < 4; i++) {
            int count = nd->count[i];
            float e = v4_get(te, i);
            if (count < 0 || !(e <= v4_get(tx, i)))
                continue;
            if (count > 0) {
                for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                    int ref = w->refs[k];
                    if (ref + 1 != skip)
                        prim_intersect(w, ref, &ri, tmin, &t_best, &hit);
                }
            } else {
                /* insertion by entry distance, nearest first */
                int j = n++;
                while (j > 0 && ct[j - 1] > e) {
                    ct[j] = ct[j - 1];
                    ci[j] = ci[j - 1];
                    j--;
                }
                ct[j] = e;
                ci[j] = nd->child[i];
            }
        }
        /* stack the farther ones (farthest deepest), go down the nearest */
        for (i = n - 1; i >= 1; i--) {
            if (ct[i] <= t_best) {
                stack[sp] = ci[i];
                stack_t[sp] = ct[i];
                sp++;
            }
        }
        if (n > 0 && ct[0] <= t_best) {
            node = ci[0];
            continue;
        }
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
    int sp = 0, node, i, k;
    cw_hit hit;
    float t_lim;

    if (w->num_nodes == 0)
        return 0;
    stack[sp++] = 0;
    while (sp > 0) {
        CW_GLOBAL const cw_bvh4_node *nd;
        v4 te, tx;
        node = stack[--sp];
        nd = &w->nodes[node];
        bvh_box4(nd, &ri, tmin, tmax, &te, &tx);
        for (i = 0; i < 4; i++) {
            int count = nd->count[i];
            if (count < 0 || !(v4_get(te, i) <= v4_get(tx, i)))
                continue;
            if (count == 0) {
                stack[sp++] = nd->child[i];
                continue;
            }
            for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                int ref = w->refs[k];
                if (ref + 1 == skip)
                    continue;
                t_lim = tmax;
                hit.kind = CW_PRIM_NONE;
                prim_intersect(w, ref, &ri, tmin, &t_lim, &hit);
                if (hit.kind != CW_PRIM_NONE)
                    return 1;
            }
        }
    }
    return 0;
}

#endif
