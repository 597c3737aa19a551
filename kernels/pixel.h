/* pix_: the per-pixel strategy (for CPUs): one work-item traces the whole ray tree of one
 * pixel sample, each shadow ray in place through bvh_any and a light's term computed only
 * when nothing blocks it; no recursion (PoCL does not compile it), a small queue of
 * pending rays instead. The formulas are shade.h's and the traversal traverse.h's, and the
 * terms reach the pixel in the wavefront's order with the same float operations, so both
 * strategies give the same image bit for bit. The wavefront (clwhitted.cl, wavefront.h)
 * runs the tree level by level: its shade kernel adds each shading point's ambient term
 * (or a miss's background) in queue order, then its occlude kernel adds each shading
 * point's sum of unblocked lights (in light order), in queue order; a ray's children are
 * queued refraction first. Here the tree is walked breadth first in the same order, a
 * level's light sums kept until its ambient terms are in. That order is the wavefront's
 * whenever its atomics keep queue order, which they do within a work-group; only where a
 * pixel's rays of one level straddle two work-groups run at once (refraction only) may
 * the wavefront add them the other way round, an ulp now and then. A level too wide for
 * the queue (depth 7 or more with refraction) has its extra subtrees walked depth first
 * at once, also an ulp now and then. */
#ifndef CW_PIXEL_H
#define CW_PIXEL_H

#include "camera.h"
#include "flags.h"
#include "isect.h"
#include "shade.h"
#include "traverse.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Without refraction a ray has at most one child, so the queue holds one ray. */
#if CW_HAS_REFRACTION
#define PIX_QUEUE CW_PIX_QUEUE
#else
#define PIX_QUEUE 1
#endif

/* A pending ray: origin, unit direction, weight (the product of the mirror and
 * transmission colours on its path), depth (the eye ray is 1), skip and skip_inst (as in
 * cw_ray). */
typedef struct {
    vec3 o, d, weight;
    int depth, skip, skip_inst;
} pix_ray;

/* What a work-item carries from one pixel sample to the next: its counts, indexed by
 * CW_COUNT_* (secondary rays (CW_COUNT_RAYS), shadow rays, and with CW_STATS hits and
 * blocked shadow rays; CW_COUNT_DEPTH is the deepest ray traced, a maximum, not a sum), and
 * its shadow cache: for each of the first PIX_OCC lights, the occluder that blocked the last
 * shadow ray toward it, if that ray was blocked (bvh_any), one for the eye rays' points
 * (occ[0]) and one for the deeper rays' (occ[1]), whose points lie elsewhere in the scene.
 * The pixels of a tile are neighbours, so a point in shadow is often shadowed by the same
 * block as the point before. Nodes and blocks the shadow rays visit, the cache's own tests
 * included, at 1024x1024: gears -23%, balls -17%, teapot -9%, 1M random triangles -9%. */
#define PIX_OCC 8
typedef struct {
    int n[CW_COUNT_DEPTH + 1];
    bvh_occluder occ[2][PIX_OCC];
} pix_state;

CW_INLINE void pix_clear(pix_state *c)
{
    int k;
    for (k = 0; k <= CW_COUNT_DEPTH; k++)
        c->n[k] = 0;
    for (k = 0; k < PIX_OCC; k++)
        c->occ[0][k].tag = c->occ[1][k].tag = BVH_OCC_NONE;
}

/* Whether counter k is counted in this build (the hits and blocked rays with CW_STATS). */
CW_INLINE int pix_counted(int k)
{
    return CW_STATS || k == CW_COUNT_RAYS || k == CW_COUNT_SHADOWS || k == CW_COUNT_DEPTH;
}

CW_INLINE pix_ray pix_make(vec3 o, vec3 d, vec3 weight, int depth, int skip, int skip_inst)
{
    pix_ray r;
    r.o = o;
    r.d = d;
    r.weight = weight;
    r.depth = depth;
    r.skip = skip;
    r.skip_inst = skip_inst;
    return r;
}

/* Traces one ray and shades what it hits: adds to *acc what the wavefront's shade kernel
 * adds for it (the background of a miss, else the ambient term), sets *sum to what its
 * occlude kernel adds (the sum of the unblocked lights, in light order; 0 for a miss) and
 * *nx to the ray's children (none on a miss or at the maximum depth). */
CW_INLINE void pix_step(const cw_world *w, CW_GLOBAL const cw_frame *f,
                        CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                        const pix_ray *ray, vec3 *acc, vec3 *sum, shade_next *nx, pix_state *c)
{
    shade_point pt;
    cw_hit hit;
    int k;

    *sum = v3(0.0f, 0.0f, 0.0f);
    nx->refract = nx->reflect = 0;
    if (ray->depth > c->n[CW_COUNT_DEPTH])
        c->n[CW_COUNT_DEPTH] = ray->depth;
    bvh_closest(w, ray->o, ray->d, 0.0f, CW_FAR, ray->skip, ray->skip_inst, &hit);
    if (hit.kind == CW_PRIM_NONE) {
        *acc = v3_add(*acc, shade_background(f, ray->weight));
        return;
    }
#if CW_STATS
    c->n[ray->depth == 1 ? CW_COUNT_EYE_HITS : CW_COUNT_SECONDARY_HITS]++;
#endif
    pt = shade_at(w, materials, ray->o, ray->d, ray->weight, hit);
    *acc = v3_add(*acc, shade_ambient(f, &pt));
    for (k = 0; k < f->num_lights; k++) {
        vec3 lp = v3_from4(lights[k].position), o, l;
        float tmax;
        bvh_occluder spare, *oc = k < PIX_OCC ? &c->occ[ray->depth > 1][k] : &spare;
        if (!shade_faces(&pt, lp)) /* facing away: no contribution, no shadow ray */
            continue;
        c->n[CW_COUNT_SHADOWS]++;
        tmax = shade_shadow_ray(&pt, lp, &o, &l);
        spare.tag = BVH_OCC_NONE;
        if (bvh_any(w, o, l, 0.0f, tmax, pt.s.flat, pt.s.inst, oc)) {
#if CW_STATS
            c->n[CW_COUNT_BLOCKED]++;
#endif
            continue;
        }
        *sum = v3_add(*sum, shade_light(&pt, l, v3_from4(lights[k].intensity)));
    }
    if (ray->depth < f->max_depth) {
        *nx = shade_secondary(&pt, f->spd_rays);
        c->n[CW_COUNT_RAYS] += nx->refract + nx->reflect;
    }
}

