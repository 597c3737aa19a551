/* v3_, v4_: vector arithmetic on vec3 (three floats) and v4 (four floats: the lanes of one
 * 4-wide box test of the BVH), for the kernel headers: written once for OpenCL C (vector
 * operators and built-ins) and once for host C99 (the structs of compat.h), so that the
 * kernel headers compile as both. */
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
/* 4-wide */
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
#endif

/* |a| per coordinate */
CW_INLINE vec3 v3_abs(vec3 a)
{
    return v3(cw_fabs(a.x), cw_fabs(a.y), cw_fabs(a.z));
}

#endif
