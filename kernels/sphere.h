/* Spheres (cw_sphere): the ray-sphere test and the surface at a hit. */
#ifndef CW_SPHERE_H
#define CW_SPHERE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Ray-sphere. With f = o - c and unit d the quadratic is t^2 + 2bt + c = 0, b = f.d,
 * c = f.f - R^2. The discriminant b^2 - c is computed as R^2 - |f - b d|^2 (the squared
 * distance from the centre to the line), which does not cancel for far or tiny spheres,
 * and the roots as q = -b - sign(b) sqrt(disc), t = q and c/q, which avoids cancellation
 * too (Haines et al., Ray Tracing Gems, ch. 7). Both paths: the textbook b^2 - c loses
 * the small spheres of the SPD scenes to acne on the fast path, for a saving of 3 flops.
 * disc < 0: no hit; disc = 0: one (tangent) hit; disc > 0: two, nearest valid wins.
 * A negative radius (NFF) makes the sphere visible from inside only: of the two roots only
 * the larger one, where the ray leaves the sphere, is a hit, so a ray from outside passes
 * the near side and meets the inside of the far side. One sign test per ray and sphere,
 * on every ray (shadow rays too), on both paths. */
CW_INLINE int isect_sphere(CW_GLOBAL const cw_sphere *s, vec3 o, vec3 d, float tmin, float tmax,
                           float *t_out)
{
    float r = s->center.w; /* < 0: visible from inside only */
    /* the dot products written out, in isect_sph8's order (a library dot may fuse) */
    float fx = o.x - s->center.x, fy = o.y - s->center.y, fz = o.z - s->center.z;
    float b = fx * d.x + fy * d.y + fz * d.z;
    float px = fx - d.x * b, py = fy - d.y * b, pz = fz - d.z * b;
    float disc = r * r - (px * px + py * py + pz * pz);
    float cc, t0, t1, tmp, q;
    if (disc < 0.0f)
        return 0;
    cc = (fx * fx + fy * fy + fz * fz) - r * r;
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
    if (t0 > tmin && t0 < tmax && r > 0.0f) {
        *t_out = t0;
        return 1;
    }
    if (t1 > tmin && t1 < tmax) {
        *t_out = t1;
        return 1;
    }
    return 0;
}

/* The spheres of blocks b0 and b1 at once, lanes 0-3 and 4-7, of the lanes set in `lanes`
 * (15: b0 only, b1 = b0; 255: both), each lane with exactly isect_sphere's float operations
 * (the same hits, bit for bit): the closest hit in (tmin, tmax). Returns its
 * lane, the first of equally close ones (as testing them one by one in lane order), or -1.
 * Each lane's hit is the one isect_sphere finds below tmax; testing them in order with
 * the lowered tmax keeps a lane's hit exactly when it is below the current tmax, since
 * its far root can only count where the near one does not. */