#if CW_HAS_REFRACTION
/* The subtree of a ray that did not fit the queue, depth first from a stack (refraction
 * child first), each ray's terms added to *acc at once. The stack holds at most one ray
 * per level below the root's, plus one. */
CW_INLINE void pix_subtree(const cw_world *w, CW_GLOBAL const cw_frame *f,
                           CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                           pix_ray root, vec3 *acc, pix_state *c)
{
    pix_ray stack[CW_PIX_STACK];
    int sp = 0;
    stack[sp++] = root;
    while (sp > 0) {
        pix_ray ray = stack[--sp];
        shade_next nx;
        vec3 sum;
        pix_step(w, f, lights, materials, &ray, acc, &sum, &nx, c);
        *acc = v3_add(*acc, sum);
        if (nx.reflect)
            stack[sp++] =
                pix_make(nx.r_o, nx.r_d, nx.r_weight, ray.depth + 1, nx.skip, nx.skip_inst);
        if (nx.refract)
            stack[sp++] =
                pix_make(nx.t_o, nx.t_d, nx.t_weight, ray.depth + 1, nx.skip, nx.skip_inst);
    }
}
#endif

/* Queues a child behind the level being traced (the queue is a ring: `head` is its first
 * ray, *count how many it holds), or walks its subtree at once when the queue is full. */
CW_INLINE void pix_enqueue(const cw_world *w, CW_GLOBAL const cw_frame *f,
                           CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                           pix_ray *queue, int head, int *count, pix_ray r, vec3 *acc, pix_state *c)
{
#if CW_HAS_REFRACTION
    if (*count == PIX_QUEUE) {
        pix_subtree(w, f, lights, materials, r, acc, c);
        return;
    }
#else
    (void)w;
    (void)f;
    (void)lights;
    (void)materials;
    (void)acc;
    (void)c;
#endif
    queue[head + *count < PIX_QUEUE ? head + *count : head + *count - PIX_QUEUE] = r;
    (*count)++;
}

/* Traces sample (sx, sy) of pixel (i, j) (j counted from the bottom row, as cam_ray) and
 * adds it to the accumulation image: its rgb and its sample count (.w, up by one); with
 * `first`, writes them (count 1) over whatever the image held. Its rays
 * are counted into *c, the work-item's sums (CW_COUNT_DEPTH: the maximum): counting there
 * directly, rather than returning one pixel's counts to be added, spares a copy whose
 * narrow stores and wide reload stalled store forwarding (4% of teapot at 2048x2048). */
CW_INLINE void pix_trace(const cw_world *w, CW_GLOBAL const cw_frame *f,
                         CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                         CW_GLOBAL float *image, int i, int j, float sx, float sy, int first,
                         pix_state *c)
{
    cw_ray eye = cam_ray(f, i, j, sx, sy);
    CW_GLOBAL float *px = &image[4 * eye.pixel];
    vec3 acc = first ? v3(0.0f, 0.0f, 0.0f) : v3(px[0], px[1], px[2]);
    pix_ray queue[PIX_QUEUE];
    vec3 sums[PIX_QUEUE];
    int head = 0, count = 1, k;

    queue[0] = pix_make(v3_from4(eye.origin), v3_from4(eye.dir), v3_from4(eye.weight), 1, 0, 0);
    while (count > 0) { /* one level: the rays queued now */
        int n = count;
        for (k = 0; k < n; k++) {
            pix_ray ray = queue[head];
            shade_next nx;
            head = head + 1 < PIX_QUEUE ? head + 1 : 0;
            count--;
            pix_step(w, f, lights, materials, &ray, &acc, &sums[k], &nx, c);
            if (nx.refract)
                pix_enqueue(
                    w, f, lights, materials, queue, head, &count,
                    pix_make(nx.t_o, nx.t_d, nx.t_weight, ray.depth + 1, nx.skip, nx.skip_inst),
                    &acc, c);
            if (nx.reflect)
                pix_enqueue(
                    w, f, lights, materials, queue, head, &count,
                    pix_make(nx.r_o, nx.r_d, nx.r_weight, ray.depth + 1, nx.skip, nx.skip_inst),
                    &acc, c);
        }
        for (k = 0; k < n; k++)
            acc = v3_add(acc, sums[k]);
    }
    px[0] = acc.x;
    px[1] = acc.y;
    px[2] = acc.z;
    px[3] = first ? 1.0f : px[3] + 1.0f;
}

#endif
