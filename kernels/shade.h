/* shade_: Blinn-Phong shading with shadow rays and ideal mirror reflection
 * (Shirley & Marschner 4.5-4.8), one ray-tree level per call: the host loops over
 * the depths, so there is no recursion. */
#ifndef CW_SHADE_H
#define CW_SHADE_H

#include "intersect.h"
#include "types.h"

#ifndef CW_HAS_MIRRORS
#define CW_HAS_MIRRORS 1
#endif

/* Unit geometric normal at a hit (not yet turned towards the ray). */
CW_INLINE vec3 shade_geometric_normal(const cw_world *w, cw_hit hit, vec3 p)
{
    if (hit.kind == CW_PRIM_SPHERE) {
        CW_GLOBAL const cw_sphere *s = &w->spheres[hit.index];
        return v3_norm(v3_sub(p, v3_from4(s->center)));
    }
    if (hit.kind == CW_PRIM_TRIANGLE) {
        CW_GLOBAL const cw_triangle *t = &w->triangles[hit.index];
        vec3 p0 = v3_from4(t->p0);
        return v3_norm(v3_cross(v3_sub(v3_from4(t->p1), p0), v3_sub(v3_from4(t->p2), p0)));
    }
    return v3_from4(w->polygons[hit.index].plane);
}

CW_INLINE int shade_material(const cw_world *w, cw_hit hit)
{
    if (hit.kind == CW_PRIM_SPHERE)
        return w->spheres[hit.index].material;
    if (hit.kind == CW_PRIM_TRIANGLE)
        return w->triangles[hit.index].material;
    return w->polygons[hit.index].material;
}

/* The distance by which secondary rays leave a surface: relative to the size of the
 * hit point's coordinates, so that it scales with the scene. */
CW_INLINE float shade_offset(vec3 p)
{
    float m = cw_fmax(cw_fmax(cw_fabs(p.x), cw_fabs(p.y)), cw_fmax(cw_fabs(p.z), 1.0f));
    return 1e-4f * m;
}

/* Shades *ray at hit: returns what it adds to its pixel and turns *ray into the mirror
 * ray of the next level, or ends it (pixel = -1). A miss returns the background. */
CW_INLINE vec3 shade_ray(const cw_world *w, CW_GLOBAL const cw_frame *f,
                         CW_GLOBAL const cw_light *lights, CW_GLOBAL const cw_material *materials,
                         cw_ray *ray, cw_hit hit)
{
    vec3 weight = v3_from4(ray->weight);
    vec3 o = v3_from4(ray->origin);
    vec3 d = v3_from4(ray->dir);
    vec3 p, ng, n, color, ka, kd, ks;
    float phong, eps;
    int k;
    CW_GLOBAL const cw_material *m;

    if (hit.kind == CW_PRIM_NONE) {
        ray->pixel = -1;
        return v3_mul(weight, v3_from4(f->background));
    }
    p = v3_add(o, v3_scale(d, hit.t));
    ng = shade_geometric_normal(w, hit, p);
    if (v3_dot(ng, d) > 0.0f) /* two-sided: use the side facing the ray */
        ng = v3_scale(ng, -1.0f);
    n = ng;
    if (hit.kind == CW_PRIM_TRIANGLE && w->triangles[hit.index].smooth) {
        CW_GLOBAL const cw_triangle *t = &w->triangles[hit.index];
        vec3 sn = v3_add(v3_scale(v3_from4(t->n0), 1.0f - hit.u - hit.v),
                         v3_add(v3_scale(v3_from4(t->n1), hit.u), v3_scale(v3_from4(t->n2), hit.v)));
        n = v3_norm(sn);
        if (v3_dot(n, d) > 0.0f)
            n = v3_scale(n, -1.0f);
    }
    m = &materials[shade_material(w, hit)];
    ka = v3_from4(m->ka);
    kd = v3_from4(m->kd);
    ks = v3_from4(m->ks);
    phong = m->ka.w;
    eps = shade_offset(p);

    color = v3_mul(ka, v3_from4(f->ambient));
    for (k = 0; k < f->num_lights; k++) {
        vec3 to_light = v3_sub(v3_from4(lights[k].position), p);
        float dist = v3_len(to_light);
        vec3 l, h, intensity;
        float ndl, ndh;

        if (!(dist > 0.0f))
            continue;
        l = v3_scale(to_light, 1.0f / dist);
        ndl = v3_dot(n, l);
        if (ndl <= 0.0f) /* facing away: no contribution and no shadow ray */
            continue;
        if (isect_any(w, v3_add(p, v3_scale(ng, eps)), l, 0.0f, dist - eps))
            continue;
        intensity = v3_from4(lights[k].intensity);
        h = v3_norm(v3_sub(l, d));
        ndh = cw_fmax(0.0f, v3_dot(n, h));
        color = v3_add(color, v3_mul(v3_add(v3_scale(kd, ndl), v3_scale(ks, cw_pow(ndh, phong))),
                                     intensity));
    }
    color = v3_mul(weight, color);

#if CW_HAS_MIRRORS
    vec3 km = v3_from4(m->km);
    if (ray->depth < f->max_depth && (km.x > 0.0f || km.y > 0.0f || km.z > 0.0f)) {
        vec3 r = v3_sub(d, v3_scale(n, 2.0f * v3_dot(d, n)));
        ray->origin = v4_from3(v3_add(p, v3_scale(ng, eps)), 0.0f);
        ray->dir = v4_from3(v3_norm(r), 0.0f);
        ray->weight = v4_from3(v3_mul(weight, km), 0.0f);
        ray->depth += 1;
        return color;
    }
#endif
    ray->pixel = -1;
    return color;
}

#endif
