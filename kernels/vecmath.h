/* v3_, v4_, v8_, vl_: vector arithmetic on vec3 (three floats), cw_float4, cw_float8 (the lanes
 * of one test of eight primitives) and cw_lanes (CW_BVH_WIDTH floats: the lanes of
 * one box test of the wide BVH), for the kernel headers: written once for
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
/* Eight lanes: the primitives of one test (a block of eight triangles, cw_tri8, or one or two
 * blocks of four spheres, cw_sph4).
 * v8_pair reads lanes 0-3 from a, 4-7 from b. Written lane by lane, not (float8)(a, b): that
 * is a shuffle from four lanes to eight, on which Oclgrind 21.10's --uninitialized check
 * crashes (the optimised build makes the same one shuffle of it either way). */
CW_INLINE cw_float8 v8_pair(cw_float4 a, cw_float4 b)
{
    return (float8)(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w);
}
CW_INLINE cw_float8 v8_splat(float a)
{
    return (float8)(a);
}
CW_INLINE cw_float8 v8_add(cw_float8 a, cw_float8 b)
{
    return a + b;
}
CW_INLINE cw_float8 v8_sub(cw_float8 a, cw_float8 b)
{
    return a - b;
}
CW_INLINE cw_float8 v8_mul(cw_float8 a, cw_float8 b)
{
    return a * b;
}
CW_INLINE cw_float8 v8_div(cw_float8 a, cw_float8 b)
{
    return a / b;
}
/* the lesser and greater of a and b per lane, as x86's minps and maxps: b where either is NaN */
CW_INLINE cw_float8 v8_min(cw_float8 a, cw_float8 b)
{
    return a < b ? a : b;
}
CW_INLINE cw_float8 v8_max(cw_float8 a, cw_float8 b)
{
    return a > b ? a : b;
}
/* c - a b (see cw_nmad) */
CW_INLINE cw_float8 v8_nmad(cw_float8 a, cw_float8 b, cw_float8 c)
{
    return cw_nmad(a, b, c);
}
CW_INLINE void v8_store(cw_float8 a, float *p)
{
    vstore8(a, 0, p);
}
/* lane masks of eight: comparisons, and, or, and-not, bits */
CW_INLINE cw_int8 v8_lt(cw_float8 a, cw_float8 b)
{
    return a < b;
}
CW_INLINE cw_int8 v8_gt(cw_float8 a, cw_float8 b)
{
    return a > b;
}
CW_INLINE cw_int8 v8_ne(cw_float8 a, cw_float8 b)
{
    return a != b;
}
CW_INLINE cw_int8 v8_ge(cw_float8 a, cw_float8 b)
{
    return a >= b;
}
/* m ? a : b per lane */
CW_INLINE cw_float8 v8_select(cw_int8 m, cw_float8 a, cw_float8 b)
{
    return select(b, a, m);
}
CW_INLINE cw_float8 v8_sqrt(cw_float8 a)
{
    return sqrt(a);
}
CW_INLINE cw_int8 m8_and(cw_int8 a, cw_int8 b)
{
    return a & b;
}
CW_INLINE cw_int8 m8_or(cw_int8 a, cw_int8 b)
{
    return a | b;
}
/* ~a & b */
CW_INLINE cw_int8 m8_andnot(cw_int8 a, cw_int8 b)
{
    return ~a & b;
}
/* the lanes set, as a bit mask (bit i: lane i): on x86 with AVX one movemask of the sign
 * bits, elsewhere the lanes' bits or'ed together */
