/* Thin entry kernels: index, bounds check, one call into the domain headers. */
#include "camera.h"
#include "intersect.h"
#include "shade.h"
#include "types.h"

#if (CW_HAS_SPHERES | CW_HAS_TRIANGLES | CW_HAS_POLYGONS | CW_HAS_MIRRORS) & ~1
#error "feature flags CW_HAS_* must be 0 or 1"
#endif

#define CW_WORLD_ARGS                                                                              \
    __global const cw_sphere *spheres, __global const cw_triangle *triangles,                      \
        __global const cw_polygon *polygons, __global const float4 *poly_verts

static cw_world make_world(__global const cw_frame *f, __global const cw_sphere *spheres,
                           __global const cw_triangle *triangles,
                           __global const cw_polygon *polygons, __global const float4 *poly_verts)
{
    cw_world w;
    w.spheres = spheres;
    w.triangles = triangles;
    w.polygons = polygons;
    w.poly_verts = poly_verts;
    w.num_spheres = f->num_spheres;
    w.num_triangles = f->num_triangles;
    w.num_polygons = f->num_polygons;
    return w;
}

/* 2-D launch over a band of rows: x = column, y = row within the band (image row 0 at
 * the top). Ray k of the band is pixel (x, row0 + y); the pixel's sample count (.w of
 * the accumulation image) goes up by one. */
__kernel void cw_raygen(__global const cw_frame *f, __global cw_ray *rays, __global float4 *image,
                        int row0, int nrows, float sx, float sy)
{
    int x = (int)get_global_id(0);
    int y = (int)get_global_id(1);
    int row = row0 + y;
    cw_ray ray;
    if (x >= f->nx || y >= nrows)
        return;
    ray = cam_ray(f, x, f->ny - 1 - row, sx, sy);
    rays[y * f->nx + x] = ray;
    image[ray.pixel].w += 1.0f;
}

__kernel void cw_intersect(__global const cw_frame *f, CW_WORLD_ARGS, __global const cw_ray *rays,
                           __global cw_hit *hits, int n)
{
    int gid = (int)get_global_id(0);
    cw_world w;
    cw_ray ray;
    if (gid >= n)
        return;
    ray = rays[gid];
    if (ray.pixel < 0)
        return;
    w = make_world(f, spheres, triangles, polygons, poly_verts);
    hits[gid] = isect_closest(&w, ray.origin.xyz, ray.dir.xyz, 0.0f, INFINITY);
}

/* Adds each ray's shading to its pixel and leaves the next level's ray in its place;
 * counts the rays that go on. One ray per pixel per level, so no two work-items write
 * the same pixel. */
__kernel void cw_shade(__global const cw_frame *f, CW_WORLD_ARGS, __global const cw_light *lights,
                       __global const cw_material *materials, __global cw_ray *rays,
                       __global const cw_hit *hits, __global float4 *image, __global int *alive,
                       int n)
{
    int gid = (int)get_global_id(0);
    cw_world w;
    cw_ray ray;
    int pixel;
    float3 c;
    if (gid >= n)
        return;
    ray = rays[gid];
    pixel = ray.pixel;
    if (pixel < 0)
        return;
    w = make_world(f, spheres, triangles, polygons, poly_verts);
    c = shade_ray(&w, f, lights, materials, &ray, hits[gid]);
    image[pixel] += (float4)(c, 0.0f);
    rays[gid] = ray;
    if (ray.pixel >= 0)
        atomic_inc(alive);
}
