/* Triangles (cw_triangle), flat or smooth (vertex normals): the ray-triangle test, one
 * triangle at a time or the eight of one block of a leaf at once (cw_tri8), and the surface at
 * a hit. */
#ifndef CW_TRIANGLE_H
#define CW_TRIANGLE_H

#include "flags.h"
#include "isect.h"
#include "surface.h"
#include "types.h"
#include "vecmath.h"
#include "world.h"

/* The eight lanes of row r of a block from its first half: r[0] (lanes 0-3) and r[1] (lanes
 * 4-7), which lie side by side (see cw_tri8): one load. */
CW_INLINE cw_float8 tri8_row(CW_GLOBAL const cw_float4 *r)
{
    return v8_pair(r[0], r[1]);
}

/* The lane of block b to report among the lanes m whose hits lie at lt[lane]: the closest
 * below tmax, leaving out unused lanes and the triangle whose CW_REF is skip - 1; the first
 * of equally close ones (as testing them one by one in lane order); -1 for none. Both
 * isect_tri8 paths end with it. */
CW_INLINE int tri8_nearest(CW_GLOBAL const cw_tri8 *b, unsigned m, const float *lt, float tmax,
                           int skip)
{
    int best = -1;
    while (m != 0u) {
        int i = cw_ctz(m), idx = b->index[i];
        m &= m - 1u;
        if (idx < 0 || CW_REF(CW_PRIM_TRIANGLE, idx) + 1 == skip || !(lt[i] < tmax))
            continue;
        tmax = lt[i];
        best = i;
    }
    return best;
}

#if CW_FAST
/* Ray-triangle, fast path: Moeller-Trumbore with a plain determinant epsilon. */
CW_INLINE int isect_triangle(CW_GLOBAL const cw_triangle *tri, const cw_rayinfo *ri, float tmin,
                             float tmax, float *t_out, float *u_out, float *v_out)
{
    vec3 p0 = v3_from4(tri->p0);
    vec3 e1 = v3_sub(v3_from4(tri->p1), p0);
    vec3 e2 = v3_sub(v3_from4(tri->p2), p0);
    vec3 pvec = v3_cross(ri->d, e2);
    float det = v3_dot(e1, pvec);
    float inv, u, v, t;
    vec3 s, qvec;

    if (cw_fabs(det) < 1e-9f)
        return 0;
    inv = 1.0f / det;
    s = v3_sub(ri->o, p0);
    u = v3_dot(s, pvec) * inv;
    if (u < 0.0f || u > 1.0f)
        return 0;
    qvec = v3_cross(s, e1);
    v = v3_dot(ri->d, qvec) * inv;
    if (v < 0.0f || u + v > 1.0f)
        return 0;
    t = v3_dot(e2, qvec) * inv;
    if (!(t > tmin && t < tmax))
        return 0;
    *t_out = t;
    *u_out = u;
    *v_out = v;
    return 1;
}

/* The eight triangles of block b at once (Moeller-Trumbore, each lane as isect_triangle; an
 * unused lane's zero vertices fail the determinant test): the closest hit in (tmin, tmax),
 * never the triangle whose CW_REF is skip - 1. Returns its lane,
 * the first of equally close ones (as testing them one by one in lane order), or -1.
 * isect_triangle's tests are lane masks, and a block whose lanes all fail the determinant
 * and u tests ends there (a loop over the lanes with a branch per test made --precision
 * fast 1.6x slower than robust on a million triangles). */
