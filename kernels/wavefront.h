/* wave_: the wavefront strategy's shading step (for GPUs): shading one queued ray adds its
 * ambient term (or the background) to the pixel and appends a shadow ray per facing light
 * and the next level's refraction and mirror rays to queues, with the formulas of
 * shade.h; the occlusion kernel later adds each unblocked light (clwhitted.cl). */
#ifndef CW_WAVEFRONT_H
#define CW_WAVEFRONT_H

#include "flags.h"
#include "shade.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* Adds c to pixel's rgb when several work-items may add to the same pixel at once. */
CW_INLINE void wave_add(CW_GLOBAL float *image, int pixel, vec3 c)
{
    if (c.x != 0.0f)
        cw_atomic_add(&image[4 * pixel + 0], c.x);
    if (c.y != 0.0f)
        cw_atomic_add(&image[4 * pixel + 1], c.y);
    if (c.z != 0.0f)
        cw_atomic_add(&image[4 * pixel + 2], c.z);
}

/* Adds c to pixel's rgb from the shade and occlude kernels. Without refraction a level
 * holds at most one ray per pixel, so a plain add is safe there; with it, a ray's refracted
 * and reflected children share the pixel. */
CW_INLINE void wave_add_local(CW_GLOBAL float *image, int pixel, vec3 c)
{
#if CW_HAS_REFRACTION
    wave_add(image, pixel, c);
#else
    image[4 * pixel + 0] += c.x;
    image[4 * pixel + 1] += c.y;
    image[4 * pixel + 2] += c.z;
#endif
}

CW_INLINE void wave_put_ray(CW_GLOBAL cw_ray *out, int slot, vec3 o, vec3 d, vec3 weight,
                            const cw_ray *parent, int skip, int skip_inst)
{
    cw_ray r;
    r.origin = v4_from3(o, 0.0f);
    r.dir = v4_from3(d, 0.0f);
    r.weight = v4_from3(weight, 0.0f);
    r.pixel = parent->pixel;
    r.depth = parent->depth + 1;
    r.skip = skip;
    r.skip_inst = skip_inst;
    out[slot] = r;
}

/* Shades *ray at hit (see the file comment). A miss adds the background. Each ray
 * reserves its queue slots with one atomic add per queue (not one per shadow ray); its
 * shadow rays are consecutive, the first holding their count (cw_shadow_ray.block), in
 * light order. */
CW_INLINE void wave_shade(const cw_world *w, CW_GLOBAL const cw_frame *f,
                          CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                          const cw_ray *ray, cw_hit hit, CW_GLOBAL float *image,
                          CW_GLOBAL cw_ray *out, CW_GLOBAL cw_shadow_ray *shadows,
                          CW_GLOBAL int *counters)
{
    vec3 weight = v3_from4(ray->weight);
    int k, count, slot, first;
    shade_point sp;
    shade_next nx;

    if (hit.kind == CW_PRIM_NONE) {
        wave_add_local(image, ray->pixel, shade_background(f, weight));
        return;
    }
    sp = shade_at(w, materials, v3_from4(ray->origin), v3_from4(ray->dir), weight, hit);
    wave_add_local(image, ray->pixel, shade_ambient(f, &sp));
    /* a shadow ray for each light the surface faces: count, reserve, write */
    count = 0;
    for (k = 0; k < f->num_lights; k++)
        if (shade_faces(&sp, v3_from4(lights[k].position)))
            count++;
    slot = count > 0 ? cw_atomic_add_int(&counters[CW_COUNT_SHADOWS], count) : 0;
    first = 1;
    for (k = 0; k < f->num_lights && count > 0; k++) {
        vec3 lp = v3_from4(lights[k].position);
        vec3 o, l;
        float tmax;
        cw_shadow_ray sr;
        if (!shade_faces(&sp, lp)) /* facing away: no contribution, no shadow ray */
            continue;
        tmax = shade_shadow_ray(&sp, lp, &o, &l);
        sr.origin = v4_from3(o, tmax);
        sr.dir = v4_from3(l, 0.0f);
        sr.color = v4_from3(shade_light(&sp, l, v3_from4(lights[k].intensity)), 0.0f);
        sr.pixel = ray->pixel;
        sr.skip = sp.s.flat;
        sr.block = first ? count : 0;
        sr.skip_inst = sp.s.inst;
        first = 0;
        shadows[slot++] = sr;
    }

    if (ray->depth >= f->max_depth)
        return;
    nx = shade_secondary(&sp, f->spd_rays);
    if (nx.refract + nx.reflect > 0) {
        slot = cw_atomic_add_int(&counters[CW_COUNT_RAYS], nx.refract + nx.reflect);
        if (nx.refract)
            wave_put_ray(out, slot++, nx.t_o, nx.t_d, nx.t_weight, ray, nx.skip, nx.skip_inst);
        if (nx.reflect)
            wave_put_ray(out, slot, nx.r_o, nx.r_d, nx.r_weight, ray, nx.skip, nx.skip_inst);
    }
}

#endif
