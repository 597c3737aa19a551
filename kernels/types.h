/* The one types header shared by the host (C99) and the kernels (OpenCL C 1.2).
 * Layout rules: no float3 (16 bytes on the device), every struct a multiple of 16
 * bytes with explicit padding; the host checks the sizes with _Static_assert. */
#ifndef CW_TYPES_H
#define CW_TYPES_H

#include "compat.h"

/* primitive kinds, as stored in cw_hit.kind and in the low three bits of a primitive
 * reference (ref = index * 8 + kind - 1). Each kind's intersection and surface code is in
 * its own header (sphere.h ...), dispatched by prim.h. An instance (a placed mesh, only in
 * the top level of the BVH) is not a primitive: its leaf entry sends the traversal into
 * its mesh's own tree (traverse.h, instance.h). */
#define CW_PRIM_NONE 0
#define CW_PRIM_SPHERE 1
#define CW_PRIM_TRIANGLE 2
#define CW_PRIM_POLYGON 3
#define CW_PRIM_CONE 4
#define CW_PRIM_INSTANCE 5
#define CW_REF(kind, index) ((index)*8 + (kind)-1)
#define CW_REF_KIND(ref) (((ref)&7) + 1)
#define CW_REF_INDEX(ref) ((ref) >> 3)

/* camera projections, as stored in cw_frame.projection */
#define CW_PROJ_PERSPECTIVE 0
#define CW_PROJ_ORTHOGRAPHIC 1
#define CW_PROJ_OBLIQUE 2

/* A sphere: 16 bytes. Its material is in a separate array (cw_world.sphere_materials),
 * so that a sphere takes 20 bytes where centre, radius and material side by side would
 * take 32 with the padding (spheres-4M: 48 MB less, host and device). */
typedef struct {
    cw_float4 center; /* xyz: centre, w: radius (< 0: visible from inside only) */
} cw_sphere;

typedef struct {
    cw_float4 p0, p1, p2; /* vertices (w unused) */
    int material;
    int normals; /* smooth triangles: index of the first of three vertex normals in the
                  * normal array; -1: flat */
    int pad0, pad1;
} cw_triangle;

/* Up to eight triangles of one BVH leaf side by side, for one 8-lane ray-triangle test
 * (isect_tri8, triangle.h): row r = 3 * k + a holds coordinate a (x, y, z) of vertex k (p0, p1,
 * p2), lanes 0-3 in v[2 * r] and lanes 4-7 in v[2 * r + 1], lane i that of triangle index[i] (an
 * index into the triangle array); an unused lane has index -1 and zero vertices. A row is 32
 * contiguous bytes, one load of eight lanes (two blocks of four side by side took a load and an
 * insert per row: 100k random triangles at 256x256, kernel instructions 201.8M -> 194.8M).
 * Lane i's material and normals are triangle index[i]'s, so that the surface at a hit in a
 * block (cw_hit.block) is made from the block the test has just read, not from a second,
 * random read of the triangle array: six cache lines in all, the rows in the first five. */
typedef struct {
    cw_float4 v[18];
    int index[8];
    int material[8];
    int normals[8];
} cw_tri8;

/* Up to four spheres of one BVH leaf side by side, tested alone or with the leaf's next
 * block in one 8-lane ray-sphere test (isect_sph8, sphere.h): lane i of cx, cy, cz, r is sphere
 * index[i]'s centre and radius (an index into the sphere array) and material[i] its material, so
 * that the surface at a hit in a block (cw_hit.block) is made from the block, not from a random
 * read of the sphere array; an unused lane has index -1, material 0 and radius 0 at the origin. */
typedef struct {
    cw_float4 cx, cy, cz, r;
    int index[4];
    int material[4];
} cw_sph4;

/* The count of a wide-BVH leaf of blocks (cw_bvhw_node.count < -1) is -1 - (nb | kind):
 * nb blocks, of spheres (cw_sph4, tested two at a time) where the CW_LEAF_SPHERES bit is set,
 * else of triangles (cw_tri8, one test each). */
#define CW_LEAF_SPHERES (1 << 24)