CW_INLINE int isect_tri8(CW_GLOBAL const cw_tri8 *b, const cw_rayinfo *ri, float tmin, float tmax,
                         int skip, float *t_out, float *u_out, float *v_out)
{
    cw_float8 dx = v8_splat(ri->d.x), dy = v8_splat(ri->d.y), dz = v8_splat(ri->d.z);
    cw_float8 p0x = tri8_row(b->v + 0), p0y = tri8_row(b->v + 2);
    cw_float8 p0z = tri8_row(b->v + 4);
    cw_float8 e1x = v8_sub(tri8_row(b->v + 6), p0x), e1y = v8_sub(tri8_row(b->v + 8), p0y);
    cw_float8 e1z = v8_sub(tri8_row(b->v + 10), p0z);
    cw_float8 e2x = v8_sub(tri8_row(b->v + 12), p0x), e2y = v8_sub(tri8_row(b->v + 14), p0y);
    cw_float8 e2z = v8_sub(tri8_row(b->v + 16), p0z);
    cw_float8 px = v8_sub(v8_mul(dy, e2z), v8_mul(dz, e2y));
    cw_float8 py = v8_sub(v8_mul(dz, e2x), v8_mul(dx, e2z));
    cw_float8 pz = v8_sub(v8_mul(dx, e2y), v8_mul(dy, e2x));
    cw_float8 det = v8_add(v8_add(v8_mul(e1x, px), v8_mul(e1y, py)), v8_mul(e1z, pz));
    cw_float8 inv = v8_div(v8_splat(1.0f), det);
    cw_float8 sx = v8_sub(v8_splat(ri->o.x), p0x), sy = v8_sub(v8_splat(ri->o.y), p0y);
    cw_float8 sz = v8_sub(v8_splat(ri->o.z), p0z);
    cw_float8 u = v8_mul(v8_add(v8_add(v8_mul(sx, px), v8_mul(sy, py)), v8_mul(sz, pz)), inv);
    cw_float8 zero = v8_splat(0.0f), one = v8_splat(1.0f), qx, qy, qz, v, t;
    /* isect_triangle's misses so far: |det| < 1e-9, u < 0, u > 1 */
    cw_int8 small = m8_and(v8_lt(det, v8_splat(1e-9f)), v8_gt(det, v8_splat(-1e-9f)));
    cw_int8 out = m8_or(small, m8_or(v8_lt(u, zero), v8_gt(u, one)));
    unsigned m = ~m8_bits(out) & 255u;
    float lu[8], lv[8], lt[8];
    int best;
    if (m == 0u)
        return -1;
    qx = v8_sub(v8_mul(sy, e1z), v8_mul(sz, e1y));
    qy = v8_sub(v8_mul(sz, e1x), v8_mul(sx, e1z));
    qz = v8_sub(v8_mul(sx, e1y), v8_mul(sy, e1x));
    v = v8_mul(v8_add(v8_add(v8_mul(dx, qx), v8_mul(dy, qy)), v8_mul(dz, qz)), inv);
    t = v8_mul(v8_add(v8_add(v8_mul(e2x, qx), v8_mul(e2y, qy)), v8_mul(e2z, qz)), inv);
    out = m8_or(v8_lt(v, zero), v8_gt(v8_add(u, v), one));
    m &= m8_bits(m8_andnot(out, m8_and(v8_gt(t, v8_splat(tmin)), v8_lt(t, v8_splat(tmax)))));
    if (m == 0u)
        return -1;
    v8_store(u, lu);
    v8_store(v, lv);
    v8_store(t, lt);
    best = tri8_nearest(b, m, lt, tmax, skip);
    if (best >= 0) {
        *t_out = lt[best];
        *u_out = lu[best];
        *v_out = lv[best];
    }
    return best;
}
#else
/* Ray-triangle, robust path: the watertight test of Woop, Benthin and Wald (JCGT 2013).
 * The vertices are moved to the ray origin, permuted so that the ray's largest direction
 * component is z, and sheared so that the ray becomes the +z axis; the 2-D edge
 * functions U, V, W then decide inside/outside. A point on a shared edge gets the same
 * edge function value (negated) from both triangles, so a ray never passes between
 * them; zero counts as inside for both. No determinant epsilon: only an exactly
 * degenerate projection (det = 0: a degenerate triangle or a ray in its plane) misses.
 * (u, v): the barycentric weights of p1 and p2. The shear of each vertex is one fused
 * multiply-add (cw_nmad) where the device has it: a function of the vertex and the ray
 * alone, so a shared vertex is moved to the same point for both of its triangles and the
 * test stays watertight (100k random triangles: 0.9% fewer kernel instructions; 1M at
 * 512x512: 8 pixels of 262144 moved by a sub-pixel decision). */
