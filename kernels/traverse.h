/* bvh_: closest-hit and any-hit traversal of the wide bounding volume hierarchy
 * (cw_bvhw_node), built on the host as a binary SAH tree (host/bvh.c) and collapsed so that
 * one box test over CW_BVH_WIDTH lanes covers up to that many children; the primitives of
 * a leaf are tested through prim_intersect (prim.h). The traversal stack holds
 * CW_BVH_STACK entries; the host checks that its tree never needs more. (The host's
 * builder, host/bvh.h, shares the bvh_ prefix: no function name is in both.) */
#ifndef CW_TRAVERSE_H
#define CW_TRAVERSE_H

#include "flags.h"
#include "instance.h"
#include "isect.h"
#include "prim.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* With CW_STATS, adds n to the walk count k (CW_COUNT_CLOSEST_NODES .. CW_COUNT_ANY_TESTS)
 * of w; nothing otherwise. */
#if CW_STATS
#define BVH_COUNT(w, k, n) ((w)->walk[(k)-CW_COUNT_CLOSEST_NODES] += (n))
#else
#define BVH_COUNT(w, k, n) ((void)0)
#endif

/* The robust path's widening of a box's exit distance, 1 + 2 gamma(3) rounded up (Ize
 * 2013): the box test's (bvh_boxes) and its redoing with a lowered tmax (bvh_entered). */
#define BVH_EXIT_WIDEN 1.0000004f

/* The child boxes of a node against [tmin, tmax] at once: the lanes a ray enters, as a bit
 * mask, and each lane's entry distance in enter[]. Each plane's distance is (o - b) * (-1/d)
 * (ri->ninv), which is (b - o) / d to the bit and lets the compiler read the node's planes
 * straight into the subtraction; per axis the lesser of the two distances is the entry, the
 * greater the exit. (Picking the planes by the direction's signs gives the same values to
 * the bit, rounding being monotonic, but costs six indexed loads whose offsets the walks
 * kept spilled to the stack. With the inlined leaf tests below: teapot 4% and balls 7%
 * faster at 1024x1024, 1M random triangles 1%.) An empty lane's box lies at +infinity: every
 * distance is +-infinity there, and no interval [entry, exit] is left. The robust path
 * widens the exit (BVH_EXIT_WIDEN). */
CW_INLINE unsigned bvh_boxes(CW_GLOBAL const cw_bvhw_node *nd, const cw_rayinfo *ri, float tmin,
                             float tmax, float *enter)
{
    CW_GLOBAL const cw_lanes *b = nd->bound;
    cw_lanes ox = vl_splat(ri->o.x), oy = vl_splat(ri->o.y), oz = vl_splat(ri->o.z);
    cw_lanes ix = vl_splat(ri->ninv.x), iy = vl_splat(ri->ninv.y), iz = vl_splat(ri->ninv.z);
    cw_lanes lx = vl_mul(vl_sub(ox, b[0]), ix), hx = vl_mul(vl_sub(ox, b[3]), ix);
    cw_lanes ly = vl_mul(vl_sub(oy, b[1]), iy), hy = vl_mul(vl_sub(oy, b[4]), iy);
    cw_lanes lz = vl_mul(vl_sub(oz, b[2]), iz), hz = vl_mul(vl_sub(oz, b[5]), iz);
    cw_lanes ex = vl_min(lx, hx), fx = vl_max(lx, hx);
    cw_lanes ey = vl_min(ly, hy), fy = vl_max(ly, hy);
    cw_lanes ez = vl_min(lz, hz), fz = vl_max(lz, hz);
    cw_lanes te = vl_max(vl_max(ex, ey), vl_max(ez, vl_splat(tmin)));
    cw_lanes tx = vl_min(vl_min(fx, fy), vl_min(fz, vl_splat(tmax)));
#if !CW_FAST
    tx = vl_mul(tx, vl_splat(BVH_EXIT_WIDEN));
#endif
    vl_store(te, enter);
    return vl_le_mask(te, tx);
}

