/* shade_: the shading formulas both execution strategies share (Shirley & Marschner
 * 4.5-4.8, 13.1): the shading point of a hit, its ambient term and the background of a
 * miss, the shadow ray toward a light and the light's Blinn-Phong term, and the ideal
 * mirror and Snell refraction rays it spawns, with their origins moved off the surface.
 * The wavefront (wavefront.h) queues the shadow and secondary rays for later kernels; the
 * per-pixel kernel (pixel.h) traces them in place. No recursion. */
#ifndef CW_SHADE_H
#define CW_SHADE_H

#include "flags.h"
#include "prim.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* The next float after x toward +infinity (dir > 0) or -infinity (dir < 0), x itself when
 * dir = 0: nextafter on the bits, for a finite x. */
CW_INLINE float shade_nudge(float x, float dir)
{
    if (dir == 0.0f)
        return x;
    if (x == 0.0f)
        return cw_as_float(dir > 0.0f ? 1 : (int)0x80000001);
    return cw_as_float(cw_as_int(x) + ((x > 0.0f) == (dir > 0.0f) ? 1 : -1));
}

/* The origin of a ray leaving the surface in direction dir: the point moved along the
 * geometric normal, to dir's side, past its error bound, then one more ulp away per
 * coordinate (pbrt, 3rd ed., 3.9.5), so the new ray starts on the right side of the
 * surface at any scene scale. The fast path moves it by a plain 1e-4. */
CW_INLINE vec3 shade_spawn(const cw_surface *s, vec3 dir)
{
    vec3 ng = v3_dot(dir, s->ng) < 0.0f ? v3_scale(s->ng, -1.0f) : s->ng;
#if CW_FAST
    return v3_add(s->p, v3_scale(ng, 1e-4f));
#else
    float dist = v3_dot(v3_abs(ng), s->err);
    vec3 off = v3_scale(ng, dist);
    vec3 po = v3_add(s->p, off);
    return v3(shade_nudge(po.x, off.x), shade_nudge(po.y, off.y), shade_nudge(po.z, off.z));
#endif
}

/* x^p for 0 <= x <= 1 and p >= 0, as 2^(p log2 x) from short series on the float's
 * exponent and mantissa, the same operations on every device (no library exp2 and log2,
 * whose bits differ between OpenCL implementations, and which took 140 instructions per
 * call on PoCL): log2 x = e + 2 atanh((m - 1) / (m + 1)) / ln 2 for x = m 2^e, m in
 * [sqrt(1/2), sqrt(2)) (series to s^9, |s| < 0.172), and 2^y = 2^i 2^f for the nearest
 * integer i and |f| <= 1/2 (the series of e^(f ln 2) to f^7). Both series are summed in
 * Estrin's order (pairs, then pairs of pairs) rather than Horner's: the same terms, half
 * as long a chain of dependent operations, which is what the call's time is. Relative
 * error 1.7e-7 (1 + |p log2 x|) at worst, 2.3 times the float library's (test_robust); 0
 * below 2^-126 and for x below the normal floats. */
CW_INLINE float shade_pow(float x, float p)
{
    int bits, e, i;
    float m, s, s2, s4, y, f, f2, f4, q;
    if (p == 0.0f)
        return 1.0f;
    if (!(x >= 1.17549435e-38f))
        return 0.0f;
    /* x = m 2^e with m in [sqrt(1/2), sqrt(2)): 0x3f3504f3 is sqrt(1/2)'s bits (the shift
     * is of a positive number: 128 added to the exponent and taken off after) */
    bits = cw_as_int(x);
    e = ((bits - 0x3f3504f3 + (128 << 23)) >> 23) - 128;
    m = cw_as_float(bits - e * (1 << 23)); /* e < 0: a product, not a shift */
    s = (m - 1.0f) / (m + 1.0f);
    s2 = s * s;
    s4 = s2 * s2;
    q = (1.0f + s2 * (1.0f / 3.0f)) + s4 * ((0.2f + s2 * (1.0f / 7.0f)) + s4 * (1.0f / 9.0f));
    y = p * ((float)e + (2.88539008f * s) * q);
    if (!(y >= -126.0f))
        return 0.0f;
    /* i the nearest integer (-126 <= y <= 0: the conversion rounds y - 1/2 up) */
    i = (int)(y - 0.5f);
    f = y - (float)i;
    f2 = f * f;
    f4 = f2 * f2;
    /* the coefficients (ln 2)^k / k! */
    q = ((1.0f + f * 0.693147181f) + f2 * (0.240226507f + f * 0.0555041087f)) +
        f4 * ((0.00961812911f + f * 0.00133335581f) + f2 * (0.000154035304f + f * 1.52527338e-05f));
    return q * cw_as_float((i + 127) << 23);
}

CW_INLINE int shade_nonzero(vec3 c)
{
    return c.x > 0.0f || c.y > 0.0f || c.z > 0.0f;
}

/* A hit as shading needs it: the surface, the shading normal turned to face the ray
 * (shading is two-sided), the ray's direction and weight (the product of the mirror and
 * transmission colours on its path), and the surface's material. */
typedef struct {
    cw_surface s;
    vec3 n, d, weight;
    CW_GLOBAL const cw_material *m;
} shade_point;

/* The shading point of the ray o + t d (weight: its weight) at hit (not a miss). */
CW_INLINE shade_point shade_at(const cw_world *w, CW_GLOBAL const cw_material *materials, vec3 o,
                               vec3 d, vec3 weight, cw_hit hit)
{
    shade_point sp;
    sp.s = prim_surface(w, hit, o, d);
    sp.n = v3_dot(sp.s.ns, d) > 0.0f ? v3_scale(sp.s.ns, -1.0f) : sp.s.ns;
    sp.d = d;
    sp.weight = weight;
    sp.m = &materials[sp.s.material];
    return sp;
}

