/* The only place OpenCL keywords appear. The kernel headers include this file, so
 * that they compile both as OpenCL C 1.2 and as host C99 (for host-side use and
 * tests): vectors are used only through the v3_* functions below. */
#ifndef CW_COMPAT_H
#define CW_COMPAT_H

#ifdef __OPENCL_VERSION__

#define CW_GLOBAL __global
#define CW_INLINE static inline

typedef float4 cw_float4;
typedef float3 vec3;

CW_INLINE vec3 v3(float x, float y, float z)
{
    return (float3)(x, y, z);
}
CW_INLINE vec3 v3_from4(cw_float4 a)
{
    return a.xyz;
}
CW_INLINE cw_float4 v4_from3(vec3 a, float w)
{
    return (float4)(a, w);
}
CW_INLINE vec3 v3_add(vec3 a, vec3 b)
{
    return a + b;
}
CW_INLINE vec3 v3_sub(vec3 a, vec3 b)
{
    return a - b;
}
CW_INLINE vec3 v3_mul(vec3 a, vec3 b)
{
    return a * b;
}
CW_INLINE vec3 v3_scale(vec3 a, float s)
{
    return a * s;
}
CW_INLINE float v3_dot(vec3 a, vec3 b)
{
    return dot(a, b);
}
CW_INLINE vec3 v3_cross(vec3 a, vec3 b)
{
    return cross(a, b);
}
CW_INLINE float v3_len(vec3 a)
{
    return length(a);
}
CW_INLINE vec3 v3_norm(vec3 a)
{
    return normalize(a);
}
/* 4-wide: the four lanes of one box test of the 4-wide BVH */
typedef float4 v4;
CW_INLINE v4 v4_splat(float a)
{
    return (float4)(a);
}
CW_INLINE v4 v4_sub(v4 a, v4 b)
{
    return a - b;
}
CW_INLINE v4 v4_mul(v4 a, v4 b)
{
    return a * b;
}
/* min and max without fmin/fmax's NaN rules (the box test never sees a NaN) */
CW_INLINE v4 v4_min(v4 a, v4 b)
{
    return a < b ? a : b;
}
CW_INLINE v4 v4_max(v4 a, v4 b)
{
    return a > b ? a : b;
}
CW_INLINE float v4_get(v4 a, int i)
{
    return i == 0 ? a.x : (i == 1 ? a.y : (i == 2 ? a.z : a.w));
}
#define cw_sqrt(x) sqrt(x)
#define cw_fabs(x) fabs(x)
#define cw_fmax(a, b) fmax((a), (b))
#define cw_fmin(a, b) fmin((a), (b))
#define cw_exp2(a) exp2(a)
#define cw_log2(a) log2(a)
#define cw_atomic_add_int(p, v) atomic_add((p), (v))
#define cw_nextafter(a, b) nextafter((a), (b))
#define cw_copysign(a, b) copysign((a), (b))
#define CW_INFINITY INFINITY

/* The robust path relies on a*b - c*d being computed the same way for both triangles of
 * a shared edge: no fused multiply-add contraction. */
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

typedef struct {
    float x, y, z, w;
} __attribute__((aligned(16))) cw_float4;

typedef struct {
    float x, y, z;
} vec3;

CW_INLINE vec3 v3(float x, float y, float z)
{
    vec3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}
CW_INLINE vec3 v3_from4(cw_float4 a)
{
    return v3(a.x, a.y, a.z);
}
CW_INLINE cw_float4 v4_from3(vec3 a, float w)
{
    cw_float4 r;
    r.x = a.x;
    r.y = a.y;
    r.z = a.z;
    r.w = w;
    return r;
}
CW_INLINE vec3 v3_add(vec3 a, vec3 b)
{
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
CW_INLINE vec3 v3_sub(vec3 a, vec3 b)
{
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
CW_INLINE vec3 v3_mul(vec3 a, vec3 b)
{
    return v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
CW_INLINE vec3 v3_scale(vec3 a, float s)
{
    return v3(a.x * s, a.y * s, a.z * s);
}
CW_INLINE float v3_dot(vec3 a, vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
CW_INLINE vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
CW_INLINE float v3_len(vec3 a)
{
    return sqrtf(v3_dot(a, a));
}
CW_INLINE vec3 v3_norm(vec3 a)
{
    return v3_scale(a, 1.0f / v3_len(a));
}
typedef cw_float4 v4;
CW_INLINE v4 v4_splat(float a)
{
    v4 r;
    r.x = r.y = r.z = r.w = a;
    return r;
}
CW_INLINE v4 v4_sub(v4 a, v4 b)
{
    a.x -= b.x;
    a.y -= b.y;
    a.z -= b.z;
    a.w -= b.w;
    return a;
}
CW_INLINE v4 v4_mul(v4 a, v4 b)
{
    a.x *= b.x;
    a.y *= b.y;
    a.z *= b.z;
    a.w *= b.w;
    return a;
}
CW_INLINE v4 v4_min(v4 a, v4 b)
{
    a.x = a.x < b.x ? a.x : b.x;
    a.y = a.y < b.y ? a.y : b.y;
    a.z = a.z < b.z ? a.z : b.z;
    a.w = a.w < b.w ? a.w : b.w;
    return a;
}
CW_INLINE v4 v4_max(v4 a, v4 b)
{
    a.x = a.x > b.x ? a.x : b.x;
    a.y = a.y > b.y ? a.y : b.y;
    a.z = a.z > b.z ? a.z : b.z;
    a.w = a.w > b.w ? a.w : b.w;
    return a;
}
CW_INLINE float v4_get(v4 a, int i)
{
    return i == 0 ? a.x : (i == 1 ? a.y : (i == 2 ? a.z : a.w));
}
#define cw_sqrt(x) sqrtf(x)
#define cw_fabs(x) fabsf(x)
#define cw_fmax(a, b) fmaxf((a), (b))
#define cw_fmin(a, b) fminf((a), (b))
#define cw_exp2(a) exp2f(a)
#define cw_log2(a) log2f(a)
CW_INLINE int cw_atomic_add_int(int *p, int v)
{
    int old = *p;
    *p += v;
    return old;
}
#define cw_nextafter(a, b) nextafterf((a), (b))
#define cw_copysign(a, b) copysignf((a), (b))
#define CW_INFINITY INFINITY
CW_INLINE void cw_atomic_add(float *p, float v)
{
    *p += v;
}

#endif

#endif