/* Whether a child lane entered at e (bvh_boxes' enter[]) is still entered once a closest-hit
 * walk has lowered its best distance to t_best: the box test's own comparison, redone with
 * tmax = t_best (widened the same way on the robust path). A closest walk asks before each
 * leaf test: a leaf of the same node, tested before it in lane order, may have found a hit
 * in front of it (1M random triangles: 4.61 -> 4.37 tests per ray, the same image). */
CW_INLINE int bvh_entered(float e, float t_best)
{
#if !CW_FAST
    t_best *= BVH_EXIT_WIDEN;
#endif
    return e <= t_best;
}

/* Each walk below reads a node's interior lanes as one mask (vl_zero_mask of its counts)
 * before its box test: the load of the node's last cache line, which holds the counts
 * and children, then starts with the loads of its planes instead of after the test
 * (1M and 4M random triangles: 4-5% faster). */

/* An interior child c, entered at distance e, met by a closest-hit walk: the nearest of a
 * node's interior children so far stays in *near (entered at *near_t; -1: none yet), the
 * other one goes on the stack with its entry distance. They are not sorted:
 * a node's stacked children come off in the reverse of their lane order, each skipped when a
 * closer hit has been found by then. Sorting them nearest first by insertion visited 3% fewer
 * nodes and tests on 1M random triangles but mispredicted more branches (cachegrind on 100k
 * triangles at 256x256: 2.04M against 1.92M); unsorted, paired renders took 0.977-0.998 of
 * the time (five sets of 8-10 rounds: 1M triangles; teapot and balls at 1024x1024), each set
 * within this machine's noise, none slower. 1M triangles, teapot, rings, tree: the same
 * images bit for bit. */
CW_INLINE void bvh_near(int *stack, float *stack_t, int *sp, int *near, float *near_t, int c,
                        float e)
{
    if (*near < 0) {
        *near = c;
        *near_t = e;
    } else if (e < *near_t) {
        stack[*sp] = *near;
        stack_t[(*sp)++] = *near_t;
        *near = c;
        *near_t = e;
    } else {
        stack[*sp] = c;
        stack_t[(*sp)++] = e;
    }
}

/* After a node of a closest-hit walk: its nearest interior child (near; -1 when it had none)
 * if entered before t_best, else the next stacked node still entered before t_best; -1 when
 * the stack runs out. */
CW_INLINE int bvh_next(const int *stack, const float *stack_t, int *sp, int near, float near_t,
                       float t_best)
{
    if (near >= 0 && near_t <= t_best)
        return near;
    for (;;) {
        if (*sp == 0)
            return -1;
        (*sp)--;
        if (stack_t[*sp] <= t_best)
            return stack[*sp];
    }
}

/* An interior child c met by an any-hit walk: the last one met in a node (*next; -1: none
 * yet) is walked next straight from a register, and each earlier one goes on the stack, in
 * the order the walk used to pop them: the same walk, without a store and load of the next
 * node on its way from one node to the next (Embree's any-hit walk does the same). The slot
 * at *sp is written either way, without a branch, so an any walk's stack has one entry
 * more than the host checks its tree needs. Paired renders of 1M random triangles: 0.951,
 * 0.996 and 0.984 of the time in sets of 12, 12 and 30 rounds (faster in 33 of 54); 4M
 * 0.975 (8 rounds). */
CW_INLINE void bvh_any_push(int *stack, int *sp, int *next, int c)
{
    stack[*sp] = *next;
    *sp += *next >= 0;
    *next = c;
}

/* After a node of an any-hit walk: its last interior child met (next; -1: none), else the
 * top of the stack; -1 when the stack is empty. */
CW_INLINE int bvh_any_next(const int *stack, int *sp, int next)
{
    if (next >= 0)
        return next;
    if (*sp == 0)
        return -1;
    return stack[--*sp];
}

/* A shadow cache entry (Haines and Greenberg's light buffer, cut down to one leaf test):
 * what blocked the last shadow ray toward one light, a test of a block of eight triangles
 * (tag BVH_OCC_TRI8, index: the block) or of one or two blocks of four spheres (BVH_OCC_SPH4,
 * index: the first block, two: the next one too), the eight lanes the walk's test met it
 * in, or a primitive (BVH_OCC_PRIM, index: its CW_REF), or nothing (BVH_OCC_NONE). bvh_any
 * tests it before its walk. The answer does not change: the entry is tested with the walk's
 * own primitive tests and skip, and a hit the primitive test finds is one the walk finds too
 * (its box test is conservative on the robust path); the walk would only have found it, or
 * another occluder, later. */
