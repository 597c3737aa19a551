/* box_: axis-aligned bounding boxes as (lo[3], hi[3]) pairs, for the BVH builder
 * (bvh.c: its primitives, bins and nodes) and the primitives' boxes (devscene.c). Header
 * only: the builder's inner loops inline them. */
#ifndef CW_BOX_H
#define CW_BOX_H

#include <math.h>

/* The empty box: every point grows it to itself. */
static inline void box_empty(float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
}

/* Grows a box to contain the box (plo, phi); NaN coordinates are ignored (the comparison
 * is false). */
static inline void box_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = plo[a] < lo[a] ? plo[a] : lo[a];
        hi[a] = phi[a] > hi[a] ? phi[a] : hi[a];
    }
}

/* Grows a box to contain the point (x, y, z); NaN coordinates are ignored. */
static inline void box_add_point(float lo[3], float hi[3], float x, float y, float z)
{
    const float p[3] = {x, y, z};
    box_grow(lo, hi, p, p);
}

/* Grows a box to contain the disc of radius rad around c, perpendicular to the unit
 * axis a. */
static inline void box_add_disc(float lo[3], float hi[3], const float c[3], const float a[3],
                                float rad)
{
    float e[3];
    for (int k = 0; k < 3; k++)
        e[k] = rad * sqrtf(fmaxf(0.0f, 1.0f - a[k] * a[k]));
    box_add_point(lo, hi, c[0] - e[0], c[1] - e[1], c[2] - e[2]);
    box_add_point(lo, hi, c[0] + e[0], c[1] + e[1], c[2] + e[2]);
}

/* Widens a box by a relative margin rel of its largest coordinate per axis. */
static inline void box_widen(float lo[3], float hi[3], float rel)
{
    for (int k = 0; k < 3; k++) {
        float m = rel * fmaxf(fabsf(lo[k]), fabsf(hi[k]));
        lo[k] -= m;
        hi[k] += m;
    }
}

/* Surface area; 0 for an empty box (or one with a NaN extent). */
static inline double box_area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0))
        return 0.0;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

#endif