/* What a ray of this weight that hits nothing adds to its pixel. */
CW_INLINE vec3 shade_background(CW_GLOBAL const cw_frame *f, vec3 weight)
{
    return v3_mul(weight, v3_from4(f->background));
}

/* The ambient term of a shading point: weight ka Ia. */
CW_INLINE vec3 shade_ambient(CW_GLOBAL const cw_frame *f, const shade_point *sp)
{
    return v3_mul(sp->weight, v3_mul(v3_from4(sp->m->ka), v3_from4(f->ambient)));
}

/* Whether the shading point faces the light at lp (n.l > 0): only then does the light
 * get a shadow ray and a term. */
CW_INLINE int shade_faces(const shade_point *sp, vec3 lp)
{
    return v3_dot(sp->n, v3_sub(lp, sp->s.p)) > 0.0f;
}

/* The shadow ray toward the light at lp: its unit direction *l and origin *o (moved off
 * the surface); returns the distance from *o to the light, the ray's tmax. The ray never
 * hits the primitive it leaves, sp->s.flat - 1 (its skip). */
CW_INLINE float shade_shadow_ray(const shade_point *sp, vec3 lp, vec3 *o, vec3 *l)
{
    vec3 to_light = v3_sub(lp, sp->s.p);
    float dist = v3_len(to_light);
    *l = v3_scale(to_light, 1.0f / dist);
    *o = shade_spawn(&sp->s, *l);
    return v3_len(v3_sub(lp, *o));
}

/* The Blinn-Phong term of a light of this intensity in direction l (unit, facing), to be
 * added when nothing blocks its shadow ray: (kd n.l + ks (n.h)^p) weight intensity. With
 * ks = 0 the power is not computed: ks (n.h)^p would be +0, which leaves the sum as it is. */
CW_INLINE vec3 shade_light(const shade_point *sp, vec3 l, vec3 intensity)
{
    vec3 kd = v3_from4(sp->m->kd), ks = v3_from4(sp->m->ks);
    float ndl = cw_fmax(v3_dot(sp->n, l), 0.0f);
    vec3 c = v3_scale(kd, ndl);
    if (ks.x != 0.0f || ks.y != 0.0f || ks.z != 0.0f) {
        vec3 h = v3_norm(v3_sub(l, sp->d));
        float ndh = cw_fmax(0.0f, v3_dot(sp->n, h));
        c = v3_add(c, v3_scale(ks, shade_pow(ndh, sp->m->ka.w)));
    }
    return v3_mul(c, v3_mul(sp->weight, intensity));
}

/* The secondary rays of a shading point (below the maximum depth): a refraction ray and a
 * mirror ray, each when there is one. Each leaves from its origin (moved off the surface)
 * in its unit direction with its weight, and never hits the primitive it leaves (skip). */
typedef struct {
    int refract, reflect;    /* 0 or 1 each */
    int skip, skip_inst;     /* as in cw_ray: the surface's flat and inst */
    vec3 t_o, t_d, t_weight; /* the refraction ray */
    vec3 r_o, r_d, r_weight; /* the mirror ray */
} shade_next;

/* spd_rays: SPD counting, where a transmitter also spawns a mirror ray when km = 0. */
CW_INLINE shade_next shade_secondary(const shade_point *sp, int spd_rays)
{
    shade_next nx;
    nx.refract = nx.reflect = 0;
    nx.skip = sp->s.flat;
    nx.skip_inst = sp->s.inst;
#if CW_HAS_MIRRORS || CW_HAS_REFRACTION
    {
        vec3 km = v3_from4(sp->m->km), refl_weight = km;
#if CW_HAS_REFRACTION
        vec3 kt = v3_from4(sp->m->kt);
#endif
        nx.reflect = shade_nonzero(km);
#if CW_HAS_REFRACTION
        if (shade_nonzero(kt)) {
            /* inside or outside from the geometric normal's side; shading stays two-sided */
            int entering = v3_dot(sp->d, sp->s.ng) < 0.0f;
            float ior = sp->m->kt.w > 0.0f ? sp->m->kt.w : 1.0f;
            float eta = entering ? 1.0f / ior : ior;
            float cosi = -v3_dot(sp->d, sp->n);
            float k2 = 1.0f - eta * eta * (1.0f - cosi * cosi);
            if (spd_rays)
                nx.reflect = 1;
            if (k2 < 0.0f) { /* total internal reflection: the transmitted share reflects */
                refl_weight = v3_add(refl_weight, kt);
                nx.reflect = 1;
            } else {
                nx.t_d = v3_norm(
                    v3_add(v3_scale(sp->d, eta), v3_scale(sp->n, eta * cosi - cw_sqrt(k2))));
                nx.t_o = shade_spawn(&sp->s, nx.t_d);
                nx.t_weight = v3_mul(sp->weight, kt);
                nx.refract = 1;
            }
        }
#endif
        if (nx.reflect) {
            nx.r_d = v3_norm(v3_sub(sp->d, v3_scale(sp->n, 2.0f * v3_dot(sp->d, sp->n))));
            nx.r_o = shade_spawn(&sp->s, nx.r_d);
            nx.r_weight = v3_mul(sp->weight, refl_weight);
        }
    }
#endif
    (void)sp;
    (void)spd_rays;
    return nx;
}

#endif
