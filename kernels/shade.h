/* shade_: Blinn-Phong shading, shadow rays, ideal mirror reflection and Snell refraction
 * (Shirley & Marschner 4.5-4.8, 13.1), one ray-tree level at a time: shading a ray adds
 * its ambient term to the pixel and appends a shadow ray per light and the next level's
 * reflection and refraction rays to queues. No recursion. */
#ifndef CW_SHADE_H
#define CW_SHADE_H

#include "flags.h"
#include "prim.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

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
    po.x = off.x > 0.0f   ? cw_nextafter(po.x, CW_INFINITY)
           : off.x < 0.0f ? cw_nextafter(po.x, -CW_INFINITY)
                          : po.x;
    po.y = off.y > 0.0f   ? cw_nextafter(po.y, CW_INFINITY)
           : off.y < 0.0f ? cw_nextafter(po.y, -CW_INFINITY)
                          : po.y;
    po.z = off.z > 0.0f   ? cw_nextafter(po.z, CW_INFINITY)
           : off.z < 0.0f ? cw_nextafter(po.z, -CW_INFINITY)
                          : po.z;
    return po;
#endif
}

/* x^p for 0 <= x <= 1 and p >= 0, as exp2(p log2 x): several times cheaper than a
 * full-range pow, with a relative error of a few 1e-7 for the exponents of real
 * materials. */
CW_INLINE float shade_pow(float x, float p)
{
    if (p == 0.0f)
        return 1.0f;
    if (!(x > 0.0f))
        return 0.0f;
    return cw_exp2(p * cw_log2(x));
}

/* Adds c to pixel's rgb when several work-items may add to the same pixel at once. */
CW_INLINE void shade_add(CW_GLOBAL float *image, int pixel, vec3 c)
{
    if (c.x != 0.0f)
        cw_atomic_add(&image[4 * pixel + 0], c.x);
    if (c.y != 0.0f)
        cw_atomic_add(&image[4 * pixel + 1], c.y);
    if (c.z != 0.0f)
        cw_atomic_add(&image[4 * pixel + 2], c.z);
}

/* Adds c to pixel's rgb from the shade kernel. Without refraction a level holds at most
 * one ray per pixel, so a plain add is safe there; with it, a ray's refracted and
 * reflected children share the pixel. */
CW_INLINE void shade_add_local(CW_GLOBAL float *image, int pixel, vec3 c)
{
#if CW_HAS_REFRACTION
    shade_add(image, pixel, c);
#else
    image[4 * pixel + 0] += c.x;
    image[4 * pixel + 1] += c.y;
    image[4 * pixel + 2] += c.z;
#endif
}

CW_INLINE int shade_nonzero(vec3 c)
{
    return c.x > 0.0f || c.y > 0.0f || c.z > 0.0f;
}

CW_INLINE void shade_put_ray(CW_GLOBAL cw_ray *out, int slot, vec3 o, vec3 d, vec3 weight,
                             const cw_ray *parent, int skip)
{
    cw_ray r;
    r.origin = v4_from3(o, 0.0f);
    r.dir = v4_from3(d, 0.0f);
    r.weight = v4_from3(weight, 0.0f);
    r.pixel = parent->pixel;
    r.depth = parent->depth + 1;
    r.skip = skip;
    r.pad0 = 0;
    out[slot] = r;
}

/* Shades *ray at hit (see the file comment). A miss adds the background. Each ray
 * reserves its queue slots with one atomic add per queue (not one per shadow ray). */
