/* The one types header shared by the host (C99) and the kernels (OpenCL C 1.2).
 * Layout rules: no float3 (16 bytes on the device), every struct a multiple of 16
 * bytes with explicit padding; the host checks the sizes with _Static_assert. */
#ifndef CW_TYPES_H
#define CW_TYPES_H

#include "compat.h"

/* primitive kinds, as stored in cw_hit.kind */
#define CW_PRIM_NONE 0
#define CW_PRIM_SPHERE 1
#define CW_PRIM_TRIANGLE 2
#define CW_PRIM_POLYGON 3

/* camera projections, as stored in cw_frame.projection */
#define CW_PROJ_PERSPECTIVE 0
#define CW_PROJ_ORTHOGRAPHIC 1
#define CW_PROJ_OBLIQUE 2

typedef struct {
    cw_float4 center; /* xyz: centre, w: radius */
    int material;
    int pad0, pad1, pad2;
} cw_sphere;

typedef struct {
    cw_float4 p0, p1, p2; /* vertices (w unused) */
    cw_float4 n0, n1, n2; /* vertex normals, used when smooth != 0 */
    int material;
    int smooth;
    int pad0, pad1;
} cw_triangle;

typedef struct {
    cw_float4 plane; /* xyz: unit normal (counter-clockwise front), w: offset d, n.x = d */
    int first;       /* index of the first vertex in the polygon vertex array */
    int count;       /* number of vertices */
    int material;
    int axis;        /* dominant axis of the normal, dropped for the 2-D inside test */
} cw_polygon;

/* One node of the flattened bounding volume hierarchy (depth-first order: an interior
 * node's first child is the next node). */
typedef struct {
    float lo[3];
    int start; /* leaf: first entry in the primitive-reference array;
                * interior: index of the second child */
    float hi[3];
    int count; /* leaf: number of primitives (> 0); interior: -(split axis) (0, -1, -2) */
} cw_bvh_node;

typedef struct {
    cw_float4 ka; /* rgb ambient, w: Phong exponent p */
    cw_float4 kd; /* rgb diffuse */
    cw_float4 ks; /* rgb specular */
    cw_float4 km; /* rgb mirror */
    cw_float4 kt; /* rgb transmission (not rendered yet), w: index of refraction */
} cw_material;

typedef struct {
    cw_float4 position;  /* xyz */
    cw_float4 intensity; /* rgb */
} cw_light;

/* Everything a pass needs to know besides the primitive arrays. */
typedef struct {
    cw_float4 eye;
    cw_float4 u, v, w;     /* orthonormal viewing basis */
    cw_float4 dir;         /* oblique projection: common ray direction */
    cw_float4 window;      /* image-plane window: l, r, b, t */
    cw_float4 background;  /* rgb */
    cw_float4 ambient;     /* rgb ambient intensity Ia */
    float d;               /* perspective: image-plane distance */
    int projection;        /* CW_PROJ_* */
    int nx, ny;            /* image size in pixels */
    int max_depth;         /* the eye ray is depth 1 */
    int num_spheres, num_triangles, num_polygons;
    int num_lights;
    int pad0, pad1, pad2;
} cw_frame;

typedef struct {
    cw_float4 origin; /* xyz */
    cw_float4 dir;    /* xyz, unit length */
    cw_float4 weight; /* rgb: product of the mirror colours along the path */
    int pixel;        /* index into the image (row 0 at the top); < 0: no ray */
    int depth;        /* 1 for eye rays */
    int pad0, pad1;
} cw_ray;

typedef struct {
    float t;   /* ray parameter of the closest hit */
    float u, v; /* barycentric coordinates (triangles) */
    int kind;  /* CW_PRIM_*; CW_PRIM_NONE for a miss */
    int index; /* index into the array of that kind */
    int pad0, pad1, pad2;
} cw_hit;

#endif