/* An open cone or cylinder (no caps) between a base and an apex disc. */
typedef struct {
    cw_float4 base; /* xyz: centre of the base disc, w: its radius */
    cw_float4 axis; /* xyz: unit vector from base to apex, w: height |apex - base| */
    float apex_radius;
    float slope; /* (apex_radius - base radius) / height: the radius gained per unit of height */
    int material;
    int pad0;
} cw_cone;

typedef struct {
    cw_float4 plane; /* xyz: unit normal (counter-clockwise front), w: offset d, n.x = d */
    int first;       /* index of the first vertex in the polygon vertex array */
    int count;       /* number of vertices */
    int material;
    int axis; /* dominant axis of the normal, dropped for the 2-D inside test */
    /* Edge bands, for polygons with many vertices (band_count 0: test every edge): the
     * projected second coordinate's range from band_lo is cut into band_count bands of
     * width 1 / band_scale; band b's (first, count) pair is at bands[band_first + 2b] and
     * lists the edges (by end vertex) whose range meets it. */
    float band_lo;
    float band_scale;
    int band_first;
    int band_count;
} cw_polygon;

/* Work-items per group, at most (the host asks for fewer where a kernel or device allows
 * fewer). */
#define CW_GROUP_SIZE 64

/* The per-pixel kernel (cw_pixel) hands out the pixels of a launch in tiles of CW_PIX_TILE x
 * CW_PIX_TILE pixels (cut at the launch's edges), one tile at a time to whichever work-item
 * asks next (an atomic counter, CW_COUNT_NEXT), to CW_PIX_GROUPS work-groups of up to
 * CW_PIX_LANES work-items per compute unit (of one on a CPU device: host/render_pass.c). */
#define CW_PIX_TILE 16
#define CW_PIX_LANES 16
#define CW_PIX_GROUPS 4

/* Entries of the kernels' BVH traversal stack (the host checks its tree needs no more). */
#define CW_BVH_STACK 128

/* The per-pixel kernel's pending rays (pixel.h), with refraction: a queue of CW_PIX_QUEUE
 * rays for the breadth-first walk of a pixel's ray tree (every level up to depth 6 fits),
 * and for a subtree that does not fit, a stack of CW_PIX_STACK for a depth-first walk,
 * which never holds more than max_depth rays (the host checks that CW_MAX_DEPTH fits). */
#ifndef CW_PIX_QUEUE /* (a test builds with a smaller queue, to walk subtrees depth first) */
#define CW_PIX_QUEUE 32
#endif
#if CW_PIX_QUEUE < 1
#error "CW_PIX_QUEUE must be at least 1"
#endif
#define CW_PIX_STACK 64

/* A node of the wide BVH the kernels traverse, collapsed from the host's binary one
 * (host/bvh.h): the boxes of up to CW_BVH_WIDTH children side by side, for one box test
 * over all lanes. bound[0..2]: lower corners (x, y, z), bound[3..5]: upper corners. An
 * empty slot's box lies at +infinity (both corners), which no ray enters (bvh_boxes). */
typedef struct {
    cw_lanes bound[6];
    int child[CW_BVH_WIDTH]; /* interior child: its node index; leaf: first entry in refs */
    int count[CW_BVH_WIDTH]; /* leaf: number of references (> 0), or for a leaf of
                              * triangles only or spheres only, -1 - its number of blocks
                              * (cw_tri8 or cw_sph4, with CW_LEAF_SPHERES) (< -1), child
                              * then the first block; interior: 0; empty: -1 */
} cw_bvhw_node;

/* A mesh placed in the world (a two-level BVH: the top level's leaf entry
 * CW_REF(CW_PRIM_INSTANCE, i) leads into the mesh's own tree at node root, whose
 * triangles are in mesh coordinates). Rows of 3x4 affine matrices, xyz the linear part and
 * w the translation; world coordinates are relative to the local origin, as everywhere. */
typedef struct {
    cw_float4 to_mesh[3];  /* world to mesh: rays go into the mesh's tree with it */
    cw_float4 to_world[3]; /* mesh to world: the hit point; normals by the transpose of
                            * to_mesh's linear part */
    int root;              /* the mesh's root node in the node array */
    int material;          /* >= 0: every triangle takes this material; -1: its own */
    int pad0, pad1;
} cw_instance;