CW_INLINE int isect_triangle(CW_GLOBAL const cw_triangle *tri, const cw_rayinfo *ri, float tmin,
                             float tmax, float *t_out, float *u_out, float *v_out)
{
    CW_GLOBAL const float *p0 = (CW_GLOBAL const float *)&tri->p0;
    CW_GLOBAL const float *p1 = (CW_GLOBAL const float *)&tri->p1;
    CW_GLOBAL const float *p2 = (CW_GLOBAL const float *)&tri->p2;
    int kx = ri->kx, ky = ri->ky, kz = ri->kz;
    float az = p0[kz] - ri->oz, bz = p1[kz] - ri->oz, cz = p2[kz] - ri->oz;
    float ax = cw_nmad(ri->sx, az, p0[kx] - ri->ox);
    float ay = cw_nmad(ri->sy, az, p0[ky] - ri->oy);
    float bx = cw_nmad(ri->sx, bz, p1[kx] - ri->ox);
    float by = cw_nmad(ri->sy, bz, p1[ky] - ri->oy);
    float cx = cw_nmad(ri->sx, cz, p2[kx] - ri->ox);
    float cy = cw_nmad(ri->sy, cz, p2[ky] - ri->oy);
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    float det, tt, inv;

    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return 0;
    det = u + v + w;
    if (det == 0.0f)
        return 0;
    tt = u * (ri->sz * az) + v * (ri->sz * bz) + w * (ri->sz * cz);
    inv = 1.0f / det;
    tt *= inv;
    if (!(tt > tmin && tt < tmax))
        return 0;
    *t_out = tt;
    *u_out = v * inv;
    *v_out = w * inv;
    return 1;
}

/* The eight triangles of block b at once, each lane with exactly isect_triangle's float operations
 * (the same hits, bit for bit): the closest hit in (tmin, tmax), never the triangle whose
 * CW_REF is skip - 1. One test of eight lanes takes about as long as one of four on a CPU
 * with 256-bit vectors, so a leaf of up to eight triangles is one test (host/bvh_sah.h). Returns
 * its lane, the first of equally close ones (as testing them one by one in lane order), or -1. The
 * edge-sign and determinant tests are lane masks, so a block the ray misses (the common case) ends
 * before the division and without a branch per lane; an unused lane (zero vertices) has det = 0. */
CW_INLINE int isect_tri8(CW_GLOBAL const cw_tri8 *b, const cw_rayinfo *ri, float tmin, float tmax,
                         int skip, float *t_out, float *u_out, float *v_out)
{
    /* each vertex's permuted coordinates through three row pointers, at fixed offsets from
     * them: indexing the rows by 3 + kx and so on kept nine offsets, each reloaded and
     * scaled before its load (kernel instructions 209.1M -> 201.8M on 100k random triangles
     * at 256x256, the same images) */
    CW_GLOBAL const cw_float4 *x = b->v + 2 * ri->kx, *y = b->v + 2 * ri->ky;
    CW_GLOBAL const cw_float4 *z = b->v + 2 * ri->kz;
    cw_float8 ox = v8_splat(ri->ox), oy = v8_splat(ri->oy), oz = v8_splat(ri->oz);
    cw_float8 sx = v8_splat(ri->sx), sy = v8_splat(ri->sy), sz = v8_splat(ri->sz);
    cw_float8 az = v8_sub(tri8_row(z), oz), bz = v8_sub(tri8_row(z + 6), oz);
    cw_float8 cz = v8_sub(tri8_row(z + 12), oz);
    cw_float8 ax = v8_nmad(sx, az, v8_sub(tri8_row(x), ox));
    cw_float8 ay = v8_nmad(sy, az, v8_sub(tri8_row(y), oy));
    cw_float8 bx = v8_nmad(sx, bz, v8_sub(tri8_row(x + 6), ox));
    cw_float8 by = v8_nmad(sy, bz, v8_sub(tri8_row(y + 6), oy));
    cw_float8 cx = v8_nmad(sx, cz, v8_sub(tri8_row(x + 12), ox));
    cw_float8 cy = v8_nmad(sy, cz, v8_sub(tri8_row(y + 12), oy));
    cw_float8 u = v8_sub(v8_mul(cx, by), v8_mul(cy, bx));
    cw_float8 v = v8_sub(v8_mul(ax, cy), v8_mul(ay, cx));
    cw_float8 w = v8_sub(v8_mul(bx, ay), v8_mul(by, ax));
    cw_float8 zero = v8_splat(0.0f), det = v8_add(v8_add(u, v), w), tt, inv, t;
    /* isect_triangle's miss: some edge function < 0 and some > 0, or det = 0; as the least
     * and greatest of the three (four lane operations fewer than six comparisons: kernel
     * instructions -4.4% on 100k random triangles, the same image). A NaN edge function
     * can pass here where it would not there, but its lane's t is NaN and fails below. */
    cw_int8 neg = v8_lt(v8_min(v8_min(u, v), w), zero);
    cw_int8 pos = v8_gt(v8_max(v8_max(u, v), w), zero);
    unsigned m = m8_bits(m8_andnot(m8_and(neg, pos), v8_ne(det, zero)));
    float lv[8], lw[8], lt[8], li[8];
    int best;
    if (m == 0u)
        return -1;
    tt = v8_add(v8_add(v8_mul(u, v8_mul(sz, az)), v8_mul(v, v8_mul(sz, bz))),
                v8_mul(w, v8_mul(sz, cz)));
    inv = v8_div(v8_splat(1.0f), det);
    t = v8_mul(tt, inv);
    m &= m8_bits(m8_and(v8_gt(t, v8_splat(tmin)), v8_lt(t, v8_splat(tmax))));
    if (m == 0u)
        return -1;
    v8_store(v, lv);
    v8_store(w, lw);
    v8_store(t, lt);
    v8_store(inv, li);
    best = tri8_nearest(b, m, lt, tmax, skip);
    if (best >= 0) {
        *t_out = lt[best];
        *u_out = lv[best] * li[best];
        *v_out = lw[best] * li[best];
    }
    return best;
}
#endif