CW_INLINE int isect_sph8(CW_GLOBAL const cw_sph4 *b0, CW_GLOBAL const cw_sph4 *b1, unsigned lanes,
                         vec3 o, vec3 d, float tmin, float tmax, float *t_out)
{
    cw_float8 zero = v8_splat(0.0f), r = v8_pair(b0->r, b1->r);
    cw_float8 dx = v8_splat(d.x), dy = v8_splat(d.y), dz = v8_splat(d.z);
    cw_float8 fx = v8_sub(v8_splat(o.x), v8_pair(b0->cx, b1->cx)),
              fy = v8_sub(v8_splat(o.y), v8_pair(b0->cy, b1->cy));
    cw_float8 fz = v8_sub(v8_splat(o.z), v8_pair(b0->cz, b1->cz));
    cw_float8 bb = v8_add(v8_add(v8_mul(fx, dx), v8_mul(fy, dy)), v8_mul(fz, dz));
    cw_float8 px = v8_sub(fx, v8_mul(dx, bb)), py = v8_sub(fy, v8_mul(dy, bb));
    cw_float8 pz = v8_sub(fz, v8_mul(dz, bb));
    cw_float8 rr = v8_mul(r, r);
    cw_float8 disc = v8_sub(rr, v8_add(v8_add(v8_mul(px, px), v8_mul(py, py)), v8_mul(pz, pz)));
    cw_float8 cc, q, t0, t1, lo, hi, t;
    cw_int8 swap, near, far;
    float lt[8];
    unsigned m = ~m8_bits(v8_lt(disc, zero)) & lanes; /* isect_sphere's disc < 0: a miss */
    int i, best = -1;
    if (m == 0u)
        return -1;
    cc = v8_sub(v8_add(v8_add(v8_mul(fx, fx), v8_mul(fy, fy)), v8_mul(fz, fz)), rr);
    q = v8_sub(v8_mul(bb, v8_splat(-1.0f)),
               v8_mul(v8_select(v8_ge(bb, zero), v8_splat(1.0f), v8_splat(-1.0f)), v8_sqrt(disc)));
    t0 = q;
    t1 = v8_div(cc, q);
    swap = v8_gt(t0, t1);
    lo = v8_select(swap, t1, t0);
    hi = v8_select(swap, t0, t1);
    near = m8_and(m8_and(v8_gt(lo, v8_splat(tmin)), v8_lt(lo, v8_splat(tmax))), v8_gt(r, zero));
    far = m8_and(v8_gt(hi, v8_splat(tmin)), v8_lt(hi, v8_splat(tmax)));
    m &= m8_bits(m8_and(m8_or(near, far), v8_ne(q, zero)));
    if (m == 0u)
        return -1;
    t = v8_select(near, lo, hi);
    v8_store(t, lt);
    while (m != 0u) {
        i = cw_ctz(m);
        m &= m - 1u;
        if ((i < 4 ? b0 : b1)->index[i & 3] < 0 || !(lt[i] < tmax))
            continue;
        tmax = lt[i];
        *t_out = lt[i];
        best = i;
    }
    return best;
}

/* Sphere i of block b as the sphere array holds it (cw_sphere.center): xyz its centre, w its
 * radius. */
CW_INLINE cw_float4 sph4_sphere(CW_GLOBAL const cw_sph4 *b, int i)
{
    CW_GLOBAL const float *x = (CW_GLOBAL const float *)&b->cx;
    return v4_from3(v3(x[i], x[4 + i], x[8 + i]), x[12 + i]);
}

/* The surface at a sphere hit; p = o + t d is projected back onto the sphere. The
 * geometric normal points outwards for an inside-only sphere too (refraction tells a ray
 * entering its inside by it, as for any sphere). A hit in a block (hit.block) reads the
 * block the test has just read, not the sphere array. */
CW_INLINE cw_surface surface_sphere(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    cw_float4 sphere;
    vec3 c, n;
    int material;
    if (hit.block > 0) {
        CW_GLOBAL const cw_sph4 *b = &w->sph_blocks[hit.block - 1];
        sphere = sph4_sphere(b, hit.lane);
        material = b->material[hit.lane];
    } else {
        sphere = w->spheres[hit.index].center;
        material = w->sphere_materials[hit.index];
    }
    c = v3_from4(sphere);
    n = v3_norm(v3_sub(p, c));
    s.ng = n;
#if !CW_FAST
    {
        float r = cw_fabs(sphere.w);
        p = v3_add(c, v3_scale(n, r));
        /* c is exact input: the error is that of r n (normalisation) and of the sum */
        s.err = v3_add(v3_scale(v3_abs(p), CW_GAMMA(2)),
                       v3_scale(v3(1.0f, 1.0f, 1.0f), CW_GAMMA(6) * r));
    }
#endif
    s.ns = s.ng;
    s.flat = 0;
    s.material = material;
    s.p = p;
    return s;
}

#endif
