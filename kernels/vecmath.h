/* v3_, v4_, vl_: vector arithmetic on vec3 (three floats), cw_float4 and cw_lanes (CW_BVH_WIDTH
 * floats: the lanes of one box test of the wide BVH), for the kernel headers: written once for
 * OpenCL C (vector operators and built-ins) and once for host C99 (the structs of compat.h), so
 * that the kernel headers compile as both. */
#ifndef CW_VECMATH_H
#define CW_VECMATH_H

#include "compat.h"

#ifdef __OPENCL_VERSION__

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
/* four lanes (the triangles of a cw_tri4) */
CW_INLINE cw_float4 v4_splat(float a)
{
    return (float4)(a);
}
CW_INLINE cw_float4 v4_add(cw_float4 a, cw_float4 b)
{
    return a + b;
}
CW_INLINE cw_float4 v4_sub(cw_float4 a, cw_float4 b)
{
    return a - b;
}
CW_INLINE cw_float4 v4_mul(cw_float4 a, cw_float4 b)
{
    return a * b;
}
CW_INLINE cw_float4 v4_div(cw_float4 a, cw_float4 b)
{
    return a / b;
}
CW_INLINE void v4_store(cw_float4 a, float *p)
{
    vstore4(a, 0, p);
}
/* lane masks of four (the triangles of a cw_tri4): comparisons, and, or, and-not, bits */
CW_INLINE cw_int4 v4_lt(cw_float4 a, cw_float4 b)
{
    return a < b;
}
CW_INLINE cw_int4 v4_gt(cw_float4 a, cw_float4 b)
{
    return a > b;
}
CW_INLINE cw_int4 v4_ne(cw_float4 a, cw_float4 b)
{
    return a != b;
}
CW_INLINE cw_int4 v4_ge(cw_float4 a, cw_float4 b)
{
    return a >= b;
}
/* m ? a : b per lane */
CW_INLINE cw_float4 v4_select(cw_int4 m, cw_float4 a, cw_float4 b)
{
    return select(b, a, m);
}
CW_INLINE cw_float4 v4_sqrt(cw_float4 a)
{
    return sqrt(a);
}
CW_INLINE cw_int4 m4_and(cw_int4 a, cw_int4 b)
{
    return a & b;
}
CW_INLINE cw_int4 m4_or(cw_int4 a, cw_int4 b)
{
    return a | b;
}
/* ~a & b */
CW_INLINE cw_int4 m4_andnot(cw_int4 a, cw_int4 b)
{
    return ~a & b;
}
/* the lanes set, as a bit mask (bit i: lane i) */
CW_INLINE unsigned m4_bits(cw_int4 m)
{
    int4 h = m & (int4)(1, 2, 4, 8);
    int2 q = h.lo | h.hi;
    return (unsigned)(q.x | q.y);
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
/* a / b per component: one vector division */
CW_INLINE vec3 v3_div(vec3 a, vec3 b)
{
    return a / b;
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
/* the lanes of one box test */
CW_INLINE cw_lanes vl_splat(float a)
{
    return (cw_lanes)(a);
}
CW_INLINE cw_lanes vl_sub(cw_lanes a, cw_lanes b)
{
    return a - b;
}
CW_INLINE cw_lanes vl_mul(cw_lanes a, cw_lanes b)
{
    return a * b;
}
/* min and max without fmin/fmax's NaN rules (the box test never sees a NaN) */
CW_INLINE cw_lanes vl_min(cw_lanes a, cw_lanes b)
{
    return a < b ? a : b;
}
CW_INLINE cw_lanes vl_max(cw_lanes a, cw_lanes b)
{
    return a > b ? a : b;
}
/* The lanes of a comparison's result m (-1 true, 0 false) as a bit mask (bit i: lane i).
 * On x86 with AVX (PoCL's and Intel's CPU devices) one movemask of the sign bits;
 * elsewhere the lanes' bits or'ed together. */
CW_INLINE unsigned vl_bits(cw_lanes_int m)
{
#if CW_BVH_WIDTH == 8 && defined(__AVX__) && defined(__x86_64__)
    return (unsigned)__builtin_ia32_movmskps256(as_float8(m));
#else
#if CW_BVH_WIDTH == 8
    int8 b = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
    int4 h = b.lo | b.hi;
#else
    int4 h = m & (int4)(1, 2, 4, 8);
#endif
    int2 q = h.lo | h.hi;
    return (unsigned)(q.x | q.y);
#endif
}
/* The lanes where a <= b, as a bit mask */
CW_INLINE unsigned vl_le_mask(cw_lanes a, cw_lanes b)
{
    return vl_bits(a <= b);
}
/* p[0, CW_BVH_WIDTH) = the lanes of a */
CW_INLINE void vl_store(cw_lanes a, float *p)
{
#if CW_BVH_WIDTH == 8
    vstore8(a, 0, p);
#else
    vstore4(a, 0, p);
#endif
}
/* The lanes where p[lane] == 0, as a bit mask: one vector load and compare */
CW_INLINE unsigned vl_zero_mask(CW_GLOBAL const int *p)
{
#if CW_BVH_WIDTH == 8
    return vl_bits(vload8(0, p) == (int8)(0));
#else
    return vl_bits(vload4(0, p) == (int4)(0));
#endif
}
#else /* host C99 */

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
#define V4_OP(name, op)                                                                            \
    CW_INLINE cw_float4 name(cw_float4 a, cw_float4 b)                                             \
    {                                                                                              \
        a.x = a.x op b.x;                                                                          \
        a.y = a.y op b.y;                                                                          \
        a.z = a.z op b.z;                                                                          \
        a.w = a.w op b.w;                                                                          \
        return a;                                                                                  \
    }
V4_OP(v4_add, +)
V4_OP(v4_sub, -)
V4_OP(v4_mul, *)
V4_OP(v4_div, /)
#undef V4_OP
CW_INLINE cw_float4 v4_splat(float a)
{
    cw_float4 r;
    r.x = r.y = r.z = r.w = a;
    return r;
}
CW_INLINE void v4_store(cw_float4 a, float *p)
{
    p[0] = a.x;
    p[1] = a.y;
    p[2] = a.z;
    p[3] = a.w;
}
#define V4_CMP(name, op)                                                                           \
    CW_INLINE cw_int4 name(cw_float4 a, cw_float4 b)                                               \
    {                                                                                              \
        cw_int4 r;                                                                                 \
        r.x = -(a.x op b.x);                                                                       \
        r.y = -(a.y op b.y);                                                                       \
        r.z = -(a.z op b.z);                                                                       \
        r.w = -(a.w op b.w);                                                                       \
        return r;                                                                                  \
    }
V4_CMP(v4_lt, <)
V4_CMP(v4_gt, >)
V4_CMP(v4_ne, !=)
V4_CMP(v4_ge, >=)
#undef V4_CMP
#define M4_OP(name, expr)                                                                          \
    CW_INLINE cw_int4 name(cw_int4 a, cw_int4 b)                                                   \
    {                                                                                              \
        cw_int4 r;                                                                                 \
        r.x = expr(a.x, b.x);                                                                      \
        r.y = expr(a.y, b.y);                                                                      \
        r.z = expr(a.z, b.z);                                                                      \
        r.w = expr(a.w, b.w);                                                                      \
        return r;                                                                                  \
    }
#define M4_AND(a, b) ((a) & (b))
#define M4_OR(a, b) ((a) | (b))
#define M4_ANDNOT(a, b) (~(a) & (b))
M4_OP(m4_and, M4_AND)
M4_OP(m4_or, M4_OR)
M4_OP(m4_andnot, M4_ANDNOT)
#undef M4_OP
#undef M4_AND
#undef M4_OR
#undef M4_ANDNOT
CW_INLINE unsigned m4_bits(cw_int4 m)
{
    return (unsigned)((m.x & 1) | (m.y & 2) | (m.z & 4) | (m.w & 8));
}
CW_INLINE cw_float4 v4_select(cw_int4 m, cw_float4 a, cw_float4 b)
{
    cw_float4 r;
    r.x = m.x ? a.x : b.x;
    r.y = m.y ? a.y : b.y;
    r.z = m.z ? a.z : b.z;
    r.w = m.w ? a.w : b.w;
    return r;
}
CW_INLINE cw_float4 v4_sqrt(cw_float4 a)
{
    cw_float4 r;
    r.x = sqrtf(a.x);
    r.y = sqrtf(a.y);
    r.z = sqrtf(a.z);
    r.w = sqrtf(a.w);
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
CW_INLINE vec3 v3_div(vec3 a, vec3 b)
{
    return v3(a.x / b.x, a.y / b.y, a.z / b.z);
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
CW_INLINE cw_lanes vl_splat(float a)
{
    cw_lanes r;
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        r.v[i] = a;
    return r;
}
CW_INLINE cw_lanes vl_sub(cw_lanes a, cw_lanes b)
{
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        a.v[i] -= b.v[i];
    return a;
}
CW_INLINE cw_lanes vl_mul(cw_lanes a, cw_lanes b)
{
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        a.v[i] *= b.v[i];
    return a;
}
CW_INLINE cw_lanes vl_min(cw_lanes a, cw_lanes b)
{
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        a.v[i] = a.v[i] < b.v[i] ? a.v[i] : b.v[i];
    return a;
}
CW_INLINE cw_lanes vl_max(cw_lanes a, cw_lanes b)
{
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        a.v[i] = a.v[i] > b.v[i] ? a.v[i] : b.v[i];
    return a;
}
CW_INLINE unsigned vl_le_mask(cw_lanes a, cw_lanes b)
{
    unsigned m = 0;
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        if (a.v[i] <= b.v[i])
            m |= 1u << i;
    return m;
}
CW_INLINE void vl_store(cw_lanes a, float *p)
{
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        p[i] = a.v[i];
}
CW_INLINE unsigned vl_zero_mask(const int *p)
{
    unsigned m = 0;
    int i;
    for (i = 0; i < CW_BVH_WIDTH; i++)
        if (p[i] == 0)
            m |= 1u << i;
    return m;
}
#endif

/* |a| per coordinate */
CW_INLINE vec3 v3_abs(vec3 a)
{
    return v3(cw_fabs(a.x), cw_fabs(a.y), cw_fabs(a.z));
}

#endif