/* Vertex k (0, 1, 2) of lane i of block b: rows 3k .. 3k + 2 (see cw_tri8). */
CW_INLINE vec3 tri8_vertex(CW_GLOBAL const cw_tri8 *b, int k, int i)
{
    CW_GLOBAL const float *x = (CW_GLOBAL const float *)&b->v[6 * k];
    return v3(x[i], x[8 + i], x[16 + i]);
}

/* The surface at a triangle hit: the point from the barycentric coordinates (u, v), the
 * shading normal interpolated from the vertex normals of a smooth triangle. A hit in a
 * block (hit.block) reads the block, which holds the same vertices, material and normals
 * as the triangle. */
CW_INLINE cw_surface surface_triangle(const cw_world *w, cw_hit hit, vec3 p)
{
    cw_surface s;
    vec3 p0, p1, p2;
    float b0 = 1.0f - hit.u - hit.v;
    int material, normals;
    if (hit.block > 0) {
        CW_GLOBAL const cw_tri8 *b = &w->tri_blocks[hit.block - 1];
        p0 = tri8_vertex(b, 0, hit.lane);
        p1 = tri8_vertex(b, 1, hit.lane);
        p2 = tri8_vertex(b, 2, hit.lane);
        material = b->material[hit.lane];
        normals = b->normals[hit.lane];
    } else {
        CW_GLOBAL const cw_triangle *t = &w->triangles[hit.index];
        p0 = v3_from4(t->p0);
        p1 = v3_from4(t->p1);
        p2 = v3_from4(t->p2);
        material = t->material;
        normals = t->normals;
    }
    s.ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    s.flat = CW_REF(CW_PRIM_TRIANGLE, hit.index) + 1;
#if !CW_FAST
    {
        vec3 q0 = v3_scale(p0, b0), q1 = v3_scale(p1, hit.u), q2 = v3_scale(p2, hit.v);
        p = v3_add(q0, v3_add(q1, q2));
        s.err = v3_scale(v3_add(v3_abs(q0), v3_add(v3_abs(q1), v3_abs(q2))), CW_GAMMA(7));
    }
#endif
    if (normals >= 0) {
        vec3 sn = v3_add(v3_scale(v3_from4(w->normals[normals]), b0),
                         v3_add(v3_scale(v3_from4(w->normals[normals + 1]), hit.u),
                                v3_scale(v3_from4(w->normals[normals + 2]), hit.v)));
        float len = v3_len(sn);
        s.ns = len > 0.0f ? v3_scale(sn, 1.0f / len) : s.ng;
    } else {
        s.ns = s.ng;
    }
    s.material = material;
    s.p = p;
    return s;
}

#endif