CW_INLINE void shade_ray(const cw_world *w, CW_GLOBAL const cw_frame *f,
                         CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                         const cw_ray *ray, cw_hit hit, CW_GLOBAL float *image,
                         CW_GLOBAL cw_ray *out, CW_GLOBAL cw_shadow_ray *shadows,
                         CW_GLOBAL int *counters)
{
    vec3 weight = v3_from4(ray->weight);
    vec3 d = v3_from4(ray->dir);
    vec3 n, ka, kd, ks, km, kt;
    float phong;
    int k, count, slot, first;
    cw_surface s;
    CW_GLOBAL const cw_material *m;

    if (hit.kind == CW_PRIM_NONE) {
        shade_add_local(image, ray->pixel, v3_mul(weight, v3_from4(f->background)));
        return;
    }
    s = prim_surface(w, hit, v3_from4(ray->origin), d);
    /* two-sided: shade the side facing the ray */
    n = v3_dot(s.ns, d) > 0.0f ? v3_scale(s.ns, -1.0f) : s.ns;
    m = &materials[s.material];
    ka = v3_from4(m->ka);
    kd = v3_from4(m->kd);
    ks = v3_from4(m->ks);
    km = v3_from4(m->km);
    kt = v3_from4(m->kt);
    phong = m->ka.w;

    shade_add_local(image, ray->pixel, v3_mul(weight, v3_mul(ka, v3_from4(f->ambient))));
    /* a shadow ray for each light the surface faces (n.l > 0): count, reserve, write */
    count = 0;
    for (k = 0; k < f->num_lights; k++)
        if (v3_dot(n, v3_sub(v3_from4(lights[k].position), s.p)) > 0.0f)
            count++;
    slot = count > 0 ? cw_atomic_add_int(&counters[CW_COUNT_SHADOWS], count) : 0;
    first = 1;
    for (k = 0; k < f->num_lights && count > 0; k++) {
        vec3 lp = v3_from4(lights[k].position);
        vec3 to_light = v3_sub(lp, s.p);
        float dist = v3_len(to_light);
        vec3 l, h, c, o;
        float ndl, ndh;
        cw_shadow_ray sr;

        if (!(v3_dot(n, to_light) > 0.0f)) /* facing away: no contribution, no shadow ray */
            continue;
        l = v3_scale(to_light, 1.0f / dist);
        ndl = cw_fmax(v3_dot(n, l), 0.0f);
        h = v3_norm(v3_sub(l, d));
        ndh = cw_fmax(0.0f, v3_dot(n, h));
        c = v3_mul(v3_add(v3_scale(kd, ndl), v3_scale(ks, shade_pow(ndh, phong))),
                   v3_mul(weight, v3_from4(lights[k].intensity)));
        o = shade_spawn(&s, l);
        sr.origin = v4_from3(o, v3_len(v3_sub(lp, o)));
        sr.dir = v4_from3(l, 0.0f);
        sr.color = v4_from3(c, 0.0f);
        sr.pixel = ray->pixel;
        sr.skip = s.flat;
        sr.block = first ? count : 0;
        sr.pad0 = 0;
        first = 0;
        shadows[slot++] = sr;
    }

    if (ray->depth >= f->max_depth)
        return;
#if CW_HAS_MIRRORS || CW_HAS_REFRACTION
    {
        vec3 refl_weight = km, td = v3(0.0f, 0.0f, 0.0f);
        int reflect = shade_nonzero(km), refract = 0;
#if CW_HAS_REFRACTION
        if (shade_nonzero(kt)) {
            /* inside or outside from the geometric normal's side; shading stays two-sided */
            int entering = v3_dot(d, s.ng) < 0.0f;
            float ior = m->kt.w > 0.0f ? m->kt.w : 1.0f;
            float eta = entering ? 1.0f / ior : ior;
            float cosi = -v3_dot(d, n);
            float k2 = 1.0f - eta * eta * (1.0f - cosi * cosi);
            if (f->spd_rays)
                reflect = 1;
            if (k2 < 0.0f) { /* total internal reflection: the transmitted share reflects */
                refl_weight = v3_add(refl_weight, kt);
                reflect = 1;
            } else {
                td = v3_norm(v3_add(v3_scale(d, eta), v3_scale(n, eta * cosi - cw_sqrt(k2))));
                refract = 1;
            }
        }
#endif
        if (reflect + refract > 0) {
            slot = cw_atomic_add_int(&counters[CW_COUNT_RAYS], reflect + refract);
            if (refract)
                shade_put_ray(out, slot++, shade_spawn(&s, td), td, v3_mul(weight, kt), ray,
                              s.flat);
            if (reflect) {
                vec3 r = v3_norm(v3_sub(d, v3_scale(n, 2.0f * v3_dot(d, n))));
                shade_put_ray(out, slot, shade_spawn(&s, r), r, v3_mul(weight, refl_weight), ray,
                              s.flat);
            }
        }
    }
#endif
    (void)km;
    (void)kt;
}

#endif