#define BVH_OCC_NONE 0
#define BVH_OCC_TRI8 1
#define BVH_OCC_SPH4 2
#define BVH_OCC_PRIM 3
typedef struct {
    int tag, index, two;
} bvh_occluder;

#if CW_HAS_SPHERES || CW_HAS_TRIANGLES
/* One leaf test (see CW_LEAF_SPHERES), in eight lanes: block k of a leaf of triangles (never
 * the triangle skip - 1), or where spheres is set, block k of a leaf of spheres and, where two
 * is set, block k + 1 too: on a hit closer than *t_best, records it in *hit and lowers
 * *t_best. Always inlined, as is bvh_any_test: as calls they made each walk spill its
 * vector registers (all caller-saved) and reload them after every leaf test. */
CW_FORCE_INLINE void bvh_leaf_test(const cw_world *w, int spheres, int k, int two,
                                   const cw_rayinfo *ri, float tmin, int skip, float *t_best,
                                   cw_hit *hit)
{
#if CW_HAS_SPHERES
    if (spheres) {
        prim_sph8(w, k, two, ri, tmin, t_best, hit);
        return;
    }
#endif
#if CW_HAS_TRIANGLES
    prim_tri8(w, k, ri, tmin, skip, t_best, hit);
#endif
    (void)spheres;
    (void)two;
    (void)skip;
}

/* A leaf of blocks (count < -1): whether it holds spheres, the end of its blocks from
 * `first` in *end, and the blocks one test takes in *step (spheres: two of four, triangles:
 * one of eight). */
CW_INLINE int bvh_leaf_spheres(int first, int count, int *end, int *step)
{
    int code = -1 - count;
#if CW_HAS_SPHERES && CW_HAS_TRIANGLES
    int spheres = (code & CW_LEAF_SPHERES) != 0;
#else
    int spheres = CW_HAS_SPHERES; /* one kind of block: no test of the bit, no variable step
                                   * (100k random triangles: kernel instructions -1.8%) */
#endif
    *end = first + (code & (CW_LEAF_SPHERES - 1));
    *step = spheres ? 2 : 1;
    return spheres;
}

/* A leaf of blocks (count < -1), of the world's tree or a mesh's: its tests in order, never
 * the triangle skip - 1; on a hit closer than *t_best, records it in *hit and lowers
 * *t_best. */
CW_INLINE void bvh_closest_leaf_blocks(const cw_world *w, int first, int count,
                                       const cw_rayinfo *ri, float tmin, int skip, float *t_best,
                                       cw_hit *hit)
{
    int end, step, spheres = bvh_leaf_spheres(first, count, &end, &step);
    BVH_COUNT(w, CW_COUNT_CLOSEST_TESTS, (end - first + step - 1) / step);
    for (int k = first; k < end; k += step)
        bvh_leaf_test(w, spheres, k, k + 1 < end, ri, tmin, skip, t_best, hit);
}

/* Whether the ray meets one leaf test (bvh_leaf_test) in (tmin, tmax). */
CW_FORCE_INLINE int bvh_any_test(const cw_world *w, int spheres, int k, int two,
                                 const cw_rayinfo *ri, float tmin, float tmax, int skip)
{
    float t_lim = tmax;
    cw_hit hit;
    BVH_COUNT(w, CW_COUNT_ANY_TESTS, 1);
    hit.kind = CW_PRIM_NONE;
    bvh_leaf_test(w, spheres, k, two, ri, tmin, skip, &t_lim, &hit);
    return hit.kind != CW_PRIM_NONE;
}

/* Whether the ray meets a leaf of blocks (count < -1) in (tmin, tmax), never the triangle
 * skip - 1: 0 if not, else 1 with the test that met it as a shadow cache entry in *oc. */
