/* The kernels' feature flags, each 0 or 1: which primitive kinds and which
 * secondary rays are compiled in, the fast path and the statistics counters. The renderer
 * passes every one of them as -D (host/render.c); host code and tests that compile the
 * kernel headers as C99 get the defaults below. The checks on them are here too. */
#ifndef CW_FLAGS_H
#define CW_FLAGS_H

#ifndef CW_HAS_SPHERES
#define CW_HAS_SPHERES 1
#endif
#ifndef CW_HAS_TRIANGLES
#define CW_HAS_TRIANGLES 1
#endif
#ifndef CW_HAS_POLYGONS
#define CW_HAS_POLYGONS 1
#endif
#ifndef CW_HAS_CONES
#define CW_HAS_CONES 1
#endif
/* placed meshes: the two-level BVH (instance.h) */
#ifndef CW_HAS_INSTANCES
#define CW_HAS_INSTANCES 1
#endif
#ifndef CW_HAS_MIRRORS
#define CW_HAS_MIRRORS 1
#endif
#ifndef CW_HAS_REFRACTION
#define CW_HAS_REFRACTION 1
#endif
/* 1: the fast path, built with -cl-fast-relaxed-math (textbook formulas, plain epsilons);
 * 0: the robust path */
#ifndef CW_FAST
#define CW_FAST 0
#endif
/* 1: count hits and blocked shadow rays (the counters of types.h) */
#ifndef CW_STATS
#define CW_STATS 0
#endif
/* The execution strategy whose entry kernels the program holds: 1: the per-pixel kernel
 * (cw_pixel, for CPUs); 0: the wavefront kernels (cw_raygen, cw_intersect, cw_shade,
 * cw_occlude, for GPUs). */
#ifndef CW_PIXEL
#define CW_PIXEL 0
#endif

#if (CW_HAS_SPHERES | CW_HAS_TRIANGLES | CW_HAS_POLYGONS | CW_HAS_CONES | CW_HAS_INSTANCES |       \
     CW_HAS_MIRRORS | CW_HAS_REFRACTION | CW_FAST | CW_STATS | CW_PIXEL) &                         \
    ~1
#error "feature flags CW_HAS_*, CW_FAST, CW_STATS and CW_PIXEL must be 0 or 1"
#endif
#if CW_HAS_INSTANCES && !CW_HAS_TRIANGLES
#error "instances place meshes of triangles: CW_HAS_INSTANCES needs CW_HAS_TRIANGLES"
#endif
#if !CW_FAST && defined(__FAST_RELAXED_MATH__)
#error "the robust path (CW_FAST=0) must not be built with -cl-fast-relaxed-math"
#endif

#endif
