/* Thin entry kernels: index, bounds check, one call into the domain headers. The program
 * holds one execution strategy's kernels (CW_PIXEL, flags.h):
 * - per pixel (CPUs): cw_pixel traces the whole ray tree of one pixel sample per
 *   work-item, shadow rays in place (pixel.h);
 * - wavefront (GPUs): raygen fills the ray queue; per level, intersect finds each queued
 *   ray's closest hit, shade adds ambient/background to the pixel and appends shadow rays
 *   and the next level's rays (wavefront.h), and occlude adds each unblocked shadow ray's
 *   light. */
#include "camera.h"
#include "flags.h"
#include "isect.h"
#include "pixel.h"
#include "shade.h"
#include "traverse.h"
#include "types.h"
#include "wavefront.h"
#include "world.h"

#if CW_STATS
/* Adds a work-item's walk counts (BVH_COUNT, traverse.h) to the counters. */
static void cw_add_walk(__global int *counters, const int *walk)
{
    for (int k = 0; k < CW_WALK_COUNTS; k++)
        if (walk[k] != 0)
            atomic_add(&counters[CW_COUNT_CLOSEST_NODES + k], walk[k]);
}
#endif

#if CW_PIXEL

/* Rows [row0, row0 + nrows) in tiles of CW_PIX_TILE x CW_PIX_TILE pixels, row by row within a
 * tile, handed out one at a time through the counter CW_COUNT_NEXT (zero at launch). A tile's
 * rays are neighbours in both directions, so one core's cache keeps the nodes and blocks they
 * share (with runs of 32 pixels of a row, the two threads taking alternate runs, 1M random
 * triangles rendered 2-5% slower at 512x512). A work-item takes tiles until none is left, so
 * the threads of a CPU device finish together however unevenly the scene spreads its work
 * over the image (with a row per work-group, PoCL's threads took the groups in large chunks
 * and one core idled at the end of each launch: 5-15% of the render at 512x512). The counts
 * are summed in private memory and added to the counters once per work-item (the maximum for
 * CW_COUNT_DEPTH); no barrier. (A local-memory sum with a barrier after a guarded call let
 * PoCL 3.1 run pix_trace for padded work-items, writing past the image: see
 * docs/portability.md.) */
/* vec_type_hint(float4): the kernel's own vector width. Intel's CPU compiler otherwise runs
 * eight work-items in the lanes of one AVX register, and their rays diverge: mount took
 * 1.58 s against 0.20 s without it at 512x512, gears 2.14 s against 0.32 s (PoCL: no change). */
__kernel __attribute__((vec_type_hint(float4))) void
cw_pixel(CW_WORLD_ARGS, __global const cw_light *lights, __global const cw_material *materials,
         __global float *image, __global int *counters, int row0, int nrows, float sx, float sy,
         int first)
{
    int cols = (f->nx + CW_PIX_TILE - 1) / CW_PIX_TILE, k;
    int jobs = cols * ((nrows + CW_PIX_TILE - 1) / CW_PIX_TILE);
    pix_state st;
    cw_world w;
    int walk[CW_WALK_COUNTS];
    CW_MAKE_WORLD(w, walk);
    pix_clear(&st);
    for (;;) {
        int job = atomic_inc(&counters[CW_COUNT_NEXT]), ty, y, y1, x, x0, x1;
        if (job >= jobs)
            break;
        ty = job / cols;
        y1 = min(nrows, (ty + 1) * CW_PIX_TILE);
        x0 = (job - ty * cols) * CW_PIX_TILE;
        x1 = min(f->nx, x0 + CW_PIX_TILE);
        for (y = ty * CW_PIX_TILE; y < y1; y++)
            for (x = x0; x < x1; x++)
                pix_trace(&w, f, lights, materials, image, x, f->ny - 1 - (row0 + y), sx, sy, first,
                          &st);
    }
    for (k = 0; k < CW_COUNT_DEPTH; k++)
        if (pix_counted(k) && st.n[k] != 0)
            atomic_add(&counters[k], st.n[k]);
    if (st.n[CW_COUNT_DEPTH] > 1)
        atomic_max(&counters[CW_COUNT_DEPTH], st.n[CW_COUNT_DEPTH]);
#if CW_STATS
    cw_add_walk(counters, walk);
#endif
}

