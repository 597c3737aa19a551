/* What differs between OpenCL C 1.2 and host C99, and nothing else: the address-space
 * and inline keywords (CW_GLOBAL, CW_INLINE, CW_FORCE_INLINE), the vector types
 * (cw_float4, cw_float8, cw_int8, vec3, cw_lanes), the math functions (cw_sqrt ...) and bit casts
 * (cw_as_int), the bit scan cw_ctz, the atomics and the contraction pragma. The kernel headers are
 * written with these so that they compile both as OpenCL C (the kernels) and as host C99 (host code
 * and tests). OpenCL C appears elsewhere only in the OpenCL branch of vecmath.h (vector operators
 * and built-ins) and in the entry kernels of clwhitted.cl (__kernel, __global, __local, work-item
 * functions and barriers), which the host never compiles. */
#ifndef CW_COMPAT_H
#define CW_COMPAT_H

/* The width of the BVH the kernels traverse (cw_bvhw_node, types.h): the child boxes of a
 * node are tested together, as one vector of CW_BVH_WIDTH lanes: 8 fills an AVX register,
 * 4 an SSE one. */
#ifndef CW_BVH_WIDTH
#define CW_BVH_WIDTH 8
#endif
#if CW_BVH_WIDTH != 4 && CW_BVH_WIDTH != 8
#error "CW_BVH_WIDTH must be 4 or 8"
#endif

#ifdef __OPENCL_VERSION__

#define CW_GLOBAL __global
#define CW_INLINE static inline
/* inlined even where the compiler would rather call (a hot function with several callers) */
#define CW_FORCE_INLINE static inline __attribute__((always_inline))

typedef float4 cw_float4;
/* the eight lanes of one test: a block of triangles (cw_tri8), two blocks of spheres (cw_sph4) */
typedef float8 cw_float8;
typedef int8 cw_int8; /* a lane mask of eight: -1 true, 0 false */
typedef float3 vec3;
/* the lanes of one box test of the wide BVH */
#if CW_BVH_WIDTH == 8
typedef float8 cw_lanes;
typedef int8 cw_lanes_int;
#else
typedef float4 cw_lanes;
typedef int4 cw_lanes_int;
#endif

#define cw_sqrt(x) sqrt(x)
#define cw_fabs(x) fabs(x)
#define cw_fmax(a, b) fmax((a), (b))
#define cw_fmin(a, b) fmin((a), (b))
#define cw_atomic_add_int(p, v) atomic_add((p), (v))
#define cw_floor(a) floor(a)
#define cw_as_int(a) as_int(a)
#define cw_as_float(a) as_float(a)
#define cw_copysign(a, b) copysign((a), (b))
/* c - a b: one fused multiply-add where the device has one (fma, rounded once; the host C
 * version is fmaf too), else a product and a difference: never the software fma of a device
 * without it. (OpenCL's mad would allow either, but PoCL builds it as the two operations under
 * FP_CONTRACT OFF.) Written only where each operand is rounded the same way for every
 * primitive that shares it: the robust triangle test's shear of a vertex. */
#if defined(FP_FAST_FMAF) || defined(__FMA__)
#define cw_nmad(a, b, c) fma(-(a), (b), (c))
#else
#define cw_nmad(a, b, c) (-(a) * (b) + (c))
#endif
#define CW_INFINITY INFINITY
/* the index of the lowest set bit of x (x != 0). OpenCL 1.2 has clz but not ctz: clang
 * compiling for the device itself (PoCL) makes one tzcnt of the builtin, where
 * 31 - clz(x & -x) took three instructions in every lane loop of the walks (100k random
 * triangles at 256x256: kernel instructions 216.3M -> 209.1M, the same images). Not where
 * the program goes through SPIR (__SPIR__: Intel's runtime, Oclgrind): the builtin becomes
 * llvm.cttz, an intrinsic SPIR does not list and Oclgrind cannot run ("Undefined external
 * function"). Any other compiler, and the portability lint, sees the clz form. */
#if defined(__clang__) && !defined(__SPIR__) && defined(__has_builtin)
#if __has_builtin(__builtin_ctz)
#define cw_ctz(x) __builtin_ctz(x)
#endif
#endif
#ifndef cw_ctz
#define cw_ctz(x) (31 - (int)clz((x) & (0u - (x))))
#endif

/* The robust path relies on a*b - c*d being computed the same way for both triangles of
 * a shared edge: no fused multiply-add contraction (cw_nmad fuses where asked). */
#pragma OPENCL FP_CONTRACT OFF

/* Atomic float add through compare-and-swap on the bits (OpenCL 1.2 has no float
 * atomics). Every access to *p is atomic (a plain first read would race with another
 * work-item's swap): the first swap, expecting 0, reads the current value. */
CW_INLINE void cw_atomic_add(volatile __global float *p, float v)
{
    volatile __global unsigned int *u = (volatile __global unsigned int *)p;
    union {
        unsigned int u;
        float f;
    } old, upd;
    unsigned int prev;
    old.u = 0u;
    upd.f = v;
    while ((prev = atomic_cmpxchg(u, old.u, upd.u)) != old.u) {
        old.u = prev;
        upd.f = old.f + v;
    }
}

#else /* host C99 */

#include <math.h>

#define CW_GLOBAL
#define CW_INLINE static inline
#define CW_FORCE_INLINE static inline __attribute__((always_inline))

typedef struct {
    float x, y, z, w;
} __attribute__((aligned(16))) cw_float4;

typedef struct {
    float v[8];
} __attribute__((aligned(32))) cw_float8;

typedef struct {
    int v[8];
} cw_int8;

typedef struct {
    float x, y, z;
} vec3;

typedef struct {
    float v[CW_BVH_WIDTH];
} __attribute__((aligned(4 * CW_BVH_WIDTH))) cw_lanes;

#define cw_sqrt(x) sqrtf(x)
#define cw_fabs(x) fabsf(x)
#define cw_fmax(a, b) fmaxf((a), (b))
#define cw_fmin(a, b) fminf((a), (b))
CW_INLINE int cw_atomic_add_int(int *p, int v)
{
    int old = *p;
    *p += v;
    return old;
}
#define cw_floor(a) floorf(a)
/* the bits of a float as an int, and back (OpenCL's as_int, as_float) */
CW_INLINE int cw_as_int(float f)
{
    union {
        float f;
        int i;
    } u;
    u.f = f;
    return u.i;
}
CW_INLINE float cw_as_float(int i)
{
    union {
        float f;
        int i;
    } u;
    u.i = i;
    return u.f;
}
#define cw_copysign(a, b) copysignf((a), (b))
#define cw_nmad(a, b, c) fmaf(-(a), (b), (c))
#define CW_INFINITY INFINITY
#define cw_ctz(x) __builtin_ctz(x)
CW_INLINE void cw_atomic_add(float *p, float v)
{
    *p += v;
}

#endif

#endif