CW_INLINE int bvh_any_leaf_blocks(const cw_world *w, int first, int count, const cw_rayinfo *ri,
                                  float tmin, float tmax, int skip, bvh_occluder *oc)
{
    int end, step, spheres = bvh_leaf_spheres(first, count, &end, &step);
    for (int k = first; k < end; k += step) {
        int two = k + 1 < end;
        if (bvh_any_test(w, spheres, k, two, ri, tmin, tmax, skip)) {
            oc->tag = spheres ? BVH_OCC_SPH4 : BVH_OCC_TRI8;
            oc->index = k;
            oc->two = two;
            return 1;
        }
    }
    return 0;
}
#endif

/* Whether the ray meets primitive ref (not an instance) in (tmin, tmax). */
CW_INLINE int bvh_any_prim(const cw_world *w, int ref, const cw_rayinfo *ri, float tmin, float tmax)
{
    float t_lim = tmax;
    cw_hit hit;
    BVH_COUNT(w, CW_COUNT_ANY_TESTS, 1);
    hit.kind = CW_PRIM_NONE;
    prim_intersect(w, ref, ri, tmin, &t_lim, &hit);
    return hit.kind != CW_PRIM_NONE;
}

#if CW_HAS_INSTANCES
/* Closest hit in a mesh's own tree from node root, for the ray ri in mesh coordinates:
 * its leaves hold triangles only (blocks of eight, or single references). On a hit closer
 * than *t_best, records it in *hit and lowers *t_best. skip: as in bvh_closest, within
 * this mesh. The walk of bvh_closest, without instances. */
CW_INLINE void bvh_mesh_closest(const cw_world *w, int root, const cw_rayinfo *ri, float tmin,
                                int skip, float *t_best, cw_hit *hit)
{
    int stack[CW_BVH_STACK];
    float stack_t[CW_BVH_STACK];
    int sp = 0, node = root, i, k;
    for (;;) {
        CW_GLOBAL const cw_bvhw_node *nd = &w->nodes[node];
        int near = -1;
        float near_t = 0.0f, enter[CW_BVH_WIDTH];
        unsigned inner = vl_zero_mask(nd->count);
        unsigned mask = bvh_boxes(nd, ri, tmin, *t_best, enter);
        BVH_COUNT(w, CW_COUNT_CLOSEST_NODES, 1);
        while (mask != 0u) {
            int count;
            i = cw_ctz(mask);
            mask &= mask - 1u;
            if (inner >> i & 1u) {
                bvh_near(stack, stack_t, &sp, &near, &near_t, nd->child[i], enter[i]);
                continue;
            }
            if (!bvh_entered(enter[i], *t_best))
                continue;
            count = nd->count[i];
            if (count > 0) {
                for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                    int ref = w->refs[k];
                    if (ref + 1 != skip) {
                        BVH_COUNT(w, CW_COUNT_CLOSEST_TESTS, 1);
                        prim_intersect(w, ref, ri, tmin, t_best, hit);
                    }
                }
            } else if (count < -1) {
                bvh_closest_leaf_blocks(w, nd->child[i], count, ri, tmin, skip, t_best, hit);
            }
        }
        node = bvh_next(stack, stack_t, &sp, near, near_t, *t_best);
        if (node < 0)
            return;
    }
}

/* Any hit in (tmin, tmax) in a mesh's own tree from node root (ri in mesh coordinates),
 * never the triangle skip - 1 of this mesh. */
CW_INLINE int bvh_mesh_any(const cw_world *w, int root, const cw_rayinfo *ri, float tmin,
                           float tmax, int skip)
{
    int stack[CW_BVH_STACK + 1]; /* one spare entry: bvh_any_push */
    int sp = 0, node = root, i, k;
    bvh_occluder unused; /* an instance's occluder is not cached (bvh_any) */
    for (;;) {
        CW_GLOBAL const cw_bvhw_node *nd = &w->nodes[node];
        float enter[CW_BVH_WIDTH];
        unsigned inner = vl_zero_mask(nd->count);
        unsigned mask = bvh_boxes(nd, ri, tmin, tmax, enter);
        int next = -1;
        BVH_COUNT(w, CW_COUNT_ANY_NODES, 1);
        while (mask != 0u) {
            int count;
            i = cw_ctz(mask);
            mask &= mask - 1u;
            if (inner >> i & 1u) {
                bvh_any_push(stack, &sp, &next, nd->child[i]);
                continue;
            }
            count = nd->count[i];
            if (count < -1 &&
                bvh_any_leaf_blocks(w, nd->child[i], count, ri, tmin, tmax, skip, &unused))
                return 1;
            for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                int ref = w->refs[k];
                if (ref + 1 != skip && bvh_any_prim(w, ref, ri, tmin, tmax))
                    return 1;
            }
        }
        node = bvh_any_next(stack, &sp, next);
        if (node < 0)
            return 0;
    }
}