CW_INLINE unsigned m8_bits(cw_int8 m)
{
#if defined(__AVX__) && defined(__x86_64__)
    return (unsigned)__builtin_ia32_movmskps256(as_float8(m));
#else
    int8 b = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
    int4 h = b.lo | b.hi;
    int2 q = h.lo | h.hi;
    return (unsigned)(q.x | q.y);
#endif
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
/* |a|, and a / |a|: as sqrt of the dot product d where that is plain (v3_plain_dot), else (a
 * huge or tiny vector) through length and normalize, which scale to avoid its overflow and
 * underflow (and cost three times the instructions on PoCL) */
CW_INLINE int v3_plain_dot(float d)
{
    return d >= 0x1p-100f && d <= 0x1p+100f;
}
CW_INLINE float v3_len(vec3 a)
{
    float d = dot(a, a);
    return v3_plain_dot(d) ? sqrt(d) : length(a);
}
CW_INLINE vec3 v3_norm(vec3 a)
{
    float d = dot(a, a);
    return v3_plain_dot(d) ? a * (1.0f / sqrt(d)) : normalize(a);
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
/* The lanes of a comparison's result m (-1 true, 0 false) as a bit mask (bit i: lane i). */
CW_INLINE unsigned vl_bits(cw_lanes_int m)
{
#if CW_BVH_WIDTH == 8
    return m8_bits(m);
#else
    int4 h = m & (int4)(1, 2, 4, 8);
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
CW_INLINE cw_float8 v8_pair(cw_float4 a, cw_float4 b)
{
    cw_float8 r;
    r.v[0] = a.x;
    r.v[1] = a.y;
    r.v[2] = a.z;
    r.v[3] = a.w;
    r.v[4] = b.x;
    r.v[5] = b.y;
    r.v[6] = b.z;
    r.v[7] = b.w;
    return r;
}
CW_INLINE cw_float8 v8_splat(float a)
{
    cw_float8 r;
    for (int i = 0; i < 8; i++)
        r.v[i] = a;
    return r;
}
#define V8_OP(name, op)                                                                            \
    CW_INLINE cw_float8 name(cw_float8 a, cw_float8 b)                                             \
    {                                                                                              \
        for (int i = 0; i < 8; i++)                                                                \
            a.v[i] = a.v[i] op b.v[i];                                                             \
        return a;                                                                                  \
    }
V8_OP(v8_add, +)
V8_OP(v8_sub, -)
V8_OP(v8_mul, *)
V8_OP(v8_div, /)
#undef V8_OP
CW_INLINE cw_float8 v8_min(cw_float8 a, cw_float8 b)
{
    for (int i = 0; i < 8; i++)
        a.v[i] = a.v[i] < b.v[i] ? a.v[i] : b.v[i];
    return a;
}
CW_INLINE cw_float8 v8_max(cw_float8 a, cw_float8 b)
{
    for (int i = 0; i < 8; i++)
        a.v[i] = a.v[i] > b.v[i] ? a.v[i] : b.v[i];
    return a;
}
CW_INLINE cw_float8 v8_nmad(cw_float8 a, cw_float8 b, cw_float8 c)
{
    for (int i = 0; i < 8; i++)
        c.v[i] = cw_nmad(a.v[i], b.v[i], c.v[i]);
    return c;
}
CW_INLINE void v8_store(cw_float8 a, float *p)
{
    for (int i = 0; i < 8; i++)
        p[i] = a.v[i];
}
#define V8_CMP(name, op)                                                                           \
    CW_INLINE cw_int8 name(cw_float8 a, cw_float8 b)                                               \
    {                                                                                              \
        cw_int8 r;                                                                                 \
        for (int i = 0; i < 8; i++)                                                                \
            r.v[i] = -(a.v[i] op b.v[i]);                                                          \
        return r;                                                                                  \
    }
V8_CMP(v8_lt, <)
V8_CMP(v8_gt, >)
V8_CMP(v8_ne, !=)
V8_CMP(v8_ge, >=)
#undef V8_CMP
#define M8_OP(name, expr)                                                                          \
    CW_INLINE cw_int8 name(cw_int8 a, cw_int8 b)                                                   \
    {                                                                                              \
        for (int i = 0; i < 8; i++)                                                                \
            a.v[i] = expr;                                                                         \
        return a;                                                                                  \
    }
M8_OP(m8_and, a.v[i] & b.v[i])
M8_OP(m8_or, a.v[i] | b.v[i])
M8_OP(m8_andnot, ~a.v[i] & b.v[i])
#undef M8_OP
CW_INLINE unsigned m8_bits(cw_int8 m)
{
    unsigned r = 0u;
    for (int i = 0; i < 8; i++)
        r |= (unsigned)(m.v[i] & 1) << i;
    return r;
}
CW_INLINE cw_float8 v8_select(cw_int8 m, cw_float8 a, cw_float8 b)
{
    for (int i = 0; i < 8; i++)
        a.v[i] = m.v[i] ? a.v[i] : b.v[i];
    return a;
}
CW_INLINE cw_float8 v8_sqrt(cw_float8 a)
{
    for (int i = 0; i < 8; i++)
        a.v[i] = sqrtf(a.v[i]);
    return a;
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