#else

/* 2-D launch over a band of rows: x = column, y = row within the band (image row 0 at
 * the top). Ray k of the band is pixel (x, row0 + y); the pixel's sample count (.w of
 * the accumulation image) goes up by one. */
__kernel void cw_raygen(__global const cw_frame *f, __global cw_ray *rays, __global float *image,
                        int row0, int nrows, float sx, float sy)
{
    int x = (int)get_global_id(0);
    int y = (int)get_global_id(1);
    cw_ray ray;
    if (x >= f->nx || y >= nrows)
        return;
    ray = cam_ray(f, x, f->ny - 1 - (row0 + y), sx, sy);
    rays[y * f->nx + x] = ray;
    image[4 * ray.pixel + 3] += 1.0f;
}

__kernel void cw_intersect(CW_WORLD_ARGS, __global const cw_ray *rays, __global cw_hit *hits,
                           __global int *counters, int n)
{
    int gid = (int)get_global_id(0);
    cw_world w;
    cw_ray ray;
    cw_hit hit;
    int walk[CW_WALK_COUNTS];
    if (gid >= n)
        return;
    ray = rays[gid];
    CW_MAKE_WORLD(w, walk);
    bvh_closest(&w, ray.origin.xyz, ray.dir.xyz, 0.0f, CW_FAR, ray.skip, ray.skip_inst, &hit);
    hits[gid] = hit;
#if CW_STATS
    if (hit.kind != CW_PRIM_NONE)
        atomic_inc(&counters[ray.depth == 1 ? CW_COUNT_EYE_HITS : CW_COUNT_SECONDARY_HITS]);
    cw_add_walk(counters, walk);
#else
    (void)counters;
#endif
}

__kernel void cw_shade(CW_WORLD_ARGS, __global const cw_light *lights,
                       __global const cw_material *materials, __global const cw_ray *rays,
                       __global const cw_hit *hits, __global float *image, __global cw_ray *out,
                       __global cw_shadow_ray *shadows, __global int *counters, int n)
{
    int gid = (int)get_global_id(0);
    cw_world w;
    cw_ray ray;
    int walk[CW_WALK_COUNTS]; /* no walk here */
    if (gid >= n)
        return;
    ray = rays[gid];
    CW_MAKE_WORLD(w, walk);
    wave_shade(&w, f, lights, materials, &ray, hits[gid], image, out, shadows, counters);
}

/* One work-item per shading point: the first of its consecutive shadow rays (block > 0)
 * tests them all and adds the sum of the unblocked lights to the pixel, in light order,
 * so the image does not depend on which work-item runs first. Without refraction a level
 * holds one shading point per pixel and the add needs no atomic. */
__kernel void cw_occlude(CW_WORLD_ARGS, __global const cw_shadow_ray *shadows,
                         __global float *image, __global int *counters, int n)
{
    int gid = (int)get_global_id(0), i, block;
    cw_world w;
    float3 sum = (float3)(0.0f, 0.0f, 0.0f);
    int walk[CW_WALK_COUNTS];
    if (gid >= n || (block = shadows[gid].block) == 0)
        return;
    CW_MAKE_WORLD(w, walk);
    for (i = gid; i < gid + block && i < n; i++) {
        cw_shadow_ray sr = shadows[i];
        bvh_occluder oc; /* no shadow cache: a work-item's shadow rays are one point's */
        oc.tag = BVH_OCC_NONE;
        if (bvh_any(&w, sr.origin.xyz, sr.dir.xyz, 0.0f, sr.origin.w, sr.skip, sr.skip_inst, &oc)) {
#if CW_STATS
            atomic_inc(&counters[CW_COUNT_BLOCKED]);
#endif
            continue;
        }
        sum += sr.color.xyz;
    }
    wave_add_local(image, shadows[gid].pixel, sum);
#if CW_STATS
    cw_add_walk(counters, walk);
#endif
    (void)counters;
}

#endif