/* The closest hit in instance k's mesh (see bvh_mesh_closest), marked with its instance. */
CW_INLINE void bvh_instance_closest(const cw_world *w, int k, vec3 o, vec3 d, float tmin, int skip,
                                    float *t_best, cw_hit *hit)
{
    CW_GLOBAL const cw_instance *in = &w->instances[k];
    cw_rayinfo mri = inst_ray(in, o, d);
    float before = *t_best;
    bvh_mesh_closest(w, in->root, &mri, tmin, skip, t_best, hit);
    if (*t_best < before)
        hit->inst = k + 1;
}
#endif

/* Closest hit in (tmin, tmax), never the primitive skip - 1 (skip = 0: none) of instance
 * skip_inst - 1 (skip_inst = 0: of the world), written to *out. Leaf children are tested as
 * they are found (in lane order), each unless a hit found by then lies in front of it
 * (bvh_entered); the nearest interior child is visited next, the others
 * stacked with their entry distance (bvh_near) and skipped when a closer hit has been found
 * by the time they come off the stack. An instance's leaf entry walks its mesh's tree at once
 * (bvh_instance_closest). (*out is private memory: the hit is written through a pointer
 * rather than returned, for Oclgrind; see docs/portability.md.) */
CW_INLINE void bvh_closest(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax, int skip,
                           int skip_inst, cw_hit *out)
{
    cw_hit hit;
    cw_rayinfo ri = isect_rayinfo(o, d);
    int stack[CW_BVH_STACK];
    float stack_t[CW_BVH_STACK];
    int sp = 0, node = 0, i, k;
    float t_best = tmax;
    int wskip = skip_inst != 0 ? 0 : skip; /* what the world's own primitives skip */

    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.kind = CW_PRIM_NONE;
    hit.index = -1;
    hit.inst = hit.block = hit.lane = 0;
    if (w->num_nodes == 0) {
        *out = hit;
        return;
    }
    for (;;) {
        CW_GLOBAL const cw_bvhw_node *nd = &w->nodes[node];
        int near = -1;
        float near_t = 0.0f, enter[CW_BVH_WIDTH];
        unsigned inner = vl_zero_mask(nd->count);
        unsigned mask = bvh_boxes(nd, &ri, tmin, t_best, enter);
        BVH_COUNT(w, CW_COUNT_CLOSEST_NODES, 1);
        while (mask != 0u) {
            int count;
            i = cw_ctz(mask);
            mask &= mask - 1u;
            if (inner >> i & 1u) {
                bvh_near(stack, stack_t, &sp, &near, &near_t, nd->child[i], enter[i]);
                continue;
            }
            if (!bvh_entered(enter[i], t_best))
                continue;
            count = nd->count[i];
            if (count > 0) {
                for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                    int ref = w->refs[k];
#if CW_HAS_INSTANCES
                    if (CW_REF_KIND(ref) == CW_PRIM_INSTANCE) {
                        int in = CW_REF_INDEX(ref);
                        bvh_instance_closest(w, in, o, d, tmin, in + 1 == skip_inst ? skip : 0,
                                             &t_best, &hit);
                        continue;
                    }
#endif
                    if (ref + 1 != wskip) {
                        BVH_COUNT(w, CW_COUNT_CLOSEST_TESTS, 1);
                        prim_intersect(w, ref, &ri, tmin, &t_best, &hit);
                    }
                }
#if CW_HAS_SPHERES || CW_HAS_TRIANGLES
            } else if (count < -1) { /* blocks of spheres or triangles */
                bvh_closest_leaf_blocks(w, nd->child[i], count, &ri, tmin, wskip, &t_best, &hit);
#endif
            }
        }
        node = bvh_next(stack, stack_t, &sp, near, near_t, t_best); /* down the nearest */
        if (node < 0) {
            *out = hit;
            return;
        }
    }
}