typedef struct {
    cw_float4 ka; /* rgb ambient, w: Phong exponent p */
    cw_float4 kd; /* rgb diffuse */
    cw_float4 ks; /* rgb specular */
    cw_float4 km; /* rgb mirror */
    cw_float4 kt; /* rgb transmission (refraction weight), w: index of refraction */
} cw_material;

typedef struct {
    cw_float4 position;  /* xyz */
    cw_float4 intensity; /* rgb */
} cw_light;

/* Everything a pass needs to know besides the primitive arrays. */
typedef struct {
    cw_float4 eye;
    cw_float4 u, v, w;    /* orthonormal viewing basis */
    cw_float4 dir;        /* oblique projection: common ray direction */
    cw_float4 window;     /* image-plane window: l, r, b, t */
    cw_float4 background; /* rgb */
    cw_float4 ambient;    /* rgb ambient intensity Ia */
    float d;              /* perspective: image-plane distance */
    int projection;       /* CW_PROJ_* */
    int nx, ny;           /* image size in pixels */
    int max_depth;        /* the eye ray is depth 1 */
    int num_lights;
    int num_nodes;      /* BVH nodes; 0: empty scene */
    int spd_rays;       /* SPD counting: transmitters spawn a reflection ray even when km = 0 */
    int cam_nx, cam_ny; /* the full image the camera spans (nx, ny unless cropped) */
    int cam_x0, cam_y0; /* pixel (0, 0) of this image (counted from the bottom row) is
                         * pixel (cam_x0, cam_y0) of the full image */
    int pad0, pad1, pad2;
} cw_frame;

typedef struct {
    cw_float4 origin; /* xyz */
    cw_float4 dir;    /* xyz, unit length */
    cw_float4 weight; /* rgb: product of the mirror and transmission colours on the path */
    int pixel;        /* index into the image (row 0 at the top); < 0: no ray */
    int depth;        /* 1 for eye rays */
    int skip;         /* 1 + reference of the flat primitive the ray leaves (never hit
                       * again); 0: none */
    int skip_inst;    /* 1 + the instance that primitive belongs to (a mesh triangle);
                       * 0: a primitive of the world */
} cw_ray;

/* A shadow ray: if nothing blocks origin + t dir for 0 < t < origin.w, color is added to
 * the pixel. */
typedef struct {
    cw_float4 origin; /* xyz; w: distance to the light (tmax) */
    cw_float4 dir;    /* xyz, unit length */
    cw_float4 color;  /* rgb: the light's contribution if unblocked */
    int pixel;
    int skip;      /* as in cw_ray */
    int block;     /* the first of a shading point's shadow rays: how many there are (they are
                    * consecutive); the others: 0 */
    int skip_inst; /* as in cw_ray */
} cw_shadow_ray;

/* Queue and statistics counters, one int each. */
#define CW_COUNT_RAYS 0    /* rays appended to the next level's queue */
#define CW_COUNT_SHADOWS 1 /* shadow rays appended */
#define CW_COUNT_EYE_HITS 2
#define CW_COUNT_SECONDARY_HITS 3
#define CW_COUNT_BLOCKED 4
#define CW_COUNT_DEPTH 5 /* per-pixel kernel: the deepest ray traced (the wavefront's levels) */
#define CW_COUNT_NEXT 6  /* per-pixel kernel: the next run of pixels to hand out */
/* With CW_STATS, the work of the BVH walks (traverse.h): the nodes the closest-hit walks
 * visit and the primitive tests they make (a block of eight triangles, or one or two blocks of four
 * spheres: one test), then the same for
 * the shadow rays' any-hit walks (a shadow cache test included). */
#define CW_COUNT_CLOSEST_NODES 7
#define CW_COUNT_CLOSEST_TESTS 8
#define CW_COUNT_ANY_NODES 9
#define CW_COUNT_ANY_TESTS 10
#define CW_NUM_COUNTERS 12

typedef struct {
    float t;    /* ray parameter of the closest hit */
    float u, v; /* barycentric coordinates (triangles) */
    int kind;   /* CW_PRIM_*; CW_PRIM_NONE for a miss */
    int index;  /* index into the array of that kind */
    int inst;   /* 1 + the instance whose mesh the hit triangle is in; 0: the world's */
    int block;  /* a hit in a block (cw_tri8, cw_sph4 by kind): 1 + the block; 0: none */
    int lane;   /* and its lane there */
} cw_hit;

#endif