/* Whether the ray meets the cached occluder *oc in (tmin, tmax), never the world's
 * primitive skip - 1: the walk's own leaf tests. */
CW_INLINE int bvh_any_cached(const cw_world *w, const bvh_occluder *oc, const cw_rayinfo *ri,
                             float tmin, float tmax, int skip)
{
    switch (oc->tag) {
#if CW_HAS_SPHERES || CW_HAS_TRIANGLES
    case BVH_OCC_TRI8:
    case BVH_OCC_SPH4:
        return bvh_any_test(w, oc->tag == BVH_OCC_SPH4, oc->index, oc->two, ri, tmin, tmax, skip);
#endif
    case BVH_OCC_PRIM:
        return oc->index + 1 != skip && bvh_any_prim(w, oc->index, ri, tmin, tmax);
    default:
        return 0;
    }
}

/* Any hit in (tmin, tmax), never the primitive skip - 1 of instance skip_inst - 1 (as in
 * bvh_closest): for shadow rays. *oc is the shadow cache entry of the ray's light: tested
 * first, then set to the occluder the walk meets, or to nothing when none blocks the ray
 * (so that a lit point's next neighbour pays no test for it) or an instance does. */
CW_INLINE int bvh_any(const cw_world *w, vec3 o, vec3 d, float tmin, float tmax, int skip,
                      int skip_inst, bvh_occluder *oc)
{
    cw_rayinfo ri = isect_rayinfo(o, d);
    int stack[CW_BVH_STACK + 1]; /* one spare entry: bvh_any_push */
    int sp = 0, node = 0, i, k;
    int wskip = skip_inst != 0 ? 0 : skip;

    if (w->num_nodes == 0)
        return 0;
    if (oc->tag != BVH_OCC_NONE && bvh_any_cached(w, oc, &ri, tmin, tmax, wskip))
        return 1;
    for (;;) {
        CW_GLOBAL const cw_bvhw_node *nd = &w->nodes[node];
        float enter[CW_BVH_WIDTH];
        unsigned inner = vl_zero_mask(nd->count);
        unsigned mask = bvh_boxes(nd, &ri, tmin, tmax, enter);
        int next = -1;
        BVH_COUNT(w, CW_COUNT_ANY_NODES, 1);
        while (mask != 0u) {
            int count;
            i = cw_ctz(mask);
            mask &= mask - 1u;
            if (inner >> i & 1u) {
                bvh_any_push(stack, &sp, &next, nd->child[i]);
                continue;
            }
            count = nd->count[i];
#if CW_HAS_SPHERES || CW_HAS_TRIANGLES
            if (count < -1 &&
                bvh_any_leaf_blocks(w, nd->child[i], count, &ri, tmin, tmax, wskip, oc))
                return 1;
#endif
            for (k = nd->child[i]; k < nd->child[i] + count; k++) {
                int ref = w->refs[k];
#if CW_HAS_INSTANCES
                if (CW_REF_KIND(ref) == CW_PRIM_INSTANCE) {
                    int in = CW_REF_INDEX(ref);
                    cw_rayinfo mri = inst_ray(&w->instances[in], o, d);
                    if (bvh_mesh_any(w, w->instances[in].root, &mri, tmin, tmax,
                                     in + 1 == skip_inst ? skip : 0)) {
                        oc->tag = BVH_OCC_NONE;
                        return 1;
                    }
                    continue;
                }
#endif
                if (ref + 1 != wskip && bvh_any_prim(w, ref, &ri, tmin, tmax)) {
                    oc->tag = BVH_OCC_PRIM;
                    oc->index = ref;
                    return 1;
                }
            }
        }
        node = bvh_any_next(stack, &sp, next);
        if (node < 0) {
            oc->tag = BVH_OCC_NONE;
            return 0;
        }
    }
}

#endif
